"""The keep-alive clock of devsim's MQTT links (OASIS MQTT 5.0, 3.1.2.10 Keep Alive): one daemon
thread per process calls each link's ping in the link's own loop when it is due.

Not a timer in the loop: while any timer is scheduled, asyncio computes a select timeout at every
loop turn (a clock read, ``min``, ``max`` and ``math.ceil``: about 5 k instructions), and a fleet
member's loop turns once per request.  Without a timer of its own a member's idle loop waits
with no timeout at all.  A keep-alive counts the broker's real seconds, not the device clock's
(nothing here waits for the simulation), as the loop's ``call_later`` did.

The thread is the process's, not a device's: it holds only the due calls (a link's next ping,
every 0.75 keep-alive intervals), each dropped once made; a call whose loop has closed is
dropped too.
"""

from __future__ import annotations

import asyncio
import contextlib
import heapq
import itertools
import os
import threading
import time
from collections.abc import Callable

__all__ = ["KeepAliveClock", "keepalive_clock"]


class KeepAliveClock:
    """Calls in a loop's thread at a ``time.monotonic()`` moment, kept by a thread of their own."""

    def __init__(self) -> None:
        self._due: list[tuple[float, int, asyncio.AbstractEventLoop, Callable[[], None]]] = []  # a heap
        self._order = itertools.count()  # (equal moments: in the order asked)
        self._changed = threading.Condition()
        self._thread: threading.Thread | None = None

    def call_at(self, when: float, loop: asyncio.AbstractEventLoop, callback: Callable[[], None]) -> None:
        """``callback()`` in ``loop``'s thread at ``when`` (``time.monotonic()``) or just after."""
        with self._changed:
            heapq.heappush(self._due, (when, next(self._order), loop, callback))
            if self._thread is None:
                self._thread = threading.Thread(target=self._run, name="devsim-mqtt-keepalive", daemon=True)
                self._thread.start()
            elif self._due[0][0] == when:  # sooner than what the thread waits for
                self._changed.notify()

    def _run(self) -> None:
        due = self._due
        with self._changed:
            while True:
                now = time.monotonic()
                while due and due[0][0] <= now:
                    _when, _order, loop, callback = heapq.heappop(due)
                    with contextlib.suppress(RuntimeError):  # the loop has closed: its links are gone
                        loop.call_soon_threadsafe(callback)
                self._changed.wait(due[0][0] - now if due else None)


_CLOCK = KeepAliveClock()
os.register_at_fork(after_in_child=_CLOCK.__init__)  # (a forked child has no thread: it starts its own)


def keepalive_clock() -> KeepAliveClock:
    """The process's keep-alive clock (its thread starts with the first call asked of it)."""
    return _CLOCK
