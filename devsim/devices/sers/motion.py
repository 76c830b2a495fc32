"""Motion of the SERS model: positioning E with its modes, jog, homing, POS0/POSR, encoder,
step loss, software limits (manual §4.5, §4.6.6, §4.8.4; spec §3.5, §5)."""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

from devsim.core.axis import RampProfile
from devsim.devices.sers import statements as st
from devsim.devices.sers.access import _sign
from devsim.devices.sers.constants import ELECTRICAL_PERIOD, INC_PER_REV, LIMIT, STANDSTILL, STEP_LOSS
from devsim.devices.sers.errors import SersError

__all__ = ["Motion"]


class Motion:
    """Part of :class:`~devsim.devices.sers.drive.SersDrive`: positioning, jog, homing, encoder."""

    # ======================================================================================
    # motion
    # ======================================================================================
    @property
    def moving(self) -> bool:
        return self.motion is not None

    def _motion_checks(self, direction: int) -> None:
        """Refusals in the spec's order (§3.5.3): limit (78), STOP (68), I7 (67), power (79)."""
        if direction > 0 and self.signals.get("limit_right"):
            raise SersError(78)
        if direction < 0 and self.signals.get("limit_left"):
            raise SersError(78)
        if self.signals.get("stop"):
            raise SersError(68)
        if self._i7_stop_active():
            raise SersError(67)
        if not self.power_stage.energized or self.power_stage.errors:
            raise SersError(79)

    def start_positioning(self) -> None:
        """E (§4.6.6) with P1014 mode 0 relative, 1 relative-clear, 2 absolute, 3 overflow."""
        if self.poly.definition is not None:
            self.poly.execute()  # E closes a polynomial segment (§4.6.7)
            return
        if self.motion == "position" and self._w_updated:
            self._w_updated = False
            return  # G-EWHILEMOVE: the running move already took the new W
        if self.motion is not None:
            raise SersError(70)
        mode = int(self.params.positioning_mode)
        w = float(self.params.position_setpoint)
        p51 = self.p51_inc()
        if mode == 1:
            start, target = 0.0, float(round(w))
        elif mode == 2:
            start, target = p51, float(round(w))
        else:
            start, target = p51, p51 + round(w)  # W in whole increments (§5.1)
        target = self._leave_zero_phase(target)
        direction = (target > start) - (target < start)
        self._motion_checks(direction)
        lo, hi = self.scaling.pos_range()
        target_user = self.scaling.inc_to_pos(target)
        if target_user > hi or target_user < lo:
            self.power_stage.warn(64)
            raise SersError(85 if target_user > hi else 86)
        if mode == 1:
            self.offset = self.axis.position()
        elif target == p51:
            return  # already there: nothing moves, POS stays 1
        self._speed = float(self.params.velocity)
        self._accel = float(self.params.acceleration)
        self._target_physical = target + self.offset
        legs = self._backlash_legs(p51 + self.offset, self._target_physical)
        for _target, speed in legs:
            _can_move(speed, self._accel)  # (the backlash legs creep at P1003)
        self.power_stage.servo_check()
        self._begin_motion("position", self._accel)
        self._setpoint = self._target_physical
        self._legs = legs
        self._next_leg()
        self._arm_position_watches()

    def _backlash_legs(self, start: float, target: float) -> list[tuple[float, float]]:
        """Backlash compensation P1037 (§4.8.4.7, spec §5.8 G-BACKLASH): the final approach
        is always made opposite to the homing direction (P147 bit 0), at speed P1003."""
        slack = abs(float(self.params.backlash))
        if not slack or target == start:
            return [(target, self._speed)]
        approach = 1 if int(self.params.homing_parameters) & 1 else -1
        creep = float(self.params.homing_velocity_slow)
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
        """P1032 ramp shape with the sections P1005–P1008 (§4.8.4.4, spec §5.2)."""
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
        mode = int(self.params.positioning_mode)
        if mode == 3:
            modulo = float(self.params.modulo)
            if modulo > 0:
                while self.p51_inc() >= modulo - 1e-6:
                    self.offset += modulo
                    self.params.counter1 = int(self.params.counter1) + 1
                while self.p51_inc() <= -modulo + 1e-6:
                    self.offset -= modulo
                    self.params.counter1 = int(self.params.counter1) - 1
        self._motion_finished()
        if self.params.report_in_position:
            self.spontaneous(f"@{self.cfg.address}POS=1")

    def _begin_motion(self, kind: str, decel: float) -> None:
        self.record_event("move_start")
        self.motion = kind
        self.pos_ok = False
        self._stop_decel = decel
        self._w_updated = False
        self.outputs.update()

    def _motion_finished(self) -> None:
        was_moving = self.motion is not None
        self.poly.cancel()
        if was_moving:
            self.record_event("move_end")
        self._stopped_at = self.clock.now()
        self.motion = None
        self.pos_ok = True
        self._homing = None
        self._jog_dir = 0
        self._jog_until = None
        self._cancel_jog_timer()
        for watch in self._watches + self._standstill_watches:
            watch.cancel()
        self._watches.clear()
        self._standstill_watches = []
        self.outputs.update()
        if was_moving:
            self.interpreter.on_motion_end()

    def _end_motion(self, quick: bool) -> None:
        if quick:
            self.axis.quick_stop()
            self._motion_finished()
        else:
            self.stop_motion()

    def abort_profiles(self) -> None:
        """A drive error: a polynomial profile and a homing run are over."""
        self.poly.cancel()
        self._homing = None

    def quick_end(self) -> None:
        """Torque off (OFF, a short circuit, U < U_L): the motion ends at once."""
        if self.motion is not None:
            self._end_motion(quick=True)

    def error_stop(self, then: Callable[[], None]) -> bool:
        """A drive error while the axis moves: brake with P1030, then ``then`` (§2.1.3)."""
        if self.motion is None or not self.axis.moving:
            return False
        self._stop_decel = self.params.error_deceleration
        self.motion = "error-stop"
        self._cancel_jog_timer()
        self.axis.stop(self.params.error_deceleration, on_done=lambda: (self._motion_finished(), then()))
        return True

    def stop_motion(self) -> None:
        """S (§4.2): decelerate with the active motion's deceleration (spec §5.4)."""
        if self.motion is None or self.motion == "error-stop":
            return
        self._homing = None
        self.poly.cancel()
        self._cancel_jog_timer()
        profile = self.ramp_profile() if self.motion == "position" else None
        self.motion = "stopping"
        self.axis.stop(self._stop_decel, on_done=self._motion_finished, profile=profile)

    # -- jog -------------------------------------------------------------------------------
    def jog(self, name: str, until: st.Condition | None = None, serial: bool = True) -> None:
        """RS/RF/LS/LF (§4.5.1): right = positive; slow P1019, fast P1020, × P108 %."""
        direction = 1 if name[0] == "R" else -1
        self._motion_checks(direction)
        if self.motion not in (None, "jog", "position", "stopping"):
            raise SersError(70)
        params = self.params
        jog_speed = params.jog_velocity_slow if name[1] == "S" else params.jog_velocity_fast
        speed = float(jog_speed) * float(params.feedrate_override) / 100
        accel = float(self.params.jog_acceleration)
        _can_move(speed, accel)
        if not (self.motion == "jog" and self._jog_dir == direction and self._jog_speed == speed):
            self.power_stage.servo_check()
            self._begin_motion("jog", accel)
            self._jog_dir = direction
            self._jog_speed = speed
            self._jog_accel = accel
            self.axis.jog(direction, speed, accel)
            self._arm_position_watches()
        self._jog_until = until
        self._cancel_jog_timer()
        if serial and until is None and self.params.jog_timeout == 1:
            self._jog_timer = self.clock.call_later(0.5, self._jog_timeout)
        if until is not None and self.evaluate(until):
            self._until_reached()

    def _jog_timeout(self) -> None:
        self._jog_timer = None
        if self.motion == "jog":
            self.stop_motion()

    def _cancel_jog_timer(self) -> None:
        if self._jog_timer is not None:
            self._jog_timer.cancel()
            self._jog_timer = None

    def _until_reached(self) -> None:
        """':' event (§4.6.9): brake with P1018, or travel the overrun distance P1039 first."""
        self._jog_until = None
        overrun = float(self.params.overrun)
        if overrun:
            target = self.axis.position() + self._jog_dir * abs(overrun)
            self.motion = "stopping"
            speed = abs(self.axis.velocity()) or self._jog_speed  # (the event came as the jog began)
            self.axis.move_to(target, speed, self._jog_accel, on_done=self._motion_finished)
        else:
            self.stop_motion()

    def _check_until(self) -> None:
        self.interpreter.poke()
        self._check_jog_until()

    def _check_jog_until(self) -> None:
        if self._jog_until is not None and self.motion == "jog" and self.evaluate(self._jog_until):
            self._until_reached()

    # -- homing ----------------------------------------------------------------------------
    def home(self, serial: bool = True) -> None:
        """H (§4.8.4.5, spec §5.5): seek the reference edge at P41, creep back at P1003.

        P147 bit 0 direction, bit 1 limit switch as reference, bit 2 then the next electrical
        zero, bit 5 centre of the switch, bit 6 encoder zero pulse instead of the switch, bit 7
        switch, then zero pulse, then electrical zero.
        """
        if self.motion is not None:
            raise SersError(70)
        p147 = int(self.params.homing_parameters)
        direction = -1 if p147 & 1 else 1
        if p147 & 2:
            signal = "limit_left" if direction < 0 else "limit_right"
            if self.signals.get("stop"):
                raise SersError(68)
            if not self.power_stage.energized or self.power_stage.errors & ~LIMIT:
                raise SersError(79)
        else:
            signal = "index" if p147 & 64 and not p147 & 128 else "reference"
            self._motion_checks(0)
        accel = float(self.params.homing_acceleration)
        _can_move(float(self.params.homing_velocity) * float(self.params.feedrate_override) / 100, accel)
        _can_move(float(self.params.homing_velocity_slow), accel)
        # (creep speed and ramp as at the start: a write during the run cannot stop it midway)
        self._homing = {"signal": signal, "direction": direction, "phase": "seek", "p147": p147,
                        "creep": float(self.params.homing_velocity_slow), "accel": accel}
        self._begin_motion("home", accel)
        if signal == "index":
            self._watches.append(self.axis.watch_index(self._on_index))
        if signal != "index" and self._homing_signal_active():
            self._creep()
        else:
            speed = float(self.params.homing_velocity) * float(self.params.feedrate_override) / 100
            self.axis.jog(direction, speed, accel)
            self._arm_position_watches(keep=True)

    def _homing_signal_active(self) -> bool:
        assert self._homing is not None
        if self._homing["signal"] == "reference":
            return self._reference_active()
        return bool(self.signals.get(self._homing["signal"]))

    def _creep(self) -> None:
        assert self._homing is not None
        self._homing["phase"] = "creep"
        self.axis.jog(-self._homing["direction"], self._homing["creep"], self._homing["accel"])

    def _on_index(self, _direction: int) -> None:
        """Encoder zero pulse (once per motor revolution) during homing with P147 bit 6/7."""
        homing = self._homing
        if homing is None:
            return
        if homing["signal"] == "index":
            self._homing_edge(homing["phase"] == "seek")
        elif homing["phase"] == "to_index":
            homing["phase"] = "edge"
            self.axis.quick_stop()
            self._electrical_reset()

    def _homing_edge(self, active: bool) -> None:
        homing = self._homing
        if homing is None:
            return
        phase, p147 = homing["phase"], homing["p147"]
        if phase == "seek" and active:
            homing["phase"] = "braking"
            self.axis.stop(homing["accel"], on_done=self._creep)
        elif phase == "creep" and not active:
            # G-HOME: at creep speed the drive stops exactly at the falling edge
            if p147 & 32 and homing["signal"] == "reference":
                homing["phase"] = "measure"
                self.axis.quick_stop()
                homing["first_edge"] = self.axis.position()
                self.axis.jog(homing["direction"], homing["creep"], homing["accel"])
            elif p147 & 128:
                homing["phase"] = "to_index"  # keep creeping to the next zero pulse
                self._watches.append(self.axis.watch_index(self._on_index))
            else:
                homing["phase"] = "edge"
                self.axis.quick_stop()
                self._electrical_reset()
        elif phase == "measure" and not active:
            homing["phase"] = "centre"
            self.axis.quick_stop()
            centre = (homing["first_edge"] + self.axis.position()) / 2
            self.axis.move_to(centre, homing["creep"], homing["accel"], on_done=self._homing_done)

    def _electrical_reset(self) -> None:
        """P147 bit 2/7: move on to the next electrical zero (every 256 increments)."""
        homing = self._homing
        assert homing is not None
        if not homing["p147"] & (4 | 128):
            self._homing_done()
            return
        here = self.axis.position()
        if -homing["direction"] > 0:
            target = math.ceil(here / ELECTRICAL_PERIOD - 1e-9) * ELECTRICAL_PERIOD
        else:
            target = math.floor(here / ELECTRICAL_PERIOD + 1e-9) * ELECTRICAL_PERIOD
        homing["phase"] = "reset"
        self.axis.move_to(target, homing["creep"], homing["accel"], on_done=self._homing_done)

    def _homing_done(self) -> None:
        self.offset = self.axis.position()
        self.homed = True
        self._motion_finished()
        if self.params.report_in_position:
            self.spontaneous(f"@{self.cfg.address}POS=1")

    def _reference_active(self) -> bool:
        selector = int(self.params.reference_input)
        if selector:
            return bool(self.signals.get(f"I{selector}"))
        return bool(self.signals.get("reference"))

    def _on_reference(self, name: str, old: Any, new: Any) -> None:
        if self._homing is not None and self._homing["signal"] == "reference" and not self.params.reference_input:
            self._homing_edge(bool(new))
        self._check_until()

    # -- POS0 / POSR -------------------------------------------------------------------------
    def pos0(self) -> None:
        """POS0 (§4.8.4.2, spec §5.13): go to the nearest phase zero, then P51 := 0.
        During a polynomial profile it ends polynomial mode instead (§4.6.7)."""
        if self.motion == "poly":
            self.stop_motion()
            return
        if self.motion is not None:
            raise SersError(70)
        p51 = self.p51_inc()
        target = round(p51 / ELECTRICAL_PERIOD) * ELECTRICAL_PERIOD
        direction = (target > p51) - (target < p51)
        self._motion_checks(direction)
        _can_move(float(self.params.homing_velocity), float(self.params.homing_acceleration))
        self._begin_motion("pos0", float(self.params.homing_acceleration))

        def done() -> None:
            self.offset = self.axis.position()
            self._motion_finished()

        self.axis.move_to(target + self.offset, float(self.params.homing_velocity), float(self.params.homing_acceleration), on_done=done)

    def posr(self, force: bool) -> None:
        """POSR (§4.8.4.2, spec §5.9): after a step loss, follow the motor's real position
        (encoder) and travel at P41 to the setpoint of the interrupted positioning.  Only with
        P11/P12 value 32, unless P1043=3."""
        if self.motion == "poly":
            self.stop_motion()  # POSR also ends polynomial mode (§4.6.7)
            return
        stepped = self.power_stage.errors & STEP_LOSS or self.power_stage.warnings & STEP_LOSS
        if not force and not stepped:
            raise SersError(3)
        if self.motion is not None:
            raise SersError(70)
        if self.power_stage.errors & STEP_LOSS:
            self.power_stage.errors &= ~STEP_LOSS
        self.power_stage.warnings &= ~STEP_LOSS
        self._resync_to_encoder()
        target = self._setpoint if self._setpoint is not None else float(self.params.position_setpoint) + self.offset
        direction = (target > self.axis.position()) - (target < self.axis.position())
        self._motion_checks(direction)
        _can_move(float(self.params.homing_velocity), float(self.params.homing_acceleration))
        self._begin_motion("posr", float(self.params.homing_acceleration))
        self.axis.move_to(target, float(self.params.homing_velocity), float(self.params.homing_acceleration), on_done=self._posr_done)
        self._arm_position_watches()

    def _posr_done(self) -> None:
        if int(self.params.posr_mode) & 2:
            self._posr_attempts = 0
        self._motion_finished()

    # -- pulse input, hand-wheel, electronic gear (§3.4, §4.8.6.6, spec §5.9) ---------------
    def pulses(self, count: int) -> None:
        """``count`` pulses (signed; 4× evaluated encoder counts) arrive at I3/I4 or ENC.

        With P1053 = 1/2/3 (I3/I4) or 5/6/7 (ENC), or P1143 = 1/2/3, the motor follows
        by count × P1054 × 64 increments, limited by A and V (hand-wheel, electric shaft)."""
        mode, alt = int(self.params.pulse_input), int(self.params.pulse_input2)
        if mode in (1, 2, 3, 5, 6, 7):
            weight, counter = float(self.params.pulse_weight), 1119
        elif alt in (1, 2, 3):
            weight, counter = float(self.params.pulse_weight2), 1120
        else:
            return
        if mode in (5, 6, 7) and "E50" not in self.cfg.options:
            return
        self.params.values[counter] = int(self.params.values.get(counter, 0)) + count
        if not self.power_stage.energized or self.power_stage.errors or self.motion not in (None, "follow"):
            return
        step = count * weight * INC_PER_REV / 200
        base = self._follow_target if self.motion == "follow" else self.axis.position()
        target = base + step
        direction = (step > 0) - (step < 0)
        try:
            self._motion_checks(direction)
        except SersError:
            return  # pulses toward a blocked direction are ignored (P1094=0)
        self._follow_target = target
        if self.motion is None:
            self._begin_motion("follow", float(self.params.acceleration))
        self.axis.move_to(target, float(self.params.velocity), float(self.params.acceleration), on_done=self._motion_finished)

    # -- load angle / step-loss monitoring (§4.8.6.6, spec §5.9) ----------------------------
    def encoder_position(self) -> float:
        """Where the rotor really is (increments): the stator field minus the steps lost."""
        if self._stall_rotor is not None:
            return self._stall_rotor
        return self.axis.position() - self.lost

    def _monitoring(self) -> bool:
        mode = int(self.params.pulse_input)
        encoder = mode == 4 or (mode == 8 and "E50" in self.cfg.options)
        return encoder and int(self.params.step_monitoring) != 0

    def _on_stall(self, name: str, old: Any, new: Any) -> None:
        if self.params.servo_mode == 1:
            self._servo_overload(bool(new))
            return
        if new:
            self._stall_rotor = self.axis.position() - self.lost
            self._arm_load_watch()
        elif self._stall_rotor is not None:
            self.lost = self.axis.position() - self._stall_rotor
            self._stall_rotor = None
            for watch in self._load_watches:
                watch.cancel()
            self._load_watches = []

    def _arm_load_watch(self) -> None:
        for watch in self._load_watches:
            watch.cancel()
        self._load_watches = []
        if self._stall_rotor is None or not self._monitoring():
            return
        window = float(self.params.load_angle_window)
        rotor = self._stall_rotor
        for where in (rotor + window, rotor - window):
            self._load_watches.append(self.axis.watch(where, lambda _d: self._step_loss()))

    def _step_loss(self) -> None:
        """The load angle exceeded P1002: P1029 1 = drive error, 2 = warning, 3 = error, motor on."""
        self.max_load_angle = max(self.max_load_angle, abs(self.axis.position() - self.encoder_position()))
        reaction = int(self.params.step_monitoring)
        if reaction == 2:
            self.power_stage.warn(STEP_LOSS)
            self.stop_motion()
        elif reaction in (1, 3):
            self.power_stage.drive_error(STEP_LOSS)
        retries = int(self.params.posr_attempts)
        if retries and self._posr_attempts < retries:
            self._posr_attempts += 1
            delay = float(self.params.posr_wait) * 0.1
            self.pos_ok = False
            self._timers.append(self.clock.call_later(delay, self._auto_posr))

    def _auto_posr(self) -> None:
        """P1138/P1139: automatic POSR after a step loss."""
        if self.motion is not None:
            self._timers.append(self.clock.call_later(0.01, self._auto_posr))
            return
        self.power_stage.errors &= ~STEP_LOSS
        self.power_stage.energize()
        try:
            self.posr(force=True)
        except SersError as exc:
            self.power_stage.record_error(exc.errno)

    def _resync_to_encoder(self) -> None:
        """Clearing a step loss: P51 takes the encoder's position (§4.8.6.6)."""
        if self.axis.moving:
            return
        rotor = self.encoder_position()
        if self._stall_rotor is None:
            self.lost = 0.0
        if rotor != self.axis.position():
            self.axis.set_position(rotor)
            if self._stall_rotor is not None:
                self._arm_load_watch()

    # -- software limits and compare positions (§4.8.6.12, §4.8.1.2) ------------------------
    def _soft_limits(self) -> tuple[float, float] | None:
        lower, upper = float(self.params.limit_negative), float(self.params.limit_positive)
        if lower < upper:
            return lower, upper
        return None

    def _outside_soft_limits(self) -> bool:
        limits = self._soft_limits()
        if limits is None:
            return False
        p51 = self.p51_inc()
        return p51 < limits[0] or p51 > limits[1]

    def _arm_position_watches(self, keep: bool = False) -> None:
        """Software limits, compare positions and standstill monitoring for a new motion."""
        if not keep:
            for watch in self._watches:
                watch.cancel()
            self._watches.clear()
        limits = self._soft_limits()
        homing = self.motion == "home" and not int(self.params.homing_parameters) & 8
        if limits is not None and not homing:
            lower, upper = (x + self.offset for x in limits)
            velocity_sign = _sign(self.axis.final_position() - self.axis.position())
            here = self.axis.position()
            if (here > upper and velocity_sign > 0) or (here < lower and velocity_sign < 0):
                self._timers.append(self.clock.call_later(0, self._soft_limit_hit))
            self._watches.append(self.axis.watch(upper + 1e-9, lambda d: d > 0 and self._soft_limit_hit()))
            self._watches.append(self.axis.watch(lower - 1e-9, lambda d: d < 0 and self._soft_limit_hit()))
        self._arm_standstill_monitor()
        params = self.params
        for position, action in ((params.compare_position1, params.compare_output1),
                                 (params.compare_position2, params.compare_output2)):
            action = int(action)
            if action:
                where = float(position) + self.offset
                self._watches.append(self.axis.watch(where, lambda _d, a=action: self._compare_action(a)))

    def _arm_standstill_monitor(self) -> None:
        """P1044/P1045 (§4.8.6.8, spec §5.7): while moving, an edge on input P1045 must come
        at least every P1044; the distance counts from the motion start and from each edge."""
        for watch in self._standstill_watches:
            watch.cancel()
        self._standstill_watches = []
        distance = abs(float(self.params.standstill_distance))
        if not distance or self.motion is None:
            return
        here = self.axis.position()
        for where in (here + distance, here - distance):
            self._standstill_watches.append(self.axis.watch(where, lambda _d: self._standstill_error()))

    def _standstill_error(self) -> None:
        if self.motion is not None and self.motion != "error-stop":
            self.power_stage.drive_error(STANDSTILL)

    def _soft_limit_hit(self) -> None:
        self.power_stage.warn(1)
        if self.motion not in (None, "stopping", "error-stop"):
            self.stop_motion()

    def _compare_action(self, action: int) -> None:
        """P1025/P1027: ±1..4 set/clear O1..O4, ±5..7 set/clear M1..M3."""
        value = action > 0
        n = abs(action)
        if n <= 4:
            self.signals.set(f"O{n}", value)
        elif n <= 7:
            self.params.values[1100 + n - 4] = int(value)  # M1..M3


def _can_move(speed: float, accel: float) -> None:
    """A jog, a homing run, POS0/POSR or a move's backlash legs need a speed and an acceleration
    above 0; with P108 = 0 % or a speed or ramp parameter set to 0 the motion is refused as V or
    A too small [SIM-CHOICE: the manual does not say what the drive does; it cannot move, and
    the simulator must not fail]."""
    if not speed > 0:
        raise SersError(121)
    if not accel > 0:
        raise SersError(119)
