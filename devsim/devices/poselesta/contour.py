"""Circular interpolation G02/G03 (manual §2.3.15, §2.4.2; spec poselesta.md §5.3, §6.6, §7.5
G-IJK): an arc in the plane of two axes (G17 XY with I/J, G18 XZ with I/K, G19 YZ with J/K),
its centre given by I/J/K as absolute coordinates, clockwise for G02 and counter-clockwise for
G03 seen from the positive third axis, at the path speed F × override.  The axes follow the arc
in closed form (:mod:`devsim.core.path`); a change of the override re-plans along the rest of
the arc, NC-Stop brakes along it."""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import TYPE_CHECKING

from devsim.core.path import Arc, SpeedProfile, arc_pieces
from devsim.devices.poselesta.tape import Block

if TYPE_CHECKING:
    from devsim.devices.poselesta.cnc import PoselestaCnc

__all__ = ["CIRCLE_TOLERANCE", "PLANES", "ArcMotion"]

#: G17/G18/G19: the axes of the plane and their centre words.
PLANES = {17: (("x", "I"), ("y", "J")), 18: (("x", "I"), ("z", "K")), 19: (("y", "J"), ("z", "K"))}
CIRCLE_TOLERANCE = 0.01  # mm: start and end radius may differ this much (spec §5.3)
FULL = 2 * math.pi


class ArcMotion:
    """One G02/G03 block's arc, from planning to arrival (re-planned from where it is)."""

    def __init__(self, cnc: PoselestaCnc, axes: tuple[str, str], arc: Arc) -> None:
        self.cnc, self.axes, self.arc = cnc, axes, arc
        self.profile = SpeedProfile.plan(0.0, 0.0, 1.0, 1.0)
        self.t0 = cnc.clock.now()
        end = arc.point(arc.length)
        self.targets = {axes[0]: cnc.from_mm(axes[0], end[0]), axes[1]: cnc.from_mm(axes[1], end[1])}

    @classmethod
    def from_block(cls, cnc: PoselestaCnc, block: Block, plane: int, absolute: bool, way: int,
                   unit: Callable[[str], float] = lambda _a: 1.0) -> ArcMotion | str | None:
        """The arc a block programs, an error text (the radii differ), or None (no end point);
        ``unit(axis)`` converts program units (inch) to the machine's."""
        (a, centre_a), (b, centre_b) = PLANES[plane]
        if block.value(a.upper()) is None and block.value(b.upper()) is None:
            return None
        start = [cnc.to_mm(axis, cnc.axes[axis].final_position()) for axis in (a, b)]
        end = []
        for axis, s in zip((a, b), start, strict=True):
            value = block.value(axis.upper())
            end.append(s if value is None else cnc.to_mm(axis, value * unit(axis)) + (0.0 if absolute else s))
        centre = []
        for axis, word, s in zip((a, b), (centre_a, centre_b), start, strict=True):
            value = block.value(word)
            centre.append(s if value is None else cnc.to_mm(axis, value * unit(axis)))
        r_start = math.hypot(start[0] - centre[0], start[1] - centre[1])
        r_end = math.hypot(end[0] - centre[0], end[1] - centre[1])
        if abs(r_start - r_end) > CIRCLE_TOLERANCE or r_start == 0:
            return f"radius {r_start:.4f} at the start, {r_end:.4f} at the end"
        begin = math.atan2(start[1] - centre[1], start[0] - centre[0])
        finish = math.atan2(end[1] - centre[1], end[0] - centre[0])
        sweep = ((finish - begin) * way) % FULL
        if sweep < 1e-12:
            sweep = FULL  # the end point is the start: a full circle
        return cls(cnc, (a, b), Arc(centre[0], centre[1], r_start, begin, way, sweep))

    def _progress(self) -> tuple[float, float]:
        s, sd, _ = self.profile.state(self.cnc.clock.now() - self.t0)
        return s, sd

    def _follow(self, arc: Arc, profile: SpeedProfile, on_done: Callable[[str], None] | None) -> None:
        cnc = self.cnc
        self.arc, self.profile, self.t0 = arc, profile, cnc.clock.now()
        scales = (cnc.from_mm(self.axes[0], 1.0), cnc.from_mm(self.axes[1], 1.0))
        pieces = arc_pieces(arc, profile, scales)
        for index, axis in enumerate(self.axes):
            done = None if on_done is None else (lambda a=axis: on_done(a))
            if pieces:
                cnc.axes[axis].follow([(d, parts[index]) for d, parts in pieces], on_done=done)
            elif done is not None:
                done()

    def _rest(self) -> Arc:
        """The part of the arc still ahead."""
        s, _ = self._progress()
        arc = self.arc
        return Arc(arc.cx, arc.cy, arc.radius, arc.angle(s), arc.way, max(0.0, arc.sweep - s / arc.radius))

    def run(self, speed: float, on_done: Callable[[str], None]) -> None:
        """Go on along the arc at path speed ``speed`` (mm/s) from the current path speed."""
        _, sd = self._progress()
        rest = self._rest()
        self._follow(rest, SpeedProfile.plan(rest.length, sd, speed, self.cnc.cfg.accel), on_done)

    def brake(self, on_done: Callable[[str], None] | None) -> None:
        """Brake along the arc with the ramp: the axes stay on the circle."""
        _, sd = self._progress()
        rest = self._rest()
        distance = min(sd * sd / (2 * self.cnc.cfg.accel), rest.length)
        self._follow(rest, SpeedProfile.plan(distance, sd, max(sd, 1e-9), self.cnc.cfg.accel), on_done)
