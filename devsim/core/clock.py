"""The one clock every device waits on.

Three flavours share one interface:

* :class:`RealClock` – wall time of the asyncio loop, optionally scaled by a speed factor
  (``--speed 10`` makes a ten-second move take one second);
* :class:`VirtualClock` – simulated time that only moves when told to (:meth:`VirtualClock.advance`)
  or, in *auto* mode, jumps straight to the next scheduled event whenever the loop has nothing
  else to do.

Everything in devsim that waits (motion events, timeouts, program delays) goes through
:meth:`Clock.call_at` / :meth:`Clock.call_later` / :meth:`Clock.sleep`; nothing uses
``time.time()``, ``threading.Timer`` or a bare ``asyncio.sleep``.  Callbacks run in the thread of
the device's event loop.
"""

from __future__ import annotations

import asyncio
import heapq
import itertools
from abc import ABC, abstractmethod
from collections.abc import Callable
from typing import Any

from devsim.core.changes import CHANGES

__all__ = ["Clock", "RealClock", "Timer", "VirtualClock", "speed_problem"]


class Timer:
    """A scheduled callback; :meth:`cancel` is idempotent."""

    __slots__ = ("when", "callback", "cancelled", "_handle", "_seq")

    def __init__(self, when: float, callback: Callable[[], Any], seq: int = 0) -> None:
        self.when = when
        self.callback = callback
        self.cancelled = False
        self._handle: asyncio.TimerHandle | None = None
        self._seq = seq

    def cancel(self) -> None:
        self.cancelled = True
        if self._handle is not None:
            self._handle.cancel()
            self._handle = None

    def __lt__(self, other: Timer) -> bool:
        return (self.when, self._seq) < (other.when, other._seq)

    def __repr__(self) -> str:  # pragma: no cover - debugging aid
        state = "cancelled" if self.cancelled else "pending"
        return f"<Timer at {self.when:.6f} {state} {self.callback!r}>"


class Clock(ABC):
    """Simulated time in seconds since the clock was created."""

    @abstractmethod
    def now(self) -> float:
        """Current simulated time."""

    @abstractmethod
    def call_at(self, when: float, callback: Callable[[], Any]) -> Timer:
        """Run ``callback`` when simulated time reaches ``when`` (at once if already past)."""

    def call_later(self, delay: float, callback: Callable[[], Any]) -> Timer:
        return self.call_at(self.now() + max(0.0, delay), callback)

    async def sleep(self, delay: float) -> None:
        """Wait ``delay`` simulated seconds."""
        loop = asyncio.get_running_loop()
        fut: asyncio.Future[None] = loop.create_future()

        def wake() -> None:
            if not fut.done():
                fut.set_result(None)

        timer = self.call_later(delay, wake)
        try:
            await fut
        finally:
            timer.cancel()

    @property
    def virtual(self) -> bool:
        return False


def speed_problem(speed: float) -> str | None:
    """What is wrong with ``speed`` as a speed factor (``must be positive``, ``must be finite``),
    or None.  A NaN or infinite one passed ``speed <= 0``: the device time was NaN, and a
    real-time scenario never reached its timeout."""
    if not speed > 0:
        return "must be positive"
    if speed == float("inf"):
        return "must be finite"
    return None


class RealClock(Clock):
    """Wall-clock time of the running asyncio loop times ``speed``.

    Must be used from the loop's thread (the loop is looked up when first needed).
    """

    def __init__(self, speed: float = 1.0) -> None:
        if (problem := speed_problem(speed)) is not None:
            raise ValueError(f"speed {problem}")
        self.speed = speed
        self._loop: asyncio.AbstractEventLoop | None = None
        self._origin = 0.0

    def _get_loop(self) -> asyncio.AbstractEventLoop:
        if self._loop is None:
            self._loop = asyncio.get_running_loop()
            self._origin = self._loop.time()
        return self._loop

    def now(self) -> float:
        loop = self._get_loop()
        return (loop.time() - self._origin) * self.speed

    def call_at(self, when: float, callback: Callable[[], Any]) -> Timer:
        loop = self._get_loop()
        timer = Timer(when, callback)

        def fire() -> None:
            timer._handle = None
            if not timer.cancelled:
                timer.cancelled = True  # a timer fires once
                CHANGES.count += 1  # (a door: devsim.core.changes)
                callback()

        timer._handle = loop.call_at(self._origin + when / self.speed, fire)
        return timer


