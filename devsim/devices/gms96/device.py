"""The GMS96 servo amplifier family as a devsim kind: the card under its FT1.2 face.

Manual "GMS96 Softwarebeschreibung", software v4.04; spec gms96.md.  The machine is
:class:`~devsim.devices.gms96.card.Gms96Card`, the link and commands
:class:`~devsim.devices.gms96.face.Gms96Face`; names and faults are declared in
:mod:`~devsim.devices.gms96.points`.  Several cards share a multidrop line through
:class:`devsim.core.bus.Bus`.
"""

from __future__ import annotations

from typing import Any, ClassVar

from devsim.core.device import Device
from devsim.core.kit import ErrorCode, Reference
from devsim.core.settings import Section
from devsim.devices.gms96 import tables
from devsim.devices.gms96.card import Gms96Card
from devsim.devices.gms96.config import Gms96Config
from devsim.devices.gms96.drive_actions import DRIVE
from devsim.devices.gms96.face import IMMEDIATE_COMMANDS, QUEUED_COMMANDS, SHORT_COMMANDS, Gms96Face
from devsim.devices.gms96.nparams import N_TABLE
from devsim.devices.gms96.points import FAULTS, POINTS

__all__ = ["Gms96Device"]


class Gms96Device(Device):
    """One GMS96 card on a serial line (RS422/485, DIN 19244 FT1.2, 8E1)."""

    kind: ClassVar[str] = "gms96"
    description: ClassVar[str] = "GMS96 servo amplifier with indexer and PLC (DIN 19244 / FT1.2, RS422)"
    config_model: ClassVar[Section] = Gms96Config
    model_class = Gms96Card
    face_classes: ClassVar[dict[str, Any]] = {"main": Gms96Face}
    points = POINTS
    drive = DRIVE
    faults = FAULTS

    @classmethod
    def reference(cls) -> Reference:
        return Reference(
            commands=[
                *(row.__class__(f"#{row.token}", row.handler, row.section, row.doc) for row in SHORT_COMMANDS),
                *IMMEDIATE_COMMANDS,
                *QUEUED_COMMANDS,
            ],
            parameter_table=N_TABLE,
            errors=[ErrorCode(str(n), text, "§4.4 MB4") for n, text in sorted(tables.MESSAGES.items())],
        )
