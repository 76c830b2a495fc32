"""The session file of ``devsim record`` / ``devsim replay``: JSON lines, one object per line.

The first line is the header::

    {"format": "devsim-session", "version": 1, "kind": "sers", "port": "main",
     "device": "/dev/pts/4", "settings": {"baudrate": 9600, "bytesize": 8, "parity": "N",
     "stopbits": 1}, "started": "2026-11-26T13:00:00+00:00"}

``kind`` is the device kind (``null`` when not given: replayed byte-exact, no live fallback),
``port`` the kind's port recorded, ``device`` where the recorder reached the device,
``settings`` the line settings it opened the device with.  Every further line is one chunk as it
passed the recorder, in the order it passed::

    {"t": 0.51234, "dir": "host", "hex": "235031313f0d", "decoded": ["#P11?\\r"]}
    {"t": 0.51301, "dir": "device", "hex": "...", "decoded": ["#P11?\\r", "P11=0\\n\\r", "\\nok1\\n\\r"]}
    {"t": 2.0, "settings": {"baudrate": 19200, "bytesize": 8, "parity": "N", "stopbits": 1}}

``t`` is seconds since the recorder started (monotonic clock), ``dir`` who sent the bytes
(``host``: host → device, ``device``: device → host), ``hex`` the bytes, ``decoded`` the
messages this chunk completed as the port's declared framing reads them
(:attr:`devsim.core.kit.PortDef.framing`; absent for ports without one).  A ``settings`` line says the host changed its line settings
(the recorder applied them to the device's port).  Lines of a newer version's unknown kinds
are skipped; readers rely on ``dir`` and ``hex`` only.  A last line cut short (the recorder's
disk full, see :class:`~devsim.transports.trace.TraceFile`) ends the recording there: the lines
before it are loaded, and :attr:`Session.cut` names the line.

:func:`load_session` cuts the host's stream into requests (the kind's framing) and gives each
the device's bytes that answered it (:class:`Exchange`): device bytes that came while a request
was still arriving (a SERS echo) are sent at once when it is complete; later ones after their
recorded delay from the request's last byte.
"""

from __future__ import annotations

import json
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import msgspec

from devsim.core.device import SerialSettings
from devsim.core.registry import port_framing
from devsim.transports.trace import TraceFile

__all__ = ["Exchange", "FORMAT", "Reply", "Session", "SessionError", "SessionWriter", "load_session"]

FORMAT = "devsim-session"
VERSION = 1


class SessionError(ValueError):
    """A file that is not a readable session (message names the file and line)."""


def settings_dict(settings: SerialSettings) -> dict[str, Any]:
    return {"baudrate": settings.baudrate, "bytesize": settings.bytesize, "parity": settings.parity,
            "stopbits": settings.stopbits}


class SessionWriter:
    """Writes a session file, one flushed line per chunk (a killed recorder loses nothing)."""

    def __init__(self, path: str | Path, *, kind: str | None, port: str, device: str, settings: SerialSettings) -> None:
        self.path = Path(path)
        self._file = TraceFile(self.path, encoding="utf-8", what="session")  # (no symlink)
        framing = port_framing(kind, port)
        self._decoders = {"host": framing.decoder("host"), "device": framing.decoder("device")}
        self.chunks = 0
        self._line({"format": FORMAT, "version": VERSION, "kind": kind, "port": port, "device": device,
                    "settings": settings_dict(settings), "started": datetime.now(UTC).isoformat(timespec="seconds")})

    def chunk(self, t: float, direction: str, data: bytes) -> None:
        """Bytes sent by ``direction`` (``"host"`` or ``"device"``) at ``t`` seconds."""
        entry: dict[str, Any] = {"t": round(t, 6), "dir": direction, "hex": data.hex()}
        decoded = self._decoders[direction].feed(data)
        if decoded is not None:
            entry["decoded"] = decoded
        if self._line(entry):
            self.chunks += 1  # (the chunks the file holds: none once the disk stopped taking it)

    def settings(self, t: float, settings: SerialSettings) -> None:
        self._line({"t": round(t, 6), "settings": settings_dict(settings)})

    def close(self) -> None:
        self._file.close()

    def _line(self, entry: dict[str, Any]) -> bool:
        """Write ``entry``; whether the file took it."""
        if self._file.closed:
            return False
        self._file.write(json.dumps(entry, ensure_ascii=True) + "\n")
        return not self._file.closed


class Reply(msgspec.Struct):
    """Device bytes answering a request, ``delay`` seconds after its last byte."""

    delay: float
    data: bytes


class Exchange(msgspec.Struct):
    """One host request and the device's answer as recorded."""

    index: int
    request: bytes
    t: float  # when its last byte passed the recorder
    replies: list[Reply] = msgspec.field(default_factory=list)

    @property
    def answer(self) -> bytes:
        return b"".join(reply.data for reply in self.replies)


