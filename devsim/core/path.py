"""Coordinated motion of several axes along one path (a circular arc), in closed form.

The speed along the path is a trapezoid (or triangle) in the path length ``s``: from the
current path speed up to ``speed`` with ``accel``, cruising, and down to rest at the end of the
path, as :meth:`devsim.core.axis.Axis.move_to` plans a single axis.  Each axis follows its
component of the path (:meth:`devsim.core.axis.Axis.follow`): the time is cut where the
profile changes its acceleration and where a component turns (an arc's quadrant points), so
that every piece is monotonic in every axis and the axis model's crossing events stay exact.
Units are the caller's: a path in millimetres, ``scale`` turning a component into increments.

Used by the POSELESTA's G02/G03 (spec poselesta.md §5.3); a straight line is the degenerate
case any kind can build the same way.
"""

from __future__ import annotations

import math

from devsim.core.record import record

__all__ = ["Arc", "ArcComponent", "SpeedProfile", "arc_pieces"]


@record
class SpeedProfile:
    """Path length ``s(t)`` from 0 to ``length``: pieces ``(t0, s0, v0, acc)`` of constant path
    acceleration, the last ending at rest at ``end``."""

    pieces: tuple[tuple[float, float, float, float], ...]
    end: float
    length: float

    @classmethod
    def plan(cls, length: float, v0: float, speed: float, accel: float) -> SpeedProfile:
        """From path speed ``v0`` to rest after ``length``, at most ``speed``, ramps ``accel``
        (braking harder only when ``v0`` cannot stop within ``length`` otherwise)."""
        pieces: list[tuple[float, float, float, float]] = []
        t = s = 0.0
        v = max(0.0, v0)
        if length <= 0:
            return cls((), 0.0, 0.0)
        if v * v / (2 * accel) >= length:  # stopping already takes all of it
            acc = -v * v / (2 * length)
            return cls(((0.0, 0.0, v, acc),), v / -acc if acc else 0.0, length)
        if v > speed:  # first down to the speed
            dt = (v - speed) / accel
            pieces.append((t, s, v, -accel))
            s += (v + speed) / 2 * dt
            t += dt
            v = speed
        peak = min(speed, math.sqrt(accel * (length - s) + v * v / 2))
        if peak > v:
            dt = (peak - v) / accel
            pieces.append((t, s, v, accel))
            s += (v + peak) / 2 * dt
            t += dt
            v = peak
        cruise = length - s - v * v / (2 * accel)
        if cruise > 1e-12 * max(1.0, length):
            pieces.append((t, s, v, 0.0))
            t += cruise / v
            s += cruise
        pieces.append((t, s, v, -accel))
        t += v / accel
        return cls(tuple(pieces), t, length)

    def _piece(self, t: float) -> tuple[float, float, float, float]:
        found = self.pieces[0]
        for piece in self.pieces:
            if piece[0] <= t:
                found = piece
        return found

    def state(self, t: float) -> tuple[float, float, float]:
        """``(s, ds/dt, d²s/dt²)`` at ``t`` (clamped to the profile)."""
        if not self.pieces or t >= self.end:
            return self.length, 0.0, 0.0
        t0, s0, v0, acc = self._piece(max(0.0, t))
        dt = max(0.0, t) - t0
        return s0 + v0 * dt + 0.5 * acc * dt * dt, v0 + acc * dt, acc

    def time_at(self, s: float) -> float:
        """When the path reaches ``s`` (the first time)."""
        if s <= 0 or not self.pieces:
            return 0.0
        if s >= self.length:
            return self.end
        for index, (t0, s0, v0, acc) in enumerate(self.pieces):
            t_next = self.pieces[index + 1][0] if index + 1 < len(self.pieces) else self.end
            dt_piece = t_next - t0
            s_next = s0 + v0 * dt_piece + 0.5 * acc * dt_piece * dt_piece
            if s <= s_next or index + 1 == len(self.pieces):
                ds = s - s0
                disc = v0 * v0 + 2 * acc * ds
                den = v0 + math.sqrt(disc) if disc > 0 else v0
                return t0 + (2 * ds / den if den > 0 else 0.0)
        return self.end


@record
class Arc:
    """A circular arc in a plane: centre, radius, start angle and the way round (+1 counter-
    clockwise, -1 clockwise), ``sweep`` radians long."""

    cx: float
    cy: float
    radius: float
    start: float
    way: int
    sweep: float

    @property
    def length(self) -> float:
        return self.radius * self.sweep

    def angle(self, s: float) -> float:
        return self.start + self.way * s / self.radius

    def point(self, s: float) -> tuple[float, float]:
        a = self.angle(s)
        return self.cx + self.radius * math.cos(a), self.cy + self.radius * math.sin(a)

    def turning_points(self) -> list[float]:
        """Path lengths where a component turns (multiples of 90°), inside the arc."""
        found = []
        k = math.floor(self.start / (math.pi / 2)) if self.way > 0 else math.ceil(self.start / (math.pi / 2))
        while True:
            k += self.way
            s = (k * math.pi / 2 - self.start) * self.way * self.radius
            if s <= 1e-12 * max(1.0, self.length):
                continue
            if s >= self.length - 1e-12 * max(1.0, self.length):
                return found
            found.append(s)


class ArcComponent:
    """One axis's share of an arc for a piece of time: ``state(dt)`` = (position, velocity,
    acceleration) in the axis's units (``scale`` × the arc's), ``dt`` from the piece's start."""

    def __init__(self, arc: Arc, profile: SpeedProfile, t_start: float, component: int, scale: float) -> None:
        self.arc, self.profile, self.t_start, self.component, self.scale = arc, profile, t_start, component, scale

    def state(self, dt: float) -> tuple[float, float, float]:
        s, sd, sdd = self.profile.state(self.t_start + dt)
        arc = self.arc
        a = arc.angle(s)
        c, n = math.cos(a), math.sin(a)
        if self.component == 0:
            x = arc.cx + arc.radius * c
            v = -arc.way * n * sd
            acc = -c * sd * sd / arc.radius - arc.way * n * sdd
        else:
            x = arc.cy + arc.radius * n
            v = arc.way * c * sd
            acc = -n * sd * sd / arc.radius + arc.way * c * sdd
        return x * self.scale, v * self.scale, acc * self.scale


def arc_pieces(arc: Arc, profile: SpeedProfile, scales: tuple[float, float]) -> list[
    tuple[float, tuple[ArcComponent, ArcComponent]]
]:
    """The arc cut into pieces monotonic in both components: ``(duration, (x part, y part))``."""
    cuts = {0.0, profile.end}
    cuts.update(t for t, *_ in profile.pieces)
    cuts.update(profile.time_at(s) for s in arc.turning_points())
    times = sorted(t for t in cuts if 0.0 <= t <= profile.end)
    pieces = []
    for t0, t1 in zip(times, times[1:], strict=False):
        if t1 - t0 > 1e-12 * max(1.0, profile.end):
            pieces.append((t1 - t0, (ArcComponent(arc, profile, t0, 0, scales[0]),
                                     ArcComponent(arc, profile, t0, 1, scales[1]))))
    return pieces
