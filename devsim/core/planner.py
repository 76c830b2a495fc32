"""The move planner of the closed-form axis (:mod:`devsim.core.axis`).

Pure functions from a state (position, velocity) and a command to the phases that carry it out
(design.md principle 2, *physics is closed-form*): :func:`move_phases` and
:func:`move_phases_profiled` stand still exactly at a target (trapezoid or triangle, braking first
when moving away or too fast), :func:`jog_phases` ramps to a cruise speed, :func:`stop_phases`
brakes to zero; ramps are constant-acceleration, or shaped by a :class:`~devsim.core.profile.Ramp`
(SERS P1032/P1005–P1008, spec §5.2).  No clock and no state: the axis turns the phases they
return into the segments of its plan (:meth:`devsim.core.axis.Axis.move_to`).
"""

from __future__ import annotations

import math

from devsim.core.profile import ABS_X, REL_X, PhaseSpec, Ramp, sign

__all__ = ["jog_phases", "move_phases", "move_phases_profiled", "peak", "stop_phases"]


def move_phases(x0: float, v0: float, target: float, speed: float, accel: float, decel: float) -> list[PhaseSpec]:
    """The phases from ``(x0, v0)`` to stand still exactly at ``target`` with constant-acceleration
    ramps (the cases of :meth:`devsim.core.axis.Axis.move_to`)."""
    phases: list[PhaseSpec] = []
    tol = max(ABS_X, REL_X * max(abs(x0), abs(target)))
    dist = target - x0
    sd = v0 * v0 / (2.0 * decel)
    if v0 != 0.0:
        toward = sign(dist) == sign(v0)
        if toward and abs(abs(dist) - sd) <= tol and abs(dist) > 0.0:
            # brakes onto the target exactly (decel adjusted by a rounding error at most)
            d_exact = v0 * v0 / (2.0 * abs(dist))
            phases.append((-sign(v0) * d_exact, abs(v0) / d_exact, 0.0, "linear"))
            return phases
        if not toward or sd > abs(dist):
            phases.append((-sign(v0) * decel, abs(v0) / decel, 0.0, "linear"))
            x0 += sign(v0) * sd
            v0 = 0.0
            dist = target - x0
    if abs(dist) > 0.0:
        s = sign(dist)
        length = abs(dist)
        u = abs(v0)  # toward the target, 0 <= u and u²/(2 decel) <= length
        if u > speed:
            phases.append((-s * decel, (u - speed) / decel, s * speed, "linear"))
            top = speed
            cruise = length - u * u / (2.0 * decel)
        else:
            top = math.sqrt((2.0 * accel * decel * length + decel * u * u) / (accel + decel))
            top = max(top, u)
            if top > speed:
                top = speed
                cruise = length - (speed * speed - u * u) / (2.0 * accel) - speed * speed / (2.0 * decel)
            else:
                cruise = 0.0
            phases.append((s * accel, (top - u) / accel, s * top, "linear"))
        if cruise > 0.0:
            phases.append((0.0, cruise / top, s * top, "linear"))
        phases.append((-s * decel, top / decel, 0.0, "linear"))
    return phases


