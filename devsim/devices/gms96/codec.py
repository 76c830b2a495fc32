"""GMS96 link layer: DIN 19244 / IEC 60870-5-1 FT1.2 frames and the GMS96 user data.

Implements spec §3.2 (frame formats), §3.5 (letter commands in the Langsatz, 24-bit
parameters, manual M §2.3), §3.6 (Kurzsatz commands and the #1 status answer, manual
M §2.3.2) and the numeric encodings of Appendix B.  Pure: no I/O, no clock – the time of
arrival is passed to :meth:`FrameDecoder.feed` – so the decoder is exact, fast and fuzzable
(design principle 1, in the style of h11).

Frames on the wire::

    E5h | A2h                               single control character (SingleChar)
    10h C A [AE...] CS 16h                  Kurzsatz, CS = (C + A + AE...) mod 256 (ShortFrame)
    68h L L 68h C A data... CS 16h          Langsatz, L = 2 + len(data), CS over C..data (LongFrame)

The decoder frames by structure – start byte, the two length octets, the checksum and the
end byte 16h – never by timing.  The inter-character timeout only discards a stale partial
frame; it is never glued to later bytes (spec §3.7, design pitfalls).  Every byte fed ends up
in exactly one decoded frame, one :class:`FrameError`, or the pending partial frame.
"""

from __future__ import annotations

import re
from collections.abc import Callable

import msgspec

__all__ = [
    "ACK",
    "NACK_CHAR",
    "START_SHORT",
    "START_LONG",
    "END",
    "SingleChar",
    "ShortFrame",
    "LongFrame",
    "Frame",
    "FrameError",
    "FrameDecoder",
    "encode",
    "checksum",
    "letter",
    "parse_letter",
    "to_s24",
    "wrap24",
    "from_s24",
    "control_host",
    "short_command_number",
    "short_command",
    "short_extension_device",
    "short_extension_host",
    "k_bytes",
    "k_frame",
    "t_reply",
    "FCB",
    "FCV",
    "PRM",
    "ACD",
    "DFC",
    "AE_FLAG",
    "S24_MIN",
    "S24_MAX",
]

ACK = 0xE5  #: single control character SC1: positive acknowledgement (spec §3.2 a)
NACK_CHAR = 0xA2  #: single control character SC2 (not used by the GMS manual)
START_SHORT = 0x10  #: start of a frame with fixed length (Kurzsatz)
START_LONG = 0x68  #: start of a frame with variable length (Langsatz)
END = 0x16  #: end character of both frame types

# Control field bits (spec §3.3).
PRM = 0x40  #: message from the primary station (host)
FCB = 0x20  #: frame count bit (primary)
FCV = 0x10  #: frame count bit valid (primary)
ACD = 0x20  #: access demand (secondary)
DFC = 0x10  #: data flow control (secondary)
AE_FLAG = 0x02  #: Kurzsatz F / K bit 1: address-extension octets follow the address (spec §3.6)

S24_MIN = -0x800000
S24_MAX = 0x7FFFFF

_MAX_L = 255  # largest Langsatz length field
_LETTER_PARAMS = 3


class SingleChar(msgspec.Struct, frozen=True):
    """A single control character (spec §3.2 a): ``E5h`` (ACK, also "no data") or ``A2h``."""

    value: int


class ShortFrame(msgspec.Struct, frozen=True):
    """Kurzsatz ``10h C A [AE...] CS 16h`` (manual §2.3.2, spec §3.6): control field ("F-Feld"), link address and the
    address-extension (AE) octets that carry short-command data or the MB4 message."""

    control: int
    address: int
    extension: bytes = b""


class LongFrame(msgspec.Struct, frozen=True):
    """Langsatz ``68h L L 68h C A data CS 16h`` (manual §2.3, spec §3.5); ``data`` is the link user data after A
    (for GMS96: command character and parameters, or identifier and value)."""

    control: int
    address: int
    data: bytes


Frame = SingleChar | ShortFrame | LongFrame


class FrameError(msgspec.Struct, frozen=True):
    """Bytes that did not form a frame, discarded without reply (spec §3.2 R6, §3.10).

    ``reason`` is one of ``"garbage"`` (bytes outside any frame), ``"timeout"`` (a partial
    frame went stale), ``"length"`` (Langsatz L below 2), ``"length_mismatch"`` (the two L
    octets differ), ``"start_byte"`` (the second 68h of a Langsatz header is missing),
    ``"checksum"`` or ``"end_byte"`` (no 16h where the frame must end).
    """

    reason: str
    discarded: bytes


