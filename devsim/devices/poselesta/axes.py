"""The four axes X, Y, Z, D of one control with their units and speeds (manual §2.2, §2.3.6,
§2.3.8, §2.5; spec poselesta.md §5.1–§5.3, §5.7).

Positions are increments of each axis's resolution (the decimals of the word format); the
speeds come from the machine parameters: rapid P44–P47, maximum feed P48–P51, gain P30–P33.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Mapping

from devsim.core.axis import Axis
from devsim.core.clock import Clock
from devsim.devices.poselesta.parameters import MachineParameters
from devsim.devices.poselesta.screen import Screen
from devsim.devices.poselesta.signals import AXES
from devsim.devices.poselesta.tape import Formats

__all__ = ["Axes"]


class Axes(Mapping[str, Axis]):
    """The closed-form axes ``x``, ``y``, ``z``, ``d`` by name, and what converts and limits
    their motion (spec §5.1–§5.3, §5.7)."""

    def __init__(self, clock: Clock, params: MachineParameters, screen: Screen, *, decimals: Mapping[str, int],
                 accel: float, kv_per_step: float, encoder_khz: float) -> None:
        self.clock = clock
        self._params = params
        self._screen = screen
        self._axes = {a: Axis(clock, name=a) for a in AXES}
        self.formats = Formats(dict(decimals))
        # programs typed in inch (V22/2 H) carry two more decimals on X, Y, Z (spec §5.1)
        self.inch_formats = Formats({a: d + (0 if a == "D" else 2) for a, d in decimals.items()})
        self.accel_mm = accel  # mm/s², every axis and the path (spec §5.3)
        self._kv_per_step = kv_per_step
        self._encoder_hz = encoder_khz * 1000

    def __getitem__(self, axis: str) -> Axis:
        return self._axes[axis]

    def __iter__(self) -> Iterator[str]:
        return iter(self._axes)

    def __len__(self) -> int:
        return len(self._axes)

    # -- units (spec §5.1) -------------------------------------------------------------------------
    def to_mm(self, axis: str, increments: float) -> float:
        return increments / 10 ** self.formats.decimals[axis.upper()]

    def from_mm(self, axis: str, mm: float) -> float:
        return mm * 10 ** self.formats.decimals[axis.upper()]

    def planned_position(self, axis: str) -> float:
        """Where the axis will stand: the end of its plan, or where it is while a key or the
        homing search drives it without an end."""
        end = self._axes[axis].final_position()
        return end if math.isfinite(end) else self._axes[axis].position()

    def display(self, axis: str, inch: bool) -> str:
        """The actual value as the screen shows it (spec §5.1): mm with the axis's decimals, or
        with V22/2 H inch with two more (100.001 mm → 3.93705); D is not converted."""
        decimals = self.formats.decimals[axis.upper()]
        value = self.to_mm(axis, self._axes[axis].position())
        if inch and axis != "d":
            return f"{value / 25.4:.{decimals + 2}f}"
        return f"{value:.{decimals}f}"

    # -- speeds (spec §5.2, §5.3) --------------------------------------------------------------------
    def rapid(self, axis: str) -> float:
        """P44–P47, in increments per second."""
        return self.from_mm(axis, self._params.rapid(axis) / 60.0)

    def max_feed(self, axis: str) -> float:
        """P48–P51, in increments per second."""
        return self.from_mm(axis, self._params.max_feed(axis) / 60.0)

    def accel(self, axis: str) -> float:
        return self.from_mm(axis, self.accel_mm)

    def kv(self, axis: str) -> float:
        """The position loop gain [1/s]: P30–P33 steps × ``kv_per_step`` (spec §5.2)."""
        return self._params.gain(axis) * self._kv_per_step

    def check_encoder(self, axis: str, speed: float) -> None:
        """Spec §5.7: the encoder signal is f = v / (4 · resolution); above the adapter's limit
        the event ``encoder_overspeed`` (speed in increments per second)."""
        if abs(speed) / 4 > self._encoder_hz:
            self._screen.record("encoder_overspeed")
            self._screen.report("axis", "encoder_overspeed", axis)
