"""Reference marks, homing and the working field (manual §2.2.2, §2.3.23, §2.4.4; spec
poselesta.md §5.5, §5.6, G-HOME, G-SOFT).

Homing (``panel.reference``, MANUAL) moves the axis towards ``home_direction`` at 10 % of its
maximum feed until it passes a reference mark while its activation input V24 is H; the actual
value there becomes ``reference_value``, the axis brakes to a stop and is referenced.  A limit
switch reached first turns the search back once; reached again, it stops with its alarm.  As for
a block or a direction key, the search's travel command goes out first and the axis moves once
the axis enable V22/3 is H (§2.4.2: "Nach Ausgabe der Fahrbefehle wartet die Steuerung die
Achsfreigabe ab, bevor in den Achsen verfahren wird", §2.3.15; the manual has no homing procedure
of its own, spec §5.6); Not-Stop ends that wait (§2.3.15) and a moving search.  The marks
sit where the configuration puts them (``axes.<a>.reference_marks``, mm from the power-on
position).  Once an axis is referenced the software limits P9–P12 (+) and P13–P16 (−) bound the
working field: leaving it makes every axis brake as with NC-Stop, V18/6 goes L, a running
program stops (``LIMIT_STOP``), and in MANUAL only motion back towards the field is allowed.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from devsim.core.axis import RegionSwitch, Watch
from devsim.core.points import BadValue
from devsim.core.signals import SignalBank
from devsim.devices.poselesta.axes import Axes
from devsim.devices.poselesta.parameters import MachineParameters
from devsim.devices.poselesta.screen import Screen
from devsim.devices.poselesta.signals import AXES

__all__ = ["OUTSIDE_WORKING_FIELD", "WorkingField"]

OUTSIDE_WORKING_FIELD = "OUTSIDE_WORKING_FIELD"
HOME_SPEED = 0.10  # of P48–P51 (spec §5.6)


class WorkingField:
    """The referencing state and the software limits of the four axes (manual §2.2.2, §2.3.23,
    §2.4.4; spec §5.5, §5.6).  ``settings(axis)`` is an axis's configuration (its reference marks,
    home direction and reference value), ``mode()`` the operating mode, ``booting()`` whether the
    control starts up; ``left()`` is what brakes when the field is left (the program, manual
    motion)."""

    def __init__(self, signals: SignalBank, axes: Axes, params: MachineParameters, screen: Screen, *,
                 settings: Callable[[str], Any], mode: Callable[[], str], booting: Callable[[], bool],
                 left: Callable[[], None]) -> None:
        self._signals = signals
        self._axes = axes
        self._params = params
        self._screen = screen
        self._settings = settings
        self._mode = mode
        self._booting = booting
        self._left = left
        self.rm_missing: set[str] = set()  # axes whose reference mark signal is lost (fault)
        self.referenced: set[str] = set()
        self.homing: str | None = None
        self.offset = dict.fromkeys(AXES, 0.0)  # axis frame − power-on frame, increments
        self._marks: list[Watch] = []
        self._direction, self._reversed = -1, False
        self._awaiting_enable = False  # the search's travel command is out, V22/3 L (§2.3.15)
        self._fields: dict[str, RegionSwitch] = {}
        params.on_change(lambda row, _value: self.rearm() if 9 <= int(row.key) <= 16 else None)
        signals.subscribe("axis_enable", self._axis_enable)
        signals.subscribe("emergency_stop", self._emergency_stop)

    # -- homing ------------------------------------------------------------------------------------
    def reference(self, a: str) -> None:
        """Start homing one axis (MANUAL, at standstill)."""
        if a not in AXES:
            raise BadValue(f"no axis {a!r}: x, y, z or d")
        if self._mode() != "MANUAL" or self.homing is not None or self._axes[a].moving:
            raise BadValue("homing needs MANUAL and the axes at standstill")
        settings = self._settings(a)
        axis = self._axes[a]
        direction = settings.home_direction
        self._direction, self._reversed = direction, False
        self.homing = a
        self.referenced.discard(a)
        self._arm_field(a)
        for mark in settings.reference_marks:
            position = self._axes.from_mm(a, mark) + self.offset[a]
            self._marks.append(axis.watch(position, lambda way, p=position: self._mark(a, p, way)))
        self._signals.set(f"travel_{a}", True)
        if self._signals.get("axis_enable"):
            self._search(a)
        else:
            self._awaiting_enable = True

    def _search(self, a: str) -> None:
        self._signals.set("machine_standstill", False)  # by the axis enable (§2.4.6)
        self._axes[a].jog(self._direction, max(self._axes.max_feed(a) * HOME_SPEED, 1e-9), self._axes.accel(a))

    def _axis_enable(self, _name: str, _old: Any, new: Any) -> None:
        """V22/3 H: a search waiting for the enable starts (a released search goes on when it
        goes L, §2.3.15)."""
        if new and self._awaiting_enable and self.homing is not None:
            self._awaiting_enable = False
            self._search(self.homing)

    def _emergency_stop(self, _name: str, _old: Any, new: Any) -> None:
        """Not-Stop ends the search, waiting ("die Wartestellung kann durch Not-Stop abgebrochen
        werden", §2.3.15) or moving (the axes stop at once, §2.3.2: the model's quick stop follows
        this brake): the axis is not referenced and a new ``panel.reference`` starts again."""
        if not new and self.homing is not None:
            self.cancel()

    def turn_back(self, a: str) -> bool:
        """A limit switch of ``a`` was hit: True when the homing search of ``a`` turns back."""
        return self.homing == a and self.reverse(a)

    def reverse(self, a: str) -> bool:
        """A limit switch before the mark: search the other way, once (spec §5.6); False the
        second time (the switch then stops everything with the alarm)."""
        if self._reversed:
            self.cancel()
            return False
        self._reversed = True
        self._direction = -self._direction
        self._screen.record("homing_reversed")
        self._axes[a].jog(self._direction, max(self._axes.max_feed(a) * HOME_SPEED, 1e-9), self._axes.accel(a))
        return True

    def _mark(self, a: str, position: float, way: int) -> None:
        if self.homing != a or way != self._direction or not self._signals.get(f"rm_enable_{a}") \
                or a in self.rm_missing:
            if self.homing == a:
                self._screen.record("reference_mark_ignored")
            return
        for watch in self._marks:
            watch.cancel()
        self._marks.clear()
        self._axes[a].stop(self._axes.accel(a), on_done=lambda: self._referenced(a, position))

    def _referenced(self, a: str, mark: float) -> None:
        axis = self._axes[a]
        shift = self._axes.from_mm(a, self._settings(a).reference_value) - mark
        axis.set_position(axis.position() + shift)
        self.offset[a] += shift
        self.homing = None
        self.referenced.add(a)
        self._signals.set(f"travel_{a}", False)
        self._signals.set("machine_standstill", True)
        self._screen.record("referenced")
        self._screen.report("axis", "referenced", a)
        self._arm_field(a)

    def cancel(self) -> None:
        """The search ends (mode change, power): the axis brakes, still not referenced."""
        for watch in self._marks:
            watch.cancel()
        self._marks.clear()
        self._awaiting_enable = False
        if self.homing is not None:
            a = self.homing
            self._axes[a].stop(self._axes.accel(a))
            self._signals.set(f"travel_{a}", False)
        self.homing = None

    # -- encoder count loss (spec §5.7) ----------------------------------------------------------------
    def lose_counts(self, a: str, increments: float) -> None:
        """The encoder of ``a`` drops ``increments`` counts: the actual value the control counts
        falls behind the true position by that much (once the axis stands, the shift is made;
        the reference marks stay where they physically are)."""
        axis = self._axes[a]
        clock = self._axes.clock
        if axis.moving:  # look again when the plan ends (a jog has no end: every 100 ms meanwhile)
            wait = axis.segments()[-1].t1 - clock.now() if axis.segments() else 0.0
            clock.call_later(min(max(wait, 0.0), 0.1), lambda: self.lose_counts(a, increments))
            return
        axis.set_position(axis.position() - increments)
        self.offset[a] -= increments
        self._screen.record("count_loss")

    # -- the working field ---------------------------------------------------------------------------
    def limits(self, a: str) -> tuple[float, float]:
        """(−, +) software limits of an axis in increments of its actual value (P13–P16,
        P9–P12): they count from the reference mark (§2.4.4 "beziehen sich immer auf die
        Referenzmarke der entsprechenden Achse"), whose actual value is ``reference_value``."""
        minus, plus = self._params.limits(a)
        mark = self._settings(a).reference_value
        return self._axes.from_mm(a, mark + minus), self._axes.from_mm(a, mark + plus)

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
                self._fields[a] = RegionSwitch(self._axes[a], low, high, lambda inside: self._changed(inside))
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
        position = self._axes[a].position()
        return (position > high and direction > 0) or (position < low and direction < 0)

    def _changed(self, _inside: Any) -> None:
        inside = self.inside
        if self._booting():
            return
        was = self._signals.get("inside_working_field")
        self._signals.set("inside_working_field", inside)
        if was and not inside:
            self._screen.show(OUTSIDE_WORKING_FIELD)
            self._screen.record("outside_working_field")
            self._left()