def checksum(data: bytes) -> int:
    """FT1.2 checksum: arithmetic sum of the octets modulo 256 (spec §3.2 R5)."""
    return sum(data) & 0xFF


def _octet(name: str, value: int) -> int:
    if not isinstance(value, int) or not 0 <= value <= 0xFF:
        raise ValueError(f"{name} must be an octet 0..255, not {value!r}")
    return value


_SHORT_START = bytes([START_SHORT])


def encode(frame: Frame) -> bytes:
    """The wire bytes of ``frame``; ``ValueError`` for fields that do not fit."""
    if isinstance(frame, SingleChar):
        return bytes([_octet("single character", frame.value)])
    if isinstance(frame, ShortFrame):
        control, address = frame.control, frame.address
        if type(control) is not int or type(address) is not int or not 0 <= control <= 0xFF or not 0 <= address <= 0xFF:
            _octet("control", control)  # (raises, naming the field)
            _octet("address", address)
        body = bytes((control, address)) + bytes(frame.extension)
        return b"".join((_SHORT_START, body, bytes((sum(body) & 0xFF, END))))
    if isinstance(frame, LongFrame):
        body = bytes([_octet("control", frame.control), _octet("address", frame.address)])
        body += bytes(frame.data)
        if len(body) > _MAX_L:
            raise ValueError(f"Langsatz user data too long: L = {len(body)} > {_MAX_L}")
        n = len(body)
        return bytes([START_LONG, n, n, START_LONG]) + body + bytes([checksum(body), END])
    raise TypeError(f"not a GMS96 frame: {frame!r}")


# -- decoder ---------------------------------------------------------------------------------

_INCOMPLETE = object()
_WHOLE_FRAMES = 16  # distinct whole-frame chunks a decoder remembers (a host polls with a few; ~2 KB at most)
_WHOLE_SIZE = 16  # the longest chunk remembered (Kurzsätze and short Langsätze)