def move_phases_profiled(
    x0: float, v0: float, target: float, speed: float, acc_ramp: Ramp, dec_ramp: Ramp
) -> list[PhaseSpec]:
    """:func:`move_phases` with sectioned ramps (the same cases as the plain planner)."""
    phases: list[PhaseSpec] = []
    tol = max(ABS_X, REL_X * max(abs(x0), abs(target)))
    dist = target - x0
    sd = dec_ramp.distance(0.0, abs(v0))
    if v0 != 0.0:
        toward = sign(dist) == sign(v0)
        if toward and abs(abs(dist) - sd) <= tol and abs(dist) > 0.0:
            # brakes onto the target exactly (decelerations scaled by a rounding error at most)
            dec_ramp.down(abs(v0), 0.0, sign(v0), phases, scale=sd / abs(dist))
            return phases
        if not toward or sd > abs(dist):
            dec_ramp.down(abs(v0), 0.0, sign(v0), phases)
            x0 += sign(v0) * sd
            v0 = 0.0
            dist = target - x0
    if abs(dist) > 0.0:
        s = sign(dist)
        length = abs(dist)
        u = abs(v0)  # toward the target, 0 <= u and its braking distance <= length
        if u > speed:
            dec_ramp.down(u, speed, s, phases)
            top = speed
            cruise = length - dec_ramp.distance(0.0, u)
        else:
            top, cruise = peak(acc_ramp, dec_ramp, u, speed, length)
            acc_ramp.up(u, top, s, phases)
        if cruise > 0.0:
            phases.append((0.0, cruise / top, s * top, "linear"))
        dec_ramp.down(top, 0.0, s, phases)
    return phases


def peak(acc_ramp: Ramp, dec_ramp: Ramp, u: float, speed: float, length: float) -> tuple[float, float]:
    """``(peak speed, cruise distance)`` to cover ``length`` from speed ``u``: accelerate to
    the peak, then brake to 0.  The distance ``f(p)`` is monotone in the peak ``p`` and, between
    two section bounds, ``f(lo) + (p² - lo²)·(1/(2a) + 1/(2d))``: solved in closed form within
    the interval that holds the solution."""

    def f(p: float) -> float:
        return acc_ramp.distance(u, p) + dec_ramp.distance(0.0, p)

    f_top = f(speed)
    if f_top <= length:
        return speed, length - f_top
    inner = {b for b in acc_ramp.bounds + dec_ramp.bounds if u < b < speed}
    points = [u, *sorted(inner), speed]
    for lo, hi in zip(points, points[1:], strict=False):
        if hi < speed and f(hi) < length:
            continue
        mid = 0.5 * (lo + hi)
        k = 0.5 / acc_ramp.acc_at(mid) + 0.5 / dec_ramp.acc_at(mid)
        p = math.sqrt(max(lo * lo + (length - f(lo)) / k, 0.0))
        return min(max(p, lo), hi), 0.0
    return speed, 0.0  # not reached: u == speed has f(speed) <= length


def jog_phases(v0: float, vt: float, speed: float, accel: float, ramp: Ramp | None) -> list[PhaseSpec]:
    """The phases from velocity ``v0`` to the cruise velocity ``vt`` (``|vt| == speed``, not 0):
    through zero first when it points the other way; ``ramp`` shapes them."""
    phases: list[PhaseSpec] = []
    if ramp is not None:
        if v0 != 0.0 and sign(v0) != sign(vt):
            ramp.down(abs(v0), 0.0, sign(v0), phases)
            ramp.up(0.0, speed, sign(vt), phases)
        elif abs(v0) < speed:
            ramp.up(abs(v0), speed, sign(vt), phases)
        elif abs(v0) > speed:
            ramp.down(abs(v0), speed, sign(vt), phases)
    elif v0 != 0.0 and sign(v0) != sign(vt):
        phases.append((-sign(v0) * accel, abs(v0) / accel, 0.0, "linear"))
        phases.append((sign(vt) * accel, speed / accel, vt, "linear"))
    elif v0 != vt:
        phases.append((sign(vt - v0) * accel, abs(vt - v0) / accel, vt, "linear"))
    return phases


def stop_phases(v0: float, decel: float, ramp: Ramp | None) -> list[PhaseSpec]:
    """The phases braking velocity ``v0`` to 0 with ``decel``, or through ``ramp``'s sections."""
    phases: list[PhaseSpec] = []
    if ramp is not None:
        ramp.down(abs(v0), 0.0, sign(v0), phases)
    elif v0 != 0.0:
        phases.append((-sign(v0) * decel, abs(v0) / decel, 0.0, "linear"))
    return phases

