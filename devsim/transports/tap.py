"""A tap on a line's trace: the last telegrams that crossed it, for a live monitor.

A :class:`TelegramTap` is a :class:`~devsim.transports.trace.TraceSink` that keeps the last
``size`` telegrams of a line in memory and hands every call on to the trace the line had before
(a ``--trace`` file, or none).  :func:`tap` puts one in front of a line the first time somebody
asks (``devsim monitor``, the control op ``telegrams``), so that a line nobody looks at keeps its
fault-free fast path.

A telegram is what one side sent in one go: consecutive chunks in the same direction less than
:data:`GAP` seconds of device time apart are joined (a host's request that arrives split over
several reads is one telegram), up to :data:`MAX_BYTES`.  With a decoder per direction (the
framing the port declares, :attr:`devsim.core.kit.PortDef.framing`, as record and replay use
it) a telegram also carries ``decoded``: the messages it completed, e.g. an FT1.2 frame's fields.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable
from typing import Any

from devsim.transports.trace import TapSink, TraceSink, render

__all__ = ["GAP", "MAX_BYTES", "TelegramTap", "tap"]

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

    def last(self, count: int) -> list[dict[str, Any]]:
        """The last ``count`` telegrams, oldest first (copies)."""
        items = list(self.telegrams)[-count:] if count > 0 else []
        return [{**item, "decoded": list(item["decoded"])} if "decoded" in item else dict(item) for item in items]


def tap(line: Any, decoder: Callable[[str], Any] | None = None) -> TelegramTap:
    """The tap in front of ``line``'s trace, put there on the first call (runs in the loop
    thread); ``decoder(direction)`` (``"host"`` or ``"device"``) makes a direction's decoder."""
    existing = line.tracer
    if isinstance(existing, TelegramTap):
        return existing
    telegram_tap = TelegramTap(existing, decoder=decoder)
    line.tracer = telegram_tap
    return telegram_tap
