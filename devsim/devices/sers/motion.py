"""Motion of the SERS: positioning ``E`` with its modes and backlash, W changed on the move,
stopping, POS0/POSR, the hand-wheel, SERVO overload and the phase current (manual §4.6.6,
§4.8.4, §4.8.6.1, §4.8.6.6, §4.8.6.7; spec §3.5, §5).

Positions are motor increments, speeds inc/s and accelerations inc/s²; P51 is the axis position
minus :attr:`Motion.offset`.  The motion owns its jog (:mod:`.jog`), homing run (:mod:`.homing`),
polynomial profile (:mod:`.polynomial`), position watches (:mod:`.watches`) and step-loss
monitoring (:mod:`.encoder`).
"""

from __future__ import annotations

from collections.abc import Callable

from devsim.core.axis import Axis, RampProfile
from devsim.core.clock import Clock
from devsim.core.signals import SignalBank
from devsim.devices.sers import statements as st
from devsim.devices.sers.constants import ELECTRICAL_PERIOD, INC_PER_REV, STEP_LOSS
from devsim.devices.sers.encoder import StepMonitor
from devsim.devices.sers.errors import SersError
from devsim.devices.sers.homing import Homing, can_move
from devsim.devices.sers.jog import Jog
from devsim.devices.sers.params import SersParameters
from devsim.devices.sers.polynomial import PolynomialMove
from devsim.devices.sers.power import PowerStage
from devsim.devices.sers.watches import PositionWatches

__all__ = ["Motion"]


