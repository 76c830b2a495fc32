"""The ELESTA POSELESTA II/III CNC as a devsim kind: three serial ports over one control.

Manual "Schnittstellenbeschreibung POSELESTA II/III" (seed 004); spec poselesta.md.  The
control is :class:`~devsim.devices.poselesta.model.PoselestaCnc`; the ports V6 (external data
media), V7 (DNC) and V8 (external keyboard, receive-only) are
:class:`~devsim.devices.poselesta.face.PoselestaPortFace`; names in
:mod:`~devsim.devices.poselesta.points`, the tape code in :mod:`~devsim.devices.poselesta.tape`.
"""

from __future__ import annotations

from typing import Any, ClassVar

from devsim.core.device import Device
from devsim.core.kit import CaptureTag, ErrorCode, PortDef, Reference
from devsim.devices.poselesta.codes import WERTBEREICHES_UEBERLAUF
from devsim.devices.poselesta.config import PoselestaConfig
from devsim.devices.poselesta.deviations import DEVIATIONS
from devsim.devices.poselesta.drive_actions import DRIVE
from devsim.devices.poselesta.face import PoselestaPortFace
from devsim.devices.poselesta.links import TRANSFERS
from devsim.devices.poselesta.model import PoselestaCnc
from devsim.devices.poselesta.parameters import PARAMETERS
from devsim.devices.poselesta.points import FAULTS, POINTS

__all__ = ["PoselestaDevice"]


class PoselestaDevice(Device):
    """One POSELESTA II/III control with its serial ports V6, V7 and V8."""

    kind: ClassVar[str] = "poselesta"
    description: ClassVar[str] = "ELESTA POSELESTA II/III CNC (tape images on V6/V7 DNC, V8 keyboard, M/S/T bus)"
    config_model = PoselestaConfig
    ports = (
        PortDef("v6", "external data media: printer, cassette, tape reader/punch, TTY", "§2.6.2",
                capture=CaptureTag(3, 6)),
        PortDef("v7", "DNC (20 mA): programs in and out", "§2.6.3", capture=CaptureTag(3, 7)),
        PortDef("v8", "external keyboard (receive only)", "§2.6.4", receive_only=True, capture=CaptureTag(3, 8)),
    )
    model_class = PoselestaCnc
    face_classes: ClassVar[dict[str, Any]] = {"v6": PoselestaPortFace, "v7": PoselestaPortFace,
                                              "v8": PoselestaPortFace}
    points = POINTS
    faults = FAULTS
    drive = DRIVE

    @classmethod
    def reference(cls) -> Reference:
        return Reference(
            commands=list(TRANSFERS),
            parameter_table=PARAMETERS,
            errors=[ErrorCode(WERTBEREICHES_UEBERLAUF, "value range overflow: wrong code, baud, format or "
                              "too many words; the transfer stops", "§2.6")],
            deviations=list(DEVIATIONS),
        )
