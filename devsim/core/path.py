"""Coordinated motion of several axes along one path (a straight line or a circular arc), in
closed form.

The speed along the path is a trapezoid (or triangle) in the path length ``s``: from the
current path speed up to ``speed`` with ``accel``, cruising, and down to rest at the end of the
path, as :meth:`devsim.core.axis.Axis.move_to` plans a single axis.  Each axis follows its
component of the path (:meth:`devsim.core.axis.Axis.follow`): the time is cut where the
profile changes its acceleration and where a component turns (an arc's quadrant points), so
that every piece is monotonic in every axis and the axis model's crossing events stay exact.
Units are the caller's: a path in millimetres, ``scale`` turning a component into increments.

Used by the POSELESTA's G01/G02/G03 and its continuous path (spec poselesta.md §5.3): a
profile may end at a speed (``v_end``), the next path starting from it.
"""

from __future__ import annotations

import math

import msgspec

__all__ = ["Arc", "Line", "Path", "PathComponent", "SpeedProfile", "path_pieces"]


class SpeedProfile(msgspec.Struct, frozen=True):
    """Path length ``s(t)`` from 0 to ``length``: pieces ``(t0, s0, v0, acc)`` of constant path
    acceleration, the last ending at rest at ``end``."""

    pieces: tuple[tuple[float, float, float, float], ...]
    end: float
    length: float
    final: float = 0.0  # the path speed at the end

    @classmethod
    def plan(cls, length: float, v0: float, speed: float, accel: float, v_end: float = 0.0) -> SpeedProfile:
        """From path speed ``v0`` to ``v_end`` (rest by default) after ``length``, at most
        ``speed``, ramps ``accel`` (braking harder only when ``v0`` cannot slow down within
        ``length`` otherwise)."""
        pieces: list[tuple[float, float, float, float]] = []
        t = s = 0.0
        v = max(0.0, v0)
        v_end = max(0.0, min(v_end, speed))
        if length <= 0:
            return cls((), 0.0, 0.0)
        if v > v_end and (v * v - v_end * v_end) / (2 * accel) >= length:  # slowing takes all of it
            acc = -(v * v - v_end * v_end) / (2 * length)
            return cls(((0.0, 0.0, v, acc),), (v_end - v) / acc, length, v_end)
        if v > speed:  # first down to the speed
            dt = (v - speed) / accel
            pieces.append((t, s, v, -accel))
            s += (v + speed) / 2 * dt
            t += dt
            v = speed
        peak = min(speed, math.sqrt(accel * (length - s) + (v * v + v_end * v_end) / 2))
        if peak > v:
            dt = (peak - v) / accel
            pieces.append((t, s, v, accel))
            s += (v + peak) / 2 * dt
            t += dt
            v = peak
        cruise = length - s - (v * v - v_end * v_end) / (2 * accel)
        if cruise > 1e-12 * max(1.0, length):
            pieces.append((t, s, v, 0.0))
            t += cruise / v
            s += cruise
        if v > v_end:
            pieces.append((t, s, v, -accel))
            t += (v - v_end) / accel
        return cls(tuple(pieces), t, length, min(v, v_end) if v_end else 0.0)

    def _piece(self, t: float) -> tuple[float, float, float, float]:
        found = self.pieces[0]
        for piece in self.pieces:
            if piece[0] <= t:
                found = piece
        return found

    def state(self, t: float) -> tuple[float, float, float]:
        """``(s, ds/dt, d²s/dt²)`` at ``t`` (clamped to the profile)."""
        if not self.pieces or t >= self.end:
            return self.length, self.final, 0.0
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


class Arc(msgspec.Struct, frozen=True):
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


    def rest(self, s: float) -> Arc:
        """The part of the arc after ``s``."""
        return Arc(self.cx, self.cy, self.radius, self.angle(s), self.way, max(0.0, self.sweep - s / self.radius))

    def component(self, i: int, s: float) -> tuple[float, float, float]:
        """Component ``i`` (0: first axis, 1: second) and its first and second derivative in s."""
        a = self.angle(s)
        c, n = math.cos(a), math.sin(a)
        if i == 0:
            return self.cx + self.radius * c, -self.way * n, -c / self.radius
        return self.cy + self.radius * n, self.way * c, -n / self.radius


class Line(msgspec.Struct, frozen=True):
    """A straight line from ``start`` to ``end`` (any number of axes)."""

    start: tuple[float, ...]
    end: tuple[float, ...]

    @property
    def length(self) -> float:
        return math.dist(self.start, self.end)

    def turning_points(self) -> list[float]:
        return []

    def point(self, s: float) -> tuple[float, ...]:
        return tuple(self.component(i, s)[0] for i in range(len(self.start)))

    def rest(self, s: float) -> Line:
        return Line(self.point(s), self.end)

    def component(self, i: int, s: float) -> tuple[float, float, float]:
        length = self.length
        unit = (self.end[i] - self.start[i]) / length if length > 0 else 0.0
        return self.start[i] + unit * s, unit, 0.0


Path = Arc | Line


class PathComponent:
    """One axis's share of a path for a piece of time: ``state(dt)`` = (position, velocity,
    acceleration) in the axis's units (``scale`` × the path's), ``dt`` from the piece's start."""

    def __init__(self, path: Path, profile: SpeedProfile, t_start: float, component: int, scale: float) -> None:
        self.path, self.profile, self.t_start, self.component, self.scale = path, profile, t_start, component, scale

    def state(self, dt: float) -> tuple[float, float, float]:
        s, sd, sdd = self.profile.state(self.t_start + dt)
        x, dx, ddx = self.path.component(self.component, s)
        return x * self.scale, dx * sd * self.scale, (ddx * sd * sd + dx * sdd) * self.scale


def path_pieces(path: Path, profile: SpeedProfile, scales: tuple[float, ...]) -> list[
    tuple[float, tuple[PathComponent, ...]]
]:
    """The path cut into pieces monotonic in every component: ``(duration, (one per axis))``."""
    cuts = {0.0, profile.end}
    cuts.update(t for t, *_ in profile.pieces)
    cuts.update(profile.time_at(s) for s in path.turning_points())
    times = sorted(t for t in cuts if 0.0 <= t <= profile.end)
    pieces = []
    for t0, t1 in zip(times, times[1:], strict=False):
        if t1 - t0 > 1e-12 * max(1.0, profile.end):
            pieces.append((t1 - t0, tuple(PathComponent(path, profile, t0, i, scale) for i, scale in enumerate(scales))))
    return pieces
