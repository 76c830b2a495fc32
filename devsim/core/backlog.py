"""Output to a reader that may not read: a file a run writes as it goes (a trace, a motion log, a
recorded session) that is a fifo, a pipe or a terminal (``--trace /dev/stdout | less``,
``--trace >(grep ...)``, a fifo another program opened).

A write into a full pipe blocks, and the whole simulator with it: a trace fifo whose reader stopped
reading froze ``devsim run sers`` after about 460 requests, and SIGTERM could not stop it.  So such
a descriptor is written without waiting (:class:`Backlog`): what the reader has not taken yet waits,
up to :data:`CAP` bytes, and goes out as the reader takes it (the running loop watches the
descriptor while something waits, so a reader that reads late gets it without new traffic); a write
that would overflow that is dropped whole and counted, so the reader gets whole writes only (whole
trace lines, whole pcap records).  A regular file takes every write at once and never needs this.
"""

from __future__ import annotations

import asyncio
import os
import select
import time
from collections.abc import Callable

__all__ = ["CAP", "Backlog"]

#: Bytes that wait at most for a reader that does not read (a trace of a busy line: a few seconds).
CAP = 1 << 20


class Backlog:
    """Writes to descriptor ``fd`` (set non-blocking here) without ever waiting for its reader.

    :meth:`write` sends what the reader takes now and keeps the rest; a write that would make more
    than ``cap`` bytes wait is dropped whole (:attr:`dropped` counts them since the last write that
    was taken).  An error of the descriptor (``EPIPE``: the reader has gone; ``EIO``) is raised by
    :meth:`write`, or, for a write the loop finished later, handed to ``failed``."""

    def __init__(self, fd: int, failed: Callable[[OSError], None], cap: int = CAP) -> None:
        os.set_blocking(fd, False)
        self.fd = fd
        self.cap = cap
        self.dropped = 0
        self._failed = failed
        self._waiting = bytearray()
        self._loop: asyncio.AbstractEventLoop | None = None  # (watching fd while bytes wait)
        self.closed = False

    @property
    def waiting(self) -> int:
        """Bytes written but not yet taken by the reader."""
        return len(self._waiting)

    def write(self, data: bytes) -> bool:
        """Send ``data`` or keep it to send; False when it was dropped (no room) or ``fd`` is closed."""
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
        if self._waiting:
            self._send_waiting()

    def close(self, patience: float = 0.5) -> None:
        """Give the reader up to ``patience`` seconds to take what waits, then close ``fd`` (what is
        left is dropped; an error of the descriptor is raised after it is closed)."""
        if self.closed:
            return
        self.closed = True
        self._unwatch()
        try:
            deadline = time.monotonic() + patience
            poller = select.poll()
            poller.register(self.fd, select.POLLOUT)
            while self._waiting and (left := deadline - time.monotonic()) > 0:
                if poller.poll(left * 1000):
                    self._send_waiting()
        finally:
            self._waiting.clear()
            os.close(self.fd)

    def _send(self, data: bytes | bytearray) -> int:
        try:
            return os.write(self.fd, data)
        except BlockingIOError:
            return 0

    def _send_waiting(self) -> None:
        del self._waiting[: self._send(self._waiting)]

    def _watch(self) -> None:
        if not self._waiting:
            self._unwatch()
        elif self._loop is None:
            try:
                loop = asyncio.get_running_loop()
            except RuntimeError:  # (no loop in this thread: what waits goes with the next write)
                return
            loop.add_writer(self.fd, self._writable)
            self._loop = loop

    def _unwatch(self) -> None:
        if self._loop is not None:
            self._loop.remove_writer(self.fd)
            self._loop = None

    def _writable(self) -> None:
        try:
            self._send_waiting()
        except OSError as exc:
            self._unwatch()
            self._failed(exc)
            return
        self._watch()
