"""The Siemens SIMATIC S5 IP247 stepper positioning module as a devsim kind.

Manual "SIMATIC S5 Positionierbaugruppe für Schrittmotoren IP247", 6ES5 998-5SB12 (seed 000);
spec ip247.md.  The machine is :class:`~devsim.devices.ip247.module.Ip247Module`; its ports are
the programmer port ``pg`` (AS511 with the "IP247-SIM/PG v1" profile, 9600 8E1) and the PLC side
``ag`` (the "IP247-SIM/AG v1" endpoint, best bound to TCP), :mod:`~devsim.devices.ip247.face`.
"""

from __future__ import annotations

from typing import Any, ClassVar

from devsim.core.device import Device
from devsim.core.kit import CaptureTag, PortDef, Reference
from devsim.devices.ip247.config import Ip247Config
from devsim.devices.ip247.deviations import DEVIATIONS
from devsim.devices.ip247.drive_actions import DRIVE, SETUP
from devsim.devices.ip247.face import AgFace, PgFace
from devsim.devices.ip247.modes import AXIS_MODES
from devsim.devices.ip247.module import OBSERVED, OPERATOR_JOBS, Ip247Module
from devsim.devices.ip247.points import FAULTS, POINTS
from devsim.devices.ip247.records import DELETE_RECORDS, READ_RECORDS, WRITE_RECORDS
from devsim.devices.ip247.tables import MACHINE_DATA, error_codes, mode_token

__all__ = ["Ip247Device"]


class Ip247Device(Device):
    """One IP247 with three stepper axes, its PG port and its PLC side."""

    kind: ClassVar[str] = "ip247"
    description: ClassVar[str] = "Siemens SIMATIC S5 IP247 stepper positioning module (PG port AS511, PLC side)"
    config_model = Ip247Config
    ports = (
        PortDef("pg", "programmer port X8 (AS511, IP247-SIM/PG v1; 9600 8E1)", "§3.3.5", capture=CaptureTag(4)),
        PortDef("ag", "PLC side: FB164/FB165 services (IP247-SIM/AG v1, length-framed; TCP)", "§6"),
    )
    model_class = Ip247Module
    face_classes: ClassVar[dict[str, Any]] = {"pg": PgFace, "ag": AgFace}
    points = POINTS
    faults = FAULTS
    drive = DRIVE
    drive_setup = SETUP

    @classmethod
    def reference(cls) -> Reference:
        return Reference(
            commands=sorted([*AXIS_MODES, OPERATOR_JOBS.rows[mode_token(17)], *WRITE_RECORDS, *DELETE_RECORDS,
                             *READ_RECORDS, *OBSERVED], key=lambda row: int(row.token.removeprefix("BA"))),
            parameter_table=MACHINE_DATA,
            errors=error_codes(),
            deviations=list(DEVIATIONS),
        )