class FrameDecoder:
    """Sans-IO frame decoder for one direction of the line.

    ``short_extension(control)`` is the number of AE octets a Kurzsatz with this control field
    carries: :func:`short_extension_device` on the card side (#8: 2, #9: 1, spec §3.6 rules
    1/2), :func:`short_extension_host` on the host side (the K answer carries one when bit 1
    is set).  ``char_timeout`` is the inter-character timeout in seconds after which a partial
    frame is discarded.  With ``accept_single`` (host side) the single characters E5h and A2h
    are frames; otherwise (card side) they are garbage like any byte outside a frame.
    """

    def __init__(
        self,
        *,
        short_extension: Callable[[int], int] = lambda control: 0,
        char_timeout: float = 0.05,
        accept_single: bool = False,
    ) -> None:
        self.short_extension = short_extension
        self.char_timeout = char_timeout
        self.accept_single = accept_single
        self._starts = frozenset({START_SHORT, START_LONG} | ({ACK, NACK_CHAR} if accept_single else set()))
        self._start_re: re.Pattern[bytes] | None = None
        #: the bytes of a partial frame held, waiting for the rest (:attr:`pending` of them)
        self.partial = bytearray()
        self._last = 0.0
        #: chunks that were one whole frame and nothing else, with that frame (frames are frozen:
        #: a host's repeated poll is decoded once); at most :data:`_WHOLE_FRAMES` of them
        self._whole: dict[bytes, Frame] = {}

    @property
    def pending(self) -> int:
        """Number of bytes of a partial frame held (waiting for the rest)."""
        return len(self.partial)

    def reset(self) -> bytes:
        """Forget a partial frame without reporting it; returns the bytes dropped."""
        dropped = bytes(self.partial)
        self.partial.clear()
        return dropped

    def expire(self, now: float) -> list[FrameError]:
        """Discard a partial frame whose last byte is older than ``char_timeout``."""
        if self.partial and now - self._last > self.char_timeout:
            stale = bytes(self.partial)
            self.partial.clear()
            return [FrameError("timeout", stale)]
        return []

    def feed(self, data: bytes, now: float) -> list[Frame | FrameError]:
        """Bytes received at time ``now`` (seconds, any monotonic origin); returns the frames
        and errors they complete, in order.  Never raises on any input."""
        if self.partial:
            out: list[Frame | FrameError] = list(self.expire(now))
            if not data:
                return out
            work = bytes(self.partial) + bytes(data)
            self.partial.clear()
        else:  # nothing pending (a host's whole frame): no copies
            if not data:
                return []
            work = data if type(data) is bytes else bytes(data)
            frame = self._whole.get(work)
            if frame is not None:  # the same whole frame as before: the same frame
                self._last = now
                return [frame]
            out = []
            if len(work) <= _WHOLE_SIZE and len(self._whole) < _WHOLE_FRAMES:
                found = self._parse(work, 0) if work[0] in self._starts else None
                if type(found) is tuple and found[1] == len(work):
                    self._whole[work] = found[0]
        self._last = now
        starts = self._starts
        i = 0
        n = len(work)
        while i < n:
            if work[i] not in starts:
                j = self._next_start(work, i)
                out.append(FrameError("garbage", work[i:j]))
                i = j
                continue
            result = self._parse(work, i)
            if result is _INCOMPLETE:
                self.partial += work[i:]
                break
            if isinstance(result, str):  # an error at this start byte: resynchronise
                j = self._next_start(work, i + 1)
                out.append(FrameError(result, work[i:j]))
                i = j
                continue
            frame, end = result
            out.append(frame)
            i = end
        return out

    def _next_start(self, work: bytes, i: int) -> int:
        """The next start byte at or after ``i`` (one regex search, not a loop per byte)."""
        if self._start_re is None:
            self._start_re = re.compile(b"[" + b"".join(re.escape(bytes([b])) for b in sorted(self._starts)) + b"]")
        found = self._start_re.search(work, i)
        return len(work) if found is None else found.start()

    def _extension(self, control: int) -> int:
        try:
            count = int(self.short_extension(control))
        except Exception:  # a faulty callback must not break the line
            return 0
        return max(0, min(count, 250))

    def _parse(self, work: bytes, i: int) -> object:
        """At start byte ``work[i]``: ``(frame, end)``, an error reason, or ``_INCOMPLETE``."""
        start = work[i]
        avail = len(work) - i
        if start in (ACK, NACK_CHAR):
            return SingleChar(start), i + 1
        if start == START_SHORT:
            if avail < 2:
                return _INCOMPLETE
            size = 5 + self._extension(work[i + 1])
            if avail < size:
                return _INCOMPLETE
            body = work[i + 1 : i + size - 2]
            if work[i + size - 1] != END:
                return "end_byte"
            if checksum(body) != work[i + size - 2]:
                return "checksum"
            return ShortFrame(body[0], body[1], bytes(body[2:])), i + size
        # Langsatz header 68 L L 68, checked octet by octet as it arrives.
        if avail < 2:
            return _INCOMPLETE
        length = work[i + 1]
        if length < 2:
            return "length"
        if avail < 3:
            return _INCOMPLETE
        if work[i + 2] != length:
            return "length_mismatch"
        if avail < 4:
            return _INCOMPLETE
        if work[i + 3] != START_LONG:
            return "start_byte"
        size = length + 6
        if avail < size:
            return _INCOMPLETE
        body = work[i + 4 : i + 4 + length]
        if work[i + size - 1] != END:
            return "end_byte"
        if checksum(body) != work[i + size - 2]:
            return "checksum"
        return LongFrame(body[0], body[1], bytes(body[2:])), i + size


# -- GMS96 user data (spec §3.5, manual M §2.3) -----------------------------------------------


def to_s24(value: int) -> bytes:
    """A parameter as 3 octets, low byte first, 24-bit two's complement (M §2.3).

    Accepts −2^23 … 2^24−1: values from 2^23 up are sent as their 24-bit pattern (they read
    back negative, e.g. ``0xFFFFFF`` = −1 = ``Q-1``)."""
    if not isinstance(value, int) or not S24_MIN <= value <= 0xFFFFFF:
        raise ValueError(f"parameter {value!r} does not fit in 24 bits")
    return (value & 0xFFFFFF).to_bytes(3, "little")


def from_s24(b: bytes) -> int:
    """3 octets, low byte first, as a signed 24-bit value (Appendix B)."""
    if len(b) != 3:
        raise ValueError(f"a 24-bit parameter has 3 octets, not {len(b)}")
    x = int.from_bytes(bytes(b), "little")
    return x - 0x1000000 if x & 0x800000 else x


def letter(command: str, *params: int) -> bytes:
    """Langsatz user data of a letter command: ``b'A' + P1 [+ P2 [+ P3]]`` (M §2.3)."""
    if not isinstance(command, str) or len(command) != 1 or ord(command) > 0xFF:
        raise ValueError(f"a command character is one latin-1 character, not {command!r}")
    if len(params) > _LETTER_PARAMS:
        raise ValueError(f"at most 3 parameters, got {len(params)}")
    return command.encode("latin-1") + b"".join(to_s24(p) for p in params)


