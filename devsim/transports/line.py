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
  (see :meth:`SerialSettings.char_time`), through the device clock's ``call_later``
  (:mod:`devsim.transports.pacing`).
* **Tracing.**  Every chunk in either direction goes to a trace (:class:`~devsim.transports.trace.Tracer`,
  or a pcap file, :mod:`devsim.transports.pcap`).
* **Injected faults** (:meth:`Line.inject` with a :class:`LineFault`): corrupted, dropped, split,
  delayed or jittered bytes, line noise, a temporary baud-rate mismatch, a pulled cable, a hung
  or a silent device.  See :class:`LineFault` for what each kind does and in which order
  several active faults apply.

A line never sleeps; everything that waits goes through the device :class:`~devsim.core.clock.Clock`.

The bit-level UART model (:func:`garble`, :func:`settings_match`) is in
:mod:`devsim.transports.uart`, the fault definitions (:class:`LineFault`, :class:`FaultHandle`)
in :mod:`devsim.transports.faults`; both are re-exported here.

While none of this is needed, a transport that offered to (:meth:`Line.offer_lane`) carries the
bytes between the host and the target without the line: the lean lane
(:mod:`devsim.transports.lane`), which the line opens and closes as its features are switched on
and off.
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Callable
from typing import Any, Protocol

import msgspec

from devsim.core.clock import Clock, Timer
from devsim.core.device import ByteSink, SerialSettings
from devsim.transports.faults import _NOISE_TICK, _Active, gate, mangle, noise_due, of_kind, take

# LineFault, FaultHandle, garble and settings_match live in .faults and .uart; they stay
# importable from here (explicit re-exports), as do the fault kind and direction types.
from devsim.transports.faults import DEFAULT_SPLIT_GAP as DEFAULT_SPLIT_GAP
from devsim.transports.faults import FaultDirection as FaultDirection
from devsim.transports.faults import FaultHandle as FaultHandle
from devsim.transports.faults import FaultKind as FaultKind
from devsim.transports.faults import LineFault as LineFault
from devsim.transports.faults import latency as fault_latency
from devsim.transports.lane import LaneSwitch, Take
from devsim.transports.pacing import EPSILON as _EPSILON
from devsim.transports.pacing import MAX_PENDING, Pacer
from devsim.transports.trace import TraceSink, render
from devsim.transports.uart import garble as garble
from devsim.transports.uart import settings_match as settings_match

__all__ = ["FaultHandle", "Line", "LineFault", "LineTarget", "garble", "settings_match", "wire_settings"]


class LineTarget(Protocol):
    """What a line can sit in front of: a device or a multidrop bus (or a facade's endpoint).  A
    target may also offer ``at_once`` (:attr:`~devsim.core.device.Port.at_once`), which a lean
    lane calls before ``feed``; one without it is fed every chunk."""

    def attach(self, write: ByteSink | None) -> None: ...

    def feed(self, data: bytes) -> None: ...

    def host_disconnected(self) -> None: ...

    @property
    def serial_settings(self) -> SerialSettings: ...


