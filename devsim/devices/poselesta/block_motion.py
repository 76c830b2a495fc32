"""The motion of one block: its targets, its speeds and the axes that still have to arrive
(manual §2.3.6, §2.3.8, §2.3.14, §2.3.22, §2.4.2, §2.4.3; spec poselesta.md §5.1–§5.3, §5.7).

G00 moves each axis at its rapid (P44–P47, × override with P64 = 1) on its own ramps; G01 is a
straight line and G02/G03 an arc at F × override (:mod:`~devsim.devices.poselesta.contour`),
no faster than the slowest rapid of its axes.  A program runs in inch while V22/2 is H, and a
program typed in inch carries two more decimals (spec §5.1).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable

from devsim.devices.poselesta.axes import Axes
from devsim.devices.poselesta.contour import PathMotion
from devsim.devices.poselesta.functions import BlockFunctions
from devsim.devices.poselesta.limits import LimitSwitches
from devsim.devices.poselesta.parameters import MachineParameters
from devsim.devices.poselesta.screen import Screen
from devsim.devices.poselesta.signals import AXES
from devsim.devices.poselesta.tape import Block

__all__ = ["BlockMotion"]

Arrived = Callable[[str], None]


class BlockMotion:
    """Plans and drives the motion of the running block on the axes (spec §5.3): the modal
    functions come from ``functions``, the override from ``override()``; ``ijk_incremental``:
    an arc's centre I/J/K is relative to its start (spec G-IJK)."""

    def __init__(self, axes: Axes, functions: BlockFunctions, limits: LimitSwitches, params: MachineParameters,
                 screen: Screen, *, override: Callable[[], float], ijk_incremental: bool = False) -> None:
        self._ijk_incremental = ijk_incremental
        self._axes = axes
        self._functions = functions
        self._limits = limits
        self._params = params
        self._screen = screen
        self._override = override
        self.targets: dict[str, float] = {}
        self.contour: PathMotion | None = None
        self.carry: float | None = None  # path speed handed on to the next block (mm/s)
        self.v0: float | None = None  # the path speed this block starts with
        self.inch = False  # V22/2 sampled at the start of the block (spec §5.1)
        self.typed_inch = False  # the running program was typed in inch (two more decimals)
        self._arriving: set[str] = set()

    def reset(self) -> None:
        self.contour = None
        self.carry = self.v0 = None

    # -- units (spec §5.1) ---------------------------------------------------------------------------
    def unit(self, a: str) -> float:
        """A stored coordinate value in units of the machine's last decimal: a program runs in
        inch while V22/2 is H (spec §5.1: the machine measures in mm; D is not converted), and a
        program typed in inch carries two more decimals."""
        if a == "d":
            return 1.0
        return (25.4 if self.inch else 1.0) / (100.0 if self.typed_inch else 1.0)

    def feed_unit(self) -> float:
        """F in mm/min, or inch/min while V22/2 is H."""
        return 25.4 if self.inch else 1.0

    # -- planning ------------------------------------------------------------------------------------
    def take_carry(self) -> None:
        """The block starts with the path speed the previous block handed on."""
        self.v0, self.carry = self.carry, None

    def plan(self, block: Block) -> dict[str, float] | str | None:
        """The targets of ``block`` (increments), an error text (an arc's radii differ), or None
        (no motion); a contour block also gets its path."""
        functions = self._functions
        self.contour = None
        if functions.motion in (2, 3) or functions.full_circle:
            contour = PathMotion.arc(self._axes, block, functions.plane, functions.absolute,
                                     -1 if functions.motion == 2 else 1, self.unit,
                                     full_circle=functions.full_circle, centre_incremental=self._ijk_incremental)
            if contour is None or isinstance(contour, str):
                return contour
            self.contour = contour
            return contour.targets
        targets: dict[str, float] = {}
        for a in AXES:
            value = block.value(a.upper())
            if value is None:
                continue
            base = 0.0 if functions.absolute else self._axes.planned_position(a)
            targets[a] = base + value * self.unit(a)
        if not targets:
            return None
        if functions.motion == 1:
            self.contour = PathMotion.line(self._axes, targets)
        return targets

    # -- moving --------------------------------------------------------------------------------------
    def start(self, continues: Callable[[], bool], arrived: Arrived) -> bool:
        """Plan every axis of the block from where it is (also a resumed hold); False when a
        limit switch or the working field refuses the motion."""
        axes = self._axes
        self._arriving = set(self.targets)
        for a, target in self.targets.items():
            if self._limits.refuses(a, target - axes[a].position()):
                return False
        if self.contour is not None:
            speed = self.path_speed(tuple(self.targets))
            v0, self.v0 = self.v0, None
            if speed is not None:
                for a in self.targets:
                    axes.check_encoder(a, axes.from_mm(a, speed))
                self.contour.continues = continues()
                self.contour.run(speed, arrived, v0)
            return True
        speeds = self.speeds()
        if speeds is None:
            return True  # override 0 %: the path stands without HOLD until the override rises (spec §5.3)
        for a, target in self.targets.items():
            speed, accel = speeds[a]
            axis = axes[a]
            if abs(target - axis.position()) < 1e-9 and not axis.moving:
                arrived(a)  # (already there: a zero move still reaches its position, §2.4.3)
                continue
            axes.check_encoder(a, speed)
            axis.move_to(target, speed, accel, on_done=lambda a=a: arrived(a))
        return True

    def speeds(self) -> dict[str, tuple[float, float]] | None:
        """G00: each axis at its rapid (P44–P47, × override with P64 = 1) with its own ramps
        (spec §5.3); speeds in inc/s, accelerations in inc/s²."""
        if self._zero_rapid(self.targets):
            return None
        factor = self._override() if self._params.rapid_override == 1 else 1.0
        if factor <= 0:
            return None
        return {a: (self._axes.rapid(a) * factor, self._axes.accel(a)) for a in self.targets}

    def _zero_rapid(self, axes: Iterable[str]) -> bool:
        """P44–P47 = 0 (after a POS II catalogue read): the axis cannot move (spec §4.8)."""
        if any(self._axes.rapid(a) <= 0 for a in axes):
            self._screen.record("zero_speed_parameter")
            return True
        return False

    def path_speed(self, axes: tuple[str, ...]) -> float | None:
        """F × override in mm/s, no faster than the slowest rapid of ``axes``; None at 0."""
        if self._zero_rapid(axes):
            return None
        feed = self._functions.feed
        path = min([feed * self.feed_unit() * self._override() / 60.0,
                    *(self._axes.to_mm(a, self._axes.rapid(a)) for a in axes)])
        if feed <= 0:
            self._screen.record("zero_feed")
        return path if path > 0 else None

    def replan(self, arrived: Arrived) -> None:
        """The override changed: the contour goes on at the new path speed, or brakes at 0."""
        assert self.contour is not None
        speed = self.path_speed(tuple(self.targets))
        if speed is None:
            self.contour.brake(None)
        else:
            self.contour.run(speed, arrived)

    def arrived(self, axis: str) -> bool:
        """``axis`` reached its target: True once every axis of the block has."""
        self._arriving.discard(axis)
        return not self._arriving

    def forget_arrivals(self) -> None:
        self._arriving.clear()

    def hand_on(self) -> bool:
        """The contour goes on in the next block at its path speed (§2.4.2): True, and the next
        block starts with that speed."""
        if self.contour is not None and self.contour.final_speed > 0:
            self.carry = self.contour.final_speed
            return True
        return False

    def brake(self, settled: Arrived) -> None:
        """Brake every axis of the block along its ramp (along the path for a contour);
        ``settled(axis)`` once it stands."""
        if self.contour is not None:
            self.contour.brake(settled)
            return
        for a in self.targets:
            axis = self._axes[a]
            if axis.moving:
                axis.stop(self._axes.accel(a), on_done=lambda a=a: settled(a))
            else:
                settled(a)

    def quick_stop(self) -> None:
        """Not-Stop (§2.3.2): every axis stops at once, without ramp."""
        for axis in self._axes.values():
            axis.quick_stop()