def parse_letter(data: bytes) -> tuple[str, tuple[int, int, int], int] | None:
    """``(command, (P1, P2, P3), number of parameters sent)``; parameters not sent are 0.

    ``None`` for a malformed parameter count (spec §3.5: no execution, no reply): empty data,
    ``len(data) - 1`` not a multiple of 3, or more than 3 parameters.  The PLC download
    command ``a`` (spec §3.8.24) may have any length: its P1..P3 are decoded from the first
    complete triples (count = how many, at most 3); the device keeps ``data[1:]`` raw.
    """
    if not data:
        return None
    command = chr(data[0])
    rest = bytes(data[1:])
    if command == "a":
        count = min(len(rest) // 3, _LETTER_PARAMS)
    else:
        if len(rest) % 3 or len(rest) > 3 * _LETTER_PARAMS:
            return None
        count = len(rest) // 3
    values = [from_s24(rest[3 * k : 3 * k + 3]) for k in range(count)]
    values += [0] * (_LETTER_PARAMS - count)
    return command, (values[0], values[1], values[2]), count


# -- control fields and GMS96 frames (spec §3.3, §3.6) ----------------------------------------


def control_host(fcb: int, fcv: int = 1, fc: int = 3) -> int:
    """Control field of a host (primary, PRM=1) frame: ``53h`` / ``73h`` for user data with
    FCB 0 / 1 (spec §3.5); ``control_host(0, 0, 0)`` = ``40h`` is "reset of remote link"."""
    return PRM | (FCB if fcb else 0) | (FCV if fcv else 0) | (fc & 0x0F)


def short_command_number(control: int) -> int:
    """The #-command number of a Kurzsatz F field: ``F & 0x0D`` (spec §3.6 rule 1)."""
    return control & 0x0D


def short_extension_device(control: int) -> int:
    """Card side: AE octets by command number, not by bit 1 (#8: 2, #9: 1; spec §3.6 rule 2)."""
    return {8: 2, 9: 1}.get(short_command_number(control), 0)


def short_extension_host(control: int) -> int:
    """Host side: the #1 answer carries one AE octet (MB4) when K bit 1 is set (spec §3.6)."""
    return 1 if control & AE_FLAG else 0


def short_command(number: int, address: int, extension: bytes = b"") -> ShortFrame:
    """Host Kurzsatz for ``#number``: F = number, with bit 1 set when AE octets follow
    (#0 → 00h, #1 → 01h, #8 → 0Ah, #9 → 0Bh; spec §3.6, Appendix B)."""
    control = number | AE_FLAG if extension else number
    return ShortFrame(_octet("command number", control), address, bytes(extension))


def k_frame(k: int, address: int, mb4: int | None) -> ShortFrame:
    """The card's answer to #1: status byte K, with K.1 set and MB4 as AE octet when a
    message is sent (M §2.3.2; octet after A per spec §3.6 / G3)."""
    if mb4 is None:
        return ShortFrame(k & ~AE_FLAG & 0xFF, address)
    return ShortFrame((k | AE_FLAG) & 0xFF, address, bytes([_octet("MB4", mb4)]))


def k_bytes(k: int, address: int, mb4: int | None) -> bytes:
    """``encode(k_frame(k, address, mb4))`` in one step (the answer to every status poll; the
    answers without MB4 are kept, by K byte and address: at most 256 × 256 of 5 bytes)."""
    if mb4 is None:
        answer = _K_ANSWERS.get((k, address))
        if answer is not None:
            return answer
    if mb4 is not None or type(address) is not int or not 0 <= address <= 0xFF or type(k) is not int:
        return encode(k_frame(k, address, mb4))
    control = k & ~AE_FLAG & 0xFF
    answer = bytes((START_SHORT, control, address, (control + address) & 0xFF, END))
    if 0 <= k <= 0xFF:
        _K_ANSWERS[(k, address)] = answer
    return answer


_K_ANSWERS: dict[tuple[int, int], bytes] = {}


def t_reply(address: int, identifier: int, value: bytes, control: int = 0x08) -> LongFrame:
    """The card's answer to ``T``: Langsatz ``A I val`` with F = 08h (user data, spec §3.5);
    E-version may add ACD 20h / DFC 10h (spec §3.9)."""
    return LongFrame(control, address, bytes([_octet("identifier", identifier)]) + bytes(value))


def wrap24(value: int) -> int:
    """Positions travel as 24-bit two's complement (wrap-around, spec §5.1)."""
    value &= 0xFFFFFF
    return value - 0x1000000 if value & 0x800000 else value
