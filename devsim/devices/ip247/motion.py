"""An IP247 axis move with the module's exponential ramp (manual §2.5.3.5–§2.5.3.7, §2.8.3;
spec ip247.md §5.3), as pieces the shared closed-form axis follows (:meth:`Axis.follow`).

From standstill the pulse frequency jumps to f_ss and rises as f(t) = f_ss + F (1 − e^(−t/τ))
until the travel frequency f_v; braking is the mirror image down to f_ss, where the pulse train
stops.  A path too short for both ramps runs with the peak frequency f_p at which the two ramps
just meet (2 · s_acc(f_p) = path); a travel frequency at or below f_ss runs at constant
frequency without ramps.  Positions are in base units (``resolution`` base units per pulse).
"""

from __future__ import annotations

import math

from devsim.devices.ip247.machine_data import Ramp

__all__ = ["ExpPiece", "move_pieces"]


class ExpPiece:
    """One piece of a move: ``state(dt)`` = (position, velocity, acceleration) in base units."""

    def __init__(self, ramp: Ramp, resolution: float, x0: float, sign: int, kind: str, t_v: float,
                 f_v: float) -> None:
        self.ramp, self.r, self.x0, self.sign, self.kind, self.t_v, self.f_v = ramp, resolution, x0, sign, kind, t_v, f_v
        # the ramp's figures, and a braking piece's whole ramp, taken once (a piece is read at every look)
        self._tau, self._big_f, self._f_ss = ramp.tau, ramp.big_f, ramp.f_ss
        self._total = self._accel(t_v)[0] if kind == "decel" else 0.0

    def _accel(self, t: float) -> tuple[float, float, float]:
        """Pulses, frequency and its slope ``t`` seconds into the acceleration."""
        tau, big_f = self._tau, self._big_f
        decay = math.exp(-t / tau)
        pulses = big_f * (t - tau * (1 - decay)) + self._f_ss * t
        return pulses, self._f_ss + big_f * (1 - decay), big_f / tau * decay

    def state(self, dt: float) -> tuple[float, float, float]:
        s, r = self.sign, self.r
        if self.kind == "accel":
            n, f, df = self._accel(dt)
        elif self.kind == "decel":
            n_back, f, df = self._accel(self.t_v - dt)
            n, df = self._total - n_back, -df
        else:  # constant frequency
            n, f, df = self.f_v * dt, self.f_v, 0.0
        return self.x0 + s * r * n, s * r * f, s * r * df


def move_pieces(start: float, distance: float, f_v: float, ramp: Ramp, resolution: float) -> list[
    tuple[float, ExpPiece]
]:
    """The pieces of a move of ``distance`` base units from ``start`` at travel frequency
    ``f_v`` (≤ f_max): ``(duration, piece)``."""
    if distance == 0 or f_v <= 0:
        return []
    sign = 1 if distance > 0 else -1
    pulses = abs(distance) / resolution
    if f_v <= ramp.f_ss:
        return [(pulses / f_v, ExpPiece(ramp, resolution, start, sign, "constant", 0.0, f_v))]
    f_v = min(f_v, ramp.f_max)
    if 2 * ramp.pulses_to(f_v) > pulses:  # the ramps meet: the peak frequency where they do
        low, high = ramp.f_ss, f_v
        for _ in range(200):
            mid = 0.5 * (low + high)
            if 2 * ramp.pulses_to(mid) > pulses:
                high = mid
            else:
                low = mid
        f_v = low
    t_v = ramp.time_to(f_v)
    ramp_pulses = ramp.pulses_to(f_v)
    cruise = max(0.0, pulses - 2 * ramp_pulses)
    pieces = [(t_v, ExpPiece(ramp, resolution, start, sign, "accel", t_v, f_v))]
    x = start + sign * resolution * ramp_pulses
    if cruise > 0:  # (after a short move's bisection, a rest of a few ulp: kept, so the end is exact)
        pieces.append((cruise / f_v, ExpPiece(ramp, resolution, x, sign, "constant", 0.0, f_v)))
        x += sign * resolution * cruise
    pieces.append((t_v, ExpPiece(ramp, resolution, x, sign, "decel", t_v, f_v)))
    return [(duration, piece) for duration, piece in pieces if duration > 0]
