"""SERS line framing (manual §4.1, §4.2; spec §3.1, G-HASH, G-CRLF, G-LINE).

Pure and byte-at-a-time: :meth:`Framer.feed` takes one received byte and returns what it
means for the line being assembled.  The device decides what to echo, execute and answer.

* Bytes before ``#`` are noise and ignored (no echo, no answer).
* ``#`` starts a line; decimal digits directly after it are the drive address, ``*`` the
  broadcast address.  A ``#`` inside a line restarts statement parsing (and may carry a new
  address), like a separator.
* CR or LF ends a line; the other terminator directly after it is the second half of a pair
  and produces no second acknowledgement (unless ``ack_each_terminator``, G-CRLF ⚙: the face
  acknowledges it).
* At most 60 characters per line are kept; the rest is dropped and reported at the line end.
"""

from __future__ import annotations

import functools
import re

import msgspec

__all__ = ["MAX_LINE", "NO_ADDRESS", "Address", "address_value", "text_end", "Framer", "Ignored", "LineEnd", "Noise", "read_address",
           "Restart", "TextChar"]

MAX_LINE = 60
CR, LF, HASH = 0x0D, 0x0A, 0x23


class Ignored(msgspec.Struct, frozen=True):
    """Noise outside a line, or the second half of a CR/LF pair (``pair``)."""

    pair: bool = False


Noise = Ignored


class Restart(msgspec.Struct, frozen=True):
    """``#`` arrived: a new line (``mid_line`` False) or a restart inside the line."""

    mid_line: bool


class AddressChar(msgspec.Struct, frozen=True):
    """A digit (or ``*``) of the address; its echo is held until the address is complete."""


class Address(msgspec.Struct, frozen=True):
    """The address token is complete: a drive number, ``"*"`` or ``None`` (no address given)."""

    value: int | str | None


class TextChar(msgspec.Struct, frozen=True):
    """A character of the statement text; ``dropped`` when beyond the 60-character limit."""

    char: str
    dropped: bool = False


class LineEnd(msgspec.Struct, frozen=True):
    """CR or LF ended the line; ``overflow`` if characters were dropped."""

    overflow: bool


_ADDRESS_CHAR = AddressChar()
_IGNORED = Ignored()


_NOT_HASH_OR_DIGIT = re.compile(rb"[^#0-9]")
_DIGITS = re.compile(rb"[0-9]+")
_DIGIT_BYTES = frozenset(b"0123456789")
_ADDRESS = re.compile(rb"\*|[0-9]*")
#: Bytes after a '#' that cannot begin an address (a '#' is left to feed(), see begin_line).
NO_ADDRESS = frozenset(range(256)) - frozenset(b"0123456789*#")


def text_end(data: bytes, start: int) -> int:
    """Where a run of a line's text from ``start`` ends: its end (the next CR or LF) or a ``#``
    (a restart), or the chunk's end.  Three ``bytes.find`` (a ``memchr`` each, about 1.6 k
    instructions a call whatever the length) rather than a regex ``[\\r\\n#]``, whose character
    set costs about 50 instructions a byte (noise's texts are about 100 bytes long)."""
    stop = data.find(b"#", start)
    if stop < 0:
        stop = len(data)
    found = data.find(b"\r", start, stop)
    if found >= 0:
        stop = found
    found = data.find(b"\n", start, stop)
    return stop if found < 0 else found


