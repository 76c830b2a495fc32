"""The SAIA PCD4.H3 servo positioning module (spec pcd4h3.md) in a simulated PCD4 PLC: the
LM628 per axis (:mod:`~devsim.devices.pcd4h3.lm628`), the PCD9.H3E1 library
(:mod:`~devsim.devices.pcd4h3.library`), the PLC cycle (:mod:`~devsim.devices.pcd4h3.model`) and
S-Bus / Ether-S-Bus as the host link (:mod:`~devsim.devices.pcd4h3.face`)."""

from devsim.devices.pcd4h3.device import Pcd4h3Device

__all__ = ["Pcd4h3Device"]
