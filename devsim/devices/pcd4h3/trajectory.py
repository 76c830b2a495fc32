"""The LM628's profile generator, one sample at a time (spec pcd4h3.md §3.5.4, §5.2; LM628
datasheet): the desired position and velocity the PID filter follows.

Fixed point as in the chip: velocity and acceleration are 16.16 counts per sample (per sample²),
the desired position carries 16 fractional bits.  Position mode runs a trapezoid to the target
(a triangle when the distance is short), starting to brake when the remaining distance is within
v²/2a plus half a step, and ends exactly on the target; velocity mode ramps to the velocity in the
direction given and holds it; a smooth stop brakes with the acceleration, an abrupt stop holds the
current position.  New parameters take effect at :meth:`Profile.start` (STT).  Pure: no clock.
"""

from __future__ import annotations

import msgspec

__all__ = ["Profile", "Trajectory"]

ONE = 1 << 16


class Trajectory(msgspec.Struct, frozen=True):
    """The LTRJ buffers (§3.5.4): what the next STT takes over."""

    acceleration: int = 0  # 16.16 counts/sample²
    velocity: int = 0  # 16.16 counts/sample
    position: int = 0  # counts
    velocity_mode: bool = False
    forward: bool = False  # RESET clears the trajectory control word


class Profile:
    """The generator's working state."""

    def __init__(self) -> None:
        self.position = 0  # desired position, counts << 16
        self.velocity = 0  # signed, 16.16
        self.acceleration = 0
        self.top = 0  # the velocity to reach (unsigned 16.16)
        self.target = 0  # counts << 16
        self.velocity_mode = False
        self.forward = False  # as after RESET (signals bit 12 reads 0)
        self.stopping = False
        self.complete = True  # "trajectory complete" (status bit 2)

    @property
    def desired(self) -> int:
        """The desired position in whole counts (RDDP)."""
        return self.position >> 16

    def start(self, trajectory: Trajectory, frame: int = 0) -> None:
        """STT: take over the buffers; ``frame`` (counts) places the target among the desired
        position's counts when these have wrapped around (the chip's registers are the wrapped ones)."""
        self.acceleration, self.top = trajectory.acceleration, trajectory.velocity
        self.velocity_mode, self.forward = trajectory.velocity_mode, trajectory.forward
        self.target = (trajectory.position + frame) << 16
        self.stopping = False
        self.complete = not self.velocity_mode and self.target == self.position and self.velocity == 0

    def stop_smoothly(self) -> None:
        self.stopping, self.complete = True, self.velocity == 0

    def stop_abruptly(self, at: int | None = None) -> None:
        """Stop at once: the desired position becomes ``at`` (counts; the actual position, manual
        §7.4 FStop bit 9: "die Sollposition gleich der Istposition") or stays where it is."""
        if at is not None:
            self.position = at << 16
        self.velocity, self.target, self.stopping, self.complete = 0, self.position, False, True

    def shift(self, counts: int) -> None:
        """The coordinates move by ``counts`` (DFH, a set actual position): desired position and
        target move with them."""
        self.target += counts << 16
        self.position += counts << 16

    def hold(self, position: int) -> None:
        """While the motor is off the desired position follows the axis (G-21)."""
        self.position = self.target = position << 16
        self.velocity, self.stopping, self.complete = 0, False, True

    def sample(self) -> None:
        """One sample period of the generator."""
        if self.complete:
            return
        a, v = self.acceleration, self.velocity
        if self.stopping:
            self._toward(0)
            if self.velocity == 0:
                self.stopping, self.complete = False, True
                self.target = self.position
            self.position += self.velocity
            return
        if self.velocity_mode:
            self._toward(self.top if self.forward else -self.top)
            self.position += self.velocity
            return
        remaining = self.target - self.position
        if remaining == 0 and v == 0:
            self.complete = True
            return
        direction = 1 if remaining > 0 else -1
        if v * direction < 0:  # moving away from the target: brake first, then turn
            self._toward(0)
        else:
            speed = abs(v)
            braking = speed * speed // (2 * a) + speed // 2 if a else 0
            if abs(remaining) <= braking:
                self._toward(0, floor=min(a, abs(remaining)) * direction if a else 0)
            else:
                self._toward(self.top * direction)
        step = self.velocity
        if step and (self.target - (self.position + step)) * direction <= 0 and v * direction >= 0:
            self.position, self.velocity, self.complete = self.target, 0, True  # arrives exactly
            return
        if step == 0 and abs(remaining) < ONE:
            self.position, self.complete = self.target, True
            return
        self.position += step

    def _toward(self, goal: int, floor: int = 0) -> None:
        """Change the velocity by at most the acceleration towards ``goal``; when braking to 0
        in position mode, keep at least ``floor`` (so the last sub-count steps still arrive)."""
        a, v = self.acceleration, self.velocity
        if v < goal:
            v = min(goal, v + a)
        elif v > goal:
            v = max(goal, v - a)
        if goal == 0 and floor and abs(v) < abs(floor):
            v = floor
        self.velocity = v
