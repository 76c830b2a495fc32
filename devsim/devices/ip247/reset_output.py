"""The reset output RS of an IP247 axis to its power unit (manual §2.8.1, §4.2.4; spec ip247.md
§2.2): high while the axis has no valid machine data (the power unit held in reset), low once it
has; a 100 ms high pulse after a machine-data input and at the start of a reference run
synchronises the power unit's current-pattern counter, and ends at the level the data give."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from devsim.core.clock import Clock
from devsim.core.signals import SignalBank

__all__ = ["RS_PULSE", "ResetOutput"]

RS_PULSE = 0.1  # seconds (spec §5.16)


class ResetOutput:
    """RS of one axis (manual §2.8.1); ``valid()`` says whether the axis has valid machine data."""

    def __init__(self, name: str, signals: SignalBank, clock: Clock, valid: Callable[[], bool]) -> None:
        self.name, self.signals, self.clock, self.valid = name, signals, clock, valid
        self._pulse: Any = None  # the timer ending a pulse

    def pulse(self) -> None:
        """A 100 ms high pulse."""
        self.signals.set(self.name, True)
        self.cancel()
        self._pulse = self.clock.call_later(RS_PULSE, self._over)

    def _over(self) -> None:
        self._pulse = None
        self.update()

    def update(self) -> None:
        """The level the machine data give; a pulse in progress ends on its own."""
        if self._pulse is None:
            self.signals.set(self.name, not self.valid())

    def cancel(self) -> None:
        """Drop a pulse in progress (power-up)."""
        if self._pulse is not None:
            self._pulse.cancel()
            self._pulse = None
