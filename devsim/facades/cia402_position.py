"""The set-points of CiA 402's profile position mode (CiA 402-2, profile position mode: the
controlword's bits 4 "new set-point", 5 "change set immediately", 6 "abs/rel", 8 "halt", the
statusword's bits 10 "target reached" and 12 "set-point acknowledge", and the figure "set-point
transmission from a host computer").

A rising bit 4 in Operation enabled, not halted, validates a set-point: the target position
(607Ah; with bit 6, relative to the position actual value when the positioning starts) at the
profile velocity (6081h).  With bit 5 = 1 ("interrupt the actual positioning and start the next
positioning") or with no positioning in process it starts at once; with bit 5 = 0 ("finish the
actual positioning and then start the next positioning") while one is in process it waits in a
buffer of one and starts when the axis has finished the one before (looked at every
:data:`SAMPLE` of device time while it waits); a set-point validated while the buffer is full is
not taken.  Bit 12 rises when a set-point is taken and falls when bit 4 has fallen and the buffer
is empty ("0: previous set-point already processed, waiting for new set-point; 1: previous
set-point still in process, set-point overwriting shall be accepted").  Leaving Operation enabled
or the mode ends the set-points in process: the buffer is emptied and bit 12 is 0, in whatever
state the drive is in then.

Bit 10 with halt = 0 is "target position reached": the axis stands, no set-point waits, and the
last positioning ran to its end (a halt that stopped it short of its target leaves bit 10 at 0 once
the halt is released: the positioning is not resumed); with halt = 1 it is "velocity of axis is 0".  Halt
stops a running positioning with the ramp (the drive's jog at 0) and drops a waiting set-point.
With the position window (6067h) switched on, the positioning's end is not enough: the position
actual value must also have stayed within the window of its target for the position window time
(6068h; :mod:`devsim.facades.cia402_position_watch`), a halt that stopped it short then counting
as reached if the axis stands within the window.

The positioning option code (60F2h, CiA 402-2) says what bit 6 is relative to, in its bits 0 and 1
(the relative option): 00b the target of the positioning before (0 if there was none since the
mode began), 01b the position demand value (the position actual value plus the following error,
60F4h), 10b the position actual value (6064h).  The other bits must be 0: change immediately
option 00b (the next positioning after the one before has ended, as bit 5 = 0 above), request-
response option 00b (the handshake above), rotary axis direction option 00b (a linear axis), no
ip option, nothing reserved or manufacturer-specific; another value, and the reserved relative
option 11b, is refused (``ValueError``: the node aborts 0609 0030h, value range exceeded), since
the drives cannot blend positionings or wrap a range.  [SIM-CHOICE] The power-on value is 0002h,
relative to the position actual value, as the node moved before it had the object.
"""

from __future__ import annotations

from typing import Any

from devsim.core.changes import CHANGES

__all__ = ["ACKNOWLEDGE", "OPTIONS", "SAMPLE", "SetPoints", "TARGET_REACHED"]

SAMPLE = 0.001  # s of device time between looks while a set-point waits for the one before to end
TARGET_REACHED, ACKNOWLEDGE = 0x0400, 0x1000
NEW_SET_POINT, CHANGE_IMMEDIATELY, RELATIVE, HALT = 0x0010, 0x0020, 0x0040, 0x0100
#: The positioning option codes (60F2h) the node honours: the relative options 00b, 01b, 10b
#: (bits 0 and 1), every other bit 0.
OPTIONS = frozenset((0x0000, 0x0001, 0x0002))
PRECEDING_TARGET, DEMAND, ACTUAL = 0, 1, 2  # the relative option (60F2h bits 0 and 1)


