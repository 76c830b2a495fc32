"""A command line of the SERS as it arrives: its state, and what its text does character by
character (manual §3.2.4, §4.1, §4.2; spec G-ADDR, G-LINE).

The serial face takes a line in one step where nothing in it can happen before its end (a
host's poll, :func:`poll_line`; a line whose statements only answer at its end, :func:`quiet`)
or where it fails at once (noise, :func:`first_failure`): these functions say when.
"""

from __future__ import annotations

import functools
import re
from collections.abc import Callable
from typing import Any

import msgspec

from devsim.devices.sers import codec
from devsim.devices.sers import statements as st
from devsim.devices.sers.access import TIMELESS, address_number, plain_reader, weighted_reader
from devsim.devices.sers.answers import Answers
from devsim.devices.sers.errors import SersError, message

__all__ = [
    "COMPLETES",
    "EXTENDS_ONLY",
    "LINE_ENDS",
    "TEXT_TO_END",
    "CommandLine",
    "KeptPoll",
    "Poll",
    "answers",
    "ends_line",
    "error_text",
    "first_byte_errors",
    "first_failure",
    "poll_line",
    "quiet",
    "runs_at_once",
]

# Characters that only ever extend the statement in progress (a number, the '?' of a query):
# nothing can complete with them, so they need no parse (the next character will do it).
EXTENDS_ONLY = frozenset("0123456789.?")
# The first character of a text run that is not one of those.
COMPLETES = re.compile(b"[^" + re.escape("".join(sorted(EXTENDS_ONLY)).encode()) + b"]")
# The rest of a line: its text and its end (within 60 characters: checked by the caller).
TEXT_TO_END = re.compile(rb"([^\r\n#]+)[\r\n]")
LINE_ENDS = (codec.CR, codec.LF)


class CommandLine(msgspec.Struct):
    """What the device knows about the command line being received (§3.2.4, §4.1)."""

    execute: bool = False  # this drive carries out the statements
    reply: bool = False  # this drive echoes and answers
    held: bytearray = msgspec.field(default_factory=bytearray)  # echo of '#' and address digits
    text: str = ""  # statement text of the current segment
    executed: int = 0  # statements of the segment already executed
    error: bool = False
    skip_next: bool = False  # single-statement IF was false
    skip_block: int = 0  # inside a false IF..THEN block (depth)
    deferred: bytearray = msgspec.field(default_factory=bytearray)  # RS-485 mode: answers until line end
    store: list[str] = msgspec.field(default_factory=list)  # programming mode: statements for the EEPROM


def answers(stmt: st.Statement) -> bool:
    """Statements that send text: their output must follow the echo of the next character."""
    if isinstance(stmt, st.Query | st.ListCmd):
        return True
    if isinstance(stmt, st.Trace):
        return stmt.query
    return isinstance(stmt, st.Command) and stmt.name == "VER"


@functools.lru_cache(maxsize=1024)
def quiet(text: bytes) -> str | None:
    """A line's text if nothing in it runs, answers or fails before its line end as the text
    arrives character by character (so it may be taken in one step, see
    :meth:`.face.SersFace._begin_line`), else None: at every character that can complete a
    statement, the text so far holds no error and no statement except one answering at its
    very end."""
    chars = text.decode("latin-1")
    for at, char in enumerate(chars):
        if char in EXTENDS_ONLY:
            continue
        result = st.parse(chars[: at + 1], False)
        if result.errno is not None:
            return None
        done = result.statements
        if done and (len(done) > 1 or done[0][1] != at + 1 or not answers(done[0][0])):
            return None
    return chars


class Poll(msgspec.Struct, frozen=True):
    """A whole line that asks one thing (``#1P11?`` and its end, §4.7), parsed once."""

    address: int | str | None
    query: st.Query
    length: int  # characters counted for the line: all but its end
    number: int | None = None  # the parameter asked, by number or alias (``P11?``, ``V?``); else None


@functools.lru_cache(maxsize=1024)
def poll_line(data: bytes) -> Poll | None:
    """``data`` as a :class:`Poll` if it is exactly one whole line, within the 60 characters,
    whose text is a single query (what a host polls with, again and again), else None.  Such a
    line, taken character by character, runs nothing before its end (:func:`quiet`)."""
    if not 2 < len(data) <= codec.MAX_LINE + 1 or data[0] != codec.HASH or data[-1] not in LINE_ENDS:
        return None
    if data.find(b"#", 1) >= 0 or data.find(b"\r", 0, -1) >= 0 or data.find(b"\n", 0, -1) >= 0:
        return None
    complete, address, stop = codec.Framer().begin_line(data, 0)
    text = quiet(data[stop:-1]) if complete else None
    if text is None:
        return None
    result = st.parse(text, True)
    if result.errno is not None or len(result.statements) != 1 or not isinstance(result.statements[0][0], st.Query):
        return None
    query = result.statements[0][0]
    number = None
    if not query.name and query.target.kind in ("P", "alias"):
        try:
            number = address_number(query.target)
        except (SersError, KeyError):
            number = None
    return Poll(address, query, len(data) - 1, number)


