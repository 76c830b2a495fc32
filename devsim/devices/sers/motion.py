"""Motion of the SERS: what moves the drive and how it stops, POS0/POSR, the hand-wheel and the
phase current (manual §4.2, §4.8.4, §4.8.6.1, §4.8.6.6; spec §3.5, §5).

Positions are motor increments, speeds inc/s and accelerations inc/s²; P51 is the axis position
minus :attr:`Motion.offset`.  The motion owns its jog (:mod:`.jog`), homing run (:mod:`.homing`),
polynomial profile (:mod:`.polynomial`), positioning ``E`` (:mod:`.positioning`), position
watches (:mod:`.watches`) and step-loss monitoring (:mod:`.encoder`).
"""

from __future__ import annotations

from collections.abc import Callable

from devsim.core.axis import Axis
from devsim.core.clock import Clock
from devsim.core.profile import Segment, sign
from devsim.core.signals import SignalBank
from devsim.devices.sers import statements as st
from devsim.devices.sers.constants import ELECTRICAL_PERIOD, INC_PER_REV, STEP_LOSS
from devsim.devices.sers.encoder import StepMonitor
from devsim.devices.sers.errors import SersError
from devsim.devices.sers.homing import Homing, can_move
from devsim.devices.sers.jog import Jog
from devsim.devices.sers.params import SersParameters
from devsim.devices.sers.polynomial import PolynomialMove
from devsim.devices.sers.positioning import Positioning
from devsim.devices.sers.power import PowerStage
from devsim.devices.sers.watches import PositionWatches

__all__ = ["Motion"]


