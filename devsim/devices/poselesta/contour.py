"""Contouring: linear interpolation G01 and circular interpolation G02/G03, and the continuous
path between such blocks (manual §2.3.15, §2.4.2, §2.4.3; spec poselesta.md §4.3.3, §5.3, §6.6,
§7.5 G-IJK).

A G01 block is a straight line of its axes, a G02/G03 block an arc in the plane of two axes
(G17 XY with I/J, G18 ZX with K/I, G19 YZ with J/K) around the centre I/J/K, taken as absolute
coordinates (relative to the arc's start with the option ``ijk_incremental``, spec G-IJK), clockwise for G02 and counter-clockwise for G03 seen from the positive third axis
(DIN 66025; the manual has no G17/G18/G19): each plane's two axes are listed in the right-handed
order, so G18 is ZX, not XZ.
The path speed is F × override; the axes follow the path in closed form
(:mod:`devsim.core.path`).  A change of the override re-plans along the rest of the path,
NC-Stop brakes along it, and a block the next one continues ends at its path speed instead of
at rest (no look-ahead beyond the next block).
"""

from __future__ import annotations

import math
from collections.abc import Callable

from devsim.core.path import Arc, Line, Path, SpeedProfile, path_pieces
from devsim.devices.poselesta.axes import Axes
from devsim.devices.poselesta.tape import Block

__all__ = ["CIRCLE_TOLERANCE", "PLANES", "PathMotion"]

#: G17/G18/G19: the axes of the plane and their centre words, in the right-handed order (the first
#: crossed with the second gives the positive third axis, from which G02 is clockwise).
PLANES = {17: (("x", "I"), ("y", "J")), 18: (("z", "K"), ("x", "I")), 19: (("y", "J"), ("z", "K"))}
CIRCLE_TOLERANCE = 0.01  # mm: start and end radius may differ this much (spec §5.3)
FULL = 2 * math.pi


class PathMotion:
    """One contouring block's path, from planning to arrival (re-planned from where it is;
    manual §2.4.2, §2.4.3; spec §5.3)."""

    def __init__(self, machine: Axes, axes: tuple[str, ...], path: Path) -> None:
        self.machine, self.axes, self.path = machine, axes, path
        self.profile = SpeedProfile.plan(0.0, 0.0, 1.0, 1.0)
        self.t0 = machine.clock.now()
        self.continues = False  # the next block goes on along the contour: end at path speed
        end = path.point(path.length)
        self.targets = {a: machine.from_mm(a, end[i]) for i, a in enumerate(axes)}

    @classmethod
    def line(cls, machine: Axes, targets: dict[str, float]) -> PathMotion:
        """G01 to ``targets`` (increments) from where the axes stand."""
        axes = tuple(targets)
        start = tuple(machine.to_mm(a, machine.planned_position(a)) for a in axes)
        return cls(machine, axes, Line(start, tuple(machine.to_mm(a, targets[a]) for a in axes)))

    @classmethod
    def arc(cls, machine: Axes, block: Block, plane: int, absolute: bool, way: int,
            unit: Callable[[str], float] = lambda _a: 1.0, *, full_circle: bool = False,
            centre_incremental: bool = False) -> PathMotion | str | None:
        """The arc a block programs, an error text (the radii differ), or None (no end point);
        ``unit(axis)`` converts program units (inch) to the machine's; ``full_circle`` (G25 with
        ``g25_full_circle``): once round the centre, back to the start; ``centre_incremental``
        (``ijk_incremental``, spec G-IJK): I/J/K count from the start point, not from zero."""
        (a, centre_a), (b, centre_b) = PLANES[plane]
        if block.value(a.upper()) is None and block.value(b.upper()) is None and not full_circle:
            return None
        start = [machine.to_mm(axis, machine.planned_position(axis)) for axis in (a, b)]
        end = []
        for axis, s in zip((a, b), start, strict=True):
            value = block.value(axis.upper())
            end.append(s if value is None or full_circle
                       else machine.to_mm(axis, value * unit(axis)) + (0.0 if absolute else s))
        centre = []
        for axis, word, s in zip((a, b), (centre_a, centre_b), start, strict=True):
            value = block.value(word)
            centre.append(s if value is None
                          else machine.to_mm(axis, value * unit(axis)) + (s if centre_incremental else 0.0))
        r_start = math.hypot(start[0] - centre[0], start[1] - centre[1])
        r_end = math.hypot(end[0] - centre[0], end[1] - centre[1])
        if abs(r_start - r_end) > CIRCLE_TOLERANCE or r_start == 0:
            return f"radius {r_start:.4f} at the start, {r_end:.4f} at the end"
        begin = math.atan2(start[1] - centre[1], start[0] - centre[0])
        finish = math.atan2(end[1] - centre[1], end[0] - centre[0])
        sweep = ((finish - begin) * way) % FULL
        if sweep < 1e-12:
            sweep = FULL  # the end point is the start: a full circle
        return cls(machine, (a, b), Arc(centre[0], centre[1], r_start, begin, way, sweep))

    def _progress(self) -> tuple[float, float]:
        s, sd, _ = self.profile.state(self.machine.clock.now() - self.t0)
        return s, sd

    def _follow(self, path: Path, profile: SpeedProfile, on_done: Callable[[str], None] | None) -> None:
        machine = self.machine
        self.path, self.profile, self.t0 = path, profile, machine.clock.now()
        pieces = path_pieces(path, profile, tuple(machine.from_mm(a, 1.0) for a in self.axes))
        for index, axis in enumerate(self.axes):
            done = None if on_done is None else (lambda a=axis: on_done(a))
            if pieces:
                machine[axis].follow([(d, parts[index]) for d, parts in pieces], on_done=done)
            elif done is not None:
                done()

    @property
    def final_speed(self) -> float:
        """The path speed the block ends with (0, or the speed handed on)."""
        return self.profile.final

    def run(self, speed: float, on_done: Callable[[str], None], v0: float | None = None) -> None:
        """Go on along the path at path speed ``speed`` (mm/s), from the current path speed
        (or ``v0``, the speed the previous block handed on)."""
        s, sd = self._progress()
        rest = self.path.rest(s)
        start = sd if v0 is None else v0
        self._follow(rest, SpeedProfile.plan(rest.length, start, speed, self.machine.accel_mm,
                                             speed if self.continues else 0.0), on_done)

    def brake(self, on_done: Callable[[str], None] | None) -> None:
        """Brake along the path with the ramp: the axes stay on it."""
        s, sd = self._progress()
        rest = self.path.rest(s)
        accel = self.machine.accel_mm
        distance = min(sd * sd / (2 * accel), rest.length)
        self._follow(rest, SpeedProfile.plan(distance, sd, max(sd, 1e-9), accel), on_done)
