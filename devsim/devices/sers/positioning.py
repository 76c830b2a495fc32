"""Positioning of the SERS: ``E`` with the modes of P1014, backlash compensation, the ramp
shapes, W changed on the move, the continuation after a stop and the SERVO mode's overload
(manual §4.6.6, §4.8.4.1, §4.8.4.2, §4.8.4.4, §4.8.4.7, §4.8.6.7; spec §3.5.3, §3.5.4, §5.1,
§5.2, §5.8, §5.10, §5.12, G-EWHILEMOVE, G-BACKLASH).
"""

from __future__ import annotations

from typing import Protocol

from devsim.core.axis import Axis, RampProfile
from devsim.core.signals import SignalBank
from devsim.devices.sers.constants import INC_PER_REV
from devsim.devices.sers.errors import SersError
from devsim.devices.sers.homing import can_move
from devsim.devices.sers.params import SersParameters
from devsim.devices.sers.power import PowerStage

__all__ = ["Positioning", "PositioningMotion"]


class PositioningMotion(Protocol):
    """What a positioning (§4.6.6) needs of the motion (:class:`~.motion.Motion`)."""

    offset: float  # the axis position of P51 = 0

    @property
    def kind(self) -> str | None: ...

    def checks(self, direction: int) -> None: ...

    def begin(self, kind: str, decel: float) -> None: ...

    def arm_watches(self, keep: bool = False) -> None: ...

    def arrived(self) -> None:
        """The target is reached: the motion ends (and ``@nPOS=1`` with P1121)."""


