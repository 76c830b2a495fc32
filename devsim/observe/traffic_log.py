"""``devsim run -v``/``devsim up -v``: every host telegram and every answer on stderr, one line
each, decoded by the port's own framing (:attr:`devsim.core.kit.PortDef.framing`, as ``record``
and the monitor decode them), like candump::

    devsim: 3.120 sers main → "#1P51\\r"
    devsim: 3.121 sers main ← "\\nP51=0\\n\\r"
    devsim: 0.512 gms96 main → long C=53 A=1 letter=P params=1,2 fcb=1 data=50 01 02

device time first, then the devices on the line, the port, ``→`` (host to device) or ``←``
(device to host) and the message: text lines printable with escapes for control characters, an
FT1.2 frame by its fields.  A port that declares no framing shows each chunk as it came.  What
the device read differently on a garbled or faulty line follows in parentheses.

A :class:`TrafficLog` is a :class:`~devsim.transports.trace.TapSink` put in front of a line's
trace (a ``--trace`` file, if any, still gets everything).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from devsim.core.framing import PLAIN, Decoder, Framing
from devsim.transports.trace import TapSink, TraceSink, render

__all__ = ["ARROWS", "TrafficLog", "message_text", "watch_traffic"]

#: The trace's directions as the log marks them.
ARROWS = {"H>D": "→", "D>H": "←"}


def message_text(message: Any) -> str:
    """One decoded message as a line: a text line escaped and quoted, a frame's fields as
    ``frame k=v ...`` (lists joined by commas)."""
    if isinstance(message, bytes):
        return render(message)
    if isinstance(message, str):
        return render(message.encode("latin-1", errors="backslashreplace"))
    if isinstance(message, dict):
        fields = dict(message)
        head = [str(fields.pop("frame"))] if "frame" in fields else []
        for key, value in fields.items():
            shown = ",".join(str(v) for v in value) if isinstance(value, list | tuple) else str(value)
            head.append(f"{key}={_escaped(shown)}")
        return " ".join(head)
    return str(message)


def _escaped(text: str) -> str:
    """A field's text with every character but printable ASCII escaped: an FT1.2 command byte 0Ah,
    85h (NEL) or 1Bh (ESC) was written as it is (``letter=`` ended the line, or reached the
    terminal as a control), DFh as ``ß``, which the card never sees."""
    if text.isascii() and text.isprintable():
        return text
    return "".join(c if c.isascii() and c.isprintable() else c.encode("unicode_escape").decode("ascii") for c in text)


class TrafficLog(TapSink):
    """Writes a line per message crossing a line (``where``: ``"sers main"``), decoded with
    ``framing``; forwards everything to ``inner`` (may be None)."""

    def __init__(self, inner: TraceSink | None, where: str, framing: Framing,
                 write: Callable[[str], None]) -> None:
        super().__init__(inner)
        self.where = where
        self.write = write
        self.decoders: dict[str, Decoder] = {"H>D": framing.decoder("host"), "D>H": framing.decoder("device")}

    def record(self, direction: str, data: bytes, when: float, note: str | None = None) -> None:
        super().record(direction, data, when, note)
        if not data:
            return
        decoder = self.decoders.get(direction)
        decoded = None
        if decoder is not None:
            try:
                decoded = decoder.feed(data)
            except Exception:  # a decoder must never break the line it watches: raw from now on
                self.decoders.pop(direction, None)
        messages = [message_text(m) for m in decoded] if decoded is not None else [render(data)]
        if note:  # what happened to this chunk: after its last message
            messages = [*messages[:-1], f"{messages[-1] if messages else render(data)}  ({note})"]
        for text in messages:
            self.write(f"devsim: {when:.3f} {self.where} {ARROWS.get(direction, direction)} {text}")


def watch_traffic(runtime: Any, write: Callable[[str], None]) -> list[TrafficLog]:
    """Put a :class:`TrafficLog` in front of every line of ``runtime``'s devices (run in the loop
    thread); a line shared by several devices (RS-485) is logged once, under all their names."""
    from devsim.runtime.process import port_key

    lines: dict[int, tuple[Any, list[str], str, Framing]] = {}
    for device in runtime.devices.values():
        for spec in device.ports:
            line = runtime.lines.get(port_key(device.name, spec.name))
            if line is None:
                continue
            entry = lines.setdefault(id(line), (line, [], spec.name, spec.framing or PLAIN))
            entry[1].append(device.name)
    logs = []
    for line, names, port, framing in lines.values():
        log = TrafficLog(line.tracer, f"{','.join(names)} {port}", framing, write)
        line.tracer = log
        logs.append(log)
    return logs
