"""The flying change G10 (manual §2.6.6.3; spec ip247.md §5.11.4): blocks joined into one motion
without a stop, as pieces the shared axis follows.

[DECISION of the spec] Each block runs at its velocity up to its end point; from there the
frequency ramps (the exponential ramp, up or down) to the next block's velocity; the last block
brakes onto its target.  A following block shorter than the previous block's braking distance,
or too short to reach its own velocity (and, as the last, to brake from it), cannot be joined:
error 52.  Pure: no clock, no axis.
"""

from __future__ import annotations

from typing import Any

from devsim.devices.ip247.machine_data import Ramp
from devsim.devices.ip247.motion import ExpPiece

__all__ = ["NotJoinable", "chain_pieces", "resume_pieces"]


class NotJoinable(ValueError):
    """Error 52 "Fliegender Wechsel konnte nicht ausgeführt werden"."""


class _Part:
    """A stretch of a ramp piece, from ``t0`` seconds into it, moved to start at ``x0``."""

    def __init__(self, base: ExpPiece, t0: float, x0: float) -> None:
        self.base, self.t0, self.x0 = base, t0, x0
        self._p0 = base.state(t0)[0]

    def state(self, dt: float) -> tuple[float, float, float]:
        x, v, a = self.base.state(self.t0 + dt)
        return self.x0 + x - self._p0, v, a


def _distance(ramp: Ramp, r: float, f: float) -> float:
    return r * ramp.pulses_to(f) if f > ramp.f_ss else 0.0


def _time(ramp: Ramp, f: float) -> float:
    return ramp.time_to(f) if f > ramp.f_ss else 0.0


def chain_pieces(ramp: Ramp, r: float, x0: float, direction: int, ends: list[float],
                 frequencies: list[float]) -> tuple[list[tuple[float, Any]], list[float]]:
    """The pieces of a chain from motor position ``x0`` through ``ends`` (motor positions, all
    in ``direction``) at ``frequencies``, and the time each block after the first begins."""
    pieces: list[tuple[float, Any]] = []
    starts: list[float] = []
    x, t, previous = x0, 0.0, 0.0
    last = len(ends) - 1
    for index, (end, f) in enumerate(zip(ends, frequencies, strict=True)):
        length = (end - x) * direction
        if index:
            starts.append(t)
            if length < _distance(ramp, r, previous):
                raise NotJoinable("shorter than the braking distance of the previous block")
        ramp_part: tuple[float, Any] | None = None
        if index == 0 and f > ramp.f_ss:
            t_v = ramp.time_to(f)
            ramp_part = (t_v, ExpPiece(ramp, r, x, direction, "accel", t_v, f))
        elif index and f > previous and f > ramp.f_ss:
            t1, t2 = _time(ramp, previous), ramp.time_to(f)
            ramp_part = (t2 - t1, _Part(ExpPiece(ramp, r, 0.0, direction, "accel", t2, f), t1, x))
        elif index and f < previous:
            t1 = ramp.time_to(previous)
            ramp_part = (t1 - _time(ramp, f), _Part(ExpPiece(ramp, r, 0.0, direction, "decel", t1, previous), 0.0, x))
        ramp_length = abs(ramp_part[1].state(ramp_part[0])[0] - x) if ramp_part else 0.0
        braking = _distance(ramp, r, f) if index == last else 0.0
        cruise = length - ramp_length - braking
        if cruise < -1e-6 * max(1.0, length):
            raise NotJoinable("too short to reach its velocity")
        if ramp_part is not None:
            pieces.append(ramp_part)
            x += direction * ramp_length
            t += ramp_part[0]
        if cruise > 0:
            pieces.append((cruise / (r * f), ExpPiece(ramp, r, x, direction, "constant", 0.0, f)))
            x += direction * cruise
            t += cruise / (r * f)
        if index == last and f > ramp.f_ss:
            t_v = ramp.time_to(f)
            pieces.append((t_v, ExpPiece(ramp, r, x, direction, "decel", t_v, f)))
            t += t_v
        previous = f
    return [(d, p) for d, p in pieces if d > 0], starts


def resume_pieces(ramp: Ramp, r: float, x0: float, direction: int, ends: list[float],
                  frequencies: list[float]) -> tuple[int, list[tuple[float, Any]], list[float]]:
    """An interrupted chain going on from ``x0`` through the rest of its blocks (manual §4.3.3):
    how many leading blocks fall away, and :func:`chain_pieces` of the others.  A block whose
    end the braking passed is done (case 3: its residual was negative); one whose rest is too
    short to reach its velocity again gives that rest to the following block (case 2); else the
    flying change runs as programmed (case 1).  NotJoinable when none of these can run."""
    skip = 1 if len(ends) > 1 and (ends[0] - x0) * direction <= 0 else 0
    try:
        return (skip, *chain_pieces(ramp, r, x0, direction, ends[skip:], frequencies[skip:]))
    except NotJoinable:
        if skip or len(ends) < 2:
            raise
    return (1, *chain_pieces(ramp, r, x0, direction, ends[1:], frequencies[1:]))