class SetPoints:
    """Profile position mode's set-points over ``actions`` on ``model``; a waiting set-point is
    looked after on ``clock``."""

    _waiting: tuple[float, bool, float] | None  # a set-point validated with bit 5 = 0: (607Ah, relative, 6081h)

    def __init__(self, actions: Any, model: Any, clock: Any, option: int) -> None:
        self.actions, self.model, self.clock = actions, model, clock
        self.option = option  # 60F2h
        self._timer: Any = None
        self.reset()

    def reset(self) -> None:
        """Nothing in process, nothing waiting, bit 12 = 0, bit 10 the axis standing."""
        self.drop()
        self.goal: float | None = None  # the absolute target of the last positioning started (none yet)
        self._short = False  # a halt stopped it (short of its goal, unless the axis stands there)

    def drop(self) -> None:
        """The set-points in process end (Operation enabled left, another mode): bit 12 = 0."""
        self.cancel()
        self.ack = False
        self._waiting = None
        self._held = False  # bit 4 as the last controlword in Operation enabled had it

    def cancel(self) -> None:
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None

    def control(self, before: int, word: int, target: int, speed: int) -> None:
        """A controlword in Operation enabled, profile position mode (``before``: the one it
        replaces; ``target``, ``speed``: 607Ah, 6081h as of now)."""
        self._held = bool(word & NEW_SET_POINT)
        a = self.actions
        if word & HALT:  # the axis is stopped with the ramp; a new set-point waits for the release
            if not before & HALT:
                self._waiting = None
                self.cancel()
                if a.moving(self.model):
                    a.jog(self.model, 0.0)
                    self._short = True
        elif word & NEW_SET_POINT and not before & NEW_SET_POINT:
            self._validate((float(target), bool(word & RELATIVE), float(speed)), bool(word & CHANGE_IMMEDIATELY))
        if not self._held:
            self.ack = self._waiting is not None

    def _validate(self, set_point: tuple[float, bool, float], immediately: bool) -> None:
        if immediately or not self.actions.moving(self.model):
            self._waiting = None
            self.cancel()
            self._start(set_point)
        elif self._waiting is None:
            self._waiting = set_point
            self._timer = self.clock.call_later(SAMPLE, self._tick)
        else:
            return  # the buffer is full: not taken
        self.ack = True

    def _start(self, set_point: tuple[float, bool, float]) -> None:
        target, relative, speed = set_point
        if relative:
            target += self._origin()
        self.actions.move_to(self.model, target, speed)
        self.goal, self._short = target, False

    def _origin(self) -> float:
        """Where a relative target counts from: the relative option of 60F2h."""
        a, relative_option = self.actions, self.option & 0x0003
        if relative_option == PRECEDING_TARGET:
            return self.goal or 0.0
        if relative_option == DEMAND:
            return a.position(self.model) + a.following_error(self.model)
        return a.position(self.model)

    def write_option(self, value: int) -> None:
        """60F2h: a code the node honours (:data:`OPTIONS`), else ``ValueError``."""
        if value not in OPTIONS:
            raise ValueError(f"positioning option code {value:04X}h is not supported")
        self.option = value

    def _tick(self) -> None:
        self._timer = None
        self.look()

    def look(self) -> None:
        """The waiting set-point starts once the axis has finished the positioning before it."""
        if self._waiting is None:
            return
        a = self.actions
        if a.fault(self.model) or not a.enabled(self.model):
            self.drop()
            return
        if a.moving(self.model):
            if self._timer is None:
                self._timer = self.clock.call_later(SAMPLE, self._tick)
            return
        CHANGES.count += 1  # (the drive actions change the model: a door, devsim.core.changes)
        set_point, self._waiting = self._waiting, None
        self.cancel()
        self._start(set_point)
        self.ack = self._held

    def bits(self, halted: bool, in_window: bool | None = None) -> int:
        """Bits 10 and 12 of the statusword as of now (``halted``: controlword bit 8; ``in_window``:
        the position window's verdict, ``None`` with the window switched off)."""
        self.look()
        word = ACKNOWLEDGE if self.ack else 0
        a = self.actions
        if a.moving(self.model):
            return word
        if halted:
            return word | TARGET_REACHED
        if self._waiting is not None:
            return word
        if self.goal is None:  # standing, no set-point given yet
            return word | TARGET_REACHED
        if in_window is None:
            in_window = not self._short or round(a.position(self.model)) == round(self.goal)
        return word | TARGET_REACHED if in_window else word
