"""Output pacing: a device's answer reaches the host at the speed of the wire.

The k-th character of a burst is released ``k`` character times
(:meth:`~devsim.core.device.SerialSettings.char_time`) after the device started sending it, and a
burst starts no earlier than the previous one has left, as a UART's transmitter does it; the
releases go through the device clock's ``call_later`` (see :class:`~devsim.transports.line.Line`,
``pacing=True``).
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable

from devsim.core.clock import Clock, Timer

__all__ = ["Pacer"]

# A real receiver accepts a byte that arrives a hair early or late; a timer may fire a few
# nanoseconds before its nominal time.  Bytes due within this margin are released.
EPSILON = 1e-7


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
    released bytes on towards the host."""

    __slots__ = ("clock", "char_time", "deliver", "queue", "free_at", "timer")

    def __init__(self, clock: Clock, char_time: Callable[[], float], deliver: Callable[[bytes], None]) -> None:
        self.clock = clock
        self.char_time = char_time
        self.deliver = deliver
        self.queue: deque[_Burst] = deque()
        self.free_at = 0.0
        self.timer: Timer | None = None

    @property
    def pending(self) -> int:
        """Bytes queued and not yet released."""
        return sum(len(b.data) - b.sent for b in self.queue)

    def put(self, data: bytes, chars: int) -> None:
        """Send ``data``, ``chars`` characters long on the wire."""
        now = self.clock.now()
        start = max(now, self.free_at)
        duration = chars * self.char_time()
        self.free_at = start + duration
        self.queue.append(_Burst(data, start, duration))
        if self.timer is None:
            self._schedule()

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
