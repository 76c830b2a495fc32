"""The crossing watches of the closed-form axis (:mod:`devsim.core.axis`).

Crossing a switch position or passing the encoder's index mark is an event (design.md principles
2 and 3): :class:`Watches` solves, per segment of the axis's plan, the instant the position
crosses a :class:`~devsim.core.profile.Rule`'s next border and schedules it as a timer on the
device's :class:`~devsim.core.clock.Clock`; a :class:`Watch` is one registered rule with its
callback.  An axis at rest schedules no timers: when it stops or is teleported,
:meth:`Watches.settle` brings every watch's side in line with the exact rest position at once.

Plans are monotonic in position per segment, so a crossing is detected by comparing the watch's
*stored* side with the segment's end position: it is never reported twice and never lost because
a re-plan happened at the crossing instant.
"""

from __future__ import annotations

import math
from collections.abc import Callable

from devsim.core.clock import Clock, Timer
from devsim.core.profile import RangeRule, Rule, Segment

__all__ = ["CrossingCallback", "Watch", "Watches"]

CrossingCallback = Callable[[int], None]


class Watch:
    """A registered crossing watch (from :meth:`devsim.core.axis.Axis.watch` / ``watch_index``)."""

    def __init__(
        self, watches: Watches, rule: Rule, callback: CrossingCallback, teleport_fires: bool, position: float
    ) -> None:
        self._watches = watches
        self._rule = rule
        self._callback = callback
        self._teleport_fires = teleport_fires
        self._state = rule.state_of(position)
        self._timer: Timer | None = None
        self._token: object | None = None
        self._cancelled = False

    @property
    def cancelled(self) -> bool:
        return self._cancelled

    @property
    def state(self) -> int:
        """The zone of the rule the watched position is in (for a region: 1 = inside)."""
        return self._state

    def cancel(self) -> None:
        """Stop watching; idempotent."""
        if self._cancelled:
            return
        self._cancelled = True
        self._unschedule()
        self._watches._watches.remove(self)

    def _unschedule(self) -> None:
        if self._timer is not None:
            self._timer.cancel()
        self._timer = None
        self._token = None


class Watches:
    """The crossing watches of one axis, scheduled on the plan the axis last handed them.

    The axis calls :meth:`follow` with every new plan that moves and :meth:`settle` whenever it
    comes to rest (a plan without motion, the end of a plan, a teleport); between those calls the
    plan and its rest position are what the watches' timers were solved on.
    """

    #: Not the watches' state (a snapshot of a device leaves it out): the epoch only tells a
    #: settle loop that a callback re-planned.
    not_state = frozenset({"_epoch"})

    def __init__(self, clock: Clock) -> None:
        self._clock = clock
        self._watches: list[Watch] = []
        self._plan: list[Segment] = []  # the axis's plan (the same list), empty at rest
        self._rest = 0.0  # where that plan ends (or where the idle axis stands)
        self._epoch = 0  # bumped by every follow/settle: a settle loop stops when a callback re-plans

    def add(self, rule: Rule, callback: CrossingCallback, teleport_fires: bool, position: float) -> Watch:
        """Watch ``rule`` from ``position`` (where the axis stands now)."""
        w = Watch(self, rule, callback, teleport_fires, position)
        self._watches.append(w)
        self._schedule(w)
        return w

    def follow(self, plan: list[Segment], rest: float) -> None:
        """The axis moves on ``plan`` (not empty), ending at ``rest``: schedule every watch's next
        crossing on it."""
        self._epoch += 1
        self._plan = plan
        self._rest = rest
        for w in list(self._watches):
            self._schedule(w)

    def settle(self, rest: float, *, teleport: bool = False) -> None:
        """The axis stands at ``rest`` (it just stopped, or was ``teleport``-ed there): bring every
        watch's side in line with it, firing the crossings that happened at this instant.  A
        teleport re-synchronises the watches that do not fire on one (index marks) silently."""
        self._epoch += 1
        epoch = self._epoch
        self._plan = []
        self._rest = rest
        if teleport:
            for w in list(self._watches):
                if not w._teleport_fires and not w._cancelled:
                    w._state = w._rule.state_of(rest)
        for w in list(self._watches):
            w._unschedule()
        for w in list(self._watches):
            while not w._cancelled:
                if self._epoch != epoch:
                    return  # a callback re-planned; that re-plan rescheduled everything
                target = w._rule.state_of(self._rest)
                if target == w._state:
                    break
                direction = 1 if target > w._state else -1
                # a range (switch) jumps straight to its new zone: a teleport across a region
                # must not flicker it; index marks are counted one by one
                w._state = target if isinstance(w._rule, RangeRule) else w._state + direction
                w._callback(direction)

    def _schedule(self, w: Watch) -> None:
        w._unschedule()
        if w._cancelled or not self._plan:
            return
        found = self._next_crossing(w, self._clock.now())
        if found is None:
            return
        when, direction = found
        token = object()

        def fire() -> None:
            if w._token is not token or w._cancelled:
                return
            w._timer = None
            w._token = None
            w._state += direction
            self._schedule(w)  # the next crossing; a re-plan in the callback redoes it
            w._callback(direction)

        w._token = token
        w._timer = self._clock.call_at(when, fire)

    def _next_crossing(self, w: Watch, now: float) -> tuple[float, int] | None:
        plan = self._plan
        state = w._state
        for i, seg in enumerate(plan):
            if seg.t1 <= now:
                continue
            d = seg.direction
            if i + 1 < len(plan):
                xe = plan[i + 1].x0
            elif seg.t1 == math.inf:
                xe = d * math.inf
            else:
                xe = self._rest
            if d > 0:
                border = w._rule.up(state)
                if border is not None and (xe > border[0] if border[1] else xe >= border[0]):
                    return crossing_time(seg, border[0], xe, now), +1
            elif d < 0:
                border = w._rule.down(state)
                if border is not None and (xe <= border[0] if border[1] else xe < border[0]):
                    return crossing_time(seg, border[0], xe, now), -1
        return None


def crossing_time(seg: Segment, p: float, xe: float, now: float) -> float:
    """When ``seg`` (ending at ``xe``) reaches ``p``, not before ``now``."""
    if p == xe and seg.t1 < math.inf:
        # ends exactly on p: the root is (near) a double root at a stop, badly conditioned
        # (1 ulp of position is ~1e-8 s); the segment's end time is the exact answer
        return max(seg.t1, now)
    return min(max(seg.solve(p), seg.t0, now), seg.t1)