class Framer:
    """Assembles SERS command lines from bytes (§3.2: ``#``, the address, the text, CR/LF)."""

    def __init__(self) -> None:
        self.in_line = False
        self._addr: str | None = None  # digits collected, None once the address phase ended
        self._length = 0
        self._overflow = False
        self._last_end: int | None = None

    def reset(self) -> None:
        self.in_line = False
        self._addr = None
        self._length = 0
        self._overflow = False
        self._last_end = None

    @property
    def idle(self) -> bool:
        """Between lines, with no line end to pair: only a ``#`` can change anything."""
        return not self.in_line and self._last_end is None

    def skip_noise(self, data: bytes, start: int) -> int:
        """Outside a line, when :attr:`idle` or ``data[start]`` is no line end: where the next
        byte that matters is (a ``#``).  The noise in between is skipped with one search
        instead of byte by byte (none of it can be the second half of a CR/LF pair)."""
        found = data.find(b"#", start)
        self._last_end = None
        return len(data) if found < 0 else found

    @property
    def length(self) -> int:
        """Characters of the line so far (``#``, address, text), counted for the 60-character
        limit (§4.1)."""
        return self._length

    @property
    def in_text(self) -> bool:
        """Inside a line, past the address: every byte up to CR, LF or ``#`` is text."""
        return self.in_line and self._addr is None

    def skip_text(self, data: bytes, start: int) -> int:
        """When :attr:`in_text` and the text is not wanted (a line in error, or for another
        drive): where the text ends (the next CR, LF or ``#``), counted into the line's length
        as :meth:`feed` would, in one search."""
        end = text_end(data, start)
        self._length += end - start
        if self._length > MAX_LINE:
            self._overflow = True
        if end > start:
            self._last_end = None
        return end

    def begin_line(self, data: bytes, start: int) -> tuple[bool, int | str | None, int]:
        """``data[start]`` is a ``#`` outside a line or in its text: take it and the address
        after it at once, as :meth:`feed` would byte by byte.  Returns whether the address is
        complete (the next byte is text or a line end), its value, and where the bytes taken
        end; an address the chunk cuts off (or a ``#`` right after it) is left to :meth:`feed`."""
        complete, address, stop = read_address(data, start)
        self._last_end = None
        if self.in_line:  # a restart inside the line: its length goes on
            self._length += stop - start
        else:
            self.in_line = True
            self._overflow = False
            self._length = stop - start
        if complete:
            self._addr = None
            return True, address, stop
        self._addr = data[start + 1 : stop].decode("ascii")
        return False, None, stop

    def take_line(self, head: int, text: int) -> None:
        """A ``#`` with its complete address (``head`` characters) and ``text`` characters of
        text after it were taken at once, as :meth:`begin_line` and then :meth:`skip_text`
        count them: a new line outside one, a restart inside one."""
        if self.in_line:
            self._length += head + text
        else:
            self.in_line, self._overflow, self._length = True, False, head + text
        self._addr = None
        self._last_end = None
        if text and self._length > MAX_LINE:
            self._overflow = True

    def skip_unaddressed(self, data: bytes, start: int, mine: int) -> int:
        """For drive ``mine`` (its address) while it is not selected, outside a line or in the
        text of a line it neither executes nor answers: where the next ``#`` that can concern
        it is (followed by ``*`` or by its address), with the lines in between, other drives'
        lines among them, framed in one step as :meth:`feed` would byte by byte (line ends,
        restarts, the 60-character count).  A ``#`` whose address the chunk cuts off (or that
        ends the chunk) is left to :meth:`feed` (more digits may follow)."""
        found = _concerning(mine).search(data, start)
        stop = len(data) if found is None else found.start()
        if stop <= start:
            return start
        last_end = max(data.rfind(b"\r", start, stop), data.rfind(b"\n", start, stop))
        tail = start
        if last_end >= 0:
            tail = last_end + 1
            if tail == stop:  # (right before the '#': whether it ended a line matters, it may pair)
                previous = max(data.rfind(b"\r", start, last_end), data.rfind(b"\n", start, last_end))
                if previous >= 0:
                    ended = data.find(b"#", previous + 1, last_end) >= 0
                else:
                    ended = self.in_line or data.find(b"#", start, last_end) >= 0
                self.in_line = False
                self._last_end = data[last_end] if ended else None
                return stop
            self.in_line = False  # (bytes follow the last line end: it pairs with none of them)
        self._last_end = None
        if not self.in_line:
            opened = data.find(b"#", tail, stop)
            if opened < 0:
                return stop  # noise between lines
            self.in_line, self._addr, self._length, self._overflow = True, None, 0, False
            tail = opened
        self._length += stop - tail
        beyond = min(self._length - MAX_LINE, stop - tail)
        if beyond > 0 and _holds_text(data, stop - beyond, stop, tail):
            self._overflow = True  # a text character beyond the limit (a '#' or an address sets nothing)
        return stop

    def whole_line(self, length: int, byte: int) -> None:
        """Outside a line: a whole line of ``length`` characters (``#``, address, text, at most
        :data:`MAX_LINE`) and its end ``byte`` were taken at once, as :meth:`begin_line`,
        :meth:`take_text` and :meth:`end_line` would take them."""
        self.in_line = False
        self._addr = None
        self._length = length
        self._overflow = False
        self._last_end = byte

    def lines_taken(self, last_end: int | None) -> None:
        """Outside a line: whole lines, each with its end (and the other half of a CR/LF pair
        or noise after it), were taken at once; ``last_end`` is the last one's end when nothing
        came after it (it may pair with the next byte), else None."""
        self.in_line = False
        self._addr = None
        self._last_end = last_end

    def end_line(self, byte: int) -> bool:
        """When :attr:`in_text`: CR or LF ``byte`` ends the line, as :meth:`feed` would;
        returns whether characters were dropped (the ``overflow`` of :class:`LineEnd`)."""
        self.in_line = False
        self._last_end = byte
        return self._overflow

    def text_run(self, data: bytes, start: int) -> int:
        """When :attr:`in_text`: where the run of kept text characters from ``start`` ends (the
        next CR, LF or ``#``, or the 60-character limit).  Changes nothing; :meth:`take_text`
        then accounts for the characters taken, as :meth:`feed` would one by one."""
        return min(text_end(data, start), start + max(0, MAX_LINE - self._length))

    def take_text(self, count: int) -> None:
        """``count`` text characters (within the limit) were taken by the device."""
        if count:
            self._length += count
            self._last_end = None

    def feed(self, byte: int) -> list[object]:
        events: list[object] = []
        last_end, self._last_end = self._last_end, None
        if byte in (CR, LF):
            if not self.in_line:
                pair = last_end is not None and last_end != byte
                events.append(Ignored(pair=pair))
                return events
            if self._addr is not None:
                events.append(self._end_address())
            events.append(LineEnd(self._overflow))
            self.in_line = False
            self._last_end = byte
            return events
        if byte == HASH:
            events.append(Restart(mid_line=self.in_line))
            if not self.in_line:
                self._length = 0
                self._overflow = False
            self.in_line = True
            self._addr = ""
            self._length += 1
            return events
        if not self.in_line:
            events.append(_IGNORED)
            return events
        self._length += 1
        if self._addr is not None:
            ch = chr(byte)
            if ("0" <= ch <= "9" and self._addr != "*") or (ch == "*" and self._addr == ""):
                self._addr += ch
                events.append(_ADDRESS_CHAR)
                return events
            events.append(self._end_address())
        if self._length > MAX_LINE:
            self._overflow = True
            events.append(TextChar(chr(byte), dropped=True))
        else:
            events.append(TextChar(chr(byte)))
        return events

    def _end_address(self) -> Address:
        digits, self._addr = self._addr, None
        return Address(address_value(digits or ""))