class KeptPoll:
    """A host's poll that the face answered, kept for the next chunk of the same bytes (a host
    polls the same lines again and again): the line's parse, and the answer last made for a
    parameter shown as its value is (:func:`.access.plain_reader`), with the whole reply it went
    out in.  The face answers a chunk of a kept poll's bytes at once while nothing else reached
    the line since a poll was answered (so the line is between lines and the drive selected:
    only a line or a power-on change that); after anything else the poll path checks the line
    again and then takes the kept poll.  Power-on drops them.  What else a poll depends on (echo
    mode P1017, programming mode, a master's request, the value, the acknowledgement, the DIP
    switches in ``cfg``) is looked at again every time, unless nothing could have changed it since
    the reply was last given (:attr:`stamp`); the value is read every time.  (Slots, the ones a
    repeated poll reads first: it touches the object.)"""

    __slots__ = ("data", "stamp", "read", "value", "reply", "cfg", "raw", "answer", "ack", "scaling", "poll", "timeless")

    #: Polls a face keeps at most (a host polls a few parameters in turn).
    MOST = 8

    def __init__(self, data: bytes, poll: Poll, cfg: object) -> None:
        self.data = data  # the chunk
        self.poll = poll
        self.cfg = cfg  # the configuration it was made under (address, encoding)
        #: The parameter's value (None: answered the general way)
        self.read: Callable[[Any], Any] | None = None if poll.number is None else plain_reader(poll.number)
        #: For a weighted parameter: what its answer is made of besides the weighting (and the
        #: weighting it was last made with, :attr:`scaling`), :func:`.access.weighted_reader`
        self.raw: Callable[[Any], Any] | None = None if poll.number is None else weighted_reader(poll.number)
        self.scaling: object = None
        self.value: Any = _NOTHING  # the value last answered, and its answer line
        self.answer = b""
        self.ack = b""  # the acknowledgement that went out with it, and the whole reply
        self.reply = b""
        #: The count of changes (:mod:`devsim.core.changes`) when :attr:`reply` was last given
        #: at once, all checked (-1: not yet)
        self.stamp = -1
        #: The value changes only with the drive's state (:data:`.access.TIMELESS`): the reply
        #: stands while the count does (:class:`devsim.core.device.Standing`)
        self.timeless = poll.number in TIMELESS

    def reply_with(self, data: bytes, answer: bytes, ack: bytes) -> bytes:
        """The echo ``data``, ``answer`` and ``ack`` in one piece (the one kept when they are the
        ones it was made of): what leaves for the poll in echo mode 0 or 1.  (Repeated inline in
        :meth:`.polls.KeptPolls.answer_at_once`.)"""
        if answer is not self.answer or ack is not self.ack or not self.reply:
            self.reply, self.ack = b"".join((data, answer, ack)), ack
        return self.reply

    def answer_line(self, answers: Answers, encoding: str) -> bytes:
        """The poll's answer line as the drive stands now (a :class:`SersError` as the query's
        own), the general way: for a query that is no value shown as it is (:attr:`read` None)."""
        poll = self.poll
        if poll.number is None:
            return (answers.query_text(poll.query) + "\n\r").encode(encoding, errors="replace")
        return answers.parameter_line(poll.query.target, poll.number, encoding)

    def remake(self, value: Any, answers: Answers, encoding: str) -> bytes:
        """The answer line for ``value`` read now (:attr:`read`), other than the one kept: kept."""
        line = answers.plain_line(self.poll.query.target, self.poll.number, value, encoding)  # type: ignore[arg-type]
        self.value, self.answer, self.reply = value, line, b""
        return line


_NOTHING = object()


@functools.lru_cache(maxsize=512)
def error_text(errno: int, english: bool, encoding: str, detail: str = "", trailing_star: bool = False) -> bytes:
    """An error message as the drive sends it (§4.8.3.1): ``*`` and its text on a line of its own;
    with ``trailing_star`` (spec G-ERRFMT ⚙ ``error_trailing_star``, the manual's OCR example
    ``*Endschalter Schalter offen*``) a ``*`` after the text too."""
    text = message(errno, english, detail) + "*" if trailing_star else message(errno, english, detail)
    return ("\n*" + text + "\n\r").encode(encoding, errors="replace")


def ends_line(data: bytes, start: int, stop: int) -> bool:
    """Whether a CR or LF is among ``data[start:stop]``."""
    return data.find(b"\r", start, stop) >= 0 or data.find(b"\n", start, stop) >= 0


@functools.cache
def first_byte_errors() -> tuple[int, ...]:
    """For each byte value: the errno of a line's text whose first character it is (not CR,
    LF, ``#``) when that character is an error as it arrives (what :func:`first_failure`
    finds at the first character), else 0.  Made at the first use."""
    errors = []
    for byte in range(256):
        char = chr(byte)
        result = st.parse(char, False) if char not in EXTENDS_ONLY else None
        errors.append(result.errno or 0 if result is not None and not result.statements else 0)
    return tuple(errors)


@functools.cache
def runs_at_once() -> frozenset[int]:
    """The bytes that, as the first character of a line's text, complete a statement by
    themselves (``H``, ``S``: it runs as it arrives, before the next character).  Made at the
    first use."""
    return frozenset(byte for byte in range(256)
                     if chr(byte) not in EXTENDS_ONLY and byte not in (codec.CR, codec.LF, codec.HASH)
                     and st.parse(chr(byte), False).statements)


@functools.lru_cache(maxsize=1024)
def first_failure(text: bytes) -> tuple[int, int] | None:
    """Where a line's text fails before any statement completes, as it arrives character by
    character: ``(characters up to and including the one that made the error, errno)``, or
    None (a statement completes first, or no error)."""
    chars = text.decode("latin-1")
    for at, char in enumerate(chars):
        if char in EXTENDS_ONLY:
            continue
        result = st.parse(chars[: at + 1], False)
        if result.statements:
            return None
        if result.errno is not None:
            return at + 1, result.errno
    return None
