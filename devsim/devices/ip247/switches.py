"""Limit switches and the reference cam of an IP247 axis at fixed mechanical positions (spec
ip247.md §4.13, §5.7, §5.15): they see where the motor really is, so after lost steps or with a
wiring fault they switch where the mechanics are, not where the module's count says.

The mechanical position is the motor position the module counts, followed by the motor with a
sense (1, −1 with T/RP swapped, 0 when it stands) up to how far it follows (step loss): for each
move the mechanical boundaries map onto motor positions, which the shared axis watches
(:meth:`~devsim.core.axis.Axis.watch`) at the exact instant.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

__all__ = ["MechanicalSwitch"]


class MechanicalSwitch:
    """Active while low <= mechanical position <= high; ``on_change(active)`` at the crossing."""

    def __init__(self, axis: Any, low: float, high: float, position: float, on_change: Callable[[bool], None]) -> None:
        self.axis, self.low, self.high, self.on_change = axis, low, high, on_change
        self.active = low <= position <= high
        self._watches: list[Any] = []

    def arm(self, x0: float, mech0: float, sense: int, follows: float) -> None:
        """A new move from motor position ``x0`` (mechanical ``mech0``)."""
        for watch in self._watches:
            watch.cancel()
        self._watches.clear()
        if sense == 0:
            return
        for boundary, entering in ((self.low, 1), (self.high, -1)):
            if math.isinf(boundary):
                continue
            x = x0 + (boundary - mech0) / sense
            if abs(x - x0) <= follows:
                self._watches.append(self.axis.watch(x, lambda d, e=entering: self._crossed(d * sense, e)))

    def _crossed(self, mechanical_direction: int, entering: int) -> None:
        active = mechanical_direction == entering
        if active != self.active:
            self.active = active
            self.on_change(active)