class Session(msgspec.Struct):
    kind: str | None
    port: str
    settings: SerialSettings
    exchanges: list[Exchange]
    preamble: bytes = b""  # device bytes before the host sent anything (not replayed)
    header: dict[str, Any] = msgspec.field(default_factory=dict)
    cut: int = 0  # the number of a last line cut short (not loaded), else 0


def _settings(raw: Any, where: str) -> SerialSettings:
    if not isinstance(raw, dict):
        raise SessionError(f"{where}: settings: expected an object")
    try:
        settings = SerialSettings(baudrate=int(raw.get("baudrate", 9600)), bytesize=int(raw.get("bytesize", 8)),
                                  parity=str(raw.get("parity", "N")), stopbits=float(raw.get("stopbits", 1)))
    except (TypeError, ValueError, OverflowError) as exc:
        raise SessionError(f"{where}: settings: {exc}") from None
    if (problem := settings.problem()) is not None:  # (one a file edited by hand names: each host byte failed)
        raise SessionError(f"{where}: settings: {problem}")
    return settings


class _Cutter:
    """Cuts the recorded stream into exchanges (see the module docstring)."""

    def __init__(self, kind: str | None, port: str) -> None:
        self.split = port_framing(kind, port).split
        self.exchanges: list[Exchange] = []
        self.pending = b""
        self.pending_t = 0.0
        self.early: list[bytes] = []
        self.preamble = b""
        self.host_bytes = 0

    def host(self, t: float, data: bytes) -> None:
        self.host_bytes += len(data)
        self.pending += data
        self.pending_t = t
        if self.split is None:
            return
        messages, self.pending = self.split(self.pending)
        for message in messages:
            self._complete(message, t)

    def device(self, t: float, data: bytes) -> None:
        if self.host_bytes == 0:
            self.preamble += data
            return
        if self.pending and self.split is None:  # unframed: the device answering ends a request
            self._complete(self.pending, self.pending_t)
            self.pending = b""
        if self.pending:  # bytes while a request arrives (an echo): sent when it is complete
            self.early.append(data)
            return
        last = self.exchanges[-1]
        last.replies.append(Reply(max(0.0, t - last.t), data))

    def finish(self) -> None:
        if self.pending and (self.split is None or self.early):
            self._complete(self.pending, self.pending_t)
        self.pending = b""

    def _complete(self, message: bytes, t: float) -> None:
        exchange = Exchange(len(self.exchanges), message, t, [Reply(0.0, data) for data in self.early])
        self.early = []
        self.exchanges.append(exchange)


def load_session(path: str | Path) -> Session:
    """Read a session file; :class:`SessionError` names the file and line of a problem."""
    path = Path(path)
    try:
        text_all = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise SessionError(f"{path}: {exc}") from None
    lines = text_all.splitlines()
    cut = len(lines) if lines and not text_all.endswith("\n") else 0  # a last line without its end
    if not lines:
        raise SessionError(f"{path}: empty file (not a devsim session)")
    try:
        header = json.loads(lines[0])
    except (ValueError, RecursionError):
        header = None
    if not isinstance(header, dict) or header.get("format") != FORMAT:
        raise SessionError(f"{path}:1: not a devsim session (no {FORMAT!r} header)")
    kind = header.get("kind")
    cutter = _Cutter(kind if isinstance(kind, str) else None, str(header.get("port") or "main"))
    torn = 0
    for number, text in enumerate(lines[1:], start=2):
        if not text.strip():
            continue
        where = f"{path}:{number}"
        try:
            entry = json.loads(text)
            if not isinstance(entry, dict):
                raise ValueError("expected an object")
            direction = entry.get("dir")
            if direction not in ("host", "device"):
                continue  # a settings line, or a newer version's record
            t = float(entry["t"])
            if t - t != 0.0:  # ("1e999", NaN: an answer due at infinity held every later one back)
                raise ValueError(f"t: {entry['t']!r} is no finite time")
            data = bytes.fromhex(entry["hex"])
        except (ValueError, KeyError, TypeError, RecursionError) as exc:
            if number == cut:
                torn = number
                break  # the recording ends before this line
            raise SessionError(f"{where}: {exc}") from None
        (cutter.host if direction == "host" else cutter.device)(t, data)
    cutter.finish()
    return Session(
        kind=kind if isinstance(kind, str) else None,
        port=str(header.get("port") or "main"),
        settings=_settings(header.get("settings", {}), f"{path}:1"),
        exchanges=cutter.exchanges,
        preamble=cutter.preamble,
        header=header,
        cut=torn,
    )
