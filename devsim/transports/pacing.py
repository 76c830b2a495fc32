"""Output pacing: a device's answer reaches the host at the speed of the wire.

The k-th character of a burst is released ``k`` character times
(:meth:`~devsim.core.device.SerialSettings.char_time`) after the device started sending it, and a
burst starts no earlier than the previous one has left, as a UART's transmitter does it; the
releases go through the device clock's ``call_later`` (see :class:`~devsim.transports.line.Line`,
``pacing=True``).

A host on a pty or a socket sends faster than the wire could carry (its bytes are not paced), so an
echoing device's output can pile up faster than it leaves: a transmitter holds at most
:data:`MAX_PENDING` bytes, and the oldest beyond that are dropped (and the ones after them moved up
on the wire), as a transport drops output nobody reads.  Without the bound a flood of garbage was
echoed for hours at 9600 baud, every later answer behind it, and the queue grew without end.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable

from devsim.core.clock import Clock, Timer

__all__ = ["Pacer"]

# A real receiver accepts a byte that arrives a hair early or late; a timer may fire a few
# nanoseconds before its nominal time.  Bytes due within this margin are released.
EPSILON = 1e-7
#: Bytes a transmitter holds at most before it drops the oldest (a transport's ``max_buffer``; at
#: 9600 baud a minute of output, more than any answer a host asks for).  [SIM-CHOICE] no manual
#: says what a device does with more output than its wire carries: on a real line it cannot
#: receive faster than that wire either.
MAX_PENDING = 64 * 1024


class _Burst:
    """Device output on its way over the wire: ``data`` spread over ``duration`` seconds."""

    __slots__ = ("data", "start", "per_byte", "sent")

    def __init__(self, data: bytes, start: float, duration: float) -> None:
        self.data = data
        self.start = start
        self.per_byte = duration / len(data)
        self.sent = 0

    def due(self, index: int) -> float:
        return self.start + (index + 1) * self.per_byte


class Pacer:
    """The transmitter of a paced line: bursts queued and released character by character.

    ``char_time()`` is the device's character time of the moment, ``deliver(data)`` hands the
    released bytes on towards the host; beyond ``max_pending`` bytes queued the oldest are dropped
    (counted in :attr:`dropped`)."""

    __slots__ = ("clock", "char_time", "deliver", "queue", "free_at", "timer", "max_pending", "pending", "dropped")

    def __init__(self, clock: Clock, char_time: Callable[[], float], deliver: Callable[[bytes], None],
                 max_pending: int = MAX_PENDING) -> None:
        self.clock = clock
        self.char_time = char_time
        self.deliver = deliver
        self.queue: deque[_Burst] = deque()
        self.free_at = 0.0
        self.timer: Timer | None = None
        self.max_pending = max_pending
        #: Bytes queued and not yet released
        self.pending = 0
        #: Bytes dropped because more than ``max_pending`` were queued
        self.dropped = 0

    def put(self, data: bytes, chars: int) -> None:
        """Send ``data``, ``chars`` characters long on the wire."""
        now = self.clock.now()
        start = max(now, self.free_at)
        duration = chars * self.char_time()
        self.free_at = start + duration
        self.queue.append(_Burst(data, start, duration))
        self.pending += len(data)
        if self.pending > self.max_pending:
            self._drop(self.pending - self.max_pending)
        if self.timer is None:
            self._schedule()

    def _drop(self, excess: int) -> None:
        """Drop the oldest ``excess`` bytes not yet released; what follows them on the wire moves
        up by their time (the next byte leaves when the first one dropped would have)."""
        queue, shift, head = self.queue, 0.0, None
        while excess > 0:
            burst = queue[0]
            n = min(len(burst.data) - burst.sent, excess)
            burst.sent += n
            burst.start -= shift + n * burst.per_byte
            shift += n * burst.per_byte
            excess -= n
            self.pending -= n
            self.dropped += n
            if burst.sent < len(burst.data):
                head = burst  # (moved up already)
            else:
                queue.popleft()
        for burst in queue:
            if burst is not head:
                burst.start -= shift
        self.free_at -= shift

    def _schedule(self) -> None:
        burst = self.queue[0]
        due = burst.due(burst.sent)
        self.timer = self.clock.call_later(due - self.clock.now(), self._release)

    def _release(self) -> None:
        self.timer = None
        now = self.clock.now() + EPSILON
        out = bytearray()
        while self.queue:
            burst = self.queue[0]
            n = len(burst.data)
            k = burst.sent
            while k < n and burst.due(k) <= now:
                k += 1
            out += burst.data[burst.sent : k]
            self.pending -= k - burst.sent
            burst.sent = k
            if k < n:
                break
            self.queue.popleft()
        if out:
            self.deliver(bytes(out))
        if self.queue:
            self._schedule()

    def close(self) -> None:
        """Drop what is still on the wire."""
        if self.timer is not None:
            self.timer.cancel()
            self.timer = None
        self.queue.clear()
        self.pending = 0