class _Stage:
    """Chunks on their way with extra latency, released in order through the clock.

    Due times never decrease, so a chunk never overtakes an earlier one.  A chunk due now on an
    idle stage is handed on at once (the fault-free path stays synchronous).  A stage holds at
    most :data:`~devsim.transports.pacing.MAX_PENDING` bytes; what would go beyond is lost
    (counted in ``dropped``), as bytes sent into a full receive buffer are.  [SIM-CHOICE] no
    manual says how much a delayed line holds: without a bound a delay or split fault kept every
    byte a host flooded it with, and a split flood's gaps put the next request hours away.
    """

    __slots__ = ("clock", "sink", "drained", "items", "last_due", "timer", "held", "dropped")

    def __init__(self, clock: Clock, sink: Callable[[bytes, int], None], drained: Callable[[], None]) -> None:
        self.clock = clock
        self.sink = sink
        self.drained = drained  # called when the last chunk waiting has been handed on
        #: Chunks waiting (a deque made when the first waits: most lines never delay one).
        self.items: deque[tuple[float, bytes, int]] | tuple[()] = ()
        self.last_due = -math.inf
        self.timer: Timer | None = None
        self.held = 0  # bytes in items
        self.dropped = 0  # bytes lost because the stage held MAX_PENDING

    @property
    def pending(self) -> int:
        return self.held

    def put(self, earliest: float, data: bytes, chars: int, gap: float = 0.0) -> None:
        """Hand ``data`` on no earlier than ``earliest`` and at least ``gap`` after the previous
        chunk; ``chars`` is what the chunk occupies on the wire (for pacing).  Beyond
        ``MAX_PENDING`` bytes held, the chunk's rest is lost."""
        due = max(earliest, self.last_due + gap)
        if not self.items and due <= self.clock.now() + _EPSILON:
            self.last_due = due
            self.sink(data, chars)
            return
        room = MAX_PENDING - self.held
        if room < len(data):
            self.dropped += len(data) - max(room, 0)
            if room <= 0:
                return
            chars = max(1, chars * room // len(data))
            data = data[:room]
        self.last_due = due
        self.held += len(data)
        items = self.items
        if not items:
            items = self.items = deque()
        items.append((due, data, chars))
        if self.timer is None:
            self._schedule()

    def _schedule(self) -> None:
        self.timer = self.clock.call_at(self.items[0][0], self._release)

    def _release(self) -> None:
        self.timer = None
        now = self.clock.now() + _EPSILON
        out = bytearray()
        chars = 0
        while self.items and self.items[0][0] <= now:
            _, data, n = self.items.popleft()  # type: ignore[union-attr]
            self.held -= len(data)
            out += data
            chars += n
        if out:
            self.sink(bytes(out), chars)
        if self.items and self.timer is None:
            self._schedule()
        elif not self.items:
            self.drained()

    def close(self) -> None:
        if self.timer is not None:
            self.timer.cancel()
            self.timer = None
        self.items = ()
        self.held = 0


# -- the line ---------------------------------------------------------------------------------


def _settings_dict(settings: SerialSettings) -> dict[str, Any]:
    return {
        "baudrate": settings.baudrate,
        "bytesize": settings.bytesize,
        "parity": settings.parity,
        "stopbits": settings.stopbits,
        "text": settings.describe(),
    }


class Line:
    """An :class:`~devsim.transports.base.Endpoint` in front of a device or a bus.

    ``target`` is anything with ``attach``/``feed``/``host_disconnected``/``serial_settings``;
    the line attaches itself as the target's output.  ``pacing`` releases device output at the
    device's character time; it is ignored on a virtual clock (see :attr:`pacing`).  Faults are
    injected with :meth:`inject` (see :class:`LineFault`).  (Slots: every poll passes through.)
    """

    __slots__ = tuple("target clock _pacing_requested _tracer _host _matched_host _matched_device _quiet _write"
                      " _in _out _delivered _pacer _faults _stages _to_device _to_host observers _lane".split())

    def __init__(
        self,
        target: LineTarget,
        clock: Clock,
        *,
        pacing: bool = False,
        tracer: TraceSink | None = None,
    ) -> None:
        self.target = target
        self.clock = clock
        self._pacing_requested = pacing
        self._tracer = tracer
        self._host: SerialSettings | None = None
        self._matched_host: SerialSettings | None = None  # the settings last found matching (_clean)
        self._matched_device: SerialSettings | None = None
        self._quiet = tracer is None  # no fault, trace or delayed chunk: the fast paths' one look (_review)
        self._write: ByteSink | None = None
        self._in = self._out = self._delivered = 0  # (what the line carried itself; bytes_in ... add the lane's)
        self._pacer: Pacer | None = None  # made when pacing first holds output
        self._faults: list[_Active] = []
        review = self._review  # (one bound method for both stages: a line per port of a plant)
        self._stages = {
            "to_device": _Stage(clock, self._to_target, review),
            "to_host": _Stage(clock, self._paced, review),
        }
        self._to_device, self._to_host = self._stages["to_device"], self._stages["to_host"]  # (the fast paths' look)
        #: ``fn(event, text)`` called on the line's rare moments (not on data): ``connect``,
        #: ``disconnect``, ``host_settings`` (text: the settings, `` (mismatch ...)`` when they
        #: differ), ``fault`` (a line fault started or ended) -- for watchers and logs.
        self.observers: list[Callable[[str, str], None]] = []
        own = self._from_device
        self._lane = LaneSwitch(target, own)
        target.attach(own)

    def _tell(self, event: str, text: str) -> None:
        for observer in list(self.observers):
            observer(event, text)

    # -- the lean lane ----------------------------------------------------------------------
    def offer_lane(self, take: Take | None) -> None:
        """A transport offers to carry the lean lane (:mod:`devsim.transports.lane`): the line
        calls ``take(lane)`` whenever nothing on it needs to see the bytes, and ``take(None)``
        when something does again.  ``None`` withdraws the offer."""
        self._lane.offer(take)
        self._review()

    def _review(self) -> None:
        """Open the lean lane while a host listens, and no fault, trace, tap, pacing, delayed
        chunk or reported host setting (a possible mismatch) needs the line; close it when one
        does.  Called whenever one of those changes."""
        quiet = self._quiet = (not self._faults and self._tracer is None and not self._to_device.items
                               and not self._to_host.items)
        self._lane.set(quiet and self._write is not None and self._host is None and not self.pacing)

    @property
    def lean(self) -> bool:
        """Whether the lean lane is open (the transport carries the bytes without the line)."""
        return self._lane.open

    @property
    def tracer(self) -> TraceSink | None:
        """Where every chunk in either direction is recorded (a trace file, a tap), or None."""
        return self._tracer

    @tracer.setter
    def tracer(self, tracer: TraceSink | None) -> None:
        self._tracer = tracer
        self._review()

    @property
    def bytes_in(self) -> int:
        """Bytes received from the host."""
        return self._in + self._lane.bytes_in

    @property
    def bytes_out(self) -> int:
        """Bytes the target sent towards the host."""
        return self._out + self._lane.bytes_out

    @property
    def bytes_delivered(self) -> int:
        """Bytes handed to the transport for the host (after garbling, faults and pacing)."""
        return self._delivered + self._lane.bytes_out

    # -- Endpoint ---------------------------------------------------------------------------
    def attach(self, write: Callable[[bytes], None] | None) -> None:
        """The transport's sink towards the host (``None``: nobody listening)."""
        if write is not None and self.observers:
            self._tell("connect", "host connected")
        self._lane.close()  # (a new writer: the transport is asked again)
        self._write = write
        self._review()

    def feed(self, data: bytes) -> None:
        """Bytes from the host; garbled on the way when the line settings do not match, and
        subject to the active faults."""
        if not data:
            return
        self._in += len(data)
        host = self._host
        if self._quiet and (host is None or (host is self._matched_host and self.target.serial_settings
                                             is self._matched_device) or self._clean()):
            self.target.feed(data)  # the fault-free path: nothing to garble, trace or delay
            return
        received = data
        lost = gate(self._faults, "to_device") if self._faults else None
        if lost is not None:
            received = b""
        else:
            host = self._effective_host()
            if host is not None and not settings_match(host, self.device_settings):
                received = garble(data, host, self.device_settings)
            if self._faults:
                received = mangle(self._faults, received, "to_device")
        if self._tracer is not None:
            if lost is not None:
                note: str | None = f"lost: {lost}"
            else:
                note = None if received == data else f"device read {render(received)}"
            self._tracer.record("H>D", data, self.clock.now(), note)
        if received:
            self._timing(received, len(received), "to_device")
        if self._faults:
            self._reap()

    def host_settings(self, settings: SerialSettings) -> None:
        """The host (re)configured its port."""
        self._host = settings
        self._review()
        if self._tracer is not None or self.observers:
            text = (f"host settings {settings.describe()}"
                    + (" (mismatch, device " + self.device_settings.describe() + ")" if self.mismatch else ""))
            if self._tracer is not None:
                self._tracer.note(text, self.clock.now())
            self._tell("host_settings", text)

    def host_disconnected(self) -> None:
        """The host went away: forget its settings (the next host brings its own)."""
        self._host = None
        self._review()
        if self._tracer is not None:
            self._tracer.note("host disconnected", self.clock.now())
        self._tell("disconnect", "host disconnected")
        self.target.host_disconnected()

    # -- faults -----------------------------------------------------------------------------
    def inject(self, fault: LineFault) -> FaultHandle:
        """Start ``fault`` now; it ends by itself after its ``duration`` or ``count``."""
        active = _Active(fault, self.clock.now())
        self._faults.append(active)
        self._review()
        handle = FaultHandle(active, self._end)
        self._note(f"fault start: {fault.describe()}")
        if fault.kind == "unplug":
            self.target.host_disconnected()
        if fault.kind == "noise":
            assert fault.rate is not None
            self._schedule_noise(active, 1)
        if fault.duration is not None:
            active.timers.append(self.clock.call_later(fault.duration, lambda: self._end(active, "ended")))
        return handle

    def clear_faults(self) -> None:
        """End every active fault (bytes already delayed still arrive, in order)."""
        for active in list(self._faults):
            self._end(active, "cleared")

    @property
    def faults(self) -> list[LineFault]:
        """The active faults, in injection order."""
        return [a.fault for a in self._faults]

    def _end(self, active: _Active, how: str) -> None:
        if not active.active:
            return
        if active.fault.kind == "noise":
            self._noise_tick(active)  # what is due up to now
        active.active = False
        for timer in active.timers:
            timer.cancel()
        active.timers.clear()
        self._faults.remove(active)
        self._review()
        self._note(f"fault {how}: {active.fault.describe()}")

    def _note(self, text: str) -> None:
        if self._tracer is not None:
            self._tracer.note(text, self.clock.now())
        self._tell("fault", text)

    def _clean(self) -> bool:
        """The host's settings, known, match the device's (the objects compared are remembered:
        the fast paths find them again with two identity checks)."""
        host, device = self._host, self.target.serial_settings
        if host is not None and settings_match(host, device):
            self._matched_host, self._matched_device = host, device
            return True
        return host is None

    def _effective_host(self) -> SerialSettings | None:
        """The host's settings as the line sees them (a ``baud_mismatch`` fault overrides the
        host's baud rate)."""
        for active in reversed(self._faults):
            if active.fault.kind == "baud_mismatch":
                assert active.fault.baudrate is not None
                return msgspec.structs.replace(self._host or self.device_settings, baudrate=active.fault.baudrate)
        return self._host

    def _reap(self) -> None:
        """End the counted faults whose count is used up (after the chunk has been traced)."""
        for active in [a for a in self._faults if a.remaining == 0]:
            self._end(active, "ended")

    def _timing(self, data: bytes, chars: int, direction: str) -> None:
        """Delay, jitter and split, then on to the stage of ``direction``."""
        stage = self._stages[direction]
        if not self._faults and not stage.items:
            # nothing delayed or queued: on at once (the common path, kept cheap: no clock read)
            stage.sink(data, chars)
            return
        now = self.clock.now()
        if not self._faults:
            stage.put(now, data, chars)
            return
        latency = fault_latency(self._faults, direction)
        splits = of_kind(self._faults, "split", direction)
        if not splits:
            stage.put(now + latency, data, chars)
            return
        split = splits[0]
        gap = DEFAULT_SPLIT_GAP if split.fault.delay is None else split.fault.delay
        n = take(split, len(data))
        for i in range(n):
            stage.put(now + latency, data[i : i + 1], 1, gap)
        if n < len(data):
            stage.put(now + latency, data[n:], len(data) - n, gap)

    def _schedule_noise(self, active: _Active, k: int) -> None:
        assert active.fault.rate is not None
        interval = max(1.0 / active.fault.rate, _NOISE_TICK)
        when = active.started + k * interval

        def tick() -> None:
            self._noise_tick(active)
            if active.active:
                self._schedule_noise(active, k + 1)

        active.timers = [t for t in active.timers if not t.cancelled]
        active.timers.append(self.clock.call_at(when, tick))

    def _noise_tick(self, active: _Active) -> None:
        for direction, noise in noise_due(active, self.clock.now()):
            self._inject_noise(noise, direction)

    def _inject_noise(self, noise: bytes, direction: str) -> None:
        lost = gate(self._faults, direction, noise=True)
        if self._tracer is not None:
            note = "noise" if lost is None else f"noise, lost: {lost}"
            self._tracer.record("H>D" if direction == "to_device" else "D>H", noise, self.clock.now(), note)
        if lost is not None:
            return
        if direction == "to_device":
            self._to_target(noise)
        else:
            self._paced(noise, len(noise))

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
        """True when the host's settings (or those a ``baud_mismatch`` fault imposes) are known
        and differ from the device's."""
        host = self._effective_host()
        return host is not None and not settings_match(host, self.device_settings)

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
            "pending_in": self._to_device.pending,
            "pending_out": (self._pacer.pending if self._pacer is not None else 0) + self._to_host.pending,
            "faults": [a.fault.kind for a in self._faults],
        }

    def close(self) -> None:
        """End the faults, detach from the target and drop output still on the wire."""
        self.offer_lane(None)
        self.clear_faults()
        for stage in self._stages.values():
            stage.close()
        if self._pacer is not None:
            self._pacer.close()
        self.target.attach(None)
        self._write = None

    # -- host → device ----------------------------------------------------------------------
    def _to_target(self, data: bytes, chars: int = 0) -> None:
        if self._faults and gate(self._faults, "to_device", noise=True) is not None:
            return  # in flight when the cable was pulled or the device hung
        self.target.feed(data)

    # -- device → host ----------------------------------------------------------------------
    def _from_device(self, data: bytes) -> None:
        if not data:
            return
        self._out += len(data)
        host = self._host
        if self._quiet and (host is None or (host is self._matched_host and self.target.serial_settings
                                             is self._matched_device) or self._clean()):
            # the fault-free path: nothing to garble, trace or hold back (what _paced and _deliver do)
            if self._pacing_requested and not self.clock.virtual:  # (self.pacing)
                self._paced(data, len(data))
            elif self._write is not None:
                self._delivered += len(data)
                self._write(data)
            return
        device = self.device_settings
        sent = data
        lost = gate(self._faults, "to_host") if self._faults else None
        if lost is not None:
            sent = b""
        else:
            host = self._effective_host()
            if host is not None and not settings_match(host, device):
                sent = garble(data, device, host)
            if self._faults:
                sent = mangle(self._faults, sent, "to_host")
        if self._tracer is not None:
            if lost is not None:
                note: str | None = f"lost: {lost}"
            else:
                note = None if sent == data else f"host read {render(sent)}"
            self._tracer.record("D>H", data, self.clock.now(), note)
        if sent:
            self._timing(sent, len(data), "to_host")
        if self._faults:
            self._reap()

    def _paced(self, sent: bytes, chars: int) -> None:
        """Onto the wire towards the host: at once, or paced at the device's character time
        (``chars`` characters long)."""
        if not self.pacing:
            self._deliver(sent)
            return
        pacer = self._pacer
        if pacer is None:
            pacer = self._pacer = Pacer(self.clock, lambda: self.device_settings.char_time(), self._deliver)
        pacer.put(sent, chars)

    def _deliver(self, data: bytes) -> None:
        if self._faults and gate(self._faults, "to_host", noise=True) is not None:
            return  # in flight when the cable was pulled
        if self._write is not None:
            self._delivered += len(data)
            self._write(data)


def wire_settings(line: Line) -> dict[str, Any]:
    """The line settings of the moment as a capture records them (:mod:`devsim.transports.pcap`):
    the host's ``baud``, ``bits``, ``parity`` and ``stop`` (a ``baud_mismatch`` fault's rate
    included; 0 / ``""`` where not known: no host report yet, or data bits and parity a pty does
    not show) and ``mismatch``."""
    host = line._effective_host()
    if host is None:
        return {"baud": 0, "bits": 0, "parity": "", "stop": 0, "mismatch": False}
    seen = host.frame_seen
    return {"baud": host.baudrate, "bits": host.bytesize if seen else 0, "parity": host.parity if seen else "",
            "stop": float(host.stopbits), "mismatch": not settings_match(host, line.device_settings)}
