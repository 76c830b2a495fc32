"""GMS96 servo amplifier family (software v4.04): link layer, device and tables."""

from devsim.devices.gms96.device import Gms96Device

__all__ = ["Gms96Device"]
