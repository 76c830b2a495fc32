"""The SAIA PCD4 with PCD4.H3 servo positioning modules as a devsim kind.

Manual "Handbuch Positioniermodule für Servoantriebe PCD4.H3..", SAIA-Burgess 26/729 D2 (seed
002); spec pcd4h3.md.  The machine is :class:`~devsim.devices.pcd4h3.model.Pcd4`: the PLC with the
PCD9.H3E1 library over an LM628 per axis; its ports are S-Bus in serial data mode (``sbus``, a
pty) and Ether-S-Bus on UDP and TCP (``ether_udp``, ``ether_tcp``), :mod:`~devsim.devices.pcd4h3.face`.
"""

from __future__ import annotations

from typing import Any, ClassVar

from devsim.core.device import Device
from devsim.core.kit import CaptureTag, Command, ErrorCode, PortDef, Reference
from devsim.devices.pcd4h3.config import Pcd4h3Config
from devsim.devices.pcd4h3.deviations import DEVIATIONS
from devsim.devices.pcd4h3.face import EtherDatagramFace, EtherStreamFace, SbusFace
from devsim.devices.pcd4h3.framing import ETHER_TCP
from devsim.devices.pcd4h3.library import FUNCTIONS
from devsim.devices.pcd4h3.model import Pcd4
from devsim.devices.pcd4h3.points import DRIVE, FAULTS, POINTS
from devsim.devices.pcd4h3.services import SERVICES
from devsim.devices.pcd4h3.tables import REGISTERS

__all__ = ["ETHER_TCP_HOSTS", "Pcd4h3Device"]

#: How many hosts the Ether-S-Bus TCP port serves at once.  The manual (a serial-era H3 manual)
#: is silent; a PCD's Ethernet interface serves several connections: 8 ([DECISION], spec §9.3).
ETHER_TCP_HOSTS = 8


class Pcd4h3Device(Device):
    """A PCD4 CPU with H3 modules running the PCD9.H3E1 library, one S-Bus station."""

    kind: ClassVar[str] = "pcd4h3"
    description: ClassVar[str] = "SAIA PCD4.H3 servo positioning module (LM628) in a PCD4, S-Bus and Ether-S-Bus"
    config_model = Pcd4h3Config
    ports = (
        PortDef("sbus", "S-Bus serial data mode (FS B5h, stuffing, CRC-16; 9600 8N1)", "§9.2",
                capture=CaptureTag(5), address="station"),
        PortDef("ether_udp", "Ether-S-Bus on UDP, one telegram per datagram", "§9.3", default="udp:5050"),
        PortDef("ether_tcp", "Ether-S-Bus on TCP, telegrams back to back", "§9.3", default="tcp:5050", framing=ETHER_TCP,
                hosts=ETHER_TCP_HOSTS),
    )
    model_class = Pcd4
    face_classes: ClassVar[dict[str, Any]] = {"sbus": SbusFace, "ether_udp": EtherDatagramFace,
                                              "ether_tcp": EtherStreamFace}
    points = POINTS
    faults = FAULTS
    drive = DRIVE
    modbus_unit = staticmethod(lambda model: model.station)  # §9.8: "Unit id = S-Bus station"

    @classmethod
    def reference(cls) -> Reference:
        commands: list[Command[Any]] = [*SERVICES, *FUNCTIONS]
        errors = [ErrorCode("ACK 0000h", "executed"), ErrorCode("NAK 0001h", "unsupported command, bad count, address "
                            "out of range, a write to the outputs or the diagnostics", "§9.2"),
                  ErrorCode("(silence)", "CRC or framing error, another station, a broadcast", "§9.2")]
        return Reference(commands=commands, errors=errors, parameter_table=REGISTERS, deviations=list(DEVIATIONS))
