"""SAIA S-Bus as the PCD4.H3 simulator's host link (spec pcd4h3.md §9.2–§9.4): the serial data
mode (SM2) with its frame synchronisation, byte stuffing and CRC, and Ether-S-Bus frames for TCP
and UDP.

Pure, no I/O: :class:`SerialReceiver` takes the host's bytes (split anywhere) and returns the
complete requests addressed to the station, :func:`serial_reply` and :func:`ether_reply` lay out
the answers, :func:`parse_ether` and :class:`EtherReceiver` read Ether-S-Bus frames.  A request
is a :class:`Request` (station, command, parameter bytes).  How a command's parameters are laid
out is its :class:`Telegram` (:class:`Reads`, :class:`Writes`, :class:`NoParameters`), which
reads them into a read or write of PLC media; the station's table of commands (the kind's
``services.SERVICES``) says which command code has which, and the receiver asks it (a
:data:`Telegrams` lookup) where a telegram ends.  CRC errors, framing errors and other stations
are dropped silently (§9.2).
"""

from __future__ import annotations

import struct
from collections.abc import Callable
from typing import Protocol

import msgspec

__all__ = [
    "ACK", "BROADCAST", "Bad", "EtherReceiver", "NAK", "NoParameters", "Read", "Reads", "Request", "SerialReceiver",
    "Simple", "Telegram", "Telegrams", "Write", "Writes", "crc16", "decode_command", "ether_ack", "ether_frame",
    "ether_reply", "pack_bits", "parse_ether", "serial_ack", "serial_reply", "stuff", "unstuff",
]

FS, DLE = 0xB5, 0xC5
REQUEST, RESPONSE, ACK_NAK = 0x00, 0x01, 0x02
ACK, NAK = 0x0000, 0x0001
BROADCAST = 255


def crc16(data: bytes, value: int = 0) -> int:
    """CRC-16/XMODEM: polynomial 1021h, initial value 0, no reflection (check "123456789" = 31C3h)."""
    for byte in data:
        value ^= byte << 8
        for _ in range(8):
            value = ((value << 1) ^ 0x1021) & 0xFFFF if value & 0x8000 else (value << 1) & 0xFFFF
    return value


def stuff(telegram: bytes) -> bytes:
    """The wire form: after the leading FS every B5h is C5h 00h and every C5h is C5h 01h."""
    return telegram[:1] + telegram[1:].replace(b"\xc5", b"\xc5\x01").replace(b"\xb5", b"\xc5\x00")


def unstuff(wire: bytes) -> bytes | None:
    """The telegram of a wire form, or None for C5h followed by anything but 00h/01h."""
    out = bytearray(wire[:1])
    index = 1
    while index < len(wire):
        byte = wire[index]
        if byte == DLE:
            if index + 1 >= len(wire) or wire[index + 1] not in (0, 1):
                return None
            out.append(FS if wire[index + 1] == 0 else DLE)
            index += 2
            continue
        out.append(byte)
        index += 1
    return bytes(out)


def _with_crc(body: bytes) -> bytes:
    return body + struct.pack(">H", crc16(body))


def serial_reply(data: bytes) -> bytes:
    """A response telegram with ``data``, on the wire."""
    return stuff(_with_crc(bytes((FS, RESPONSE)) + data))


def serial_ack(code: int = ACK) -> bytes:
    """ACK (0) or NAK (1 … 4) on the wire."""
    return stuff(_with_crc(bytes((FS, ACK_NAK)) + struct.pack(">H", code)))


class Request(msgspec.Struct, frozen=True):
    station: int
    command: int
    parameters: bytes


