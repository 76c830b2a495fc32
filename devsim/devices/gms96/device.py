"""The GMS96 servo amplifier family as a devsim kind: the card under its FT1.2 face.

Manual "GMS96 Softwarebeschreibung", software v4.04 (§2 the interface, §2.3 the commands); spec
gms96.md.  The machine is
:class:`~devsim.devices.gms96.model.Gms96Card`, the link and commands
:class:`~devsim.devices.gms96.face.Gms96Face`; names and faults are declared in
:mod:`~devsim.devices.gms96.points`.  Several cards share a multidrop line through
:class:`devsim.core.bus.Bus`.
"""

from __future__ import annotations

from typing import Any, ClassVar

import msgspec

from devsim.core.device import Device
from devsim.core.kit import CaptureTag, Command, ErrorCode, PortDef, Reference, Table
from devsim.devices.gms96 import tables
from devsim.devices.gms96.commands import (
    G_FUNCTIONS,
    H_FUNCTIONS,
    M_FUNCTIONS,
    Q_TYPES,
    QUEUED_COMMANDS,
    RESET_FUNCTIONS,
)
from devsim.devices.gms96.config import Gms96Config
from devsim.devices.gms96.deviations import DEVIATIONS
from devsim.devices.gms96.drive_actions import DRIVE
from devsim.devices.gms96.face import ON_RECEIPT, P_ON_RECEIPT, SHORT_COMMANDS, T_QUERIES, Gms96Face
from devsim.devices.gms96.framing import FT12
from devsim.devices.gms96.model import Gms96Card
from devsim.devices.gms96.nparams import N_TABLE
from devsim.devices.gms96.plc import FB254_FUNCTIONS
from devsim.devices.gms96.points import FAULTS, POINTS
from devsim.devices.gms96.program import DIRECT_COMMANDS, P_FUNCTIONS
from devsim.devices.gms96.spindle import SPINDLE_FUNCTIONS

__all__ = ["Gms96Device"]


def _spelled(prefix: str, table: Table[Any]) -> list[Command[Any]]:
    """A sub-table's rows as the manual writes them (``T1;4``, ``p10;16``)."""
    return [msgspec.structs.replace(row, token=prefix + row.token) for row in table]


class Gms96Device(Device):
    """One GMS96 card on a serial line (RS422/485, DIN 19244 FT1.2, 8E1; manual §2.1, spec §2)."""

    kind: ClassVar[str] = "gms96"
    description: ClassVar[str] = "GMS96 servo amplifier with indexer and PLC (DIN 19244 / FT1.2, RS422)"
    config_model = Gms96Config
    model_class = Gms96Card
    face_classes: ClassVar[dict[str, Any]] = {"main": Gms96Face}
    ports = (PortDef(framing=FT12, capture=CaptureTag(2), address="dil.address"),)  # the DIL switch (§2.2)
    points = POINTS
    drive = DRIVE
    faults = FAULTS

    @classmethod
    def reference(cls) -> Reference:
        return Reference(
            commands=[
                *_spelled("#", SHORT_COMMANDS),
                *ON_RECEIPT,
                *_spelled("p", P_ON_RECEIPT),
                *_spelled("T", T_QUERIES),
                *QUEUED_COMMANDS,
                *_spelled("G", G_FUNCTIONS),
                *_spelled("H", H_FUNCTIONS),
                *_spelled("m", M_FUNCTIONS),
                *_spelled("p", P_FUNCTIONS),
                *_spelled("p10;", DIRECT_COMMANDS),
                *_spelled("Q", Q_TYPES),
                *_spelled("Q8;", SPINDLE_FUNCTIONS),
                *_spelled("r", RESET_FUNCTIONS),
                *_spelled("FB254 Accu1=", FB254_FUNCTIONS),
            ],
            parameter_table=N_TABLE,
            errors=[ErrorCode(str(n), text, "§4.4 MB4") for n, text in sorted(tables.MESSAGES.items())],
            deviations=list(DEVIATIONS),
        )
