"""Segments, ramp shapes and crossing rules of the closed-form axis (:mod:`devsim.core.axis`).

A :class:`Segment` is one piece of a plan: constant acceleration, or a raised-cosine ("sine")
velocity ramp, with its position, velocity and acceleration in closed form and the time it
reaches a position solved (a quadratic; a safeguarded Newton iteration on a sine segment).  A
:class:`RampProfile` describes ramp shapes (SERS P1032/P1005–P1008, spec §5.2); a :class:`Rule`
divides the axis into zones whose boundaries a watch reports (a range, the encoder's index marks).
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from typing import Any, Literal

import msgspec

__all__ = [
    "ABS_X",
    "HISTORY",
    "REL_T",
    "REL_X",
    "IndexRule",
    "Phase",
    "PhaseSpec",
    "Ramp",
    "RampProfile",
    "RangeRule",
    "Rule",
    "Segment",
    "Shape",
    "make_ramp",
    "sign",
    "theta_minus_sin",
]

Phase = Literal["idle", "accel", "const", "decel"]
Shape = Literal["linear", "sine", "curve"]
PhaseSpec = tuple[float, float, float, Shape]  # (acceleration, duration, end velocity, shape)

REL_X = 1e-11  # relative position tolerance (positions are up to ~1e9 inc)
ABS_X = 1e-9
REL_T = 1e-12  # phases shorter than this (relative to the clock) are dropped
HISTORY = 64


def sign(x: float) -> int:
    return (x > 0) - (x < 0)


def theta_minus_sin(th: float) -> float:
    """``th - sin(th)`` without the cancellation for small ``th`` (series below 0.25)."""
    if th < 0.25:
        q = th * th
        return th * q / 6.0 * (1.0 - q / 20.0 * (1.0 - q / 42.0 * (1.0 - q / 72.0 * (1.0 - q / 110.0))))
    return th - math.sin(th)


class RampProfile(msgspec.Struct, frozen=True):
    """SERS P1032/P1005–P1008 (spec §5.2): up to three speed sections per ramp.

    Section 1: 0 → v1 = ``speed1``·V with acceleration ``accel1``·A; section 2: v1 → v2 =
    ``speed2``·V with ``accel2``·A; section 3: v2 → V with A (and beyond V, when an axis that is
    faster than the new V slows down, A as well).  Deceleration mirrors the same sections with the
    deceleration as base (braking from V to v2 with D, v2 → v1 with ``accel2``·D, v1 → 0 with
    ``accel1``·D).  The fractions are in 0..1 (P1007 = ``speed1``·100 %, P1005 = ``accel1``·100 %,
    P1008 = ``speed2``·100 %, P1006 = ``accel2``·100 %).  A section whose speed range is empty
    (v1 = 0, v2 <= v1) or whose acceleration fraction is 0 is absent: its speed range belongs to
    the next section present.

    ``shape`` (P1032): ``"linear"`` is constant acceleration in each section; ``"sine"`` makes each
    section's velocity change a raised cosine ``v(t) = va + (vb-va)·(1-cos(pi·t/T))/2`` with the
    linear section's duration ``T = (vb-va)/a``: the average acceleration is the section's, the
    peak pi/2 of it, and durations and distances equal the linear ones.  With every fraction 1.0
    and ``"linear"`` this is the plain trapezoid (exactly the plan made without a profile).
    """

    speed1: float = 1.0
    accel1: float = 1.0
    speed2: float = 1.0
    accel2: float = 1.0
    shape: Shape = "linear"

    def __post_init__(self) -> None:
        for name in ("speed1", "accel1", "speed2", "accel2"):
            value = getattr(self, name)
            if not 0.0 <= value <= 1.0:  # also rejects nan
                raise ValueError(f"{name} must be in 0..1, not {value!r}")
        if self.shape not in ("linear", "sine"):
            raise ValueError(f"shape must be 'linear' or 'sine', not {self.shape!r}")


class Ramp:
    """A :class:`RampProfile` made concrete for reference speed ``vref`` and base acceleration
    ``base``: speed sections ``[bounds[i-1], bounds[i])`` (from 0; the last bound is inf) with
    acceleration ``accs[i]``.  Distances and durations are those of constant acceleration per
    section, whatever the shape (a raised cosine has the linear section's average velocity)."""

    def __init__(self, profile: RampProfile, vref: float, base: float) -> None:
        self.shape: Shape = profile.shape
        self.bounds: list[float] = []
        self.accs: list[float] = []
        fracs: list[float] = []
        lo = 0.0
        for fv, fa in ((profile.speed1, profile.accel1), (profile.speed2, profile.accel2), (math.inf, 1.0)):
            if fa == 0.0:
                continue
            hi = math.inf if fv == math.inf else fv * vref
            if not hi > lo:
                continue
            if fracs and fracs[-1] == fa and self.shape == "linear":
                self.bounds[-1] = hi  # the same constant acceleration: one section
            else:
                self.bounds.append(hi)
                self.accs.append(fa * base)
                fracs.append(fa)
            lo = hi

    @property
    def trivial(self) -> bool:
        """One linear section with the base acceleration: the plain ramp."""
        return self.shape == "linear" and len(self.accs) == 1

    def _overlaps(self, lo: float, hi: float) -> Iterator[tuple[float, float, float]]:
        """``(a, b, acc)`` for each section's overlap with the speed range ``(lo, hi)``, ascending."""
        start = 0.0
        for bound, acc in zip(self.bounds, self.accs, strict=True):
            a, b = max(start, lo), min(bound, hi)
            if b > a:
                yield a, b, acc
            start = bound
            if start >= hi:
                break

    def acc_at(self, v: float) -> float:
        for bound, acc in zip(self.bounds, self.accs, strict=True):
            if v < bound:
                return acc
        return self.accs[-1]

    def distance(self, lo: float, hi: float) -> float:
        """Distance covered while the speed changes between ``lo`` and ``hi`` (``lo <= hi``)."""
        return sum((b - a) * (b + a) / (2.0 * acc) for a, b, acc in self._overlaps(lo, hi))

    def up(self, u: float, w: float, s: int, phases: list[PhaseSpec]) -> None:
        """Append the phases speeding up from ``u`` to ``w`` (magnitudes) in direction ``s``."""
        for a, b, acc in self._overlaps(u, w):
            phases.append((s * acc, (b - a) / acc, s * b, self.shape))

    def down(self, w: float, u: float, s: int, phases: list[PhaseSpec], scale: float = 1.0) -> None:
        """Append the phases slowing down from ``w`` to ``u`` (magnitudes) in direction ``s``;
        ``scale`` multiplies every section's deceleration."""
        for a, b, acc in reversed(list(self._overlaps(u, w))):
            acc *= scale
            phases.append((-s * acc, (b - a) / acc, s * a, self.shape))


def make_ramp(profile: RampProfile | None, vref: float, base: float) -> Ramp | None:
    """The concrete ramp, or None where it is the plain constant-acceleration ramp."""
    if profile is None:
        return None
    ramp = Ramp(profile, vref, base)
    return None if ramp.trivial else ramp


class Segment(msgspec.Struct, frozen=True):
    """Constant acceleration ``a`` from ``t0`` to ``t1`` starting at ``x0`` with velocity ``v0``.

    ``t1`` is ``math.inf`` for an endless cruise (a jog).

    ``shape="sine"``: the velocity is a raised cosine from ``v0`` to ``v0 + a*span`` over
    ``span`` seconds (``a`` is the average acceleration, ``span`` the full ramp time, equal to
    ``t1 - t0`` except for a segment cut short in the history):
    ``v = v0 + a*span*(1 - cos(pi*dt/span))/2``,
    ``x = x0 + v0*dt + a*span/2*(dt - span/pi*sin(pi*dt/span))``.
    """

    t0: float
    t1: float
    x0: float
    v0: float
    a: float
    shape: Shape = "linear"
    span: float = 0.0
    #: ``shape="curve"``: the axis's share of a path (:mod:`devsim.core.path`), an object whose
    #: ``state(dt)`` gives position, velocity and acceleration; monotonic in position.
    curve: Any = None

    def position(self, t: float) -> float:
        return self._position(t - self.t0)

    def velocity(self, t: float) -> float:
        if self.shape == "linear":
            return self.v0 + self.a * (t - self.t0)
        if self.shape == "curve":
            return float(self.curve.state(t - self.t0)[1])
        return self._velocity(t - self.t0)

    def acceleration(self, t: float) -> float:
        """Instantaneous acceleration (for a sine segment: ``a*pi/2*sin(pi*dt/span)``)."""
        if self.shape == "linear":
            return self.a
        if self.shape == "curve":
            return float(self.curve.state(t - self.t0)[2])
        return 0.5 * math.pi * self.a * math.sin(math.pi * (t - self.t0) / self.span)

    def _position(self, dt: float) -> float:
        if self.shape == "linear":
            return self.x0 + (self.v0 + 0.5 * self.a * dt) * dt
        if self.shape == "curve":
            return float(self.curve.state(dt)[0])
        span = self.span
        return (
            self.x0
            + self.v0 * dt
            + self.a * span * span / (2.0 * math.pi) * theta_minus_sin(math.pi * dt / span)
        )

    def _velocity(self, dt: float) -> float:
        h = math.sin(0.5 * math.pi * dt / self.span)
        return self.v0 + self.a * self.span * h * h

    @property
    def direction(self) -> int:
        """+1/-1: the way the position moves (segments never reverse inside)."""
        if self.shape == "curve":
            return sign(self._position(self.t1 - self.t0) - self.x0)
        return sign(self.v0) or sign(self.a)

    def solve(self, p: float) -> float:
        """Time at which the position reaches ``p`` (first root, moving in :attr:`direction`).

        Uses the cancellation-free form ``tau = 2 dx / (v0 + dir*sqrt(v0² + 2 a dx))``; a slightly
        negative discriminant (``p`` at the segment's turning point) is treated as zero.  A sine
        segment is monotone in position, so its root is bracketed in ``[t0, t0 + span]`` and found
        by Newton steps safeguarded with bisection, to a few ulp of the segment's time scale.
        """
        if self.shape == "curve":
            return self._solve_curve(p)
        if self.shape != "linear":
            return self._solve_sine(p)
        dx = p - self.x0
        if self.a == 0.0:
            tau = dx / self.v0 if self.v0 != 0.0 else 0.0
        else:
            disc = self.v0 * self.v0 + 2.0 * self.a * dx
            den = self.v0 + self.direction * (math.sqrt(disc) if disc > 0.0 else 0.0)
            tau = 2.0 * dx / den if den != 0.0 else 0.0
        return self.t0 + tau

    def _solve_curve(self, p: float) -> float:
        """Bisection on a monotonic curve piece, to a few ulp of its time scale."""
        d = self.direction
        lo, hi = 0.0, self.t1 - self.t0
        if d == 0 or (self._position(lo) - p) * d >= 0.0:
            return self.t0
        if (self._position(hi) - p) * d <= 0.0:
            return self.t1
        eps = 4.0 * math.ulp(max(hi, 1.0))
        while hi - lo > eps:
            mid = 0.5 * (lo + hi)
            if (self._position(mid) - p) * d >= 0.0:
                hi = mid
            else:
                lo = mid
        return self.t0 + hi

    def _solve_sine(self, p: float) -> float:
        d = self.direction
        span = self.span
        lo, hi = 0.0, span
        if (self._position(0.0) - p) * d >= 0.0:
            return self.t0
        if (self._position(span) - p) * d <= 0.0:
            return self.t0 + span
        # start from the linear segment with the same end points
        tau = Segment(0.0, span, self.x0, self.v0, self.a).solve(p)
        if not lo < tau < hi:
            tau = 0.5 * span
        eps = 4.0 * math.ulp(span)
        for _ in range(200):
            g = (self._position(tau) - p) * d
            if g == 0.0:
                break
            if g > 0.0:
                hi = tau
            else:
                lo = tau
            v = abs(self._velocity(tau))
            nxt = tau - g / v if v > 0.0 else math.nan
            if not lo < nxt < hi:  # also catches nan
                nxt = 0.5 * (lo + hi)
            step = abs(nxt - tau)
            tau = nxt
            if step <= eps or hi - lo <= eps:
                break
        return self.t0 + tau


# --------------------------------------------------------------------------------------------
# watches


class Rule:
    """How a watch divides the axis into numbered zones and where the zone borders are."""

    def state_of(self, x: float) -> int:
        raise NotImplementedError

    def up(self, state: int) -> tuple[float, bool] | None:
        """Border above zone ``state`` as ``(position, strict)``; strict: beyond means ``x > p``."""
        raise NotImplementedError

    def down(self, state: int) -> tuple[float, bool] | None:
        """Border below zone ``state``; strict: below it means ``x <= p``, else ``x < p``."""
        raise NotImplementedError


class RangeRule(Rule):
    """Zones 0: x < low, 1: low <= x <= high, 2: x > high (a point watch is low=p, high=inf)."""

    def __init__(self, low: float, high: float) -> None:
        self.low = low
        self.high = high

    def state_of(self, x: float) -> int:
        if x < self.low:
            return 0
        return 1 if x <= self.high else 2

    def up(self, state: int) -> tuple[float, bool] | None:
        if state == 0:
            return (self.low, False)
        if state == 1 and self.high != math.inf:
            return (self.high, True)
        return None

    def down(self, state: int) -> tuple[float, bool] | None:
        if state == 2:
            return (self.high, True)
        if state == 1 and self.low != -math.inf:
            return (self.low, False)
        return None


class IndexRule(Rule):
    """Zone n: mark(n) <= x < mark(n+1) with mark(k) = k*period + offset."""

    def __init__(self, period: float, offset: float) -> None:
        self.period = period
        self.offset = offset

    def mark(self, k: int) -> float:
        return k * self.period + self.offset

    def state_of(self, x: float) -> int:
        n = math.floor((x - self.offset) / self.period)
        while x < self.mark(n):
            n -= 1
        while x >= self.mark(n + 1):
            n += 1
        return n

    def up(self, state: int) -> tuple[float, bool] | None:
        return (self.mark(state + 1), False)

    def down(self, state: int) -> tuple[float, bool] | None:
        return (self.mark(state), False)
