"""The shared closed-form axis model.

Implements design.md principle 2, *physics is closed-form and event-driven*: an :class:`Axis` is a
list of :class:`Segment` objects (constant acceleration, or a raised-cosine "sine" velocity ramp);
its position, velocity and acceleration at any instant are computed from that list, never
integrated tick by tick.  Reaching a target, crossing a switch position (:meth:`Axis.watch`,
:class:`RegionSwitch`) or passing the encoder's index mark (:meth:`Axis.watch_index`) are events
whose times are solved per segment (a quadratic; a safeguarded Newton iteration on a sine segment)
and scheduled as timers on the device's :class:`~devsim.core.clock.Clock` (principle 3).  An axis
at rest schedules no timers at all.

Ramp shapes (SERS P1032/P1005–P1008, spec §5.2) are described by a :class:`RampProfile`, passed to
:meth:`Axis.move_to`, :meth:`Axis.jog` and :meth:`Axis.stop`; without one the ramps are plain
constant-acceleration ramps.

Units are the device's raw units: positions in increments, velocities in inc/s, accelerations in
inc/s²; unit scaling is the device's business.

The :class:`Axis` holds the state (its plan, the recent past, the done timer) and the commands;
the phases of a move, jog or stop are planned by the pure functions of :mod:`devsim.core.planner`,
and the crossing watches are solved and scheduled by :class:`~devsim.core.crossing.Watches`.

Plans are built so that every segment is monotonic in position (a reversal is split at v = 0);
a crossing is therefore detected by comparing the watch's *stored* side with the segment's end
position, which keeps event firing exact under floating point: a crossing is never reported twice
and never lost because a re-plan happened at the crossing instant.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import msgspec

from devsim.core.clock import Clock, Timer
from devsim.core.crossing import CrossingCallback, Watch, Watches
from devsim.core.planner import jog_phases, move_phases, move_phases_profiled, stop_phases
from devsim.core.profile import (
    HISTORY,
    REL_T,
    IndexRule,
    Phase,
    PhaseSpec,
    RampProfile,
    RangeRule,
    Rule,
    Segment,
    Shape,
    make_ramp,
    sign,
)

__all__ = ["Axis", "IndexRule", "Phase", "RampProfile", "RangeRule", "RegionSwitch", "Rule", "Segment", "Shape", "Watch"]


Callback = Callable[[], None]


# --------------------------------------------------------------------------------------------
# the axis


class Axis:
    """One simulated axis: a plan of constant-acceleration segments on a clock.

    ``counts_per_rev`` and ``index_offset`` place the encoder's index marks for
    :meth:`watch_index`.  All commands re-plan from the exact current state (position and velocity
    stay continuous); a new command supersedes the previous plan, its ``on_done`` and its timers.
    """

    #: Not the axis's state (a snapshot of a device leaves it out): the plan generation only
    #: tells a plan's timers from an older plan's.
    not_state = frozenset({"_gen"})

    def __init__(
        self,
        clock: Clock,
        *,
        position: float = 0.0,
        counts_per_rev: int = 12800,
        index_offset: float = 0.0,
        name: str = "axis",
    ) -> None:
        if counts_per_rev <= 0:
            raise ValueError("counts_per_rev must be positive")
        self.clock = clock
        self.name = name
        self.counts_per_rev = counts_per_rev
        self.index_offset = index_offset
        self._plan: list[Segment] = []
        self._rest = float(position)  # where the plan ends (or where the idle axis stands)
        self._idle_since = clock.now()
        self._history: list[Segment] = []  # the last HISTORY segments (a list: no block until used)
        self._watches = Watches(clock)
        self._gen = 0  # bumped by every plan change; stale timers and loops check it
        self._done_timer: Timer | None = None
        self._on_done: Callback | None = None
        self._vref: float | None = None  # speed of the last move_to/jog: a profile's reference V

    def __repr__(self) -> str:
        return f"<Axis {self.name} x={self.position():.3f} v={self.velocity():.3f} {self.phase()}>"

    # -- state ---------------------------------------------------------------------------------
    def _state(self, t: float | None) -> tuple[float, float, float]:
        return self._lookup(t)[:3]

    def _lookup(self, t: float | None) -> tuple[float, float, float, Segment | None]:
        """``(position, velocity, acceleration, segment)`` at ``t``; the segment is the one moving
        the axis at ``t`` (None at rest)."""
        if t is None:
            t = self.clock.now()
        plan = self._plan
        if plan and t >= plan[0].t0:
            for seg in plan:
                if t < seg.t1:
                    return seg.position(t), seg.velocity(t), seg.acceleration(t), seg
            return self._rest, 0.0, 0.0, None
        if not plan and t >= self._idle_since:
            return self._rest, 0.0, 0.0, None
        for seg in reversed(self._history):  # the recent past
            if t >= seg.t0:
                if t < seg.t1:
                    return seg.position(t), seg.velocity(t), seg.acceleration(t), seg
                return seg.position(seg.t1), seg.velocity(seg.t1), 0.0, None
        first = self._history[0] if self._history else (plan[0] if plan else None)
        if first is None:
            return self._rest, 0.0, 0.0, None
        return first.x0, first.v0, 0.0, None

    def position(self, t: float | None = None) -> float:
        """Position at ``t`` (default: now)."""
        return self._state(t)[0]

    def velocity(self, t: float | None = None) -> float:
        return self._state(t)[1]

    def acceleration(self, t: float | None = None) -> float:
        return self._state(t)[2]

    def _plan_end(self) -> float:
        return self._plan[-1].t1 if self._plan else self._idle_since

    @property
    def moving(self) -> bool:
        """True while a plan with motion remains (including an instant of v = 0 at a reversal)."""
        return bool(self._plan) and self.clock.now() < self._plan[-1].t1

    def stopped_since(self) -> float | None:
        """When the axis came to rest (the end of its last plan); None while it moves."""
        return None if self.moving else self._plan_end()

    def remembered_since(self) -> float:
        """The earliest instant the axis still answers for from its history (``position(t)``
        of an instant before it gives where the history starts); ``inf`` for an axis that has
        never moved (it has no past but its standing)."""
        history, plan = self._history, self._plan
        if history:
            return history[0].t0
        return plan[0].t0 if plan else math.inf

    def phase(self, t: float | None = None) -> Phase:
        """``idle``, ``accel`` (|v| increasing), ``const`` (cruising) or ``decel``."""
        _, v, a, seg = self._lookup(t)
        if seg is not None and seg.shape == "sine":
            # a raised cosine starts and ends with zero acceleration: its average decides
            return "accel" if sign(seg.a) == seg.direction else "decel"
        if a == 0.0:
            return "const" if v != 0.0 else "idle"
        if v == 0.0 or sign(a) == sign(v):
            return "accel"
        return "decel"

    def stopping_distance(
        self, decel: float, profile: RampProfile | None = None, *, speed: float | None = None
    ) -> float:
        """Distance needed to brake from the current velocity with ``decel``: v²/(2·decel), or
        with ``profile`` the sum over its sections (reference speed as for :meth:`stop`)."""
        if not decel > 0:  # also refuses NaN
            raise ValueError("decel must be positive")
        v = self.velocity()
        ramp = make_ramp(profile, self._reference_speed(speed, v), decel) if v != 0.0 else None
        if ramp is not None:
            return ramp.distance(0.0, abs(v))
        return v * v / (2.0 * decel)

    def _reference_speed(self, speed: float | None, v: float) -> float:
        if speed is not None:
            if not speed > 0:
                raise ValueError("speed must be positive")
            return float(speed)
        return self._vref if self._vref is not None else abs(v)

    def final_position(self) -> float:
        """Where the current plan comes to rest; ±inf while a jog cruises for ever."""
        if self._plan and self._plan[-1].t1 == math.inf:
            return math.inf * self._plan[-1].v0
        return self._rest

    def segments(self, since: float | None = None) -> list[Segment]:
        """The current plan (empty when idle); ``since``: with the remembered past, all running after it."""
        return list(self._plan) if since is None else [s for s in (*self._history, *self._plan) if s.t1 > since]

    # -- commands ------------------------------------------------------------------------------
    def move_to(
        self,
        target: float,
        speed: float,
        accel: float,
        decel: float | None = None,
        on_done: Callback | None = None,
        *,
        profile: RampProfile | None = None,
    ) -> float:
        """Plan from the current state to stand still exactly at ``target``; returns the end time.

        Trapezoid or triangle with ``|v| <= speed``, accelerating with ``accel`` and braking with
        ``decel`` (default ``accel``).  Moving away from the target, or too fast to stop before
        it, first brakes to zero (with ``decel``) and comes back; faster than ``speed`` first
        slows to ``speed`` with ``decel``.  ``on_done`` runs from a clock timer on arrival.

        ``profile`` shapes every ramp by its speed sections (fractions of ``speed``; the bases
        are ``accel`` and ``decel``); a triangle's peak speed is solved exactly within the right
        section.  From a moving state the ramps start at the current speed, inside whatever
        section it lies in; with ``shape="sine"`` every piece (also such a partial first piece,
        from the current velocity) is a raised cosine, so the acceleration may jump at the re-plan
        instant while position and velocity stay continuous.
        """
        decel = accel if decel is None else decel
        if not (speed > 0 and accel > 0 and decel > 0):
            raise ValueError("speed, accel and decel must be positive")
        if not math.isfinite(target):
            raise ValueError("target must be finite")
        now = self.clock.now()
        x_now, v_now, _ = self._state(now)
        self._vref = float(speed)
        acc_ramp = make_ramp(profile, speed, accel)
        dec_ramp = make_ramp(profile, speed, decel)
        if acc_ramp is not None and dec_ramp is not None:
            phases = move_phases_profiled(x_now, v_now, target, speed, acc_ramp, dec_ramp)
        else:
            phases = move_phases(x_now, v_now, target, speed, accel, decel)
        return self._install(now, x_now, v_now, phases, target, on_done)

    def jog(
        self,
        direction: int,
        speed: float,
        accel: float,
        on_done: Callback | None = None,
        *,
        profile: RampProfile | None = None,
    ) -> None:
        """Ramp with ``accel`` to velocity ``sign(direction)*speed`` and cruise for ever.

        ``on_done`` runs (from a clock timer) when the cruise speed is reached.  ``direction == 0``
        is a ramped :meth:`stop` with ``accel``.  ``profile`` shapes the ramps (sections are
        fractions of ``speed``, base ``accel``), as for :meth:`move_to`.
        """
        if not (speed > 0 and accel > 0):
            raise ValueError("speed and accel must be positive")
        if direction == 0:
            self.stop(accel, on_done, profile=profile, speed=speed)
            return
        now = self.clock.now()
        x0, v0, _ = self._state(now)
        self._vref = float(speed)
        vt = sign(direction) * float(speed)
        phases = jog_phases(v0, vt, speed, accel, make_ramp(profile, speed, accel))
        self._install(now, x0, v0, phases, None, on_done, cruise=vt)

    def stop(
        self,
        decel: float,
        on_done: Callback | None = None,
        *,
        profile: RampProfile | None = None,
        speed: float | None = None,
    ) -> float:
        """Ramp the velocity to 0 with ``decel``; returns the time the axis stands still.

        ``profile`` brakes through its sections (base ``decel``); their speeds are fractions of
        ``speed``, by default the speed of the last :meth:`move_to`/:meth:`jog` (the current
        |velocity| if there was none).
        """
        if not decel > 0:  # also refuses NaN
            raise ValueError("decel must be positive")
        now = self.clock.now()
        x0, v0, _ = self._state(now)
        ramp = make_ramp(profile, self._reference_speed(speed, v0), decel) if v0 != 0.0 else None
        phases = stop_phases(v0, decel, ramp)
        return self._install(now, x0, v0, phases, None, on_done)

    def quick_stop(self) -> None:
        """Velocity 0 at once at the current position (torque off); the old on_done is dropped."""
        now = self.clock.now()
        x0 = self._state(now)[0]
        self._install(now, x0, 0.0, [], x0, None)

    def set_position(self, position: float) -> None:
        """Teleport a standing axis (power-on restore, setting the actual position).

        Point watches and region switches whose side changes are called; index watches are
        re-synchronised silently.  Raises :class:`RuntimeError` while moving.
        """
        if self.moving:
            raise RuntimeError(f"{self.name}: set_position while moving")
        now = self.clock.now()
        self._archive(now)
        self._cancel_plan()
        self._plan = []
        self._rest = float(position)
        self._idle_since = now
        self._gen += 1
        self._watches.settle(self._rest, teleport=True)

    # -- watches -------------------------------------------------------------------------------
    def watch(self, position: float, callback: CrossingCallback) -> Watch:
        """Call ``callback(+1)`` when the axis becomes ``>= position``, ``callback(-1)`` when it
        becomes ``< position`` again (each time, exactly at the solved instant)."""
        return self._add_watch(RangeRule(float(position), math.inf), callback, teleport_fires=True)

    def watch_index(self, callback: CrossingCallback) -> Watch:
        """Like :meth:`watch` for every index mark ``k*counts_per_rev + index_offset``."""
        return self._add_watch(
            IndexRule(float(self.counts_per_rev), self.index_offset), callback, teleport_fires=False
        )

    def _add_watch(self, rule: Rule, callback: CrossingCallback, teleport_fires: bool) -> Watch:
        return self._watches.add(rule, callback, teleport_fires, self.position())

    # -- planning machinery --------------------------------------------------------------------
    def _archive(self, now: float) -> None:
        """Keep the part of the old plan that lies in the past, for queries of past instants."""
        history = self._history
        for seg in self._plan:
            if seg.t0 >= now:
                break
            # a segment already over is kept as it is (frozen); the running one ends now
            history.append(seg if seg.t1 <= now else msgspec.structs.replace(seg, t1=now))
        end = self._plan_end()
        if end < now:
            history.append(Segment(end, now, self._rest, 0.0, 0.0))
        if len(history) > HISTORY:
            del history[: len(history) - HISTORY]

    def _cancel_plan(self) -> None:
        if self._done_timer is not None:
            self._done_timer.cancel()
        self._done_timer = None
        self._on_done = None

    def dwell(self, seconds: float, on_done: Callable[[], None] | None = None) -> None:
        """A standstill that is part of a plan: ``moving`` stays true for ``seconds`` while the
        position does not change (a card's planned dwell); ``on_done`` at its end."""
        x = self.position()
        self._install(self.clock.now(), x, 0.0, [(0.0, seconds, 0.0, "linear")], x, on_done)

    @property
    def plan_generation(self) -> int:
        """Bumped by every change of plan: a watch armed under an older one must re-arm."""
        return self._gen

    def follow(self, pieces: list[tuple[float, Any]], on_done: Callback | None = None) -> float:
        """Follow a path's component (:mod:`devsim.core.path`) from now: ``pieces`` of
        ``(duration, curve)``, each monotonic in position, the first starting where the axis
        stands; it ends at rest where the last piece ends.  Returns the end time."""
        now = self.clock.now()
        segs: list[Segment] = []
        t = now
        for duration, curve in pieces:
            x0, v0, a0 = curve.state(0.0)
            segs.append(Segment(t, t + duration, x0, v0, a0, "curve", duration, curve))
            t += duration
        rest = pieces[-1][1].state(pieces[-1][0])[0] if pieces else self.position(now)
        self._vref = None
        return self._set_plan(now, segs, rest, on_done, t, t)

    def track(self, position: float, velocity: float) -> None:
        """The axis is moved by a sampled loop (a servo chip computing its samples in batches):
        it is at ``position`` now and goes on at ``velocity`` until the loop's next report
        corrects it; ``velocity`` 0 stands it still.  Watches and switches fire on that
        extrapolation, so within one report of the exact instant."""
        now = self.clock.now()
        if velocity == 0.0:
            self._install(now, position, 0.0, [], position, None)
        else:
            self._install(now, position, velocity, [], None, None, cruise=velocity)

    def _install(
        self,
        now: float,
        x0: float,
        v0: float,
        phases: list[PhaseSpec],
        rest: float | None,
        on_done: Callback | None,
        cruise: float | None = None,
    ) -> float:
        """Replace the plan with ``phases`` from ``(now, x0, v0)``; ``rest`` is the exact end
        position (``None``: wherever the phases end).  ``cruise`` appends an endless segment."""
        segs: list[Segment] = []
        t, x, v = now, x0, v0
        for a, dur, v_end, shape in phases:
            if dur > REL_T * max(1.0, abs(t)):
                if shape == "linear" or a == 0.0:
                    segs.append(Segment(t, t + dur, x, v, a))
                else:
                    segs.append(Segment(t, t + dur, x, v, a, "sine", dur))
                x += 0.5 * (v + v_end) * dur
                t += dur
            v = v_end
        ramp_end = t
        if cruise is not None and cruise != 0.0:
            segs.append(Segment(t, math.inf, x, cruise, 0.0))
            t = math.inf
        return self._set_plan(now, segs, x if rest is None or cruise is not None else rest, on_done, t, ramp_end)

    def _set_plan(self, now: float, segs: list[Segment], rest: float, on_done: Callback | None, t: float,
                  ramp_end: float) -> float:
        """Make ``segs`` the plan from ``now``, ending at ``rest`` at ``t`` (``inf``: a cruise)."""
        self._archive(now)
        self._cancel_plan()
        self._gen += 1
        gen = self._gen
        self._plan = segs
        self._rest = rest
        if not segs:
            self._idle_since = now
        self._on_done = on_done
        if t < math.inf and segs:
            self._done_timer = self.clock.call_at(t, lambda: self._finish(gen))
        elif on_done is not None:  # already there, or a jog reaching its cruise speed
            self._done_timer = self.clock.call_at(ramp_end, lambda: self._run_done(gen))
        if segs:
            self._watches.follow(segs, rest)
        else:
            self._watches.settle(rest)
        return t if t < math.inf else ramp_end

    def _run_done(self, gen: int) -> None:
        if gen != self._gen:
            return
        self._done_timer = None
        on_done, self._on_done = self._on_done, None
        if on_done is not None:
            on_done()

    def _finish(self, gen: int) -> None:
        """The plan's last segment ended: stand still at the exact end position."""
        if gen != self._gen:
            return
        self._done_timer = None
        on_done, self._on_done = self._on_done, None
        end = self._plan[-1].t1
        self._archive(end)
        self._plan = []
        self._idle_since = end
        self._gen += 1
        gen = self._gen
        self._watches.settle(self._rest)
        if gen == self._gen and on_done is not None:
            on_done()


class RegionSwitch:
    """A switch (limit, reference cam) that is active while low <= position <= high (either bound
    may be +/-inf).  ``on_change(active)`` runs at the exact instant the axis enters or leaves the
    region, however fast it moves.

    ``make_watch(rule, callback)`` lets a device watch something other than the axis position
    with the same region logic (the GMS96 watches its actual position, set-point − v/Kv).
    """

    def __init__(
        self,
        axis: Axis,
        low: float,
        high: float,
        on_change: Callable[[bool], None] | None = None,
        *,
        make_watch: Callable[[Rule, CrossingCallback], Any] | None = None,
    ) -> None:
        if low > high:
            raise ValueError("low must not exceed high")
        self.axis = axis
        self.low = low
        self.high = high
        self.on_change = on_change
        rule = RangeRule(low, high)
        if make_watch is None:
            self._watch = axis._add_watch(rule, self._crossed, teleport_fires=True)
        else:
            self._watch = make_watch(rule, self._crossed)
        self._active = self._watch.state == 1

    @property
    def active(self) -> bool:
        return self._active

    def _crossed(self, direction: int) -> None:
        active = self._watch.state == 1
        if active != self._active:
            self._active = active
            if self.on_change is not None:
                self.on_change(active)

    def cancel(self) -> None:
        self._watch.cancel()
