"""The set-points of CiA 402's profile position mode (CiA 402-2, profile position mode: the
controlword's bits 4 "new set-point", 6 "abs/rel", 8 "halt", the statusword's bits 10 "target
reached" and 12 "set-point acknowledge", and the figure "set-point transmission from a host
computer").

A rising bit 4 in Operation enabled, not halted, validates a set-point: the target position
(607Ah; with bit 6, relative to the position actual value) at the profile velocity (6081h); it
starts at once.  Bit 12 rises when a set-point is taken and falls when bit 4 has fallen ("0:
previous set-point already processed, waiting for new set-point; 1: previous set-point still in
process, set-point overwriting shall be accepted").  Leaving Operation enabled or the mode ends
the set-points in process: bit 12 is 0, in whatever state the drive is in then.

Bit 10 is 1 while the axis stands.  Halt stops a running positioning with the ramp (the drive's
jog at 0).
"""

from __future__ import annotations

from typing import Any

__all__ = ["ACKNOWLEDGE", "SetPoints", "TARGET_REACHED"]

TARGET_REACHED, ACKNOWLEDGE = 0x0400, 0x1000
NEW_SET_POINT, RELATIVE, HALT = 0x0010, 0x0040, 0x0100


class SetPoints:
    """Profile position mode's set-points over ``actions`` on ``model`` (``clock``: the device's)."""

    def __init__(self, actions: Any, model: Any, clock: Any) -> None:
        self.actions, self.model, self.clock = actions, model, clock
        self.reset()

    def reset(self) -> None:
        """Nothing in process, bit 12 = 0."""
        self.drop()

    def drop(self) -> None:
        """The set-points in process end (Operation enabled left, another mode): bit 12 = 0."""
        self.ack = False

    def cancel(self) -> None:
        """(Nothing is looked after on the clock.)"""

    def control(self, before: int, word: int, target: int, speed: int) -> None:
        """A controlword in Operation enabled, profile position mode (``before``: the one it
        replaces; ``target``, ``speed``: 607Ah, 6081h as of now)."""
        a = self.actions
        if word & HALT:  # the axis is stopped with the ramp; a new set-point waits for the release
            if not before & HALT and a.moving(self.model):
                a.jog(self.model, 0.0)
        elif word & NEW_SET_POINT and not before & NEW_SET_POINT:
            self._start((float(target), bool(word & RELATIVE), float(speed)))
            self.ack = True
        if not word & NEW_SET_POINT:
            self.ack = False

    def _start(self, set_point: tuple[float, bool, float]) -> None:
        target, relative, speed = set_point
        if relative:
            target += self.actions.position(self.model)
        self.actions.move_to(self.model, target, speed)

    def bits(self, halted: bool) -> int:
        """Bits 10 and 12 of the statusword as of now (``halted``: controlword bit 8)."""
        word = ACKNOWLEDGE if self.ack else 0
        if not self.actions.moving(self.model):
            word |= TARGET_REACHED
        return word
