"""The hardware limit switches V19/4–11 (manual §2.3, section 2.3.4 lost; spec poselesta.md §5.5,
G-LIMIT): L = actuated.  A switch actuated while its axis moves towards it stops every axis at
once (no ramp, the loops stay closed), aborts the program and shows the alarm ``LIMIT_SWITCH``;
motion towards an actuated switch is refused, motion away from it is allowed (MANUAL)."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from devsim.core.signals import SignalBank
from devsim.devices.poselesta.axes import Axes
from devsim.devices.poselesta.screen import Screen
from devsim.devices.poselesta.signals import AXES

__all__ = ["LIMIT_SWITCH", "LimitSwitches"]

LIMIT_SWITCH = "LIMIT_SWITCH"


class LimitSwitches:
    """The eight limit-switch inputs V19/4–11 of one control (manual §2.3; spec §5.5).

    ``outside_towards(axis, direction)`` says whether a motion would leave the working field
    further (the working field's rule joins the switches' in :meth:`refuses`);
    ``homing_turn(axis)`` lets a homing search turn back at a switch once; ``stopped()`` is what
    else stops when a switch is hit (manual motion, the program)."""

    def __init__(self, signals: SignalBank, axes: Axes, screen: Screen, *,
                 outside_towards: Callable[[str, float], bool], homing_turn: Callable[[str], bool],
                 stopped: Callable[[], None]) -> None:
        self._signals = signals
        self._axes = axes
        self._screen = screen
        self._outside_towards = outside_towards
        self._homing_turn = homing_turn
        self._stopped = stopped
        changed = self._changed  # one bound method for every switch
        for a in AXES:
            for side in ("pos", "neg"):
                signals.subscribe(f"limit_{side}_{a}", changed)

    def blocked(self, axis: str, direction: float) -> bool:
        """Would a motion of ``axis`` in ``direction`` run into an actuated switch?"""
        if direction == 0:
            return False
        return not self._signals.get(f"limit_{'pos' if direction > 0 else 'neg'}_{axis}")

    def refuses(self, axis: str, direction: float) -> bool:
        """A motion towards an actuated switch or further out of the working field is refused
        (spec §5.5): the alarm shows, and True."""
        if self.blocked(axis, direction) or self._outside_towards(axis, direction):
            self.refuse(axis)
            return True
        return False

    def refuse(self, axis: str) -> None:
        self._screen.show(LIMIT_SWITCH)
        self._screen.record("limit_inhibit")
        self._screen.report("limit", "inhibit", axis)

    def _changed(self, name: str, _old: Any, new: Any) -> None:
        if new:
            return
        _, side, a = name.split("_")
        velocity = self._axes[a].velocity()
        if velocity == 0 or (velocity > 0) != (side == "pos"):
            return  # actuated at rest or while moving away: only further motion towards it is refused
        if self._homing_turn(a):
            return  # the homing search turns back once (spec §5.6)
        for axis in self._axes.values():
            axis.quick_stop()
        self._screen.show(LIMIT_SWITCH)
        self._screen.record("limit_switch")
        self._screen.report("limit", "switch", name)
        self._stopped()
