"""Reference marks, homing and the working field (manual §2.2.2, §2.3.23, §2.4.4; spec
poselesta.md §5.5, §5.6, G-HOME, G-SOFT).

Homing (``panel.reference``, MANUAL) moves the axis towards ``home_direction`` at 10 % of its
maximum feed until it passes a reference mark while its activation input V24 is H; the actual
value there becomes ``reference_value``, the axis brakes to a stop and is referenced.  A limit
switch reached first turns the search back once; reached again, it stops with its alarm.  The marks
sit where the configuration puts them (``axes.<a>.reference_marks``, mm from the power-on
position).  Once an axis is referenced the software limits P9–P12 (+) and P13–P16 (−) bound the
working field: leaving it makes every axis brake as with NC-Stop, V18/6 goes L, a running
program stops (``LIMIT_STOP``), and in MANUAL only motion back towards the field is allowed.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from devsim.core.axis import RegionSwitch, Watch
from devsim.core.points import BadValue
from devsim.devices.poselesta.signals import AXES

if TYPE_CHECKING:
    from devsim.devices.poselesta.cnc import PoselestaCnc

__all__ = ["OUTSIDE_WORKING_FIELD", "WorkingField"]

OUTSIDE_WORKING_FIELD = "OUTSIDE_WORKING_FIELD"
HOME_SPEED = 0.10  # of P48–P51 (spec §5.6)


class WorkingField:
    """The referencing state and the software limits of the four axes."""

    def __init__(self, cnc: PoselestaCnc) -> None:
        self.cnc = cnc
        self.referenced: set[str] = set()
        self.homing: str | None = None
        self.offset = dict.fromkeys(AXES, 0.0)  # axis frame − power-on frame, increments
        self._marks: list[Watch] = []
        self._direction, self._reversed = -1, False
        self._fields: dict[str, RegionSwitch] = {}

    # -- homing ------------------------------------------------------------------------------------
    def reference(self, a: str) -> None:
        """Start homing one axis (MANUAL, at standstill)."""
        cnc = self.cnc
        if a not in AXES:
            raise BadValue(f"no axis {a!r}: x, y, z or d")
        if cnc.mode != "MANUAL" or self.homing is not None or cnc.axes[a].moving:
            raise BadValue("homing needs MANUAL and the axes at standstill")
        settings = getattr(cnc.cfg.axes, a)
        axis = cnc.axes[a]
        direction = settings.home_direction
        self._direction, self._reversed = direction, False
        self.homing = a
        self.referenced.discard(a)
        self._arm_field(a)
        for mark in settings.reference_marks:
            position = cnc.from_mm(a, mark) + self.offset[a]
            self._marks.append(axis.watch(position, lambda way, p=position: self._mark(a, p, way)))
        cnc.signals.set(f"travel_{a}", True)
        cnc.signals.set("machine_standstill", False)
        axis.jog(direction, max(cnc.max_feed(a) * HOME_SPEED, 1e-9), cnc.accel(a))

    def reverse(self, a: str) -> bool:
        """A limit switch before the mark: search the other way, once (spec §5.6); False the
        second time (the switch then stops everything with the alarm)."""
        if self._reversed:
            self.cancel()
            return False
        self._reversed = True
        self._direction = -self._direction
        cnc = self.cnc
        cnc.record_event("homing_reversed")
        cnc.axes[a].jog(self._direction, max(cnc.max_feed(a) * HOME_SPEED, 1e-9), cnc.accel(a))
        return True

    def _mark(self, a: str, position: float, way: int) -> None:
        cnc = self.cnc
        if self.homing != a or way != self._direction or not cnc.signals.get(f"rm_enable_{a}") or a in cnc.rm_missing:
            if self.homing == a:
                cnc.record_event("reference_mark_ignored")
            return
        for watch in self._marks:
            watch.cancel()
        self._marks.clear()
        cnc.axes[a].stop(cnc.accel(a), on_done=lambda: self._referenced(a, position))

    def _referenced(self, a: str, mark: float) -> None:
        cnc = self.cnc
        axis = cnc.axes[a]
        shift = cnc.from_mm(a, getattr(cnc.cfg.axes, a).reference_value) - mark
        axis.set_position(axis.position() + shift)
        self.offset[a] += shift
        self.homing = None
        self.referenced.add(a)
        cnc.signals.set(f"travel_{a}", False)
        cnc.signals.set("machine_standstill", True)
        cnc.record_event("referenced")
        cnc.announce("event", "axis", "referenced", a)
        self._arm_field(a)

    def cancel(self) -> None:
        """The search ends (mode change, power): the axis brakes, still not referenced."""
        for watch in self._marks:
            watch.cancel()
        self._marks.clear()
        if self.homing is not None:
            a = self.homing
            self.cnc.axes[a].stop(self.cnc.accel(a))
            self.cnc.signals.set(f"travel_{a}", False)
        self.homing = None

    # -- encoder count loss (spec §5.7) ----------------------------------------------------------------
    def lose_counts(self, a: str, increments: float) -> None:
        """The encoder of ``a`` drops ``increments`` counts: the actual value the control counts
        falls behind the true position by that much (once the axis stands, the shift is made;
        the reference marks stay where they physically are)."""
        axis = self.cnc.axes[a]
        if axis.moving:  # look again when the plan ends (a jog has no end: every 100 ms meanwhile)
            wait = axis.segments()[-1].t1 - self.cnc.clock.now() if axis.segments() else 0.0
            self.cnc.clock.call_later(min(max(wait, 0.0), 0.1), lambda: self.lose_counts(a, increments))
            return
        axis.set_position(axis.position() - increments)
        self.offset[a] -= increments
        self.cnc.record_event("count_loss")

    # -- the working field ---------------------------------------------------------------------------
    def limits(self, a: str) -> tuple[float, float]:
        """(−, +) software limits of an axis in increments (P13–P16, P9–P12)."""
        minus, plus = self.cnc.params.limits(a)
        return self.cnc.from_mm(a, minus), self.cnc.from_mm(a, plus)

    def rearm(self) -> None:
        """The limits changed (P9–P16): watch the new ones."""
        for a in list(self._fields):
            self._arm_field(a)

    def _arm_field(self, a: str) -> None:
        old = self._fields.pop(a, None)
        if old is not None:
            old.cancel()
        if a in self.referenced:
            low, high = self.limits(a)
            if low <= high:
                self._fields[a] = RegionSwitch(self.cnc.axes[a], low, high, lambda inside: self._changed(inside))
        self._changed(True)

    @property
    def inside(self) -> bool:
        return all(switch.active for switch in self._fields.values())

    def outside_towards(self, a: str, direction: float) -> bool:
        """Would a motion of ``a`` in ``direction`` go further out of the field?"""
        switch = self._fields.get(a)
        if switch is None or switch.active or direction == 0:
            return False
        low, high = self.limits(a)
        position = self.cnc.axes[a].position()
        return (position > high and direction > 0) or (position < low and direction < 0)

    def _changed(self, _inside: Any) -> None:
        cnc = self.cnc
        inside = self.inside
        was = cnc.signals.get("inside_working_field")
        if cnc.booting:
            return
        cnc.signals.set("inside_working_field", inside)
        if was and not inside:
            cnc.message = OUTSIDE_WORKING_FIELD
            cnc.record_event("outside_working_field")
            cnc.executor.left_field()
            cnc.manual.left_field()
