"""Output to a reader that may not read, or not at once: a serving process's lines (its ports, its
log) in a harness's pipe or on a terminal, and a file a run writes as it goes (a trace, a motion
log, a recorded session) that is a fifo or a terminal.

A write into a full pipe blocks, and the whole simulator with it: a harness that started
``devsim run -v`` with ``stderr=PIPE`` and never read it stopped the simulator after about 400
requests, a trace fifo whose reader stopped reading after about 460, and SIGTERM could not stop
either.  Dropping what a full pipe does not take at once is no answer either: a harness that
reads a big plant's port lines as they come is often a little behind, and lost some of them.

So such a descriptor is written without waiting (:class:`Backlog`): what the reader has not taken
yet waits, up to :data:`CAP` bytes, and goes out as the reader takes it (the running loop watches
the descriptor while something waits, so a reader that reads late gets it without new output);
only a write that would make more wait is dropped, whole and counted, so that the reader gets
whole writes (whole lines, whole pcap records).  The descriptor is not made non-blocking (a
terminal's or a pipe's is shared with the shell and the processes that started this one): a
piece of at most ``PIPE_BUF`` bytes goes out only when ``poll`` says the descriptor takes it,
which a pipe with a free page and a terminal not stopped (Ctrl-S) do without waiting.
"""

from __future__ import annotations

import asyncio
import os
import select
import threading
import time
from collections.abc import Callable

__all__ = ["CAP", "Backlog"]

#: Bytes that wait at most for a reader (a 20,000-device plant's port lines; a busy line's trace
#: for a few seconds).
CAP = 1 << 20

_PIECE = select.PIPE_BUF  # (a pipe's write of at most this much is atomic: it never waits for a part)


class Backlog:
    """Writes to descriptor ``fd`` without ever waiting for its reader.

    :meth:`write` sends what the reader takes now and keeps the rest; a write that would make more
    than ``cap`` bytes wait is dropped whole (:attr:`dropped` counts them since the last write that
    was taken).  An error of the descriptor (``EPIPE``: the reader has gone; ``EIO``) is raised by
    :meth:`write`, or, for a write the loop finished later, handed to ``failed``.  :meth:`settle`
    gives the reader a last moment (the end of a run); :meth:`close` also closes ``fd``.  Threads
    may share one (a log line from the web page's thread): each call holds its lock."""

    def __init__(self, fd: int, failed: Callable[[OSError], None], cap: int = CAP) -> None:
        self.fd = fd
        self.cap = cap
        self.dropped = 0
        self.closed = False
        self._failed = failed
        self._waiting = bytearray()
        self._poller = select.poll()
        self._poller.register(fd, select.POLLOUT)
        self._loop: asyncio.AbstractEventLoop | None = None  # (watching fd while bytes wait)
        self._lock = threading.RLock()

    def takes_now(self) -> bool:
        """Whether the descriptor takes a write now (a pipe with a free page, a terminal not stopped)."""
        return bool(self._poller.poll(0))

    @property
    def waiting(self) -> int:
        """Bytes written but not yet taken by the reader."""
        return len(self._waiting)

    def write(self, data: bytes) -> bool:
        """Send ``data`` or keep it to send; False when it was dropped (no room) or ``fd`` is closed."""
        with self._lock:
            return self._write(data)

    def _write(self, data: bytes) -> bool:
        if self.closed:
            return False
        if self._waiting:
            self._send_waiting()
        if len(self._waiting) + len(data) > self.cap:
            self.dropped += 1
            return False
        self.dropped = 0
        if self._waiting:
            self._waiting += data
        else:
            self._waiting += data[self._send(data):]
        self._watch()
        return True

    def flush(self) -> None:
        """Send what waits and the reader takes now (never waits for it)."""
        with self._lock:
            if self._waiting:
                self._send_waiting()
                self._watch()

    def settle(self, patience: float) -> None:
        """Give the reader up to ``patience`` seconds to take what waits; what is left is dropped
        (an error of the descriptor is raised)."""
        with self._lock:
            self._unwatch()
            try:
                deadline = time.monotonic() + patience
                while self._waiting and (left := deadline - time.monotonic()) > 0:
                    if self._poller.poll(left * 1000):
                        self._send_waiting()
            finally:
                self._waiting.clear()

    def close(self, patience: float = 0.5) -> None:
        """:meth:`settle`, then close ``fd``."""
        if self.closed:
            return
        self.closed = True
        try:
            self.settle(patience)
        finally:
            os.close(self.fd)

    def _send(self, data: bytes | bytearray) -> int:
        sent = 0
        while sent < len(data) and self.takes_now():
            try:
                sent += os.write(self.fd, data[sent:sent + _PIECE])
            except BlockingIOError:  # (a descriptor someone else set non-blocking, filled meanwhile)
                break
        return sent

    def _send_waiting(self) -> None:
        del self._waiting[: self._send(self._waiting)]

    def _watch(self) -> None:
        if not self._waiting:
            self._unwatch()
        elif self._loop is None:
            try:
                loop = asyncio.get_running_loop()
                loop.add_writer(self.fd, self._writable)
            except (RuntimeError, OSError):  # (no loop in this thread, or one that cannot watch
                return  # this descriptor: what waits goes with the next write)
            self._loop = loop

    def _unwatch(self) -> None:
        loop, self._loop = self._loop, None
        if loop is None or loop.is_closed():
            return
        try:
            here = asyncio.get_running_loop()
        except RuntimeError:
            here = None
        if here is loop:
            loop.remove_writer(self.fd)
        else:  # (another thread's loop watches: it is told, not touched)
            try:
                loop.call_soon_threadsafe(loop.remove_writer, self.fd)
            except RuntimeError:  # (it closed meanwhile)
                pass

    def _writable(self) -> None:
        with self._lock:
            try:
                self._send_waiting()
            except OSError as exc:
                self._unwatch()
                self._failed(exc)
                return
            self._watch()
