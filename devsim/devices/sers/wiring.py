"""The motor as the machine sees it: its direction of rotation (P1134, manual §4.8.2.3) and the
switches that sit along the axis (§2.1.2; the configuration's ``axis`` geometry).

The drive commands its motor in its own coordinate, the :class:`~devsim.core.axis.Axis` every
part of the motion works in: RS/RF, a positive W, P51 and the homing direction of P147 count
in it.  P1134=1 "has the same effect as swapping the leads within one motor phase (the motor
then physically turns the other way)": the drive's coordinate is unchanged, the rotor turns the
other way.  The machine side -- the limit switches and the reference cam at their positions,
the encoder's zero pulse, the points ``axis.position`` / ``axis.velocity`` /
``encoder.position`` -- sees the physical rotor::

    physical = origin + sign · (drive - anchor)

(``sign`` −1 with P1134=1; ``anchor``/``origin`` the positions where the sense last changed,
so the rotor does not jump).  The switches' inputs keep their meaning for the drive: the right
limit input stops positive (RS) travel whichever way the rotor turns, as on a real drive whose
motor leads are swapped and whose switches are not.  The encoder sits on the motor shaft; the
drive counts it with the same sense as its motor (the step monitoring is not fooled).
"""

from __future__ import annotations

import math

from devsim.core.axis import Axis, RegionSwitch
from devsim.core.signals import SignalBank
from devsim.devices.sers.config import AxisGeometry
from devsim.devices.sers.constants import INC_PER_REV

__all__ = ["MotorWiring"]


class MotorWiring:
    """The sense of rotation (P1134, §4.8.2.3) and the switches along the axis (§2.1.2)."""

    def __init__(self, axis: Axis, signals: SignalBank, geometry: AxisGeometry) -> None:
        self.axis = axis
        self.signals = signals
        self.geometry = geometry
        self.sign = 1  # +1 standard, −1 with P1134=1
        self._anchor = 0.0  # drive position where the sense last changed
        self._origin = 0.0  # physical position there
        self._switches: list[RegionSwitch] = []
        self._build_switches()

    # -- the two coordinates ----------------------------------------------------------------------
    def physical(self, drive: float) -> float:
        """The physical rotor position (increments from power-on) of drive position ``drive``."""
        return self._origin + self.sign * (drive - self._anchor)

    def to_drive(self, physical: float) -> float:
        """The drive position at which the rotor stands at ``physical``."""
        return self._anchor + self.sign * (physical - self._origin)

    def position(self) -> float:
        """Where the rotor physically is (the point ``axis.position``)."""
        return self.physical(self.axis.position())

    def velocity(self) -> float:
        return self.sign * self.axis.velocity()

    def acceleration(self) -> float:
        return self.sign * self.axis.acceleration()

    # -- P1134 --------------------------------------------------------------------------------------
    def set_inverted(self, inverted: bool) -> None:
        """P1134 (§4.8.2.3) takes effect: from here on the rotor turns the other way for the same
        commands (it does not move now; the switches stay where they are)."""
        sign = -1 if inverted else 1
        if sign == self.sign:
            return
        here = self.axis.position()
        self._origin = self.physical(here)
        self._anchor = here
        self.sign = sign
        self._build_switches()

    # -- the switches along the axis ------------------------------------------------------------------
    def _region(self, low: float, high: float) -> tuple[float, float]:
        ends = sorted((self.to_drive(low), self.to_drive(high)))
        return ends[0], ends[1]

    def _build_switches(self) -> None:
        """The switches of the configured geometry as regions of the drive's coordinate; the
        encoder's zero pulse (physically at ``index_offset`` in every revolution) likewise."""
        self.close()
        geo = self.geometry
        if geo.limit_left is not None:
            self._switch(-math.inf, geo.limit_left, "limit_left")
        if geo.limit_right is not None:
            self._switch(geo.limit_right, math.inf, "limit_right")
        if geo.reference_low is not None:
            high = geo.reference_high if geo.reference_high is not None else math.inf
            self._switch(geo.reference_low, high, "reference")
        self.axis.index_offset = self.to_drive(geo.index_offset) % INC_PER_REV

    def _switch(self, low: float, high: float, signal: str) -> None:
        lo, hi = self._region(low, high)
        region = RegionSwitch(self.axis, lo, hi, lambda active: self.signals.set(signal, active))
        self._switches.append(region)
        self.signals.signal(signal).value = region.active

    def close(self) -> None:
        for switch in self._switches:
            switch.cancel()
        self._switches.clear()