class VirtualClock(Clock):
    """Simulated time that moves only by :meth:`advance`, or by itself in *auto* mode.

    ``advance(dt)`` runs every timer due up to ``now + dt`` in time order, setting ``now`` to
    each timer's time before its callback runs, so a callback sees exactly the instant it was
    scheduled for.  Callbacks may schedule further timers; those due within the window run too.

    In auto mode (:meth:`start_auto`) the clock watches the loop: whenever the loop has been idle
    for one turn, time jumps to the next pending timer.  That is what scenario runs use when they
    script the host as well.
    """

    def __init__(self, start: float = 0.0) -> None:
        self._now = start
        # (when, sequence, timer): the heap compares tuples in C, not Timer.__lt__ in Python
        self._heap: list[tuple[float, int, Timer]] = []
        self._seq = itertools.count()
        self._auto_task: asyncio.Task[None] | None = None
        self._listeners: list[Callable[[], None]] = []

    @property
    def virtual(self) -> bool:
        return True

    def now(self) -> float:
        return self._now

    def call_at(self, when: float, callback: Callable[[], Any]) -> Timer:
        seq = next(self._seq)
        timer = Timer(max(when, self._now), callback, seq)
        heapq.heappush(self._heap, (timer.when, seq, timer))
        for listener in self._listeners:
            listener()
        return timer

    def next_event(self) -> float | None:
        """Time of the earliest pending timer, or ``None``."""
        heap = self._heap
        while heap and heap[0][2].cancelled:
            heapq.heappop(heap)
        return heap[0][0] if heap else None

    def _run_due(self, limit: float) -> int:
        heap = self._heap
        ran = 0
        while heap:
            when, _seq, timer = heap[0]
            if timer.cancelled:
                heapq.heappop(heap)
                continue
            if when > limit:
                break
            heapq.heappop(heap)
            if when > self._now:
                self._now = when
            timer.cancelled = True
            CHANGES.count += 1  # (a door: devsim.core.changes)
            timer.callback()
            ran += 1
        return ran

    def advance(self, seconds: float) -> int:
        """Move time forward by ``seconds``, running due timers; returns how many ran."""
        if seconds < 0:
            raise ValueError("time does not run backwards")
        target = self._now + seconds
        ran = self._run_due(target)
        self._now = max(self._now, target)
        return ran

    def advance_to(self, when: float) -> int:
        return self.advance(max(0.0, when - self._now))

    def run_until(self, predicate: Callable[[], bool], timeout: float) -> bool:
        """Jump from event to event until ``predicate()`` holds or ``timeout`` simulated
        seconds have passed; returns the predicate's final value."""
        deadline = self._now + timeout
        while not predicate():
            when = self.next_event()
            if when is None or when > deadline:
                self._now = max(self._now, deadline)
                return predicate()
            self._run_due(when)
        return True

    # -- auto mode -------------------------------------------------------------------------
    def start_auto(self) -> None:
        """Jump to the next event whenever the running loop is otherwise idle."""
        if self._auto_task is None:
            self._auto_task = asyncio.get_running_loop().create_task(self._auto())

    def stop_auto(self) -> None:
        if self._auto_task is not None:
            self._auto_task.cancel()
            self._auto_task = None

    async def _auto(self) -> None:
        loop = asyncio.get_running_loop()
        wake = asyncio.Event()
        self._listeners.append(wake.set)
        try:
            while True:
                # Let every ready callback and task run (two turns: tasks woken by the
                # previous turn get their chance too) before time is allowed to jump.
                for _ in range(2):
                    await asyncio.sleep(0)
                ready = getattr(loop, "_ready", None)
                if ready:
                    continue
                when = self.next_event()
                if when is None:
                    wake.clear()
                    await wake.wait()
                    continue
                self._run_due(when)
        finally:
            self._listeners.remove(wake.set)
