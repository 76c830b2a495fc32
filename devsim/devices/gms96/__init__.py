"""GMS96 servo amplifier family (software v4.04; manual §1-§6, spec gms96.md): the device."""

from devsim.devices.gms96.device import Gms96Device

__all__ = ["Gms96Device"]
