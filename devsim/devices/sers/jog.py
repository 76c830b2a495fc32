"""Jogging of the SERS: RS, RF, LS, LF with the serial timeout and the ``:`` condition (manual
§4.5.1, §4.6.9, §4.8.6.4; spec §3.5.8, §5.3, G-JOGPROG).

Right is positive; slow P1019, fast P1020, both × the override P108, ramp P1018.  From the
serial line a jog stops 500 ms after the last jog command (P1035 = 1); with ``:condition`` it
runs until the condition holds, then brakes with P1018 or first travels the overrun P1039.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Protocol

from devsim.core.axis import Axis
from devsim.core.clock import Clock, Timer
from devsim.devices.sers import statements as st
from devsim.devices.sers.errors import SersError
from devsim.devices.sers.homing import can_move
from devsim.devices.sers.params import SersParameters
from devsim.devices.sers.power import PowerStage

__all__ = ["Jog", "JogMotion"]


class JogMotion(Protocol):
    """What a jog (§4.5.1) needs of the motion (:class:`~.motion.Motion`)."""

    @property
    def kind(self) -> str | None: ...

    def checks(self, direction: int) -> None: ...

    def begin(self, kind: str, decel: float) -> None: ...

    def arm_watches(self, keep: bool = False) -> None: ...

    def stop_motion(self) -> None: ...

    def overrun(self, target: float, speed: float, accel: float) -> None:
        """Travel on to ``target`` and end the motion there."""


class Jog:
    """The jog of one SERS (§4.5.1)."""

    def __init__(
        self,
        clock: Clock,
        axis: Axis,
        params: SersParameters,
        power: PowerStage,
        motion: JogMotion,
        *,
        evaluate: Callable[[st.Condition], bool],
    ) -> None:
        self.clock = clock
        self.axis = axis
        self.params = params
        self.power = power
        self.motion = motion
        self._evaluate = evaluate  # a ':' condition, as a program's IF sees it
        self._direction = 0
        self._speed = 0.0  # (of the jog under way)
        self._accel = 0.0
        self._until: st.Condition | None = None
        self._timer: Timer | None = None

    def reset(self) -> None:
        """The motion ended (or the drive powers on): no jog under way."""
        self._direction = 0
        self._until = None
        self.cancel_timer()

    def power_on(self) -> None:
        self.reset()
        self._speed = self._accel = 0.0

    def start(self, name: str, until: st.Condition | None = None, serial: bool = True) -> None:
        """RS/RF/LS/LF (§4.5.1): right = positive; slow P1019, fast P1020, × P108 %."""
        direction = 1 if name[0] == "R" else -1
        motion, params = self.motion, self.params
        motion.checks(direction)
        if motion.kind not in (None, "jog", "position", "stopping"):
            raise SersError(70)
        jog_speed = params.jog_velocity_slow if name[1] == "S" else params.jog_velocity_fast
        speed = float(jog_speed) * float(params.feedrate_override) / 100
        accel = float(params.jog_acceleration)
        can_move(speed, accel)
        if until is not None:  # (an operand that does not exist, I0, O17, P99999, is the statement's
            self._evaluate(until)  # error before a jog starts or stays armed to raise at an input change)
        if not (motion.kind == "jog" and self._direction == direction and self._speed == speed):
            self.power.servo_check()
            motion.begin("jog", accel)
            self._direction = direction
            self._speed = speed
            self._accel = accel
            self.axis.jog(direction, speed, accel)
            motion.arm_watches()
        self._until = until
        self.cancel_timer()
        if serial and until is None and params.jog_timeout == 1:
            self._timer = self.clock.call_later(0.5, self._timeout)
        if until is not None and self._evaluate(until):  # (as the jog, begun, sees it)
            self._until_reached()

    def write_p1031(self, value: float, home: Callable[[], None]) -> None:
        """P1031 (§4.8.6.3): 1 LS, 2 RS, 4 LF, 8 RF, 16 H."""
        commands = {1: "LS", 2: "RS", 4: "LF", 8: "RF"}
        if value == 16:
            home()
        elif value in commands:
            self.start(commands[int(value)])
        else:
            raise SersError(3)

    def _timeout(self) -> None:
        self._timer = None
        if self.motion.kind == "jog":
            self.motion.stop_motion()

    def cancel_timer(self) -> None:
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None

    def _until_reached(self) -> None:
        """':' event (§4.6.9): brake with P1018, or travel the overrun distance P1039 first."""
        self._until = None
        overrun = float(self.params.overrun)
        if overrun:
            target = self.axis.position() + self._direction * abs(overrun)
            speed = abs(self.axis.velocity()) or self._speed  # (the event came as the jog began)
            self.motion.overrun(target, speed, self._accel)
        else:
            self.motion.stop_motion()

    def check_until(self) -> None:
        """The drive's state changed: a ':' condition may hold now."""
        if self._until is not None and self.motion.kind == "jog" and self._evaluate(self._until):
            self._until_reached()
