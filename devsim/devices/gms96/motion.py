"""The GMS96 indexer on the shared closed-form axis (manual §1.3, §2.3.1 A/B/f/M/o, §2.7).

Spec §5.1–§5.3 (units: Hz = inc/s, B in Hz/ms → a = 1000·B inc/s²; linear or sin² ramps, N24),
§5.2 (working speed, V-factor quantisation, override), §5.4 (blending: one plan to the chain's
last target, junctions are crossings; a slower next move is braked for at a watched brake point), §5.7 (following error e = v/Kv, ``blocked`` actual
position, trip at |e| > N20 solved as a crossing time), §5.8 (backlash compensation: on a
reversal the set-point stands N41/N42 ms while the motor takes up the slack), §5.11 (mechanical
end stops hold the actual position; the set-point runs on until |e| > N20).  The axis runs in *physical* increments; the card's position counter is
``axis.position() - origin`` (the device's business).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any, Protocol

from devsim.core.axis import Axis, IndexRule, RampProfile, RegionSwitch, Rule, Segment, Watch
from devsim.core.clock import Clock, Timer
from devsim.core.parameters import Param
from devsim.core.settings import Settings
from devsim.core.signals import SignalBank
from devsim.devices.gms96.feed import Feed
from devsim.devices.gms96.image import ProcessImage
from devsim.devices.gms96.params import NParameters
from devsim.devices.gms96.stage import PowerStage


class IndexerEvents(Protocol):
    """What the indexer tells its card (spec §5.5, §5.7): the plan changed (H7 and in-position re-arm), the
    following error tripped, an event for the log."""

    def plan_changed(self) -> None: ...
    def following_error_fault(self, reason: str) -> None: ...
    def record_event(self, name: str) -> None: ...


__all__ = ["ActualSwitch", "ActualWatch", "Indexer"]

_SINE = RampProfile(shape="sine")

#: The N parameters whose write re-arms the position loop's events (N10, N20, N27, N28).
LOOP_PARAMETERS = frozenset({"position_gain", "following_error_limit", "in_position_window", "in_position_time_ms"})


class Indexer:
    """Set-point generation and the position-loop model of one card (manual §1.3, §2.7; spec §5.1-§5.8)."""

    def __init__(
        self,
        *,
        clock: Clock,
        axis: Axis,
        feed: Feed,
        params: NParameters,
        stage: PowerStage,
        image: ProcessImage,
        signals: SignalBank,
        geometry: Settings,
        stepper: bool,
        card: IndexerEvents,
        max_speed: float | None = None,
    ) -> None:
        self.clock = clock
        self.axis = axis
        self.feed = feed
        self.params = params
        self.stage = stage
        self.image = image
        self.signals = signals
        self.geometry = geometry  # the configured axis: kv_per_n10, brake_stop_ms, end_stops
        self.stepper = stepper
        self.max_speed = max_speed  # a stepper card's maximum step frequency [Hz] (manual §6)
        self.card = card
        params.on_change(self._parameter_written)
        self.target: float | None = None  # physical end of the running plan (chain)
        self.kind = "work"  # which speed applies: work | search | spindle | rapid_nv
        self.jog_dir = 0  # endless run (reference search, spindle) instead of a target
        self.spindle_speed = 0.0
        self.on_arrive: Callable[[], None] | None = None
        self.blocked_at: float | None = None  # actual position held by a blockage
        # backlash compensation (spec §5.8): the side the slack was last taken up on (0: unknown,
        # nothing compensated before the first motion) and a reversal in progress
        self.last_dir = 0
        self.comp_dir = 0
        self.comp_phase = ""  # "" | "brake" (to standstill first) | "dwell" (motor takes up N41)
        self._fe_timer: Timer | None = None
        self._fe_watches: list[Watch] = []
        # blending (spec §5.4): the next junction and the feed (f, frac) of the move behind it
        self.junction: float | None = None
        self.junction_feed: tuple[int, int] | None = None
        self._junction_braking = False  # past the brake point: the next move's speed applies
        self._junction_watch: Watch | None = None
        # switches and index marks on the ACTUAL position (spec §5.6, §5.11): re-armed with the
        # following-error watch, i.e. on every re-plan, arrival, halt, power off, blockage, N10
        self._actual_watches: list[ActualWatch] = []

    def _parameter_written(self, row: Param, value: int) -> None:
        """N10 (Kv), N20 (the limit), N27/N28 (in position): the loop's events are solved anew."""
        if row.attr in LOOP_PARAMETERS:
            self.arm_following_error()

    def plan_changes_at(self) -> float | None:
        """The next boundary of the axis plan after now: where the motion's status bits (M0.3
        moving, M1.4 speed reached) may change by themselves (None: at rest or cruising for ever)."""
        now = self.clock.now()
        times = [t for seg in self.axis.segments() for t in (seg.t0, seg.t1) if now < t < math.inf]
        return min(times, default=None)

    # -- speeds ---------------------------------------------------------------------------------
    def override_pct(self) -> float:
        return self.feed.override_pct(float(self.signals.get("override_pot")))

    def enable_blocked(self) -> bool:
        """N51 = 1 and E0.0 at 0 V: the indexer is not enabled (spec §4.2.4)."""
        return self.params.enable_input == 1 and not self.signals.get("E0.0")

    def speed(self, feed: tuple[int, int] | None = None) -> float:
        """The commanded speed now for the running plan (0: hold); ``feed`` as for
        :meth:`Feed.work_speed` (default: the next move's feed once braking for its junction)."""
        fd = self.feed
        if feed is None and self._junction_braking:
            feed = self.junction_feed
        if self.image.marker(0, 0) or self.enable_blocked():
            return 0.0  # M0.0 STOP, or no enable (N51: "alle Fahrten", the spindle simulation too)
        if self.kind == "search":
            v = float(fd.S)
        elif self.kind == "spindle":
            v = min(self.spindle_speed, float(fd.M)) * self.override_pct() / 100.0
        elif self.kind == "rapid_nv":
            v = float(fd.eeprom_M) * self.override_pct() / 100.0
        else:
            v = min(fd.work_speed(feed) * self.override_pct() / 100.0, float(fd.M))
        if self.max_speed is not None:
            v = min(v, self.max_speed)
        vf = fd.v_factor()
        return vf * math.floor(v / vf + 1e-9) if self.kind in ("work", "rapid_nv") else v

    def accel(self) -> tuple[float, RampProfile | None]:
        """(axis acceleration, profile): sin² with peak a = 1000·B needs the axis' raised cosine
        with average 2a/π (spec §5.3: T = π/2·Δv/a)."""
        a = 1000.0 * self.feed.B
        if self.params.ramp_type == 1:
            return a * 2.0 / math.pi, _SINE
        return a, None

    # -- commands -------------------------------------------------------------------------------
    def go(self, target: float, kind: str = "work", on_arrive: Callable[[], None] | None = None) -> None:
        self.target = float(target)
        self.jog_dir = 0
        self.kind = kind
        self.on_arrive = on_arrive
        self.replan()

    def run(self, direction: int, kind: str) -> None:
        """Endless run (reference search, spindle simulation)."""
        self.target = None
        self.jog_dir = direction
        self.kind = kind
        self.on_arrive = None
        self.replan()

    def replan(self) -> None:
        """Re-plan from the exact current state after any change of speed, override or STOP."""
        if self.target is None and self.jog_dir == 0:
            return
        if self.comp_phase and not self.axis.moving:
            self._cancel_backlash()  # the axis was stopped under the compensation (torque abort)
        direction = self._direction()
        if self.comp_phase == "dwell" or (self.comp_phase == "brake" and direction == self.comp_dir):
            return  # the compensation re-plans when it is over
        self._cancel_backlash()
        v = self.speed()
        acc, profile = self.accel()
        if v <= 0.0:
            self.axis.stop(acc, profile=profile, speed=max(abs(self.axis.velocity()), 1.0))
        elif self._needs_backlash(direction):
            self.comp_dir = direction
            if self.axis.velocity() != 0.0:  # still running the other way: brake first
                self.comp_phase = "brake"
                self.axis.stop(acc, self._backlash_dwell, profile=profile, speed=max(abs(self.axis.velocity()), 1.0))
            else:
                self._backlash_dwell()
        else:
            if self.target is not None:
                self.axis.move_to(self.target, v, acc, on_done=self._arrived, profile=profile)
            else:
                self.axis.jog(self.jog_dir, v, acc, profile=profile)
            if direction:
                self.last_dir = direction
        self.card.record_event("replan")
        self.arm_following_error()
        self._arm_junction()

    # -- blending junctions (spec §5.4) ---------------------------------------------------------
    def set_junction(self, x: float | None, feed: tuple[int, int] | None = None) -> None:
        """The running chain passes ``x`` where the next move's ``feed`` takes over; if that is
        slower, the set-point brakes before ``x`` and passes it at the new speed."""
        if self._junction_watch is not None:
            self._junction_watch.cancel()
            self._junction_watch = None
        self.junction = x
        self.junction_feed = feed if x is not None else None
        self._junction_braking = False
        if x is not None:
            self._arm_junction()

    def _arm_junction(self) -> None:
        if self._junction_watch is not None:
            self._junction_watch.cancel()
            self._junction_watch = None
        x = self.junction
        if x is None or self._junction_braking or self.target is None or self.kind != "work":
            return
        v_now, v_next = self.speed(), self.speed(self.junction_feed)
        if v_next >= v_now:
            return
        pos = self.axis.position()
        s = 1 if x > pos else -1
        brake = x - s * (v_now * v_now - v_next * v_next) / (2.0 * self.accel()[0])
        if (brake - pos) * s <= 0:
            self._junction_brake()
            return
        self._junction_watch = self.axis.watch(brake, lambda side: side == s and self._junction_brake())

    def _junction_brake(self) -> None:
        self._junction_watch = None
        self._junction_braking = True
        self.replan()

    def final_braking(self) -> bool:
        """The plan is in its last deceleration to standstill (too late to blend a next move)."""
        return self.axis.phase() == "decel" and not self._junction_braking

    # -- backlash compensation (spec §5.8) ------------------------------------------------------
    def _direction(self) -> int:
        """The way the running plan wants the set-point to go (0: nowhere)."""
        if self.target is None:
            return self.jog_dir
        x, v = self.axis.position(), self.axis.velocity()
        if v != 0.0:  # a target short of the braking point means: brake and come back
            s = 1 if v > 0 else -1
            stop = x + v * abs(v) / (2.0 * self.accel()[0])
            return s if (self.target - stop) * s >= 0 else -s
        d = self.target - x
        return (d > 0) - (d < 0)

    def _needs_backlash(self, direction: int) -> bool:
        return self.params.backlash > 0 and direction != 0 and self.last_dir != 0 and direction != self.last_dir

    def backlash_time(self) -> float:
        """N41 increments at N42 inc/ms: N41/N42 ms."""
        return self.params.backlash / (max(self.params.backlash_speed, 1) * 1000.0)

    def _backlash_dwell(self) -> None:
        """The motor takes up the slack while the set-point (counter, ``T0``, the load) stands:
        for the axis a standstill that still counts as motion."""
        self.comp_phase = "dwell"
        self.card.record_event("backlash")
        self.axis.dwell(self.backlash_time(), self._backlash_done)

    def _backlash_done(self) -> None:
        self.last_dir = self.comp_dir
        self.comp_dir = 0
        self.comp_phase = ""
        self.replan()

    def _cancel_backlash(self) -> None:
        self.comp_dir = 0
        self.comp_phase = ""

    def _arrived(self) -> None:
        self.target = None
        callback, self.on_arrive = self.on_arrive, None
        self.arm_following_error()
        if callback is not None:
            callback()

    def halt(self, on_stopped: Callable[[], None] | None = None) -> None:
        """Decelerate with the programmed ramp (abort, #0); ``on_stopped`` at standstill."""
        self.target = None
        self.jog_dir = 0
        self.on_arrive = None
        self._cancel_backlash()
        acc, profile = self.accel()
        if self.axis.moving:
            self.axis.stop(acc, on_stopped, profile=profile, speed=max(abs(self.axis.velocity()), 1.0))
        elif on_stopped is not None:
            self.clock.call_later(0.0, on_stopped)
        self.arm_following_error()

    def power_off(self, brake: bool) -> None:
        """Current off: the axis stops within ``brake_stop_ms`` where it is (spec §5.13)."""
        self.target = None
        self.jog_dir = 0
        self.on_arrive = None
        self._cancel_backlash()
        v = abs(self.axis.velocity())
        ms = self.geometry.brake_stop_ms
        if self.blocked_at is not None or v == 0.0 or ms <= 0 or not brake or self._past_end_stop():
            actual = self.actual()
            self.axis.quick_stop()
            if not self.axis.moving:
                self.axis.set_position(actual)
        else:
            self.axis.stop(v / (ms / 1000.0))
        self.arm_following_error()

    # -- position loop (spec §5.7) --------------------------------------------------------------
    def kv(self) -> float:
        return max(self.geometry.kv_per_n10 * self.params.position_gain, 1e-6)

    def following_error(self) -> float:
        if not self.stage.controller:
            return 0.0
        if self.blocked_at is not None:
            return self.axis.position() - self.blocked_at
        if self.stepper:
            return 0.0
        x = self.axis.position()
        return x - self._end_stop(x - self.axis.velocity() / self.kv())

    def actual(self) -> float:
        if self.blocked_at is not None:
            return self.blocked_at
        if not self.stage.controller:
            return self._end_stop(self.axis.position())
        return self.axis.position() - self.following_error()

    def _end_stop(self, x: float) -> float:
        """The mechanics end where the end stops are (spec §5.11 b); a stepper card does not see
        it (no feedback)."""
        stops = self.geometry.end_stops
        if stops is None or self.stepper:
            return x
        return min(max(x, stops[0]), stops[1])

    def _past_end_stop(self) -> bool:
        x = self.axis.position()
        return self._end_stop(x) != x

    def at_end_stop(self) -> bool:
        """The axis presses against an end stop: the set-point is past it (with the lag) — the
        set-point itself too, or it only leaves a stop the axis stands at."""
        stops = self.geometry.end_stops
        if self.blocked_at is not None or not self.stage.controller or stops is None or self.stepper:
            return False
        return _pressing(self.axis.position(), self.axis.velocity(), stops, self.kv())

    def end_stop_contact(self) -> float | None:
        """The first instant >= now at which the actual position (set-point - v/Kv) reaches an end
        stop under the current plan (None: not in this plan)."""
        stops = self.geometry.end_stops
        if stops is None or self.stepper or not self.stage.controller or self.blocked_at is not None:
            return None
        return _end_stop_contact(self.axis.segments(), self.clock.now(), stops, self.kv())

    def block(self, active: bool) -> None:
        if active and self.blocked_at is None:
            self.blocked_at = self.actual()
        elif not active and self.blocked_at is not None:
            self.blocked_at = None
        self.arm_following_error()

    def arm_following_error(self) -> None:
        """Schedule the following-error trip as an event: a crossing of the set-point past the
        blockage (or an end stop) ± N20, or the instant the planned speed exceeds N20·Kv.  The
        plan-dependent H7 and in-position events are re-armed with it."""
        self.card.plan_changed()
        self.arm_actual_watches()
        if self._fe_timer is not None:
            self._fe_timer.cancel()
            self._fe_timer = None
        for w in self._fe_watches:
            w.cancel()
        self._fe_watches = []
        if not self.stage.controller or self.stepper:
            return
        limit = float(self.params.following_error_limit)
        if self.blocked_at is not None:
            hold = self.blocked_at
            if abs(self.axis.position() - hold) > limit:
                self.clock.call_later(0.0, lambda: self.card.following_error_fault("blocked"))
                return
            self._fe_watches.append(self.axis.watch(hold + limit + 1e-6, lambda s: s > 0 and self._trip()))
            self._fe_watches.append(self.axis.watch(hold - limit, lambda s: s < 0 and self._trip()))
            return
        stops = self.geometry.end_stops
        if stops is not None:
            lo, hi = stops
            self._fe_watches.append(self.axis.watch(hi + limit + 1e-6, lambda s: s > 0 and self._trip()))
            self._fe_watches.append(self.axis.watch(lo - limit, lambda s: s < 0 and self._trip()))
        when = _speed_exceeds(self.axis.segments(), self.clock.now(), limit * self.kv())
        if when is not None:
            self._fe_timer = self.clock.call_at(when, self._trip)

    # -- the actual position as a function of time (switches, index marks) -----------------------
    def actual_now(self) -> float:
        """:meth:`actual` (kept for the watches' first state)."""
        return self.actual()

    def actual_function(self) -> Callable[[Segment | None, float], float] | None:
        """``f(seg, t)``: the actual position at ``t`` under plan segment ``seg`` (``None``: the
        plan's rest position) -- the same model as :meth:`actual`; ``None``: it stands still."""
        if self.blocked_at is not None:
            return None
        rest = self.axis.final_position()
        if not self.stage.controller:
            return lambda seg, t: self._end_stop(seg.position(t) if seg is not None else rest)
        if self.stepper:
            return lambda seg, t: seg.position(t) if seg is not None else rest
        kv = self.kv()
        return lambda seg, t: self._end_stop(seg.position(t) - seg.velocity(t) / kv if seg is not None else rest)

    def watch_actual_index(self, callback: Callable[[int], None]) -> ActualWatch:
        """Like :meth:`Axis.watch_index` on the actual position (the encoder sees the motor)."""
        rule = IndexRule(float(self.axis.counts_per_rev), self.axis.index_offset)
        return ActualWatch(self, rule, callback, jump_fires=False)

    def arm_actual_watches(self) -> None:
        for w in list(self._actual_watches):
            w.arm()

    def add_watch(self, watch: ActualWatch) -> None:
        self._actual_watches.append(watch)

    def remove_watch(self, watch: ActualWatch) -> None:
        self._actual_watches.remove(watch)

    def _trip(self) -> None:
        self.card.following_error_fault("speed" if self.blocked_at is None else "blocked")

    def state(self) -> dict[str, Any]:
        return {
            "target": self.target,
            "kind": self.kind,
            "run": self.jog_dir,
            "speed": self.speed() if (self.target is not None or self.jog_dir) else 0.0,
            "override": self.override_pct(),
            "blocked_at": self.blocked_at,
            "backlash": {"side": self.last_dir, "phase": self.comp_phase},
        }


