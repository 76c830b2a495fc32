"""The hardware limit switches V19/4–11 (manual §2.3, section 2.3.4 lost; spec poselesta.md §5.5,
G-LIMIT): L = actuated.  A switch actuated while its axis moves towards it stops every axis at
once (no ramp, the loops stay closed), aborts the program and shows the alarm ``LIMIT_SWITCH``;
motion towards an actuated switch is refused, motion away from it is allowed (MANUAL)."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from devsim.devices.poselesta.signals import AXES

if TYPE_CHECKING:
    from devsim.devices.poselesta.cnc import PoselestaCnc

__all__ = ["LIMIT_SWITCH", "LimitSwitches"]

LIMIT_SWITCH = "LIMIT_SWITCH"


class LimitSwitches:
    """The eight limit-switch inputs V19/4–11 of one control (manual §2.3; spec §5.5)."""

    def __init__(self, cnc: PoselestaCnc) -> None:
        self.cnc = cnc
        for a in AXES:
            for side in ("pos", "neg"):
                cnc.signals.subscribe(f"limit_{side}_{a}", self._changed)

    def blocked(self, axis: str, direction: float) -> bool:
        """Would a motion of ``axis`` in ``direction`` run into an actuated switch?"""
        if direction == 0:
            return False
        return not self.cnc.signals.get(f"limit_{'pos' if direction > 0 else 'neg'}_{axis}")

    def refuse(self, axis: str) -> None:
        self.cnc.message = LIMIT_SWITCH
        self.cnc.record_event("limit_inhibit")
        self.cnc.announce("event", "limit", "inhibit", axis)

    def _changed(self, name: str, _old: Any, new: Any) -> None:
        if new:
            return
        _, side, a = name.split("_")
        velocity = self.cnc.axes[a].velocity()
        if velocity == 0 or (velocity > 0) != (side == "pos"):
            return  # actuated at rest or while moving away: only further motion towards it is refused
        cnc = self.cnc
        if cnc.field.homing == a and cnc.field.reverse(a):
            return  # the homing search turns back once (spec §5.6)
        for axis in cnc.axes.values():
            axis.quick_stop()
        cnc.message = LIMIT_SWITCH
        cnc.record_event("limit_switch")
        cnc.announce("event", "limit", "switch", name)
        cnc.manual.reset()
        cnc.executor.abort()
