"""CiA 402's homing mode (6060h = 6) over a kind's own reference run (CiA 402-2 / IEC 61800-7-201,
homing mode: the objects 607Ch home offset, 6098h homing method, 6099h homing speeds, 609Ah homing
acceleration; the controlword's bit 4 "homing operation start" and bit 8 halt; the statusword's
bits 10 "target reached", 12 "homing attained" and 13 "homing error").

The drive does not invent a homing: a kind declares the reference run its device has
(:class:`devsim.core.kit.Homing`), one row per homing method number that run performs (for
instance 21: the negative home switch, the home position where the switch goes inactive moving
in the positive direction; 33/34: the index pulse in the negative/positive direction).  6098h
takes those and 0 (its power-on value, no method: a start with it is a homing error); any other
value is refused (``ValueError``, the node aborts 0609 0030h).  The speeds (6099h sub 1 "during
search for switch", sub 2 "during search for zero") and the acceleration (609Ah) go to the
run's own parameters where the device has them; 0, their power-on value, leaves the device's own.

Bit 4 (CiA 402-2: "0 → 1 start homing mode, 1 homing mode active, 1 → 0 interrupt homing mode"):
a rising bit 4 in Operation enabled with halt = 0 starts the run, a falling one interrupts it, as
halt (bit 8 = 1) does: the axis is stopped with the ramp (the drive's jog at 0); a rising bit 4
while halted starts nothing.  Leaving Operation enabled or the mode interrupts it too.

Home offset (607Ch): "the difference between the zero position for the application and the machine
home position (found during homing) … once the homing is completed, the zero position is offset
from the home position by adding the home offset to the home position.  All subsequent absolute
moves shall be taken relative to this new zero position" (CiA DSP 402, object 607Ch; quoted in
the Elmo "CANopen DSP 402 Implementation Guide" §9.2): when a run is attained, the position the
402 objects show (6064h, 607Ah) is shifted so that the home position is −607Ch; the device's
own position is not changed.

The statusword's bits 13, 12, 10 (CiA 402-2, homing mode, "definition of bit 10, bit 12 and
bit 13"): 0 0 0 homing procedure in progress; 0 0 1 interrupted or not started; 0 1 0 homing
attained, target not reached; 0 1 1 homing procedure completed successfully; 1 0 0 homing error,
velocity not 0; 1 0 1 homing error, velocity 0.  A device error (the drive's fault) during the
run is a homing error; a halt or a falling bit 4 is "interrupted" once the axis stands.
"""

from __future__ import annotations

from typing import Any

from devsim.core.points import BadValue

__all__ = ["HOMING_ATTAINED", "HOMING_ERROR", "HomingMode", "START", "TARGET_REACHED"]

TARGET_REACHED, HOMING_ATTAINED, HOMING_ERROR = 0x0400, 0x1000, 0x2000
START, HALT = 0x0010, 0x0100


class HomingMode:
    """607Ch, 6098h, 6099h, 609Ah and the run's phase over ``actions`` (the drive's own, not
    shifted) on ``model``; ``phase`` is ``idle`` (not started), ``running``, ``interrupted``,
    ``attained`` or ``error``."""

    def __init__(self, actions: Any, model: Any, defaults: dict[str, int]) -> None:
        self.actions, self.model, self._defaults = actions, model, defaults
        self.homing = actions.homing
        self.shift = 0.0  # what the 402 objects add to the drive's position (607Ch at the last home)
        self.reset()

    def reset(self) -> None:
        """The power-on values: no method, the device's own speeds and ramp, no offset, nothing
        started, the drive's position unshifted."""
        d = self._defaults
        self.offset = d["home_offset"]  # 607Ch
        self.method = d["homing_method"]  # 6098h
        self.speeds = [d["homing_speed_switch"], d["homing_speed_zero"]]  # 6099h sub 1, sub 2
        self.acceleration = d["homing_acceleration"]  # 609Ah
        self.phase = "idle"
        self.shift = 0.0

    def methods(self) -> list[int]:
        """The homing methods the kind's reference run performs."""
        return sorted(int(row.token) for row in self.homing.methods) if self.homing is not None else []

    def write_method(self, value: int) -> None:
        """6098h: 0 or a method of the kind's reference run, else ``ValueError``."""
        if value != 0 and value not in self.methods():
            raise ValueError(f"homing method {value} is not one this drive's reference run performs")
        self.method = value

    def write_speed(self, sub: int, value: int) -> None:
        if value < 0:
            raise ValueError("a homing speed is not negative")
        self.speeds[sub - 1] = value

    def write_acceleration(self, value: int) -> None:
        if value < 0:
            raise ValueError("the homing acceleration is not negative")
        self.acceleration = value

    # -- the run ------------------------------------------------------------------------------------
    def control(self, before: int, word: int) -> None:
        """A controlword in Operation enabled, homing mode."""
        self.look()
        if word & HALT:
            if not before & HALT:
                self.interrupt()
        elif word & START and not before & START:
            self._start()
        elif before & START and not word & START:
            self.interrupt()

    def _start(self) -> None:
        if self.phase == "running":
            return
        start = self.homing.methods.get(str(self.method)) if self.homing is not None else None
        if start is None:
            self.phase = "error"
            return
        try:
            start(self.model, float(self.speeds[0]), float(self.speeds[1]), float(self.acceleration))
        except BadValue:
            self.phase = "error"
            return
        self.phase = "running"
        self.look()

    def interrupt(self, stop: bool = True) -> None:
        """Halt, a falling bit 4, Operation enabled or the mode left: a run under way is stopped
        with the ramp (``stop``; leaving Operation enabled, the state's own command stops it)."""
        self.look()
        if self.phase == "running":
            self.phase = "interrupted"
            if stop and self.actions.moving(self.model):
                self.actions.jog(self.model, 0.0)

    def look(self) -> None:
        """A run under way ends when the device's does: attained (the 402 position shifted to
        −607Ch here) or a homing error; a fault of the drive is a homing error at once."""
        if self.phase != "running" or self.homing is None:
            return
        if self.actions.fault(self.model):
            self.phase = "error"
            return
        state = self.homing.state(self.model)
        if state == "running":
            return
        if state == "attained":
            self.phase = "attained"
            self.shift = -self.offset - self.actions.position(self.model)
        else:
            self.phase = "error"

    def bits(self) -> int:
        """Bits 10, 12 and 13 of the statusword as of now."""
        self.look()
        standing = not self.actions.moving(self.model)
        if self.phase == "running":
            return 0
        word = HOMING_ATTAINED if self.phase == "attained" else HOMING_ERROR if self.phase == "error" else 0
        return word | (TARGET_REACHED if standing else 0)