class Positioning:
    """``E`` and what goes with it, for one SERS (§4.6.6)."""

    def __init__(
        self, axis: Axis, params: SersParameters, signals: SignalBank, power: PowerStage, motion: PositioningMotion
    ) -> None:
        self.axis = axis
        self.params = params
        self.signals = signals
        self.power = power
        self.motion = motion
        self.w_updated = False  # W was changed on the move: the next E is already done
        #: The target of the last E (POSR goes there, P1033=1 continues to it).
        self.setpoint: float | None = None
        self._interrupted = False  # a stop interrupted the last E: with P1033=1 the next E continues it
        self._legs: list[tuple[float, float]] = []  # (target, speed) still to go, backlash
        self._target = 0.0  # physical target of the positioning under way
        self._speed = 0.0
        self._accel = 0.0
        self.overloaded = False  # SERVO: the load holds the rotor (§4.8.6.7)
        self._servo_resume = False
        self._ramp: tuple[tuple[object, ...], RampProfile | None] | None = None  # (P1032, P1005–P1008), profile

    def power_on(self) -> None:
        self.w_updated = False
        self._legs = []
        self.setpoint = None
        self._interrupted = False
        self.overloaded = False
        self._servo_resume = False

    def start(self) -> None:
        """E (§4.6.6) with P1014 mode 0 relative, 1 relative-clear, 2 absolute, 3 overflow."""
        motion = self.motion
        if motion.kind == "position" and self.w_updated:
            self.w_updated = False
            return  # G-EWHILEMOVE: the running move already took the new W
        if motion.kind is not None:
            raise SersError(70)
        params = self.params
        if self._interrupted and int(params.continuation_after_stop) == 1:
            self._interrupted = False
            self.resume()  # (standing at the setpoint already: nothing moves)
            return
        self._interrupted = False
        mode = int(params.positioning_mode)
        w = float(params.position_setpoint)
        p51 = self.axis.position() - motion.offset
        if mode == 1:
            start, target = 0.0, float(round(w))
        elif mode == 2:
            start, target = p51, float(round(w))
        else:
            start, target = p51, p51 + round(w)  # W in whole increments (§5.1)
        target = self._leave_zero_phase(target)
        direction = (target > start) - (target < start)
        motion.checks(direction)
        scaling = params.scaling
        lo, hi = scaling.pos_range()
        target_user = scaling.inc_to_pos(target)
        if target_user > hi or target_user < lo:
            self.power.warn(64)
            raise SersError(85 if target_user > hi else 86)
        if mode == 1:
            motion.offset = self.axis.position()
        elif target == p51:
            return  # already there: nothing moves, POS stays 1
        self._speed = float(params.velocity)
        self._accel = float(params.acceleration)
        self._target = target + motion.offset
        legs = self._backlash_legs(p51 + motion.offset, self._target)
        for _target, speed in legs:
            can_move(speed, self._accel)  # (the backlash legs creep at P1003)
        self.power.servo_check()
        motion.begin("position", self._accel)
        self.setpoint = self._target
        self._legs = legs
        self._next_leg()
        motion.arm_watches()

    def stopped(self, positioning: bool) -> None:
        """A stop command or signal (S, the STOP input, I7) came, while an ``E`` ran
        (``positioning``) or not (§4.8.6.2): "nach einem einmaligem Stop-Befehl ... und einem
        erneutem Start-Befehl" P1033=1 continues the interrupted positioning, "Nach zweimaligem
        Stop → Verfahren wie bei P1033=0" -- a second stop ends that."""
        self._interrupted = positioning

    def resume(self) -> bool:
        """P1033=1: a program stopped during ``E`` continues the interrupted move; False if it
        stands at the setpoint already (or there is none)."""
        setpoint = self.setpoint
        if setpoint is None:
            return True
        here = self.axis.position()
        direction = (setpoint > here) - (setpoint < here)
        self.motion.checks(direction)
        if direction == 0:
            return False
        self._speed = float(self.params.velocity)
        self._accel = float(self.params.acceleration)
        self._target = setpoint
        self.motion.begin("position", self._accel)
        self._legs = [(setpoint, self._speed)]
        self._next_leg()
        self.motion.arm_watches()
        return True

    def _backlash_legs(self, start: float, target: float) -> list[tuple[float, float]]:
        """Backlash compensation P1037 (§4.8.4.7, spec §5.8 G-BACKLASH): the final approach
        is always made opposite to the homing direction (P147 bit 0), at speed P1003."""
        params = self.params
        slack = abs(float(params.backlash))
        if not slack or target == start:
            return [(target, self._speed)]
        approach = 1 if int(params.homing_parameters) & 1 else -1
        creep = float(params.homing_velocity_slow)
        direction = 1 if target > start else -1
        if direction == approach:
            if abs(target - start) <= slack:
                return [(target, creep)]
            return [(target - direction * slack, self._speed), (target, creep)]
        return [(start + direction * slack, creep), (target + direction * slack, self._speed), (target, creep)]

    def _next_leg(self) -> None:
        target, speed = self._legs.pop(0)
        done = self._next_leg if self._legs else self._positioning_done
        self.axis.move_to(target, speed, self._accel, on_done=done, profile=self.ramp_profile())

    def ramp_profile(self) -> RampProfile | None:
        """P1032 ramp shape with the sections P1005–P1008 (§4.8.4.4, spec §5.2); made again
        only when one of them changed (every E asks)."""
        settings = self.params.ramp_settings()
        made = self._ramp
        if made is not None and made[0] == settings:
            return made[1]
        profile = self._make_ramp_profile()
        self._ramp = (settings, profile)
        return profile

    def _make_ramp_profile(self) -> RampProfile | None:
        p = self.params
        shape = "sine" if int(p.ramp_shape) == 1 else "linear"
        fractions = [float(v) / 100 for v in (p.ramp_velocity1, p.ramp_acceleration1, p.ramp_velocity2,
                                              p.ramp_acceleration2)]
        if shape == "linear" and all(f == 1.0 for f in fractions):
            return None
        speed1, accel1, speed2, accel2 = fractions
        return RampProfile(speed1=speed1, accel1=accel1, speed2=speed2, accel2=accel2, shape=shape)

    def _leave_zero_phase(self, target: float) -> float:
        """P1001 (§4.8.4.2): keep 0.1°/0.2°/0.3° away from multiples of 1.8° (64 increments)."""
        level = int(self.params.leave_zero_phase)
        if not level:
            return target
        step = INC_PER_REV / 200
        keep = level * 0.1 * INC_PER_REV / 360
        nearest = round(target / step) * step
        if abs(target - nearest) < keep - 1e-9:
            return float(round(nearest + (keep if target >= nearest else -keep)))
        return target

    def _positioning_done(self) -> None:
        params, motion = self.params, self.motion
        if int(params.positioning_mode) == 3:
            modulo = float(params.modulo)
            if modulo > 0:
                while self.axis.position() - motion.offset >= modulo - 1e-6:
                    motion.offset += modulo
                    params.counter1 = int(params.counter1) + 1
                while self.axis.position() - motion.offset <= -modulo + 1e-6:
                    motion.offset -= modulo
                    params.counter1 = int(params.counter1) - 1
        motion.arrived()

    def write_w(self, new: float) -> None:
        """W (P47, increments): free while standing; while moving only in the constant phase,
        and then the move under way goes to the new target (§4.6.6)."""
        params = self.params
        if self.motion.kind != "position":
            params.position_setpoint = new
            self._interrupted = False  # a new W is a new positioning [SIM-CHOICE]
            return
        if self.axis.phase() != "const":
            raise SersError(81)
        mode = params.positioning_mode
        target = self._target + new if mode in (0, 1, 3) else new + self.motion.offset
        position = self.axis.position()
        direction = 1 if self.axis.velocity() > 0 else -1
        remaining = (target - position) * direction
        if remaining < self.axis.stopping_distance(self._accel, self.ramp_profile()):
            params.position_setpoint = new
            raise SersError(87)
        params.position_setpoint = new
        self._target = target
        self.w_updated = True
        self._legs = []
        self.axis.move_to(target, self._speed, self._accel, on_done=self._positioning_done,
                          profile=self.ramp_profile())
        self.motion.arm_watches()

    def servo_overload(self, overloaded: bool) -> None:
        """Under overload the SERVO drive loses no steps: the stator field holds at the rotor
        and the move resumes when the load goes away, at P1163 if P1162=1 (catch-up), else at
        V (arriving later).  P1160 signals the overload on an output."""
        self.overloaded = overloaded
        params = self.params
        sel = int(params.overload_output)
        if sel:
            port, value = abs(sel) if abs(sel) <= 4 else abs(sel) - 4, sel > 0
            if overloaded or abs(sel) > 4:
                self.signals.set(f"O{port}", value if overloaded else not value)
        if overloaded:
            if self.motion.kind == "position":
                self.axis.quick_stop()
                self._servo_resume = True
            return
        if self._servo_resume and self.motion.kind == "position":
            self._servo_resume = False
            speed = self._speed
            if params.use_catch_up_velocity == 1:
                speed = max(speed, float(params.catch_up_velocity))
            self.axis.move_to(self._target, speed, self._accel, on_done=self._positioning_done)
