"""A wire trace: one text line per chunk that crossed a line, in simulated time.

Format of a data line::

    12.345678 H>D 23 4f 4e 0d "#ON\\r"
    12.347120 D>H 4f 4b 0d "OK\\r"  (host read "\\x9e\\xfc")

* simulated timestamp (the device clock's ``now()``, six decimals),
* direction: ``H>D`` host to device, ``D>H`` device to host,
* the bytes in hex,
* the same bytes as an escaped ASCII rendering in double quotes,
* optionally a note in parentheses (e.g. what the other side actually read on a mismatched line).

Events that are not data (host settings, disconnects) are written as ``TIME -- text``.  A device's
port traced by ``devsim run``/``up``/``scenario run`` starts with the note of what it traces
(:func:`source_note`): ``0.000000 -- source card port main kind gms96`` (devices comma-separated
on a multidrop line), so that a reader (``devsim plot``) decodes the traffic with the port's
declared framing.  Every line
is flushed at once, so a trace survives a crash and can be followed with ``tail -f``.

A trace file is never written through a symlink (:func:`create_trace_file`, also used by the
pcap trace of :mod:`devsim.transports.pcap`); :func:`devsim.transports.tracing.open_trace` picks
the text or the pcap form by the file's suffix.  A trace the file system stops taking (a full
disk, a medium removed) ends there with one line on stderr, and the line goes on
(:class:`TraceFile`): a trace never stops a device from answering.
"""

from __future__ import annotations

import errno
import os
import re
import stat
from collections.abc import Callable, Sequence
from types import TracebackType
from typing import IO, Any, Protocol

import msgspec

from devsim.core.backlog import Backlog
from devsim.core.console import warn

__all__ = ["Source", "TapSink", "TraceFile", "TraceFileError", "TraceSink", "Tracer", "create_trace_file",
           "parse_source_note", "render", "source_note"]

_ESCAPES = {0x0D: "\\r", 0x0A: "\\n", 0x09: "\\t", 0x22: '\\"', 0x5C: "\\\\"}


def render(data: bytes) -> str:
    """Printable, unambiguous ASCII rendering of ``data`` in double quotes."""
    parts = []
    for byte in data:
        if byte in _ESCAPES:
            parts.append(_ESCAPES[byte])
        elif 0x20 <= byte < 0x7F:
            parts.append(chr(byte))
        else:
            parts.append(f"\\x{byte:02x}")
    return '"' + "".join(parts) + '"'


class Source(msgspec.Struct, frozen=True):
    """What a trace traces: the devices on the line, their port, their kind."""

    devices: tuple[str, ...]
    port: str
    kind: str


#: A source note (compiled by :mod:`re` at the first note read, not by every start: issue 31).
_SOURCE = r"^source (\S+) port (\S+) kind (\S+)$"


def source_note(devices: Sequence[str], port: str, kind: str) -> str:
    """The note a trace starts with: ``source card port main kind gms96``."""
    return f"source {','.join(devices)} port {port} kind {kind}"


def parse_source_note(text: str) -> Source | None:
    """The :class:`Source` a note names, or None for any other note."""
    match = re.match(_SOURCE, text)
    return None if match is None else Source(tuple(match[1].split(",")), match[2], match[3])


class TraceSink(Protocol):
    """What a line writes its trace to: a :class:`Tracer`, a pcap tracer, or a tap on either."""

    def record(self, direction: str, data: bytes, when: float, note: str | None = None) -> None:
        """One chunk of data, ``"H>D"`` (host to device) or ``"D>H"``, at simulated time ``when``."""

    def note(self, text: str, when: float) -> None:
        """An event that is not data."""

    def close(self) -> None:
        """Flush and close."""


class TapSink:
    """A tap in front of a line's trace (``inner``, or none): every call passes through; a
    subclass keeps what it needs of the data in :meth:`record` and calls ``super().record``."""

    def __init__(self, inner: TraceSink | None) -> None:
        self.inner = inner

    def record(self, direction: str, data: bytes, when: float, note: str | None = None) -> None:
        if self.inner is not None:
            self.inner.record(direction, data, when, note)

    def note(self, text: str, when: float) -> None:
        if self.inner is not None:
            self.inner.note(text, when)

    def close(self) -> None:
        if self.inner is not None:
            self.inner.close()


class TraceFileError(OSError):
    """A file a run writes (a trace, a motion log, a recorded session) that cannot be had:
    ``filename`` is its path, ``strerror`` why; the command line says them after the option that
    named the file (``--trace: adir: Is a directory``), where a port's own errors name the port."""


def create_trace_file(path: str | os.PathLike[str]) -> int:
    """Open ``path`` for writing, created or truncated, and return the descriptor; refuses a
    symlink (``refusing to write a trace through the symlink``), so that a trace never
    truncates a file someone linked to where the trace goes.  Raises :class:`TraceFileError`."""
    name = os.fspath(path)
    try:
        return os.open(name, os.O_WRONLY | os.O_CREAT | os.O_TRUNC | os.O_NOFOLLOW | os.O_CLOEXEC, 0o644)
    except OSError as exc:
        reason = "refusing to write a trace through the symlink" if exc.errno == errno.ELOOP else exc.strerror
        raise TraceFileError(exc.errno, reason, name) from None


