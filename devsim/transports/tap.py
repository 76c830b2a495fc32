"""Taps on a line's trace: the last telegrams that crossed it, for a live monitor; every chunk as
it crosses, for a live capture.

A :class:`TelegramTap` is a :class:`~devsim.transports.trace.TraceSink` that keeps the last
``size`` telegrams of a line in memory and hands every call on to the trace the line had before
(a ``--trace`` file, or none).  :func:`tap` puts one in front of a line the first time somebody
asks (``devsim monitor``, the control op ``telegrams``), so that a line nobody looks at keeps its
fault-free fast path.

A telegram is what one side sent in one go: consecutive chunks in the same direction less than
:data:`GAP` seconds of device time apart are joined (a host's request that arrives split over
several reads is one telegram), up to :data:`MAX_BYTES`; a longer read (a pty's 4 KiB, a TCP
read's 64 KiB) is cut into telegrams of :data:`MAX_BYTES` too, so that a tap keeps at most
``size`` × :data:`MAX_BYTES` bytes.  With a decoder per direction (the framing the port declares,
:attr:`devsim.core.kit.PortDef.framing`, as record and replay use it) a telegram also carries
``decoded``: the messages it completed, e.g. an FT1.2 frame's fields.

A :class:`ChunkTap` (:func:`chunk_tap`) hands every chunk, as it crosses, to its listeners
(``listener(direction, data, when)``): the control op ``capture`` streams them to Wireshark's
extcap (:mod:`devsim.runtime.capture_stream`).  It is taken out of the line's trace again when
its last listener leaves (:func:`untap_chunks`), so that the line gets back its fast path.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable
from typing import Any

from devsim.transports.trace import TapSink, TraceSink, render

__all__ = ["GAP", "MAX_BYTES", "ChunkTap", "TelegramTap", "capturing", "chunk_tap", "tap", "untap_chunks"]

#: Chunks in the same direction closer than this (device seconds) are one telegram.
GAP = 0.005
#: A telegram longer than this is cut (noise on a line would otherwise grow one forever).
MAX_BYTES = 512


class TelegramTap(TapSink):
    """Keeps the last ``size`` telegrams; forwards everything to ``inner`` (may be None)."""

    def __init__(self, inner: TraceSink | None, size: int = 200,
                 decoder: Callable[[str], Any] | None = None) -> None:
        super().__init__(inner)
        #: per direction, a stateful decoder (``feed(data)`` -> descriptions), or none
        self.decoders = {"H>D": decoder("host"), "D>H": decoder("device")} if decoder is not None else {}
        self.telegrams: deque[dict[str, Any]] = deque(maxlen=size)
        #: ``fn(telegram)`` called for each telegram as it starts (later chunks extend it).
        self.listeners: list[Callable[[dict[str, Any]], None]] = []
        self._last_at = -1.0
        self._data = bytearray()

    def record(self, direction: str, data: bytes, when: float, note: str | None = None) -> None:
        super().record(direction, data, when, note)
        if not data:
            return
        for start in range(0, len(data), MAX_BYTES):  # a long read (pty 4 KiB, TCP 64 KiB) is cut too
            self._keep(direction, data[start:start + MAX_BYTES], when, note)
        self._last_at = when
        decoder = self.decoders.get(direction)
        if decoder is not None:
            try:
                decoded = decoder.feed(data)
            except Exception:  # a decoder must never break the line it watches
                self.decoders.pop(direction, None)
                decoded = None
            if decoded:
                target = self.telegrams[-1]
                target["decoded"] = (target.get("decoded", []) + list(decoded))[-8:]

    def _keep(self, direction: str, data: bytes, when: float, note: str | None) -> None:
        """``data`` (at most :data:`MAX_BYTES`) joined to the last telegram or a new one."""
        last = self.telegrams[-1] if self.telegrams else None
        if (last is not None and last["dir"] == direction and when - self._last_at <= GAP
                and len(self._data) + len(data) <= MAX_BYTES and not note and not last.get("note")):
            self._data += data
            last["hex"] = self._data.hex(" ")
            last["text"] = render(bytes(self._data))
        else:
            self._data = bytearray(data)
            telegram: dict[str, Any] = {"t": when, "dir": direction, "hex": data.hex(" "), "text": render(data)}
            if note:
                telegram["note"] = note
            self.telegrams.append(telegram)
            for listener in list(self.listeners):
                listener(telegram)

    def last(self, count: int) -> list[dict[str, Any]]:
        """The last ``count`` telegrams, oldest first (copies)."""
        items = list(self.telegrams)[-count:] if count > 0 else []
        return [{**item, "decoded": list(item["decoded"])} if "decoded" in item else dict(item) for item in items]


def _find(line: Any, cls: type[TapSink]) -> Any:
    """The tap of class ``cls`` somewhere in ``line``'s chain of trace sinks, or None."""
    sink = line.tracer
    while sink is not None:
        if isinstance(sink, cls):
            return sink
        sink = getattr(sink, "inner", None)
    return None


def tap(line: Any, decoder: Callable[[str], Any] | None = None) -> TelegramTap:
    """The tap in front of ``line``'s trace, put there on the first call (runs in the loop
    thread); ``decoder(direction)`` (``"host"`` or ``"device"``) makes a direction's decoder."""
    existing = _find(line, TelegramTap)
    if existing is not None:
        return existing
    telegram_tap = TelegramTap(line.tracer, decoder=decoder)
    line.tracer = telegram_tap
    return telegram_tap


#: What a chunk tap's listener gets: direction (``"H>D"``/``"D>H"``), the bytes, the device time.
ChunkListener = Callable[[str, bytes, float], None]


class ChunkTap(TapSink):
    """Hands every chunk to its listeners (in the loop thread, as it crosses); forwards
    everything to ``inner`` (may be None).  A listener must not block: it queues."""

    def __init__(self, inner: TraceSink | None) -> None:
        super().__init__(inner)
        self.listeners: list[ChunkListener] = []

    def record(self, direction: str, data: bytes, when: float, note: str | None = None) -> None:
        super().record(direction, data, when, note)
        if data:
            for listener in list(self.listeners):
                listener(direction, bytes(data), when)


def chunk_tap(line: Any) -> ChunkTap:
    """The chunk tap on ``line``'s trace, put in front of it on the first call (loop thread)."""
    existing = _find(line, ChunkTap)
    if existing is not None:
        return existing
    chunks = ChunkTap(line.tracer)
    line.tracer = chunks
    return chunks


def untap_chunks(line: Any, listener: ChunkListener) -> None:
    """Take ``listener`` off ``line``'s chunk tap; the tap leaves the line with its last listener
    when nothing has been put in front of it since."""
    chunks = _find(line, ChunkTap)
    if chunks is None:
        return
    if listener in chunks.listeners:
        chunks.listeners.remove(listener)
    if not chunks.listeners and line.tracer is chunks:
        line.tracer = chunks.inner


def capturing(line: Any) -> int:
    """How many live captures listen on ``line`` now."""
    chunks = _find(line, ChunkTap)
    return 0 if chunks is None else len(chunks.listeners)
