"""The line: what a real serial cable does between a transport and a device.

A :class:`Line` sits between a transport (pty, TCP, RFC 2217) and its target – a
:class:`~devsim.core.device.Device` or a :class:`~devsim.core.bus.Bus`.  It is the transport's
:class:`~devsim.transports.base.Endpoint` and the target's byte sink, and adds three things a
plain byte pipe does not have:

* **Line settings mismatch.**  When the host opened its port with other line settings than the
  device's UART is configured for (another baud rate, data bits, parity or stop bits), neither
  side receives what the other sent.  :func:`garble` models this at bit level: the sender's
  waveform (start bit, data bits LSB first, parity, stop bits, idle high) is sampled by a
  receiver running at its own rate and frame format, exactly as a UART does it.  Until a
  transport reports the host's settings (:meth:`Line.host_settings`) the host is assumed to
  match – a raw TCP client never reports any.
* **Output pacing** (``pacing=True``).  The device's answer reaches the host at the speed of the
  wire: the k-th character is released ``k`` character times after the device started sending
  (see :meth:`SerialSettings.char_time`), through the device clock's ``call_later``.
* **Tracing.**  Every chunk in either direction goes to a :class:`~devsim.transports.trace.Tracer`.

A line never sleeps; everything that waits goes through the device :class:`~devsim.core.clock.Clock`.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable
from typing import Any, Protocol

from devsim.core.clock import Clock, Timer
from devsim.core.device import ByteSink, SerialSettings
from devsim.transports.trace import Tracer, render

__all__ = ["Line", "LineTarget", "garble", "settings_match"]

# A real receiver accepts a byte that arrives a hair early or late; a timer may fire a few
# nanoseconds before its nominal time.  Bytes due within this margin are released.
_EPSILON = 1e-7


class LineTarget(Protocol):
    """What a line can sit in front of: a device or a multidrop bus."""

    def attach(self, write: ByteSink | None) -> None: ...

    def feed(self, data: bytes) -> None: ...

    def host_disconnected(self) -> None: ...

    @property
    def serial_settings(self) -> SerialSettings: ...


def settings_match(a: SerialSettings, b: SerialSettings) -> bool:
    """True when two UARTs with these settings understand each other."""
    return (
        a.baudrate == b.baudrate
        and a.bytesize == b.bytesize
        and a.parity.upper() == b.parity.upper()
        and float(a.stopbits) == float(b.stopbits)
    )


# -- bit-level model of a mismatched line ------------------------------------------------------


def _parity_bit(value: int, bytesize: int, parity: str) -> int | None:
    parity = parity.upper()
    if parity == "N":
        return None
    ones = bin(value & ((1 << bytesize) - 1)).count("1")
    if parity == "E":
        return ones & 1
    if parity == "O":
        return (ones & 1) ^ 1
    if parity == "M":
        return 1
    if parity == "S":
        return 0
    raise ValueError(f"unknown parity {parity!r}")


def _waveform(data: bytes, tx: SerialSettings) -> list[int]:
    """The sender's line level in half-bit steps (half bits make 1.5 stop bits exact)."""
    stop_halves = round(float(tx.stopbits) * 2)
    levels: list[int] = []
    for byte in data:
        levels += [0, 0]  # start bit
        for i in range(tx.bytesize):
            bit = (byte >> i) & 1
            levels += [bit, bit]
        parity = _parity_bit(byte, tx.bytesize, tx.parity)
        if parity is not None:
            levels += [parity, parity]
        levels += [1] * stop_halves
    return levels


