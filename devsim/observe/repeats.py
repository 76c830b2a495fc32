"""Repeated log lines, rate-limited: the first of a kind is written, the repeats that follow within
:data:`WINDOW` seconds are counted, and the count is written once the window ends (``devsim:
12.300 cnc v8.v8_parity_error ... repeated 12345 times in the last 5 s``).

A host sending garbage (a bad byte per character on the POSELESTA's V8) would otherwise write a
line per byte.  The key is what the line says, not when: (device, port, message kind), given by
the caller.  The window runs on a wall clock (injectable): the limit protects the reader and the
disk, which live in real time whatever the device clock's speed or a virtual clock's jumps.  Pure:
the caller calls :meth:`RepeatLimiter.due` now and then (every few seconds) while
:attr:`RepeatLimiter.pending` to get the counts.  A line nothing repeated needs no call: its window
ends by itself (the next line of its key is written), so a log whose lines do not repeat (a host's
connect) needs no timer.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Hashable

__all__ = ["WINDOW", "RepeatLimiter"]

#: Seconds after a line during which lines of the same key are counted, not written.
WINDOW = 5.0


class _Run:
    __slots__ = ("count", "start", "text")

    def __init__(self, start: float, text: str) -> None:
        self.start, self.text, self.count = start, text, 0


class RepeatLimiter:
    """Decides which lines are written (see the module docstring); ``clock()`` gives seconds."""

    def __init__(self, window: float = WINDOW, clock: Callable[[], float] = time.monotonic) -> None:
        self.window, self.clock = window, clock
        self._runs: dict[Hashable, _Run] = {}
        self._prune_at = 64  # (the table is pruned of ended windows when it grows past this)

    def counted(self, key: Hashable) -> bool:
        """A line of ``key`` now is a repeat inside its window: counted here, nothing to write
        (a caller asks this first and makes the line's text only for :meth:`offer` when not)."""
        run = self._runs.get(key)
        if run is not None and self.clock() - run.start < self.window:
            run.count += 1
            return True
        return False

    def offer(self, key: Hashable, text: str) -> list[str]:
        """The lines to write for ``text`` of ``key`` now: ``[text]``, a count then ``[text]``
        (the window had ended), or none (a repeat, counted)."""
        now = self.clock()
        run = self._runs.get(key)
        if run is not None and now - run.start < self.window:
            run.count += 1
            return []
        out = [self._count_line(run, now)] if run is not None and run.count else []
        self._runs[key] = _Run(now, text)
        if len(self._runs) > self._prune_at:
            self._prune(now)
        return [*out, text]

    def _prune(self, now: float) -> None:
        """Forget the keys whose window ended with nothing counted (amortised: the next prune
        waits until the table has doubled)."""
        for key, run in list(self._runs.items()):
            if not run.count and now - run.start >= self.window:
                del self._runs[key]
        self._prune_at = max(64, 2 * len(self._runs))

    @property
    def pending(self) -> bool:
        """A repeat has been counted and its count is not written yet: :meth:`due` has something
        to write when its window ends."""
        return any(run.count for run in self._runs.values())

    def due(self) -> list[str]:
        """The counts of the windows that have ended; a key quiet for a whole window is forgotten
        (the table holds only the keys seen in the last window)."""
        now = self.clock()
        out = []
        for key, run in list(self._runs.items()):
            if now - run.start < self.window:
                continue
            if run.count:
                out.append(self._count_line(run, now))
                run.start, run.count = now, 0
            else:
                del self._runs[key]
        return out

    def flush(self) -> list[str]:
        """Every count not yet written (at the end of the log)."""
        now = self.clock()
        out = [self._count_line(run, now) for run in self._runs.values() if run.count]
        self._runs.clear()
        return out

    @staticmethod
    def _count_line(run: _Run, now: float) -> str:
        seconds = max(now - run.start, 0.0)
        return f"{run.text} ... repeated {run.count} times in the last {seconds:.0f} s"
