"""The I²t limitation of the power stage (manual §3.1, §2.3.1 N15; spec §4.5.3, §5.7).

The integral ``q`` of ``(i² - level²) / level²`` over time (never below 0) starts the limitation
when it reaches ``3 · i2t_t_allow_s`` (2 s at 100 % overload); while it limits, the current is held
at the N15 level and the integral runs back; the limitation ends when it is 0 again.  The
crossings are solved and scheduled on the device clock, never sampled.
"""

from __future__ import annotations

from collections.abc import Callable

from devsim.core.clock import Clock, Timer
from devsim.core.parameters import Param
from devsim.core.settings import Settings
from devsim.devices.gms96.params import NParameters

__all__ = ["I_BASE", "I2t"]

I_BASE = 0.05  # the motor current at rest, fraction of Imax (spec §5.7)


class I2t:
    """The I²t integral, the limitation (I.5) and its latch (I.6, K.0, M1.1) of one card (spec §5.7)."""

    def __init__(
        self,
        clock: Clock,
        params: NParameters,
        geometry: Settings,
        load_pct: Callable[[], float],
        settled: Callable[[], None],
        record_event: Callable[[str], None],
    ) -> None:
        self.clock = clock
        self.params = params
        self.geometry = geometry  # the configured axis: i2t_t_allow_s
        self.load_pct = load_pct
        self.settled = settled  # the limitation may have changed: blockage, outputs, waits
        self.record_event = record_event
        self.q = 0.0
        self.t = clock.now()
        self.limiting = False
        self.latched = False
        self.rate = 0.0  # dq/dt since the last update
        self._timer: Timer | None = None
        params.on_change(self._parameter_written)

    def _parameter_written(self, row: Param, value: int) -> None:
        """N15 (the level) and N39 (the peak current) change the integral's rate."""
        if row.attr in ("i2t_level", "peak_current_pct"):
            self.update()

    def power_on(self) -> None:
        """The integral and the flags start afresh: a crossing scheduled before the power went
        off is forgotten, and the integral runs from now with the current the load asks for."""
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None
        self.q = 0.0
        self.t = self.clock.now()
        self.limiting = False
        self.latched = False
        self.rate = 0.0
        self._integrate()

    def power_off(self) -> None:
        """No current flows without power: nothing is integrated and no crossing is due."""
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None
        self.rate = 0.0

    def level(self) -> float:
        """N15 as a fraction of Imax."""
        return self.params.i2t_level / 255.0

    def demand(self) -> float:
        """The current the load asks for, limited by N39."""
        i_lim = self.params.peak_current_pct / 100.0
        return min(i_lim, I_BASE + self.load_pct() / 100.0)

    def _rate(self) -> float:
        level = self.level()
        if level <= 0:
            return 0.0
        i = self.demand()
        if self.limiting:
            i = min(i, level)
        return (i * i - level * level) / (level * level)

    def update(self) -> None:
        """Integrate up to now, switch the limitation, schedule the next crossing; tell the card."""
        self._integrate()
        self.settled()

    def _integrate(self) -> None:
        now = self.clock.now()
        self.q = max(0.0, self.q + self.rate * (now - self.t))
        self.t = now
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None
        threshold = 3.0 * self.geometry.i2t_t_allow_s
        rate = self._rate()
        # (a crossing closer than the clock can resolve at this time is reached now: a timer for
        # it would fire at the same instant, integrate nothing and be set again, for ever)
        if not self.limiting and self.level() > 0 and (
                self.q >= threshold - 1e-9 or (rate > 0 and now + (threshold - self.q) / rate <= now)):
            self.limiting = True
            self.latched = True
            self.record_event("i2t_limit")
        elif self.limiting and rate <= 0 and (self.q <= 1e-9 or (rate < 0 and now + self.q / -rate <= now)):
            self.limiting = False
        self.rate = self._rate()
        if not self.limiting and self.rate > 0:
            self._timer = self.clock.call_later((threshold - self.q) / self.rate, self.update)
        elif self.limiting and self.rate < 0:
            self._timer = self.clock.call_later(self.q / -self.rate, self.update)
