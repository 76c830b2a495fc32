"""The Stögra SERS stepper drive as a devsim kind: the model under its ASCII face.

Manual "SERS Version V04, Firmware ab 120901"; spec sers.md.  The machine is
:class:`~devsim.devices.sers.model.SersDrive`, the serial line protocol
:class:`~devsim.devices.sers.face.SersFace`; names and faults are declared in
:mod:`~devsim.devices.sers.points`, commands in :mod:`~devsim.devices.sers.execution`.
"""

from __future__ import annotations

from typing import Any, ClassVar

from devsim.core.device import Device
from devsim.core.kit import CaptureTag, ErrorCode, PortDef, Reference
from devsim.devices.sers.config import SersConfig
from devsim.devices.sers.constants import DRIVE_ERRORS
from devsim.devices.sers.deviations import DEVIATIONS
from devsim.devices.sers.drive_actions import DRIVE
from devsim.devices.sers.errors import ERRNO
from devsim.devices.sers.execution import COMMANDS, STATEMENTS
from devsim.devices.sers.face import SersFace
from devsim.devices.sers.framing import LINES
from devsim.devices.sers.interactive import INTERACTIVE
from devsim.devices.sers.model import SersDrive
from devsim.devices.sers.parameters import PARAMETER_TABLE
from devsim.devices.sers.points import FAULTS, POINTS

__all__ = ["SersDevice"]


class SersDevice(Device):
    """One SERS drive on a serial line (RS-232, or RS-485 multidrop with others; §1, §3.6)."""

    kind: ClassVar[str] = "sers"
    description: ClassVar[str] = "Stögra SERS stepper driver with positioning control (ASCII, RS-232/RS-485)"
    config_model = SersConfig
    hears_others: ClassVar[bool] = True  # a master's statements reach its slaves (§3.6.2)
    model_class = SersDrive
    face_classes: ClassVar[dict[str, Any]] = {"main": SersFace}
    ports = (PortDef(framing=LINES, capture=CaptureTag(1), address="address"),)  # DIP switch 2 (§3.1.1)
    points = POINTS
    faults = FAULTS
    drive = DRIVE

    @property
    def talks_to_others(self) -> bool:
        """Only a master (address 0) sends statements of its own to the drives on its line; what
        a slave sends on its own (``@nPOS=1``, ``@nP0=0``, §4.8.6.11) the others pass over."""
        return bool(self.model.cfg.address == 0)

    @classmethod
    def reference(cls) -> Reference:
        return Reference(
            commands=[*INTERACTIVE, *STATEMENTS, *COMMANDS],
            parameter_table=PARAMETER_TABLE,
            errors=[*(ErrorCode(str(n), f"{de} — {en}", "§4.8.3.1") for n, (de, en) in sorted(ERRNO.items())),
                    *(ErrorCode(f"P11 {bit}", f"drive error: {text}", "§4.8.3 P11")
                      for bit, text in sorted(DRIVE_ERRORS.items()))],
            deviations=list(DEVIATIONS),
        )