class ActualWatch:
    """A crossing watch on the actual position (spec §5.6, §5.11: set-point - v/Kv, held by a blockage or an end
    stop), solved per planned segment like :meth:`Indexer.end_stop_contact`: closed form while
    cruising, a fine subdivision plus bisection on ramps (linear and sin²).

    Direction tracking: a crossing counts only in the direction the set-point moves (or at
    standstill).  The static lag model makes the actual dip backwards at the start of a move
    (and forwards at the start of a reversal) -- the real position loop never moves the motor
    against its set-point, so such a dip must not flicker a switch or count an index mark.
    ``jump_fires``: a jump of the actual at a re-arm (teleport, N10 change, power off) fires the
    callback (switches); otherwise the zone is silently re-synchronised (index marks)."""

    _STEPS = 64

    def __init__(self, indexer: Indexer, rule: Rule, callback: Callable[[int], None], jump_fires: bool) -> None:
        self.indexer = indexer
        self.rule = rule
        self.callback = callback
        self.jump_fires = jump_fires
        self.state = rule.state_of(indexer.actual_now())
        self._timer: Timer | None = None
        self._gen = -1
        self.cancelled = False
        indexer.add_watch(self)
        self.arm()

    def cancel(self) -> None:
        if self.cancelled:
            return
        self.cancelled = True
        self._unschedule()
        self.indexer.remove_watch(self)

    def _unschedule(self) -> None:
        if self._timer is not None:
            self._timer.cancel()
        self._timer = None

    def _changed(self, x: float, v: float) -> int:
        """+1/-1: the actual ``x`` (set-point speed ``v``) is a valid crossing out of the zone."""
        zone = self.rule.state_of(x)
        if zone == self.state:
            return 0
        d = 1 if zone > self.state else -1
        return d if v == 0.0 or (v > 0) == (d > 0) else 0

    def arm(self) -> None:
        """(Re)compute the next crossing under the current plan."""
        self._unschedule()
        if self.cancelled:
            return
        ix = self.indexer
        axis = ix.axis
        clock = ix.clock
        now = clock.now()
        self._gen = axis.plan_generation
        f = ix.actual_function()
        if f is None or not axis.moving:
            zone = self.rule.state_of(ix.actual_now())
            if zone != self.state:  # the actual jumped (teleport, N10, power off) or stands there
                if self.jump_fires:
                    self._schedule(now, 1 if zone > self.state else -1, zone)
                else:
                    self.state = zone
            return
        end = None
        for seg in axis.segments():
            if seg.t1 <= now:
                continue
            t0 = max(seg.t0, now)
            d = self._changed(f(seg, t0), seg.velocity(t0))
            if d:
                self._schedule(t0, d)
                return
            if seg.t1 == math.inf:
                self._cruise(seg, t0, f)
                return
            found = self._search(seg, t0, f)
            if found is not None:
                self._schedule(*found)
                return
            end = seg.t1
        if end is not None:
            d = self._changed(f(None, end), 0.0)
            if d:
                self._schedule(end, d)

    def _cruise(self, seg: Segment, t0: float, f: Callable[[Segment | None, float], float]) -> None:
        v = seg.velocity(t0)
        if v == 0.0:
            return
        border = self.rule.up(self.state) if v > 0 else self.rule.down(self.state)
        if border is None:
            return
        x0 = f(seg, t0)
        t = t0 + (border[0] - x0) / v
        t = max(t, t0)
        # the end stops may hold the actual short of the border
        if self._changed(f(seg, t + 1e-9 * max(1.0, abs(t))), v) or self._changed(f(seg, t), v):
            self._schedule(t, 1 if v > 0 else -1)

    def _search(self, seg: Segment, t0: float, f: Callable[[Segment | None, float], float]) -> tuple[float, int] | None:
        def test(t: float) -> int:
            return self._changed(f(seg, t), seg.velocity(t))

        prev = t0
        for k in range(1, self._STEPS + 1):
            t = t0 + (seg.t1 - t0) * k / self._STEPS
            if test(t):
                a, b = prev, t
                for _ in range(60):
                    mid = 0.5 * (a + b)
                    if test(mid):
                        b = mid
                    else:
                        a = mid
                return b, test(b)
            prev = t
        return None

    def _schedule(self, when: float, direction: int, zone: int | None = None) -> None:
        def fire() -> None:
            self._timer = None
            if self.cancelled:
                return
            if self.indexer.axis.plan_generation != self._gen:
                self.arm()  # the plan changed under the watch without a re-arm
                return
            self.state = self.state + direction if zone is None else zone
            self.arm()
            self.callback(direction)

        self._timer = self.indexer.clock.call_at(when, fire)