class TraceFile:
    """A file a run writes as it goes (a trace, a motion log, a recorded session): created by
    :func:`create_trace_file`, ``head`` written first (an error there is the caller's: the file
    cannot be had), then every :meth:`write` flushed at once unless ``at_once`` is off.

    A write, flush or close the file system refuses later (``ENOSPC``, ``EIO``) ends the file
    there: it is closed, one line on stderr (``devsim: trace FILE: No space left on device; it
    ends here``, ``what`` naming the file) says so, and the caller goes on as if the file had
    taken it, because what it records (a line, a model) must not stop for it.  A fifo whose
    reader has gone (``EPIPE``: Wireshark ends a capture) ends so too, without the line; the
    writer learns it from :attr:`closed`.

    A fifo, pipe or terminal is written through a :class:`~devsim.core.backlog.Backlog`: a reader
    that does not read (``less`` scrolled back, a terminal stopped with Ctrl-S) never makes a write
    wait; what it has no room for is dropped whole, one line on stderr says so the first time, and
    :attr:`dropped` tells the writer how many went (a text trace notes them).  A process whose only
    job is to feed the reader (``devsim extcap`` feeding Wireshark) passes ``wait``: its writes wait."""

    def __init__(self, path: str | os.PathLike[str], *, text: bool = True, encoding: str = "ascii",
                 newline: str | None = "\n", head: str | bytes = "", at_once: bool = True, what: str = "trace",
                 wait: bool = False) -> None:
        self.path = os.fspath(path)
        self.what = what
        self.at_once = at_once
        fd = create_trace_file(self.path)
        self._encoding = encoding if text else None
        self._told = False
        self._file: IO[Any] | Backlog
        if wait or stat.S_ISREG(os.fstat(fd).st_mode):
            self._file = open(fd, "w", encoding=encoding, newline=newline) if text else open(fd, "wb")  # noqa: SIM115
        else:  # a fifo, a pipe, a terminal: its reader may not read (newline: "\n" on POSIX)
            self._file = Backlog(fd, self._end)
        if head:
            try:
                self._put(head, flush=True)
            except OSError as exc:
                self._close(patience=0)
                raise TraceFileError(exc.errno, exc.strerror, self.path) from None

    @property
    def closed(self) -> bool:
        return self._file.closed

    @property
    def dropped(self) -> int:
        """Writes dropped since the last one the file took: a fifo's, pipe's or terminal's reader did
        not take them (always 0 for a regular file)."""
        return self._file.dropped if isinstance(self._file, Backlog) else 0

    def write(self, data: str | bytes) -> None:
        if self._file.closed:
            return
        try:
            self._put(data, flush=self.at_once)
        except OSError as exc:
            self._end(exc)

    def _put(self, data: str | bytes, flush: bool) -> None:
        if not isinstance(self._file, Backlog):
            self._file.write(data)
            if flush:
                self._file.flush()
        elif not self._file.write(data.encode(self._encoding or "ascii") if isinstance(data, str) else data):
            if not self._told:
                self._told = True
                warn(f"devsim: {self.what} {self.path}: its reader does not keep up; what it has no room for "
                     "is dropped")

    def _close(self, patience: float) -> None:
        if isinstance(self._file, Backlog):
            self._file.close(patience)
        else:
            self._file.close()

    def flush(self) -> None:
        self._guarded(self._file.flush)

    def close(self) -> None:
        self._guarded(self._file.close)  # (what was left in the buffer refused: closed all the same)

    def _guarded(self, step: Callable[[], object]) -> None:
        if not self._file.closed:
            try:
                step()
            except OSError as exc:
                self._end(exc)

    def _end(self, exc: OSError) -> None:
        if not isinstance(exc, BrokenPipeError):  # (a fifo's reader gone: its end, and no news)
            warn(f"devsim: {self.what} {self.path}: {exc.strerror or exc}; it ends here")
        try:
            self._close(patience=0)
        except OSError:
            pass  # (the buffer's rest again: the descriptor is closed all the same)


class Tracer:
    """Writes a trace file (truncated when opened)."""

    def __init__(self, path: str | os.PathLike[str]) -> None:
        self.path = os.fspath(path)
        self._file = TraceFile(self.path)

    @property
    def closed(self) -> bool:
        return self._file.closed

    def record(self, direction: str, data: bytes, when: float, note: str | None = None) -> None:
        """One chunk; ``direction`` is ``"H>D"`` or ``"D>H"``."""
        if direction not in ("H>D", "D>H"):
            raise ValueError(f"direction must be 'H>D' or 'D>H', not {direction!r}")
        if not data or self._file.closed:
            return
        line = f"{when:.6f} {direction} {data.hex(' ')} {render(data)}"
        if note:
            line += f"  ({note})"
        self._write(line, when)

    def note(self, text: str, when: float) -> None:
        """A non-data event."""
        if not self._file.closed:
            self._write(f"{when:.6f} -- {text}", when)

    def _write(self, line: str, when: float) -> None:
        lost = self._file.dropped  # (a fifo's reader that did not read: the trace says where)
        if lost:
            line = f"{when:.6f} -- {lost} line{'' if lost == 1 else 's'} dropped here: the trace's reader did not take them\n{line}"
        self._file.write(line + "\n")

    def close(self) -> None:
        self._file.close()

    def __enter__(self) -> Tracer:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.close()
