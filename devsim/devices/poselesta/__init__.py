"""ELESTA POSELESTA II/III CNC (kind ``poselesta``)."""

from devsim.devices.poselesta.device import PoselestaDevice

__all__ = ["PoselestaDevice"]