@functools.cache
def _concerning(mine: int) -> re.Pattern[bytes]:
    """A ``#`` that can concern drive ``mine`` while it is not selected: followed by ``*``, by
    its address (leading zeros allowed), or by digits up to the chunk's end, or ending it.
    (The lookahead first: at a ``#`` followed by anything else, what noise mostly has, the
    search fails at once instead of trying each alternative: 5 k instructions per 4 KiB.)"""
    return re.compile(rb"#(?![^*0-9])(?:\*|0*" + str(mine).encode() + rb"(?![0-9])|[0-9]*\Z)")


def _holds_text(data: bytes, first: int, stop: int, line_start: int) -> bool:
    """Whether ``data[first:stop]``, the last bytes of a line whose bytes in this chunk begin
    at ``line_start`` (its ``#``, or text), holds a text character: any byte but ``#`` and the
    digits of an address (right after a ``#``)."""
    if _NOT_HASH_OR_DIGIT.search(data, first, stop):
        return True
    for run in _DIGITS.finditer(data, first, stop):  # (only '#' and digits left)
        at = run.start()
        while at > line_start and data[at - 1] in _DIGIT_BYTES:
            at -= 1
        if at == line_start or data[at - 1] != HASH:
            return True
    return False


def read_address(data: bytes, start: int) -> tuple[bool, int | str | None, int]:
    """``data[start]`` is a ``#``: the address after it, as :meth:`Framer.begin_line` takes it,
    but changing nothing.  Returns whether it is complete (the next byte is text or a line
    end), its value (None when incomplete) and where it ends."""
    after = data[start + 1] if start + 1 < len(data) else HASH
    if after in NO_ADDRESS:  # the common case in noise: no address at all
        return True, None, start + 1
    stop = _ADDRESS.match(data, start + 1).end()  # type: ignore[union-attr]
    if stop < len(data) and data[stop] != HASH:
        return True, address_value(data[start + 1 : stop].decode("ascii")), stop
    return False, None, stop


def address_value(digits: str) -> int | str | None:
    """The drive address after ``#``: a number, ``"*"`` (broadcast) or ``None`` (none given)."""
    if not digits:
        return None
    if digits == "*":
        return "*"
    return int(digits)
