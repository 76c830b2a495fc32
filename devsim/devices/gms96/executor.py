"""The command executor: queued (CNC) commands in order, BUSY, waits and blending.

What each command does is :mod:`.commands` (the executor runs it through the ``run`` it is
given).  Manual §2.3.1 (queued letter commands), §2.4.3 (PLC direct commands p10), §2.5 (CNC
programs); spec §4.2.2 (executor states), §4.2.4 (motion preconditions: a move while IDXOFF = 1 is skipped),
§4.2.5 (queue capacity), §5.4 (blending: consecutive moves in one direction are one plan to the
chain's last target; a move inside the chain completes when the set-point crosses its end point,
so SETO/RESO/SNDF/SNDM between them act "on the fly", the chain's last move when the set-point
stops; a slower f/G0 between two moves is reached by braking before the junction), §5.5 (H2:
in position per N27/N28; H7: armed for the next move only, consumed when it ends).
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Callable
from typing import Any, Protocol

import msgspec

from devsim.core.axis import Axis, Watch
from devsim.core.clock import Clock, Timer
from devsim.devices.gms96 import tables
from devsim.devices.gms96.coordinates import Coordinates
from devsim.devices.gms96.counter import CounterInput
from devsim.devices.gms96.feed import Feed
from devsim.devices.gms96.motion import Indexer
from devsim.devices.gms96.params import NParameters
from devsim.devices.gms96.reference import ReferenceRun


class CardEvents(Protocol):
    """What the executor asks of its card (spec §4.2.4): whether a move may start, and that it tells others."""

    def can_move(self) -> bool: ...
    def changed(self) -> None: ...
    def record_event(self, name: str) -> None: ...
    def arm_torque_abort(self) -> None: ...
    def programs_ended(self) -> None: ...


__all__ = ["Cmd", "Executor", "TRANSPARENT_P10"]

TRANSPARENT_P10 = frozenset({16, 17, 28, 29})  # SETO RESO SNDF SNDM keep blending (M §2.4.3)
MOVES = frozenset("A+")


class Cmd(msgspec.Struct, frozen=True):
    """One queued command (manual §2.3.1): letter, P1..P3 and how many parameters were sent."""

    letter: str
    p1: int = 0
    p2: int = 0
    p3: int = 0
    n: int = 0
    program: int | None = None  # a program's row, or its "_end" marker: that program (None: the host's)

    def as_list(self) -> list[Any]:
        return [self.letter, self.p1, self.p2, self.p3, self.n]


def transparent(cmd: Cmd) -> bool:
    """Commands that do not break move blending (spec §5.4)."""
    return (
        cmd.letter == "f"
        or (cmd.letter == "G" and cmd.p1 == 0)
        or (cmd.letter == "p" and cmd.p1 == 10 and cmd.p2 in TRANSPARENT_P10)
    )


class Executor:
    """FIFO of queued commands and the one command being executed (spec §4.2.2), the moves and
    their blending (spec §5.4), the H7 arming (spec §5.5)."""

    def __init__(
        self,
        *,
        clock: Clock,
        indexer: Indexer,
        counter: CounterInput,
        feed: Feed,
        coordinates: Coordinates,
        params: NParameters,
        card: CardEvents,
        run: Callable[[Cmd], bool],
        queue_capacity: int,
    ) -> None:
        self.clock = clock
        self.indexer = indexer
        self.counter = counter
        self.feed = feed
        self.coordinates = coordinates
        self.params = params
        self.card = card
        #: Carries out one command; True if it is complete at once (:mod:`.commands`).
        self.run = run
        self.queue_capacity = queue_capacity
        self.waiting_in_position = False  # H2 waits (M3.5)
        self.queue: deque[Cmd] = deque()
        self.deferred: deque[tuple[Cmd, Callable[[], None]]] = deque()
        self.current: Cmd | None = None
        self.waiting: Callable[[], bool] | None = None
        self.wait_name = ""
        self.reference: ReferenceRun | None = None
        self.rejected_moves = 0
        self.program_depth = 0
        self.h7_level: int | None = None
        self.h7_in_move = False  # the running move is the one H7 armed (spec §5.5)
        self.last_target: float | None = None
        self._timer: Timer | None = None
        #: When the condition of :meth:`wait` may change by itself (None: only when the card changes).
        self._changes_at: Callable[[], float | None] | None = None
        self._watch: Watch | None = None
        self._running = False

    # -- state --------------------------------------------------------------------------------
    @property
    def busy(self) -> bool:
        return self.current is not None or bool(self.queue)

    @property
    def full(self) -> bool:
        """The host's commands fill the queue; a running program's rows come from the FLASH (M §1.5)."""
        return sum(c.program is None for c in self.queue) >= self.queue_capacity

    # -- input --------------------------------------------------------------------------------
    def submit(self, cmd: Cmd) -> None:
        self.queue.append(cmd)
        self._maybe_extend_chain()
        self.kick()

    def defer(self, cmd: Cmd, reply: Callable[[], None]) -> None:
        self.deferred.append((cmd, reply))

    def _release_deferred(self) -> None:
        while self.deferred and not self.full:
            cmd, reply = self.deferred.popleft()
            self.queue.append(cmd)
            reply()

    # -- the loop -----------------------------------------------------------------------------
    def kick(self) -> None:
        if self._running:
            return
        self._running = True
        try:
            while self.current is None and self.queue:
                cmd = self.queue.popleft()
                self._release_deferred()
                self.current = cmd
                if self.run(cmd):
                    self.current = None
        finally:
            self._running = False
        self._release_deferred()

    def complete(self) -> None:
        """The current command finished; go on with the next."""
        self._clear_wait()
        if self.h7_in_move:  # H7 applies to the next move only: that move is over (spec §5.5)
            self.h7_in_move = False
            self.h7_level = None
        self.current = None
        self.kick()
        self.card.changed()

    def poke(self) -> None:
        """Something changed (marker, input, speed): re-check the wait condition."""
        if self.waiting is not None and self.current is not None:
            if self.waiting():
                self.complete()
            else:
                self._arm_recheck()

    def wait(
        self, name: str, condition: Callable[[], bool], changes_at: Callable[[], float | None] | None = None
    ) -> bool:
        """Wait until ``condition`` holds, re-checked whenever the card changes; ``changes_at``
        names the next instant the condition may change by itself (a status bit that follows
        the motion), when it is checked again too."""
        if condition():
            return True
        self.waiting = condition
        self.wait_name = name
        self._changes_at = changes_at
        self._arm_recheck()
        return False

    def _arm_recheck(self) -> None:
        if self._changes_at is None:
            return
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None
        when = self._changes_at()
        if when is not None and math.isfinite(when):
            self._timer = self.clock.call_later(max(0.0, when - self.clock.now()), self._recheck)

    def _recheck(self) -> None:
        self._timer = None
        self.poke()

    def h7_active(self) -> float | None:
        """The torque-abort level (fraction of Imax) while the armed move runs, else None."""
        if self.h7_level is None or not self.h7_in_move:
            return None
        return self.h7_level / 100.0

    def disarm_h7(self) -> None:
        """The torque abort fired: the level is spent."""
        self.h7_level = None

    def torque_aborted(self) -> None:
        """H7 stopped the axis: the move it armed is complete (another command goes on)."""
        if self.current is not None and self.current.letter in "A+vw":
            self.complete()
        else:
            self.h7_in_move = False

    def _clear_wait(self) -> None:
        self.waiting = None
        self._changes_at = None
        self.wait_name = ""
        self.waiting_in_position = False
        ix = self.indexer
        if ix.on_arrive == self._arrival:
            ix.on_arrive = None
        ix.set_junction(None)
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None
        if self._watch is not None:
            self._watch.cancel()
            self._watch = None

    def after(self, seconds: float, name: str) -> bool:
        self.wait_name = name
        self._timer = self.clock.call_later(seconds, self.complete)
        return False

    def _discard(self) -> None:
        """Forget the queue, deferred acknowledgements (sent now), programs, H7 and Q runs."""
        self.queue.clear()
        for _cmd, reply in self.deferred:
            reply()
        self.deferred.clear()
        self.program_depth = 0
        self.card.programs_ended()
        self.h7_level = None
        self.h7_in_move = False
        if self.reference is not None:
            self.reference.abort()
            self.reference = None

    def abort(self) -> None:
        """#0 / M0.1: discard the queue, end the running command (spec §4.2.3)."""
        self._discard()
        self._clear_wait()
        cur, self.current = self.current, None
        if self.counter.stop_sync():  # m49 ends: the set-point brakes with the ramp
            self.current = Cmd("_halt")
            self.indexer.halt(self.complete)
        elif cur is not None and (cur.letter in MOVES or cur.letter in "vwQ"):
            self.current = Cmd("_halt")
            self.indexer.halt(self.complete)
        elif self.indexer.target is not None:
            self.indexer.halt()
        self.card.changed()

    def flush(self) -> None:
        """A fault: the queue is gone and the executor idle at once (spec §4.5.3)."""
        self._discard()
        self.counter.sync = False  # a fault ends m49 (the fault stops the axis itself)
        self._clear_wait()
        self.current = None

    # -- moves ----------------------------------------------------------------------------------
    def _target_of(self, cmd: Cmd, base: float) -> float:
        p1 = max(tables.POSITION_MIN, min(tables.POSITION_MAX, cmd.p1))
        if cmd.letter == "+" or (cmd.letter == "A" and self.coordinates.g_relative):
            return base + p1
        return self.coordinates.work_to_physical(p1)

    def move(self, cmd: Cmd, blend: bool = True) -> bool:
        """``A``, ``+``, ``v``: a move to the command's target (``blend``: one plan with the
        blendable moves queued behind it, spec §5.4); rejected unless the card can move."""
        card = self.card
        if not card.can_move():
            self.rejected_moves += 1
            card.record_event("move_rejected")
            return True
        ix = self.indexer
        base = self.last_target if (ix.target is not None and self.last_target is not None) else ix.axis.position()
        x = self._target_of(cmd, base)
        self.last_target = x
        if self.h7_level is not None:
            self.h7_in_move = True  # this move carries the H7 arming (spec §5.5)
        if self.params.motion_disabled == 1:  # N17: the move runs in time only (M3.4)
            shadow = Axis(self.clock, position=ix.axis.position())
            acc, profile = ix.accel()
            end = shadow.move_to(x, max(ix.speed(), 1.0), acc, profile=profile)
            return self.after(end - self.clock.now(), "N17")
        if not ix.axis.moving and ix.axis.position() == x:
            self._consume_h7()
            return True  # already there (a blended move behind it starts from rest)
        final = self._chain_end(x) if blend else x
        if ix.target != final or not ix.axis.moving:
            ix.go(final, "work")
            card.record_event("move_start")
        self._complete_at(x)
        self._plan_junction(x)
        card.arm_torque_abort()
        return False

    def _consume_h7(self) -> None:
        if self.h7_in_move:
            self.h7_in_move = False
            self.h7_level = None

    def _complete_at(self, x: float) -> None:
        """Complete the running move when the set-point reaches ``x``: on arrival if ``x`` ends the
        plan (exactly when the set-point stops, either direction), else when the set-point passes
        the junction ``x`` on the fly (spec §5.4)."""
        ix = self.indexer
        if self._watch is not None:
            self._watch.cancel()
            self._watch = None
        if ix.on_arrive == self._arrival:
            ix.on_arrive = None
        if ix.target == x:
            ix.on_arrive = self._arrival  # also while held (STOP, override 0): arrival comes later
            return
        direction = 1 if x >= ix.axis.position() else -1
        point = x if direction > 0 else x + 1e-6

        def crossed(side: int) -> None:
            if side == direction and self.current is not None:
                self._arrival()

        self._watch = ix.axis.watch(point, crossed)

    def _arrival(self) -> None:
        if self.current is not None and (self.current.letter in MOVES or self.current.letter in "vw"):
            self.card.record_event("move_end")
            self.complete()

    def _plan_junction(self, x: float) -> None:
        """Spec §5.4: a slower speed for the next blended move (``f``/``G0`` between the moves) is
        reached *at* the junction ``x``: the indexer brakes before it."""
        ix = self.indexer
        if ix.target is None or ix.target == x:
            ix.set_junction(None)
            return
        feed = self.feed
        f, frac = feed.f, feed.f_frac
        for cmd in self.queue:
            if cmd.letter in MOVES:
                break
            if cmd.letter == "f":
                f, frac = feed.clamp_feed(cmd.p1, cmd.p2)
            elif cmd.letter == "G" and cmd.p1 == 0:
                f = feed.M
        if (f, frac) == (feed.f, feed.f_frac):
            ix.set_junction(None)
        else:
            ix.set_junction(x, (f, frac))

    def _chain_end(self, x: float) -> float:
        """Last target of the blendable moves queued behind the current one (spec §5.4)."""
        ix = self.indexer
        start = ix.axis.position()
        direction = 1 if x > start else -1
        end = x
        for cmd in self.queue:
            if transparent(cmd):
                continue
            if cmd.letter not in MOVES:
                break
            nxt = self._target_of(cmd, end)
            if (nxt - end) * direction <= 0:
                break
            end = nxt
        return end

    def _maybe_extend_chain(self) -> None:
        cur = self.current
        ix = self.indexer
        if cur is None or cur.letter not in MOVES or ix.target is None or not ix.axis.moving:
            return
        if ix.final_braking():
            return  # too late: the move stops, the next one starts from rest
        if self.last_target is None:
            return
        new_end = self._chain_end(self.last_target)
        if new_end != ix.target:
            ix.go(new_end, "work")
            self._complete_at(self.last_target)
            self._plan_junction(self.last_target)
            self.card.arm_torque_abort()

    def state(self) -> dict[str, Any]:
        return {
            "current": self.current.as_list() if self.current else None,
            "waiting": self.wait_name,
            "queue_length": len(self.queue),
            "deferred": len(self.deferred),
            "rejected_moves": self.rejected_moves,
            "reference": self.reference.phase if self.reference else None,
        }