class Motion:
    """What moves one SERS's motor, and how it stops (§4.6.6, §4.8.4)."""

    def __init__(
        self,
        clock: Clock,
        axis: Axis,
        params: SersParameters,
        signals: SignalBank,
        power: PowerStage,
        *,
        evaluate: Callable[[st.Condition], bool],
        i7_stop: Callable[[], bool],
        ended: Callable[[], None],
        poke: Callable[[], None],
        segment_ended: Callable[[], None],
        in_position_message: Callable[[], None],
        has_option_e50: Callable[[], bool],
        record_event: Callable[[str], None],
        changed: Callable[[], None],
    ) -> None:
        self.clock = clock
        self.axis = axis
        self.params = params
        self.signals = signals
        self.power = power
        self._i7_stop = i7_stop  # input I7 as a stop (§4.8.1.1)
        self._ended = ended  # a program waiting for the motion goes on
        self._poke = poke  # a program's WAIT looks again
        self._in_position_message = in_position_message  # @nPOS=1 with P1121 (§4.8.6.11)
        self._has_option_e50 = has_option_e50
        self._record_event = record_event
        self._changed = changed  # the outputs (P1125 in position) follow
        #: What moves the drive: position, jog, home, pos0, posr, poly, follow, stopping,
        #: error-stop; None at rest.
        self.kind: str | None = None
        self.pos_ok = True  # P336
        self.offset = 0.0  # axis position of P51 = 0
        self._stop_decel = 0.0  # the deceleration of S for the motion under way
        self._w_updated = False  # W was changed on the move: the next E is already done
        self._legs: list[tuple[float, float]] = []  # (target, speed) still to go, backlash
        self._setpoint: float | None = None  # target of the last E (POSR, P1033=1)
        self._target = 0.0  # physical target of the positioning under way
        self._speed = 0.0
        self._accel = 0.0
        self._follow_target = 0.0  # hand-wheel
        self._stopped_at = 0.0  # when the last motion ended (phase current reduction)
        self.servo_overload = False
        self._servo_resume = False
        self.watches = PositionWatches(clock, axis, params, signals, power, offset=lambda: self.offset,
                                       kind=lambda: self.kind, stop=self.stop_motion)
        self.homing = Homing(axis, params, signals, power, self)
        self.jog = Jog(clock, axis, params, power, self, evaluate=evaluate)
        self.encoder = StepMonitor(clock, axis, params, power, self, has_option_e50=has_option_e50)
        self.poly = PolynomialMove(axis, params, self, record_error=power.record_error, segment_ended=segment_ended)

    # -- power ----------------------------------------------------------------------------------
    def power_on(self) -> None:
        """At rest (P51 follows from the memory: :meth:`set_p51`)."""
        self.cancel_all()
        self.axis.quick_stop()
        self.kind = None
        self.pos_ok = True
        self._stop_decel = 0.0
        self._w_updated = False
        self._legs = []
        self._setpoint = None
        self._follow_target = 0.0
        self._stopped_at = 0.0
        self.servo_overload = False
        self._servo_resume = False
        self.homing.homed = False
        self.homing.cancel()
        self.jog.power_on()
        self.encoder.power_on()
        self.poly.cancel()

    def power_off(self) -> None:
        self.cancel_all()
        self.axis.quick_stop()
        self.kind = None
        self.pos_ok = True

    def cancel_all(self) -> None:
        """Every timer and watch of the motion (power off, power on, close)."""
        self.watches.cancel_timers()
        self.watches.cancel()
        self.jog.cancel_timer()
        self.encoder.cancel()
        self.homing.drop_watches()

    # -- state ------------------------------------------------------------------------------------
    @property
    def moving(self) -> bool:
        return self.kind is not None

    def p51_inc(self) -> float:
        """P51, the actual position, in increments."""
        return self.axis.position() - self.offset

    def set_p51(self, increments: float) -> None:
        """``P51=``: the actual position is ``increments`` from now on."""
        self.offset = self.axis.position() - increments

    def out_of_position(self) -> None:
        self.pos_ok = False

    def phase_current(self) -> float:
        """Commanded phase current in mA (§4.8.6.1, spec §5.11): P1010; with P1011 bit 0
        50 % at standstill from 20 ms after the last motion; +20 % boost per bits 1/2."""
        if not self.power.energized:
            return 0.0
        params = self.params
        current = float(params.phase_current)
        bits = int(params.current_parameters)
        standing = self.kind is None and self.clock.now() - self._stopped_at >= 0.02
        if standing and bits & 1:
            current *= 0.5
        accel = abs(self.axis.acceleration())
        if (bits & 2 and accel > float(params.boost_acceleration)) or (bits & 4 and standing):
            current *= 1.2
        return current

    # -- starting and ending --------------------------------------------------------------------
    def checks(self, direction: int) -> None:
        """Refusals in the spec's order (§3.5.3): limit (78), STOP (68), I7 (67), power (79)."""
        signals = self.signals
        if direction > 0 and signals.get("limit_right"):
            raise SersError(78)
        if direction < 0 and signals.get("limit_left"):
            raise SersError(78)
        if signals.get("stop"):
            raise SersError(68)
        if self._i7_stop():
            raise SersError(67)
        if not self.power.energized or self.power.errors:
            raise SersError(79)

    def begin(self, kind: str, decel: float) -> None:
        self._record_event("move_start")
        self.kind = kind
        self.pos_ok = False
        self._stop_decel = decel
        self._w_updated = False
        self._changed()

    def finish(self) -> None:
        """The motion has ended (the axis stands)."""
        was_moving = self.kind is not None
        self.poly.cancel()
        if was_moving:
            self._record_event("move_end")
        self._stopped_at = self.clock.now()
        self.kind = None
        self.pos_ok = True
        self.homing.cancel()
        self.jog.reset()
        self.watches.cancel()
        self._changed()
        if was_moving:
            self._ended()

    def arm_watches(self, keep: bool = False) -> None:
        self.watches.arm(keep)

    def stop_motion(self) -> None:
        """S (§4.2): decelerate with the active motion's deceleration (spec §5.4)."""
        if self.kind is None or self.kind == "error-stop":
            return
        self.homing.cancel()
        self.poly.cancel()
        self.jog.cancel_timer()
        profile = self.ramp_profile() if self.kind == "position" else None
        self.kind = "stopping"
        self.axis.stop(self._stop_decel, on_done=self.finish, profile=profile)

    def abort_profiles(self) -> None:
        """A drive error: a polynomial profile and a homing run are over."""
        self.poly.cancel()
        self.homing.cancel()

    def quick_end(self) -> None:
        """Torque off (OFF, a short circuit, U < U_L): the motion ends at once."""
        if self.kind is not None:
            self.axis.quick_stop()
            self.finish()

    def error_stop(self, then: Callable[[], None]) -> bool:
        """A drive error while the axis moves: brake with P1030, then ``then`` (§2.1.3)."""
        if self.kind is None or not self.axis.moving:
            return False
        decel = self.params.error_deceleration
        self._stop_decel = decel
        self.kind = "error-stop"
        self.jog.cancel_timer()
        self.axis.stop(decel, on_done=lambda: (self.finish(), then()))
        return True

    def overrun(self, target: float, speed: float, accel: float) -> None:
        """A jog's ':' condition held: travel the overrun P1039, then stand (§4.6.9)."""
        self.kind = "stopping"
        self.axis.move_to(target, speed, accel, on_done=self.finish)

    def home_reached(self) -> None:
        self.offset = self.axis.position()
        self.finish()
        self._report_in_position()

    def check_until(self) -> None:
        """The drive's state changed: a program's WAIT and a jog's ':' look again."""
        self._poke()
        self.jog.check_until()

    def _report_in_position(self) -> None:
        if self.params.report_in_position:
            self._in_position_message()

    # -- positioning E (§4.6.6) -----------------------------------------------------------------
    def start_positioning(self) -> None:
        """E (§4.6.6) with P1014 mode 0 relative, 1 relative-clear, 2 absolute, 3 overflow."""
        if self.poly.definition is not None:
            self.poly.execute()  # E closes a polynomial segment (§4.6.7)
            return
        if self.kind == "position" and self._w_updated:
            self._w_updated = False
            return  # G-EWHILEMOVE: the running move already took the new W
        if self.kind is not None:
            raise SersError(70)
        params = self.params
        mode = int(params.positioning_mode)
        w = float(params.position_setpoint)
        p51 = self.p51_inc()
        if mode == 1:
            start, target = 0.0, float(round(w))
        elif mode == 2:
            start, target = p51, float(round(w))
        else:
            start, target = p51, p51 + round(w)  # W in whole increments (§5.1)
        target = self._leave_zero_phase(target)
        direction = (target > start) - (target < start)
        self.checks(direction)
        scaling = params.scaling
        lo, hi = scaling.pos_range()
        target_user = scaling.inc_to_pos(target)
        if target_user > hi or target_user < lo:
            self.power.warn(64)
            raise SersError(85 if target_user > hi else 86)
        if mode == 1:
            self.offset = self.axis.position()
        elif target == p51:
            return  # already there: nothing moves, POS stays 1
        self._speed = float(params.velocity)
        self._accel = float(params.acceleration)
        self._target = target + self.offset
        legs = self._backlash_legs(p51 + self.offset, self._target)
        for _target, speed in legs:
            can_move(speed, self._accel)  # (the backlash legs creep at P1003)
        self.power.servo_check()
        self.begin("position", self._accel)
        self._setpoint = self._target
        self._legs = legs
        self._next_leg()
        self.arm_watches()

    def continue_positioning(self) -> bool:
        """P1033=1: a program stopped during ``E`` continues the interrupted move; False if it
        stands at the setpoint already (or there is none)."""
        setpoint = self._setpoint
        if setpoint is None:
            return True
        here = self.axis.position()
        direction = (setpoint > here) - (setpoint < here)
        self.checks(direction)
        if direction == 0:
            return False
        self._speed = float(self.params.velocity)
        self._accel = float(self.params.acceleration)
        self._target = setpoint
        self.begin("position", self._accel)
        self._legs = [(setpoint, self._speed)]
        self._next_leg()
        self.arm_watches()
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
        params = self.params
        if int(params.positioning_mode) == 3:
            modulo = float(params.modulo)
            if modulo > 0:
                while self.p51_inc() >= modulo - 1e-6:
                    self.offset += modulo
                    params.counter1 = int(params.counter1) + 1
                while self.p51_inc() <= -modulo + 1e-6:
                    self.offset -= modulo
                    params.counter1 = int(params.counter1) - 1
        self.finish()
        self._report_in_position()

    def write_w(self, new: float) -> None:
        """W (P47, increments): free while standing; while moving only in the constant phase,
        and then the move under way goes to the new target (§4.6.6)."""
        params = self.params
        if self.kind != "position":
            params.position_setpoint = new
            return
        if self.axis.phase() != "const":
            raise SersError(81)
        mode = params.positioning_mode
        target = self._target + new if mode in (0, 1, 3) else new + self.offset
        position = self.axis.position()
        direction = 1 if self.axis.velocity() > 0 else -1
        remaining = (target - position) * direction
        if remaining < self.axis.stopping_distance(self._accel, self.ramp_profile()):
            params.position_setpoint = new
            raise SersError(87)
        params.position_setpoint = new
        self._target = target
        self._w_updated = True
        self._legs = []
        self.axis.move_to(target, self._speed, self._accel, on_done=self._positioning_done,
                          profile=self.ramp_profile())
        self.arm_watches()

    # -- polynomial profiles (the host of :class:`.polynomial.PolynomialMove`) ------------------
    def begin_polynomial(self, end: float) -> None:
        """The first segment of a polynomial profile starts toward ``end``."""
        here = self.axis.position()
        self.checks((end > here) - (end < here))
        self._speed = float(self.params.velocity)
        self._accel = float(self.params.acceleration)
        self.begin("poly", self._accel)
        self.arm_watches()

    def polynomial_finished(self) -> None:
        if self.kind is not None:
            self.finish()
            self._report_in_position()

    # -- POS0 / POSR (§4.8.4.2) -------------------------------------------------------------------
    def home(self) -> None:
        """H (§4.8.4.5)."""
        self.homing.home(self.kind is not None)

    def pos0(self) -> None:
        """POS0 (§4.8.4.2, spec §5.13): go to the nearest phase zero, then P51 := 0.
        During a polynomial profile it ends polynomial mode instead (§4.6.7)."""
        if self.kind == "poly":
            self.stop_motion()
            return
        if self.kind is not None:
            raise SersError(70)
        p51 = self.p51_inc()
        target = round(p51 / ELECTRICAL_PERIOD) * ELECTRICAL_PERIOD
        direction = (target > p51) - (target < p51)
        self.checks(direction)
        speed, accel = float(self.params.homing_velocity), float(self.params.homing_acceleration)
        can_move(speed, accel)
        self.begin("pos0", accel)

        def done() -> None:
            self.offset = self.axis.position()
            self.finish()

        self.axis.move_to(target + self.offset, speed, accel, on_done=done)

    def posr(self, force: bool) -> None:
        """POSR (§4.8.4.2, spec §5.9): after a step loss, follow the motor's real position
        (encoder) and travel at P41 to the setpoint of the interrupted positioning.  Only with
        P11/P12 value 32, unless P1043=3."""
        if self.kind == "poly":
            self.stop_motion()  # POSR also ends polynomial mode (§4.6.7)
            return
        power = self.power
        stepped = power.errors & STEP_LOSS or power.warnings & STEP_LOSS
        if not force and not stepped:
            raise SersError(3)
        if self.kind is not None:
            raise SersError(70)
        power.clear_step_loss()
        self.encoder.resync()
        target = self._setpoint if self._setpoint is not None else float(self.params.position_setpoint) + self.offset
        here = self.axis.position()
        direction = (target > here) - (target < here)
        self.checks(direction)
        speed, accel = float(self.params.homing_velocity), float(self.params.homing_acceleration)
        can_move(speed, accel)
        self.begin("posr", accel)
        self.axis.move_to(target, speed, accel, on_done=self._posr_done)
        self.arm_watches()

    def _posr_done(self) -> None:
        self.encoder.retried()
        self.finish()

    # -- pulse input, hand-wheel, electronic gear (§3.4, §4.8.6.6, spec §5.9) ---------------------
    def pulses(self, count: int) -> None:
        """``count`` pulses (signed; 4× evaluated encoder counts) arrive at I3/I4 or ENC.

        With P1053 = 1/2/3 (I3/I4) or 5/6/7 (ENC), or P1143 = 1/2/3, the motor follows
        by count × P1054 × 64 increments, limited by A and V (hand-wheel, electric shaft)."""
        params = self.params
        mode, alt = int(params.pulse_input), int(params.pulse_input2)
        if mode in (1, 2, 3, 5, 6, 7):
            weight, counter = float(params.pulse_weight), 1119
        elif alt in (1, 2, 3):
            weight, counter = float(params.pulse_weight2), 1120
        else:
            return
        if mode in (5, 6, 7) and not self._has_option_e50():
            return
        params.values[counter] = int(params.values.get(counter, 0)) + count
        if not self.power.energized or self.power.errors or self.kind not in (None, "follow"):
            return
        step = count * weight * INC_PER_REV / 200
        base = self._follow_target if self.kind == "follow" else self.axis.position()
        target = base + step
        direction = (step > 0) - (step < 0)
        try:
            self.checks(direction)
        except SersError:
            return  # pulses toward a blocked direction are ignored (P1094=0)
        self._follow_target = target
        if self.kind is None:
            self.begin("follow", float(params.acceleration))
        self.axis.move_to(target, float(params.velocity), float(params.acceleration), on_done=self.finish)

    # -- the load (§4.8.6.6, §4.8.6.7) ------------------------------------------------------------
    def stall(self, stalled: bool) -> None:
        """The load stalls the rotor: a step loss, or in SERVO mode (P1152=1) the field waits."""
        if self.params.servo_mode == 1:
            self._servo_overload(stalled)
        else:
            self.encoder.stall(stalled)

    def _servo_overload(self, overloaded: bool) -> None:
        """Under overload the SERVO drive loses no steps: the stator field holds at the rotor
        and the move resumes when the load goes away, at P1163 if P1162=1 (catch-up), else at
        V (arriving later).  P1160 signals the overload on an output."""
        self.servo_overload = overloaded
        params = self.params
        sel = int(params.overload_output)
        if sel:
            port, value = abs(sel) if abs(sel) <= 4 else abs(sel) - 4, sel > 0
            if overloaded or abs(sel) > 4:
                self.signals.set(f"O{port}", value if overloaded else not value)
        if overloaded:
            if self.kind == "position":
                self.axis.quick_stop()
                self._servo_resume = True
            return
        if self._servo_resume and self.kind == "position":
            self._servo_resume = False
            speed = self._speed
            if params.use_catch_up_velocity == 1:
                speed = max(speed, float(params.catch_up_velocity))
            self.axis.move_to(self._target, speed, self._accel, on_done=self._positioning_done)