class Motion:
    """What moves one SERS's motor, and how it stops (§4.6.6, §4.8.4)."""

    #: (Slots: a host's repeated poll reads this part: one block of memory instead of an object and its values)
    __slots__ = ("clock", "axis", "params", "signals", "power", "_i7_stop", "_ended", "_poke",
                 "_in_position_message", "_has_option_e50", "_record_event", "_changed", "kind", "pos_ok",
                 "offset", "_stop_decel", "_follow_target", "_stopped_at", "_ramp", "watches", "homing", "jog",
                 "encoder", "positioning", "poly")

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
        self._follow_target = 0.0  # hand-wheel
        self._stopped_at = 0.0  # when the last motion ended (phase current reduction)
        #: P1156 (SERVO): the motion under way began after this instant; the last ramp measured before
        self._ramp = (clock.now(), 0.0)
        self.watches = PositionWatches(clock, axis, params, signals, power, offset=lambda: self.offset,
                                       kind=lambda: self.kind, stop=self.stop_motion)
        self.homing = Homing(axis, params, signals, power, self)
        self.jog = Jog(clock, axis, params, power, self, evaluate=evaluate)
        self.encoder = StepMonitor(clock, axis, params, power, self, has_option_e50=has_option_e50)
        self.positioning = Positioning(axis, params, signals, power, self)
        self.poly = PolynomialMove(axis, params, self, record_error=power.record_error, segment_ended=segment_ended)

    # -- power ----------------------------------------------------------------------------------
    def power_on(self) -> None:
        """At rest (P51 follows from the memory: :meth:`set_p51`)."""
        self.cancel_all()
        self.axis.quick_stop()
        self.kind = None
        self.pos_ok = True
        self._stop_decel = 0.0
        self._follow_target = 0.0
        self._stopped_at = 0.0
        self._ramp = (self.clock.now(), 0.0)  # (no ramp measured since power-on)
        self.positioning.power_on()
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
        """Every timer and watch of the motion (power off, power on, close); a homing run is
        over (a real drive starts afresh after power-on, §4.8.3.2 P403)."""
        self.watches.cancel_timers()
        self.watches.cancel()
        self.jog.cancel_timer()
        self.encoder.cancel()
        self.homing.cancel()

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
        self.positioning.w_updated = False
        self._changed()

    def finish(self) -> None:
        """The motion has ended (the axis stands)."""
        was_moving = self.kind is not None
        # P1156: the ramps of this motion are measured now; the next motion's come after
        self._ramp = (self.clock.now(), self.ramp_acceleration() if self.params.servo_mode == 1 else self._ramp[1])
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

    def stop_command(self) -> None:
        """A stop command (S) or signal (the STOP input, I7): the motion stops, and an interrupted
        ``E`` is continued by the next with P1033=1 (§4.8.6.2)."""
        self.positioning.stopped(self.kind == "position")
        self.stop_motion()

    def stop_motion(self) -> None:
        """S (§4.2): decelerate with the active motion's deceleration (spec §5.4)."""
        if self.kind is None or self.kind == "error-stop":
            return
        self.homing.cancel()
        self.poly.cancel()
        self.jog.cancel_timer()
        profile = self.positioning.ramp_profile() if self.kind == "position" else None
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
        if not decel > 0:  # P1030 = 0 (§4.8.4.4 gives no minimum): no ramp to brake on, torque off at once
            self.quick_end()  # [SIM-CHOICE, as a short circuit; the caller opens the relay now]
            return False
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
        """E (§4.6.6); after a polynomial segment's definition it closes the segment (§4.6.7)."""
        if self.poly.definition is not None:
            self.poly.execute()
            return
        self.positioning.start()

    def continue_positioning(self) -> bool:
        """P1033=1: continue the interrupted move; False if it stands at the setpoint already."""
        return self.positioning.resume()

    def arrived(self) -> None:
        self.finish()
        self._report_in_position()

    # -- polynomial profiles (the host of :class:`.polynomial.PolynomialMove`) ------------------
    def begin_polynomial(self, end: float) -> None:
        """The first segment of a polynomial profile starts toward ``end``."""
        here = self.axis.position()
        self.checks((end > here) - (end < here))
        self.begin("poly", float(self.params.acceleration))
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
        setpoint = self.positioning.setpoint
        target = setpoint if setpoint is not None else float(self.params.position_setpoint) + self.offset
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
        by count × P1054 × 64 increments, limited by A and V (hand-wheel, electric shaft).
        P1053 = 2 and P1143 = 2 are pulse and direction: "wie 1, jedoch zusätzlich mit
        Drehrichtung an digitalem Eingang I 4 (aktiv = negativ)" -- the pulses count backwards
        while I4 is active."""
        params = self.params
        mode, alt = int(params.pulse_input), int(params.pulse_input2)
        if mode in (1, 2, 3, 5, 6, 7):
            weight, counter, with_direction = float(params.pulse_weight), 1119, mode == 2
        elif alt in (1, 2, 3):
            weight, counter, with_direction = float(params.pulse_weight2), 1120, alt == 2
        else:
            return
        if mode in (5, 6, 7) and not self._has_option_e50():
            return
        if with_direction and self.signals.get("I4"):
            count = -count
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
    def ramp_acceleration(self) -> float:
        """P1156 (§4.8.6.7) "Ist-Beschleunigung im SERVO-Modus, gemessen und gemittelt über die
        gesamte Beschleunigungsrampe": with P1152=1 the speed the rotor gained in its last
        acceleration ramp that has ended, divided by the ramp's time (inc/s², a magnitude), from
        the axis's segments in closed form (the rotor follows the set profile unless the load holds
        it); 0 before the first ramp after power-on, and with P1152=0."""
        if self.params.servo_mode != 1:
            return 0.0
        since, measured = self._ramp
        found = _last_ramp(self.axis.segments(since=since), self.clock.now())
        return measured if found is None else found

    def stall(self, stalled: bool) -> None:
        """The load stalls the rotor: a step loss, or in SERVO mode (P1152=1) the field waits."""
        if self.params.servo_mode == 1:
            self.positioning.servo_overload(stalled)
        else:
            self.encoder.stall(stalled)


def _speeds_up(seg: Segment) -> bool:
    """The segment is part of an acceleration ramp: its speed magnitude grows."""
    if seg.shape == "curve" or seg.a == 0.0:
        return False
    return sign(seg.a) == seg.direction if seg.shape == "sine" else seg.v0 == 0.0 or sign(seg.a) == sign(seg.v0)


def _last_ramp(segments: list[Segment], now: float) -> float | None:
    """The mean acceleration (speed gained / time, a magnitude) of the last acceleration ramp among
    ``segments`` (in time order; consecutive speeding-up segments are one ramp) that has ended by
    ``now``; None if none has."""
    found: float | None = None
    start: tuple[float, float] | None = None  # (t0, |v0|) of the ramp being followed
    end = (0.0, 0.0)  # (t1, |v1|) of its last segment so far
    for seg in [*segments, None]:
        joins = seg is not None and _speeds_up(seg) and start is not None and seg.t0 == end[0]
        if not joins and start is not None:
            if start[0] < end[0] <= now:
                found = (end[1] - start[1]) / (end[0] - start[0])
            start = None
        if seg is None or not _speeds_up(seg):
            continue
        if start is None:
            start = (seg.t0, abs(seg.v0))
        end = (seg.t1, abs(seg.velocity(seg.t1)))
    return found
