"""Counter input (synchronous input) as position set-point source (manual §2.6; spec §5.10).

An M value < 2 saved with ``s85;170`` selects, from the next restart (emergency-stop release or
power cycle), the quadrature counter input K10/K20 (4x evaluation) instead of the internal
indexer as the set-point source.  Every counted increment moves the set-point by N23 (1..8)
increments: an electronic gear.  Indexer moves are rejected in this mode (spec §5.10 [R]).

Control API (like the SERS ``encoder.pulses``):

* ``counter.pulses`` (set, signed int): that many 4x-evaluated increments arrive at once; the
  set-point jumps by ``pulses · N23`` (applied when the axis stands; during a
  ``counter.rate_hz`` run the jump waits for the run to stop);
* ``counter.rate_hz`` (set, signed float): a continuous pulse stream; the set-point runs at
  ``rate · N23`` inc/s (the motion status follows the activity);
* ``counter.count`` (read): the counted increments since power-on; ``counter.mode``: active?

The set-point only follows while the position controller is active (no emergency stop, no
monitoring, no following error); the count always counts.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from devsim.devices.gms96.device import Gms96Device

__all__ = ["CounterInput"]

FOLLOW_ACCEL = 1e9  # the set-point follows the counter input without a ramp of its own


class CounterInput:
    def __init__(self, dev: Gms96Device) -> None:
        self.dev = dev
        self.active = False
        self._count = 0.0
        self.rate = 0.0
        self._since = dev.clock.now()
        self._pending = 0.0

    @property
    def count(self) -> int:
        """Counted increments: the discrete pulses plus the stream's integral."""
        return int(self._count + self.rate * (self.dev.clock.now() - self._since))

    def power_on(self) -> None:
        """The mode is read at restart from the M value in EEPROM (manual §2.6)."""
        self.active = self.dev.nv_M() < 2
        self._count = 0.0
        self.rate = 0.0
        self._since = self.dev.clock.now()
        self._pending = 0.0

    def following(self) -> bool:
        d = self.dev
        return self.active and d.controller and not d.estop and not d.monitoring_cause()

    def weight(self) -> int:
        return max(1, min(8, self.dev.n(23)))

    def pulses(self, count: int) -> None:
        self._count += int(count)
        if not self.following():
            return
        self._pending += int(count) * self.weight()
        self._apply()

    def _apply(self) -> None:
        axis = self.dev.axis
        if self._pending and not axis.moving:
            axis.set_position(axis.position() + self._pending)
            self._pending = 0.0
            self.dev.indexer.arm_following_error()
            self.dev.changed()

    def set_rate(self, rate_hz: float) -> None:
        now = self.dev.clock.now()
        self._count += self.rate * (now - self._since)
        self._since = now
        self.rate = float(rate_hz)
        axis = self.dev.axis
        if not self.following():
            return
        if self.rate:
            axis.jog(1 if self.rate > 0 else -1, abs(self.rate) * self.weight(), FOLLOW_ACCEL)
        elif axis.moving:
            axis.stop(FOLLOW_ACCEL, self._apply)
        self.dev.indexer.arm_following_error()
        self.dev.changed()

    def state(self) -> dict[str, object]:
        return {"mode": self.active, "count": self.count, "rate_hz": self.rate, "weight": self.weight()}