class ActualSwitch(RegionSwitch):
    """:class:`~devsim.core.axis.RegionSwitch` on the actual position: active while
    low <= actual <= high (spec §5.11); ``on_change(active)`` at the solved instant."""

    def __init__(self, indexer: Indexer, low: float, high: float, on_change: Callable[[bool], None] | None = None) -> None:
        super().__init__(
            indexer.axis, low, high, on_change,
            make_watch=lambda rule, callback: ActualWatch(indexer, rule, callback, jump_fires=True),
        )


def _pressing(x: float, v: float, stops: tuple[float, float], kv: float) -> bool:
    """Set-point ``x`` at speed ``v`` presses into an end stop: the actual (x - v/Kv) and the
    set-point are past the same stop (a set-point leaving a stop the axis stands at lags behind
    it: the actual estimate x - v/Kv lies past the stop, but the controller pulls away)."""
    lo, hi = stops
    actual = x - v / kv
    return (actual > hi and x > hi) or (actual < lo and x < lo)


def _end_stop_contact(segments: list[Segment], now: float, stops: tuple[float, float], kv: float) -> float | None:
    """The first instant >= ``now`` at which set-point - v/Kv leaves ``stops`` under the plan
    ``segments`` and the set-point presses into that stop (:func:`_pressing`): closed form while
    cruising, sign changes on a fine subdivision then bisection."""

    def outside(seg: Segment, t: float) -> bool:
        return _pressing(seg.position(t), seg.velocity(t), stops, kv)

    for seg in segments:
        if seg.t1 <= now:
            continue
        t0 = max(seg.t0, now)
        if outside(seg, t0):
            return t0
        if seg.t1 == math.inf:  # a cruise: the actual moves linearly
            v = seg.velocity(t0)
            edge = stops[1] if v > 0 else stops[0]
            if v == 0.0:
                return None
            t = t0 + (edge - (seg.position(t0) - v / kv)) / v
            return t if t >= t0 else None
        steps = 64
        prev = t0
        for k in range(1, steps + 1):
            t = t0 + (seg.t1 - t0) * k / steps
            if outside(seg, t):
                a, b = prev, t
                for _ in range(60):
                    mid = 0.5 * (a + b)
                    if outside(seg, mid):
                        b = mid
                    else:
                        a = mid
                return b
            prev = t
    return None


def _speed_exceeds(segments: list[Segment], now: float, vmax: float) -> float | None:
    """The first instant >= ``now`` at which the planned speed exceeds ``vmax`` (bisection)."""
    for seg in segments:
        if seg.t1 <= now:
            continue
        t0 = max(seg.t0, now)
        t1 = seg.t1 if seg.t1 < math.inf else t0 + 1.0
        if abs(seg.velocity(t0)) > vmax:
            return t0
        if abs(seg.velocity(t1)) > vmax:
            lo, hi = t0, t1
            for _ in range(60):
                mid = 0.5 * (lo + hi)
                if abs(seg.velocity(mid)) > vmax:
                    hi = mid
                else:
                    lo = mid
            return hi
    return None