def garble(data: bytes, sender: SerialSettings, receiver: SerialSettings) -> bytes:
    """What a UART configured with ``receiver`` reads when a UART configured with ``sender``
    transmits ``data`` back to back (one burst, idle line before and after).

    A deterministic, pure model of the receiver: it waits for the line to be low, confirms the
    start bit in its middle, samples each data bit, the parity bit and the stop bit in the middle
    of *its own* bit cells.  A character with a framing error (stop bit sampled low) is handed
    over as sampled – the garbage a device's UART register holds; a receiver configured for
    parity checks it and hands over a character with a parity error as NUL (what a POSIX port
    with ``INPCK`` delivers), so a 7E1 device never mistakes 8N1 ASCII for its own.  After the
    stop bit sample it looks for the next start bit (resynchronising at once after a framing
    error, as a 16550 does).

    A faster sender squeezes several characters into one received character; a slower sender's
    single character is read as a character plus framing garbage.  With matching settings the
    output equals the input.  Time is counted in integer units (``1 / (4 * tx_baud * rx_baud)``
    seconds) so the result never depends on floating-point rounding.
    """
    if not data:
        return b""
    if settings_match(sender, receiver):
        return bytes(data)
    tx_baud, rx_baud = int(sender.baudrate), int(receiver.baudrate)
    if tx_baud <= 0 or rx_baud <= 0:
        raise ValueError("baud rates must be positive")
    levels = _waveform(data, sender)
    half = 2 * rx_baud  # one sender half bit, in time units
    rx_bit = 4 * tx_baud  # one receiver bit, in time units
    end = len(levels) * half

    def level(t: int) -> int:
        h = t // half
        return levels[h] if 0 <= h < len(levels) else 1

    def next_low(t: int) -> int | None:
        h = t // half
        if h < len(levels) and levels[h] == 0:
            return t
        h += 1
        while h < len(levels):
            if levels[h] == 0:
                return h * half
            h += 1
        return None

    rx_parity = receiver.parity.upper() != "N"
    out = bytearray()
    t = 0
    while t < end:
        edge = next_low(t)
        if edge is None:
            break
        # Middle of the start bit: a glitch shorter than half a bit is not a start bit.
        if level(edge + rx_bit // 2) != 0:
            t = edge + rx_bit // 2 + 1
            continue
        value = 0
        for i in range(receiver.bytesize):
            value |= level(edge + (2 * (i + 1) + 1) * rx_bit // 2) << i
        cells = 1 + receiver.bytesize
        if rx_parity:
            sampled = level(edge + (2 * cells + 1) * rx_bit // 2)
            cells += 1
            if sampled != _parity_bit(value, receiver.bytesize, receiver.parity):
                value = 0  # parity error: reported as NUL, as a POSIX port with INPCK does
        stop_sample = edge + (2 * cells + 1) * rx_bit // 2
        out.append(value)  # a framing error (low stop bit) still delivers what was sampled
        t = stop_sample
    return bytes(out)


# -- the line ---------------------------------------------------------------------------------


def _settings_dict(settings: SerialSettings) -> dict[str, Any]:
    return {
        "baudrate": settings.baudrate,
        "bytesize": settings.bytesize,
        "parity": settings.parity,
        "stopbits": settings.stopbits,
        "text": settings.describe(),
    }


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


class Line:
    """An :class:`~devsim.transports.base.Endpoint` in front of a device or a bus.

    ``target`` is anything with ``attach``/``feed``/``host_disconnected``/``serial_settings``;
    the line attaches itself as the target's output.  ``pacing`` releases device output at the
    device's character time; it is ignored on a virtual clock (see :attr:`pacing`).
    """

    def __init__(
        self,
        target: LineTarget,
        clock: Clock,
        *,
        pacing: bool = False,
        tracer: Tracer | None = None,
    ) -> None:
        self.target = target
        self.clock = clock
        self._pacing_requested = pacing
        self.tracer = tracer
        self._host: SerialSettings | None = None
        self._write: ByteSink | None = None
        self.bytes_in = 0
        self.bytes_out = 0
        self._queue: deque[_Burst] = deque()
        self._tx_free_at = 0.0
        self._timer: Timer | None = None
        target.attach(self._from_device)

    # -- Endpoint ---------------------------------------------------------------------------
    def attach(self, write: Callable[[bytes], None] | None) -> None:
        """The transport's sink towards the host (``None``: nobody listening)."""
        self._write = write

    def feed(self, data: bytes) -> None:
        """Bytes from the host; garbled on the way when the line settings do not match."""
        if not data:
            return
        self.bytes_in += len(data)
        received = data
        host = self._host
        if host is not None and not settings_match(host, self.device_settings):
            received = garble(data, host, self.device_settings)
        if self.tracer is not None:
            note = None if received == data else f"device read {render(received)}"
            self.tracer.record("H>D", data, self.clock.now(), note)
        if received:
            self.target.feed(received)

    def host_settings(self, settings: SerialSettings) -> None:
        """The host (re)configured its port."""
        self._host = settings
        if self.tracer is not None:
            self.tracer.note(
                f"host settings {settings.describe()}"
                + (" (mismatch, device " + self.device_settings.describe() + ")" if self.mismatch else ""),
                self.clock.now(),
            )

    def host_disconnected(self) -> None:
        """The host went away: forget its settings (the next host brings its own)."""
        self._host = None
        if self.tracer is not None:
            self.tracer.note("host disconnected", self.clock.now())
        self.target.host_disconnected()

    # -- state ------------------------------------------------------------------------------
    @property
    def device_settings(self) -> SerialSettings:
        """The UART settings of the device (or the bus's first device)."""
        return self.target.serial_settings

    @property
    def serial_settings(self) -> SerialSettings:
        """Same as :attr:`device_settings`; lets a transport preset its port to the device's
        settings (a pty, the RFC 2217 port's initial state)."""
        return self.target.serial_settings

    @property
    def host(self) -> SerialSettings | None:
        """The host's last reported line settings, ``None`` while unknown (assumed matching)."""
        return self._host

    @property
    def mismatch(self) -> bool:
        """True when the host's settings are known and differ from the device's."""
        return self._host is not None and not settings_match(self._host, self.device_settings)

    @property
    def pacing(self) -> bool:
        """Whether device output is actually paced.

        Never on a virtual clock: virtual time only moves when a test or scenario advances it
        (or, in auto mode, jumps over every wait), and the host on the other side of a pty or
        socket lives in wall time.  Pacing would either hold the answer back until somebody
        advances the clock – a host waiting for that answer before the script moves on would
        deadlock – or be skipped over instantly, so it adds nothing but a stall.
        """
        return self._pacing_requested and not self.clock.virtual

    def status(self) -> dict[str, Any]:
        """A JSON-serialisable snapshot for the control API."""
        return {
            "device": _settings_dict(self.device_settings),
            "host": None if self._host is None else _settings_dict(self._host),
            "mismatch": self.mismatch,
            "pacing": self.pacing,
            "bytes_in": self.bytes_in,
            "bytes_out": self.bytes_out,
            "pending_out": sum(len(b.data) - b.sent for b in self._queue),
        }

    def close(self) -> None:
        """Detach from the target and drop output still on the wire."""
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None
        self._queue.clear()
        self.target.attach(None)
        self._write = None

    # -- device → host ----------------------------------------------------------------------
    def _from_device(self, data: bytes) -> None:
        if not data:
            return
        self.bytes_out += len(data)
        device = self.device_settings
        sent = data
        host = self._host
        if host is not None and not settings_match(host, device):
            sent = garble(data, device, host)
        if self.tracer is not None:
            note = None if sent == data else f"host read {render(sent)}"
            self.tracer.record("D>H", data, self.clock.now(), note)
        if not sent:
            return
        if not self.pacing:
            self._deliver(sent)
            return
        now = self.clock.now()
        start = max(now, self._tx_free_at)
        duration = len(data) * device.char_time()
        self._tx_free_at = start + duration
        self._queue.append(_Burst(sent, start, duration))
        if self._timer is None:
            self._schedule()

    def _deliver(self, data: bytes) -> None:
        if self._write is not None:
            self._write(data)

    def _schedule(self) -> None:
        burst = self._queue[0]
        due = burst.due(burst.sent)
        self._timer = self.clock.call_later(due - self.clock.now(), self._release)

    def _release(self) -> None:
        self._timer = None
        now = self.clock.now() + _EPSILON
        out = bytearray()
        while self._queue:
            burst = self._queue[0]
            n = len(burst.data)
            k = burst.sent
            while k < n and burst.due(k) <= now:
                k += 1
            out += burst.data[burst.sent : k]
            burst.sent = k
            if k < n:
                break
            self._queue.popleft()
        if out:
            self._deliver(bytes(out))
        if self._queue:
            self._schedule()