class SerialReceiver:
    """Requests out of the serial byte stream for one station (§9.2): B5h always starts a new
    telegram; a telegram ends when its command's parameters and the two CRC bytes are in.
    ``crc_excludes_fs`` is the spec's tolerance option (§9.2): a CRC computed without the leading
    FS byte is taken too (the CRC over FS … data stays the one the station sends)."""

    def __init__(self, station: int, telegrams: Telegrams, *, crc_excludes_fs: bool = False) -> None:
        self.station, self.telegrams = station, telegrams
        self.crc_excludes_fs = crc_excludes_fs
        self._raw: bytearray | None = None  # the telegram so far, unstuffed
        self._dle = False
        self.errors = {"crc": 0, "framing": 0}

    def reset(self) -> None:
        self._raw, self._dle = None, False

    def feed(self, data: bytes) -> list[Request]:
        requests: list[Request] = []
        for byte in data:
            if byte == FS:
                self._raw, self._dle = bytearray((FS,)), False
                continue
            raw = self._raw
            if raw is None:
                continue  # noise between telegrams
            if self._dle:
                self._dle = False
                if byte not in (0, 1):
                    self.errors["framing"] += 1
                    self._raw = None
                    continue
                raw.append(FS if byte == 0 else DLE)
            elif byte == DLE:
                self._dle = True
                continue
            else:
                raw.append(byte)
            request = self._complete(raw)
            if request is not None or self._raw is None:
                self._raw = None
                if request is not None and request.station in (self.station, BROADCAST):
                    requests.append(request)
        return requests

    def _complete(self, raw: bytearray) -> Request | None:
        if len(raw) < 4:
            return None
        if raw[1] != REQUEST:
            self._raw = None  # (a response or an ACK on the line: not for a station)
            return None
        telegram = self.telegrams(raw[3])
        # an unknown command: its CRC follows at once (answered with NAK)
        wanted = 0 if telegram is None else telegram.length(bytes(raw[4:]))
        if wanted is None:
            return None
        end = 4 + wanted + 2
        if len(raw) < end:
            return None
        body, crc = bytes(raw[: end - 2]), struct.unpack(">H", raw[end - 2 : end])[0]
        if crc16(body) != crc and not (self.crc_excludes_fs and crc16(body[1:]) == crc):
            self.errors["crc"] += 1
            self._raw = None
            return None
        return Request(raw[2], raw[3], bytes(raw[4 : end - 2]))


# -- commands ---------------------------------------------------------------------------------
class Read(msgspec.Struct, frozen=True):
    medium: str
    address: int
    count: int


class Write(msgspec.Struct, frozen=True):
    medium: str
    address: int
    values: tuple[int, ...]  # register values (signed 32-bit) or flag/output bits (0/1)


class Simple(msgspec.Struct, frozen=True):
    name: str


class Bad(msgspec.Struct, frozen=True):
    """A valid telegram the station cannot carry out: NAK 0001h (§9.2)."""

    reason: str


class Telegram(Protocol):
    """How a command's parameters are laid out (§9.4)."""

    def length(self, parameters: bytes) -> int | None:
        """How many parameter bytes the telegram has, seeing the first ones (None: not known yet)."""
        ...

    def decode(self, parameters: bytes) -> Read | Write | Simple | Bad: ...


#: The telegram of a command code, or None for a code the station does not know.
Telegrams = Callable[[int], Telegram | None]


class Reads(msgspec.Struct, frozen=True):
    """A read of ``medium``: count − 1, address high, low; at most ``most`` elements (§9.4)."""

    medium: str
    most: int

    def length(self, parameters: bytes) -> int | None:
        return 3

    def decode(self, parameters: bytes) -> Read | Bad:
        p = parameters
        if len(p) != 3:
            return Bad("wrong parameter count")
        count = p[0] + 1
        if count > self.most:
            return Bad(f"at most {self.most} {self.medium}s per telegram")
        return Read(self.medium, p[1] << 8 | p[2], count)


