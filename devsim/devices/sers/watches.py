"""What the SERS watches while it moves: the software limits P1040/P1041, the range of P51 (P12 8),
the compare positions P1024/P1026 with their outputs P1025/P1027 and the standstill monitoring
P1044/P1045 (manual §4.8.6.12, §4.8.3.1, §4.8.1.2, §4.8.6.8; spec §5.6, §5.7).

Each is a position on the axis whose crossing is solved for (:meth:`devsim.core.axis.Axis.watch`),
not sampled.
"""

from __future__ import annotations

from collections.abc import Callable

from devsim.core.axis import Axis, Watch
from devsim.core.clock import Clock, Timer
from devsim.core.signals import SignalBank
from devsim.devices.sers.constants import STANDSTILL
from devsim.devices.sers.params import SersParameters
from devsim.devices.sers.power import PowerStage

__all__ = ["PositionWatches"]


def _sign(x: float) -> int:
    return (x > 0) - (x < 0)


class PositionWatches:
    """Software limits, compare positions and standstill monitoring of one motion (§4.8.6.12,
    §4.8.1.2, §4.8.6.8)."""

    def __init__(
        self,
        clock: Clock,
        axis: Axis,
        params: SersParameters,
        signals: SignalBank,
        power: PowerStage,
        *,
        offset: Callable[[], float],
        kind: Callable[[], str | None],
        stop: Callable[[], None],
    ) -> None:
        self.clock = clock
        self.axis = axis
        self.params = params
        self.signals = signals
        self.power = power
        self._offset = offset  # physical position of P51 = 0
        self._kind = kind  # the motion under way
        self._stop = stop  # S: brake the motion
        self._watches: list[Watch] = []
        self._standstill: list[Watch] = []
        self._timers: list[Timer] = []

    def cancel(self) -> None:
        """The motion ended (or the drive powers off): nothing is watched any more."""
        for watch in self._watches + self._standstill:
            watch.cancel()
        self._watches.clear()
        self._standstill = []

    def cancel_timers(self) -> None:
        for timer in self._timers:
            timer.cancel()
        self._timers.clear()

    # -- software limits (§4.8.6.12) ------------------------------------------------------------
    def soft_limits(self) -> tuple[float, float] | None:
        """P1040 … P1041 in increments from P51 = 0, or None (switched off: lower ≥ upper)."""
        lower, upper = float(self.params.limit_negative), float(self.params.limit_positive)
        if lower < upper:
            return lower, upper
        return None

    def outside_soft_limits(self, p51: float) -> bool:
        """P1042: the position ``p51`` lies outside the software limits."""
        limits = self.soft_limits()
        if limits is None:
            return False
        return p51 < limits[0] or p51 > limits[1]

    def arm(self, keep: bool = False) -> None:
        """Software limits, compare positions and standstill monitoring for a new motion
        (``keep``: the watches a homing run set stay)."""
        if not keep:
            for watch in self._watches:
                watch.cancel()
            self._watches.clear()
        self._arm_position_range()
        lower, upper, distance, action1, action2 = self.params.watched()
        if not (float(lower) < float(upper) or float(distance) or int(action1) or int(action2)):
            for watch in self._standstill:  # (nothing to watch, the factory setting)
                watch.cancel()
            self._standstill = []
            return
        params, axis = self.params, self.axis
        offset = self._offset()
        limits = self.soft_limits()
        homing = self._kind() == "home" and not int(params.homing_parameters) & 8
        if limits is not None and not homing:
            lower, upper = (x + offset for x in limits)
            velocity_sign = _sign(axis.final_position() - axis.position())
            here = axis.position()
            if (here > upper and velocity_sign > 0) or (here < lower and velocity_sign < 0):
                self._timers.append(self.clock.call_later(0, self._soft_limit_hit))
            self._watches.append(axis.watch(upper + 1e-9, lambda d: d > 0 and self._soft_limit_hit()))
            self._watches.append(axis.watch(lower - 1e-9, lambda d: d < 0 and self._soft_limit_hit()))
        self.arm_standstill()
        for position, action in ((params.compare_position1, params.compare_output1),
                                 (params.compare_position2, params.compare_output2)):
            action = int(action)
            if action:
                where = float(position) + offset
                self._watches.append(axis.watch(where, lambda _d, a=action: self._compare_action(a)))

    def _arm_position_range(self) -> None:
        """P12 8 (§4.8.3.1: "Interner Lagegrenzwert - der intern berechnete Positionswert kann
        nicht auf den skalierten Wert abgebildet werden"): P51 leaves the range of the position
        weighting (§4.8.4.2, e.g. ±214748.3647°).  A positioning cannot: its target is checked
        at E (errno 85/86)."""
        if self._kind() in (None, "position"):
            return
        scaling = self.params.scaling
        lo, hi = (scaling.pos_to_inc(x) + self._offset() for x in scaling.pos_range())
        here = self.axis.position()
        if here > hi or here < lo:
            self.power.warn(8)
        self._watches.append(self.axis.watch(hi + 1e-6, lambda d: d > 0 and self.power.warn(8)))
        self._watches.append(self.axis.watch(lo - 1e-6, lambda d: d < 0 and self.power.warn(8)))

    def _soft_limit_hit(self) -> None:
        self.power.warn(1)
        if self._kind() not in (None, "stopping", "error-stop"):
            self._stop()

    def _compare_action(self, action: int) -> None:
        """P1025/P1027: ±1..4 set/clear O1..O4, ±5..7 set/clear M1..M3."""
        value = action > 0
        n = abs(action)
        if n <= 4:
            self.signals.set(f"O{n}", value)
        elif n <= 7:
            self.params.values[1100 + n - 4] = int(value)  # M1..M3

    # -- standstill monitoring (§4.8.6.8) ---------------------------------------------------------
    def arm_standstill(self) -> None:
        """P1044/P1045 (§4.8.6.8, spec §5.7): while moving, an edge on input P1045 must come
        at least every P1044; the distance counts from the motion start and from each edge."""
        for watch in self._standstill:
            watch.cancel()
        self._standstill = []
        distance = abs(float(self.params.standstill_distance))
        if not distance or self._kind() is None:
            return
        here = self.axis.position()
        for where in (here + distance, here - distance):
            self._standstill.append(self.axis.watch(where, lambda _d: self._standstill_error()))

    def _standstill_error(self) -> None:
        kind = self._kind()
        if kind is not None and kind != "error-stop":
            self.power.drive_error(STANDSTILL)
