"""The I²t limitation of the power stage (manual §3.1, §2.3.1 N15; spec §4.5.3, §5.7).

Manual §3.1: "Die Motorelektronik prüft ständig, ob der angegebene Stromwert ... überschritten
wird. Dabei wird der Betrag des Stromes bewertet": the integral ``q`` of ``(i² - level²) / level²``
over time (never below 0) of the motor current ``i`` — the load's current and the current that
accelerates the axis, the peak current while a blockage or an end stop holds it (spec §5.7, as
``T1;5`` reports it) — starts the limitation when it reaches
``3 · i2t_t_allow_s`` (2 s at 100 % overload); while it limits, the current is held at the N15
level and the integral runs back; the limitation ends when it is 0 again.  The current follows the
axis's segments (constant on a linear ramp, ``a·π/2·sin`` on a sin² ramp), so the integral is
exact in closed form and the crossings are solved and scheduled on the device clock, never sampled.
While the position and current control are off (manual §3.1: "wird die Lage- und Stromregelung
abgeschaltet"; a following error, Notaus) no current flows and the integral runs back.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator

from devsim.core.clock import Clock, Timer
from devsim.core.parameters import Param
from devsim.core.settings import Settings
from devsim.devices.gms96.motion import Indexer
from devsim.devices.gms96.params import NParameters
from devsim.devices.gms96.stage import PowerStage

__all__ = ["A_REF", "I_BASE", "K_ACC", "I2t"]

I_BASE = 0.05  # the motor current at rest, fraction of Imax (spec §5.7)
K_ACC, A_REF = 0.3, 50000.0  # current per acceleration (spec §5.7)
_EPS_T = 1e-9  # a crossing closer than this to now is reached now (the clock cannot resolve it)

# a stretch of time on which the current (before the caps) is base + amp·sin(omega·(t - origin)),
# omega = 0: the constant base + amp
Piece = tuple[float, float, float, float, float, float]  # t0, t1, base, amp, origin, omega


def _square_integral(base: float, amp: float, omega: float, tau: float) -> float:
    """∫₀^τ (base + amp·sin(omega·s))² ds."""
    if omega == 0.0:
        return (base + amp) ** 2 * tau
    wt = omega * tau
    return (base * base * tau + 2.0 * base * amp * (1.0 - math.cos(wt)) / omega
            + amp * amp * (0.5 * tau - math.sin(2.0 * wt) / (4.0 * omega)))


class I2t:
    """The I²t integral, the limitation (I.5) and its latch (I.6, K.0, M1.1) of one card (spec §5.7)."""

    def __init__(
        self,
        clock: Clock,
        params: NParameters,
        geometry: Settings,
        indexer: Indexer,
        stage: PowerStage,
        settled: Callable[[], None],
        record_event: Callable[[str], None],
    ) -> None:
        self.clock = clock
        self.params = params
        self.geometry = geometry  # the configured axis: i2t_t_allow_s
        self.indexer = indexer  # the axis's segments give the accelerating current; blockage, end stops
        self.stage = stage  # no current while the position and current control are off
        self.settled = settled  # the limitation may have changed: blockage, outputs, waits
        self.record_event = record_event
        self.q = 0.0
        self.t = clock.now()
        self.limiting = False
        self.latched = False
        self.powered = True
        self._timer: Timer | None = None
        # what held since ``t``: the load (%), the N15 level and the N39 peak (fractions of Imax), control
        # on, and from when a blockage or an end stop holds the moving axis (inf: not in this plan)
        self._held = (0.0, self.level(), params.peak_current_pct / 100.0, False, math.inf)  # until power-on
        params.on_change(self._parameter_written)

    def _parameter_written(self, row: Param, value: int) -> None:
        """N15 (the level) and N39 (the peak current) change the integral's rate."""
        if row.attr in ("i2t_level", "peak_current_pct"):
            self.update()

    def power_on(self) -> None:
        """The integral and the flags start afresh: a crossing scheduled before the power went
        off is forgotten, and the integral runs from now with the current the motor draws."""
        self._cancel()
        self.q = 0.0
        self.t = self.clock.now()
        self.limiting = False
        self.latched = False
        self.powered = True
        self._integrate()

    def power_off(self) -> None:
        """No current flows without power: nothing is integrated and no crossing is due."""
        self._integrate()
        self._cancel()
        self.powered = False

    def level(self) -> float:
        """N15 as a fraction of Imax."""
        return self.params.i2t_level / 255.0

    def load_pct(self) -> float:
        """The machine side's load (``quantity.load_pct``): current beyond rest, % of Imax."""
        return float(self.stage.signals.get("load_pct"))

    def _inputs(self) -> tuple[float, float, float, bool, float]:
        return (self.load_pct(), self.level(), self.params.peak_current_pct / 100.0, self.stage.controller,
                self._held_from())

    def _held_from(self) -> float:
        """From when a blockage or an end stop holds the moving axis (inf: not under this plan)."""
        ix = self.indexer
        if ix.blocked_at is not None:
            return self.clock.now()
        contact = ix.end_stop_contact()
        return math.inf if contact is None else contact

    def demand(self) -> float:
        """The current the load asks for (without acceleration), limited by N39."""
        i_lim = self.params.peak_current_pct / 100.0
        return min(i_lim, I_BASE + self.load_pct() / 100.0)

    def update(self) -> None:
        """Integrate up to now, switch the limitation, schedule the next crossing; tell the card."""
        self._integrate()
        self.settled()

    def replan(self) -> None:
        """The axis planned anew: solve the next crossing again; tell the card only if the
        limitation changed on the way."""
        before = self.limiting
        self._integrate()
        if self.limiting != before:
            self.settled()

    # -- the integral ---------------------------------------------------------------------------
    def _cancel(self) -> None:
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None

    def _pieces(self, start: float) -> Iterator[Piece]:
        """The current from ``start`` on, piece by piece to inf (spec §5.7, as :class:`Torque`
        reports it): none while the control is off; while a blockage or an end stop holds the
        moving axis the peak current (N39); else rest, load and the accelerating current."""
        load, _level, peak, on, held = self._held
        if not on:
            yield start, math.inf, 0.0, 0.0, 0.0, 0.0
            return
        base = I_BASE + load / 100.0
        t = start
        for seg in self.indexer.axis.segments(since=start):
            if seg.t0 > t:
                yield t, seg.t0, base, 0.0, 0.0, 0.0  # at rest in between
            t0, t1 = max(seg.t0, t), seg.t1
            if t0 < held:
                end = min(t1, held)
                if seg.shape == "sine" and seg.span > 0:
                    yield t0, end, base, K_ACC * 0.5 * math.pi * abs(seg.a) / A_REF, seg.t0, math.pi / seg.span
                else:
                    a = seg.acceleration(0.5 * (t0 + end)) if end < math.inf else seg.acceleration(t0)
                    yield t0, end, base, K_ACC * abs(a) / A_REF, 0.0, 0.0
            if t1 > held:
                yield max(t0, held), t1, peak, 0.0, 0.0, 0.0  # pressed against the blockage / end stop
            t = t1
        if t < math.inf:
            yield t, math.inf, base, 0.0, 0.0, 0.0

    def _scan(self, q: float, start: float, until: float, limiting: bool) -> tuple[float, float | None]:
        """Integrate from ``start`` toward ``until`` with the limitation ``limiting`` fixed; stop at
        the first crossing (q reaching the threshold, or 0 while limiting).  Returns q and the
        instant of that crossing (None: none before ``until``, q is then the value at ``until``)."""
        _load, level, cap, _on, _held = self._held
        if level <= 0 or until <= start:
            return q, None
        if limiting:
            cap = min(cap, level)
        threshold = 3.0 * self.geometry.i2t_t_allow_s
        l2 = level * level
        for t0, t1, base, amp, origin, omega in self._pieces(start):
            if t0 >= until:
                break
            for u0, u1, b, k, w in self._split(t0, min(t1, until), base, amp, origin, omega, (cap, level), cap):
                if u1 == math.inf:  # a constant current for ever
                    rate = ((b + k) ** 2 - l2) / l2
                    if not limiting and rate > 0:
                        return threshold, u0 + max(0.0, threshold - q) / rate
                    if limiting and rate < 0:
                        return 0.0, u0 + q / -rate
                    return (0.0 if rate < 0 else q), None

                def gain(t: float, u0: float = u0, b: float = b, k: float = k, w: float = w, o: float = origin) -> float:
                    return (_square_integral(b, k, w, t - o) - _square_integral(b, k, w, u0 - o)
                            - l2 * (t - u0)) / l2

                total = gain(u1)
                if not limiting and total > 0 and q + total >= threshold - 1e-12:
                    return threshold, self._solve(gain, threshold - q, u0, u1)
                if limiting and total < 0 and q + total <= 1e-12:
                    return 0.0, self._solve(lambda t, g=gain: -g(t), q, u0, u1)
                q = max(0.0, q + total)
        return q, None

    @staticmethod
    def _split(t0: float, t1: float, base: float, amp: float, origin: float, omega: float,
               values: tuple[float, float], cap: float) -> Iterator[tuple[float, float, float, float, float]]:
        """The piece cut where its current crosses ``values`` (the cap and the level), so that on
        each part the integrand keeps its sign and the cap either holds or not: (t0, t1, base,
        amp, omega) of each part, a capped part as the constant cap."""
        cuts = [t0, t1]
        if omega > 0 and amp > 0:
            for v in values:
                r = (v - base) / amp
                if 0.0 < r < 1.0:
                    x = math.asin(r)
                    cuts += [t for t in (origin + x / omega, origin + (math.pi - x) / omega) if t0 < t < t1]
        cuts.sort()
        for a, b in zip(cuts, cuts[1:], strict=False):
            if b <= a:
                continue
            mid = 0.5 * (a + b) if b < math.inf else a + 1.0
            current = base + (amp * math.sin(omega * (mid - origin)) if omega > 0 else amp)
            if current >= cap:
                yield a, b, cap, 0.0, 0.0
            else:
                yield a, b, base, amp, omega

    @staticmethod
    def _solve(gain: Callable[[float], float], target: float, lo: float, hi: float) -> float:
        """The instant in [lo, hi] where the monotonic ``gain`` reaches ``target``."""
        for _ in range(200):
            mid = 0.5 * (lo + hi)
            if mid <= lo or mid >= hi:
                break
            if gain(mid) >= target:
                hi = mid
            else:
                lo = mid
        return hi

    def _integrate(self) -> None:
        now = self.clock.now()
        self._cancel()
        if not self.powered:
            self.t, self._held = now, self._inputs()
            return
        for _ in range(100):
            q, hit = self._scan(self.q, self.t, now + _EPS_T, self.limiting)
            if hit is None:
                self.q, self.t = q, now
                break
            self.q, self.t = q, min(hit, now)
            self.limiting = not self.limiting
            if self.limiting:
                self.latched = True
                self.record_event("i2t_limit")
        self._held = self._inputs()  # from now on: a change of the load or of N15/N39 is integrated from now
        _q, hit = self._scan(self.q, now, math.inf, self.limiting)
        if hit is not None:
            self._timer = self.clock.call_at(max(hit, now), self.update)