class Writes(msgspec.Struct, frozen=True):
    """A write of ``medium``: byte count, address high, low, then the data (§9.4): registers in 4
    bytes each; flags and outputs as count − 1 and the bits, the first in bit 0; at most ``most``
    elements, as a read (a longer write is refused with NAK, nothing written)."""

    medium: str
    most: int

    def length(self, parameters: bytes) -> int | None:
        return None if not parameters else parameters[0] + 2

    def decode(self, parameters: bytes) -> Write | Bad:
        p = parameters
        if len(p) < 4:
            return Bad("wrong parameter count")
        if len(p) != p[0] + 2:  # (on Ether-S-Bus the frame's length bounds the data, not the count)
            return Bad("the byte count does not match the data")
        address = p[1] << 8 | p[2]
        if self.medium == "register":
            data = p[3:]
            if len(data) % 4 or not data:
                return Bad("register data come in 4 bytes")
            if len(data) // 4 > self.most:
                return Bad(f"at most {self.most} {self.medium}s per telegram")
            return Write(self.medium, address, struct.unpack(f">{len(data) // 4}i", data))
        count = p[3] + 1
        if count > self.most:
            return Bad(f"at most {self.most} {self.medium}s per telegram")
        bits = p[4:]
        if len(bits) != (count + 7) // 8:
            return Bad("the byte count does not match the flag count")
        return Write(self.medium, address, tuple(bits[i // 8] >> (i % 8) & 1 for i in range(count)))


class NoParameters(msgspec.Struct, frozen=True):
    """A command without parameters (status, station, firmware, run, stop, restart)."""

    name: str

    def length(self, parameters: bytes) -> int | None:
        return 0

    def decode(self, parameters: bytes) -> Simple | Bad:
        if parameters:  # (bytes after it in an Ether-S-Bus frame)
            return Bad(f"{self.name} takes no parameters")
        return Simple(self.name)


def decode_command(request: Request, telegrams: Telegrams) -> Read | Write | Simple | Bad:
    """A request's parameters read as its command's telegram lays them out."""
    telegram = telegrams(request.command)
    if telegram is None:
        return Bad(f"command {request.command:02X}h is not supported")
    return telegram.decode(request.parameters)


def pack_bits(values: list[int]) -> bytes:
    """Flags, inputs or outputs for a read reply: the first in bit 0 of the first byte."""
    out = bytearray((len(values) + 7) // 8)
    for index, value in enumerate(values):
        if value:
            out[index // 8] |= 1 << (index % 8)
    return bytes(out)


# -- Ether-S-Bus (§9.3) ----------------------------------------------------------------------------
#: The shortest Ether-S-Bus telegram (9-byte header, one byte, CRC: the answer to "read PCD
#: status" or "read station number", spec EV14) and the longest one taken (a length field outside
#: them is not a frame); a request carries station and command at least.
ETHER_MIN, ETHER_MAX = 12, 4096
ETHER_REQUEST_MIN = 13


def ether_length_ok(length: int) -> bool:
    """Whether a telegram's length field can be a frame's."""
    return ETHER_MIN <= length <= ETHER_MAX


def ether_frame(version: int, sequence: int, attribute: int, payload: bytes) -> bytes:
    body = struct.pack(">IBBHB", 4 + 1 + 1 + 2 + 1 + len(payload) + 2, version, 0, sequence, attribute) + payload
    return body + struct.pack(">H", crc16(body))


def parse_ether(frame: bytes) -> tuple[int, int, Request] | None:
    """(version, sequence, request) of one Ether-S-Bus request frame, or None (bad length,
    type, attribute or CRC: dropped)."""
    if len(frame) < ETHER_REQUEST_MIN:
        return None
    length, version, kind, sequence, attribute = struct.unpack(">IBBHB", frame[:9])
    if length != len(frame) or version not in (0, 1) or kind != 0 or attribute != REQUEST:
        return None
    if crc16(frame[:-2]) != struct.unpack(">H", frame[-2:])[0]:
        return None
    payload = frame[9:-2]
    return version, sequence, Request(payload[0], payload[1], payload[2:])


def ether_reply(version: int, sequence: int, data: bytes) -> bytes:
    return ether_frame(version, sequence, RESPONSE, data)


def ether_ack(version: int, sequence: int, code: int = ACK) -> bytes:
    return ether_frame(version, sequence, ACK_NAK, struct.pack(">H", code))


class EtherReceiver:
    """Ether-S-Bus frames out of a TCP byte stream (back to back, delimited by the length)."""

    def __init__(self) -> None:
        self._buffer = bytearray()

    def feed(self, data: bytes) -> list[bytes]:
        self._buffer += data
        frames = []
        while len(self._buffer) >= 4:
            (length,) = struct.unpack_from(">I", self._buffer)
            if not ether_length_ok(length):
                self._buffer.clear()  # not a frame length: resynchronise on the next write
                break
            if len(self._buffer) < length:
                break
            frames.append(bytes(self._buffer[:length]))
            del self._buffer[:length]
        return frames
