"""The simulator's application profile on the PG port, "IP247-SIM/PG v1" (spec ip247.md §3.6):
what the parameters of an AS511 transaction (:mod:`devsim.devices.ip247.as511`) ask for, and
the response data the module sends.  The IP247's real PG function codes are not public; this
profile is simulator-defined and carries the services of the mode table with the fields of the
FB164 parameters and the record layouts of §3.4 (manual §6.3.8).

Pure: :func:`parse_request` turns a function code and its parameter bytes into a request (or
:class:`Malformed`, answered with ack 82H); :func:`response` lays out the answer.
"""

from __future__ import annotations

import struct
from collections.abc import Callable
from typing import ClassVar

import msgspec

from devsim.core.kit import Command, Table
from devsim.devices.ip247.as511 import function_token

__all__ = [
    "ACK_ACCEPTED", "ACK_FULL", "ACK_MALFORMED", "ACK_NEGATIVE", "ACK_QUEUED", "COMMAND_NAMES", "COMMANDS", "FUNCTIONS",
    "Delete", "command_code", "pack_words",
    "Header", "Malformed", "Observe", "Observation", "Operate", "ReadRecord", "WriteRecord", "parse_request",
    "response",
]

OPERATE, OBSERVE, WRITE_REC, READ_REC, DELETE_REC = 0x61, 0x62, 0x63, 0x64, 0x65
#: Commands of OPERATE (spec §3.6.2, simulator encoding).
COMMANDS = {1: "Start", 2: "Stopp", 3: "Vorwärts", 4: "Rückwärts", 5: "Übernahme"}
#: The commands by name, German as in the table above or English.
COMMAND_NAMES = {**{name.lower(): code for code, name in COMMANDS.items()},
                 "stop": 2, "forward": 3, "backward": 4, "take_over": 5}
ACK_ACCEPTED, ACK_QUEUED, ACK_NEGATIVE, ACK_FULL, ACK_MALFORMED = 0x00, 0x01, 0x80, 0x81, 0x82
MAX_PARAMETERS = 1100  # the longest parameter block, bytes after DLE removal: longer gets DLE NAK (spec §3.6.5)


class Operate(msgspec.Struct, frozen=True):
    """An operator command BA1 … BA17: FB164's byte, word and double-word parameters."""

    function: ClassVar[int] = OPERATE

    page: int
    ba: int
    cmd: int
    b: int
    w: int
    dd: int


class Observe(msgspec.Struct, frozen=True):
    function: ClassVar[int] = OBSERVE

    page: int


class WriteRecord(msgspec.Struct, frozen=True):
    """BA20 (machine data), BA22 (program), BA24 (SYS-ID): the record's words."""

    function: ClassVar[int] = WRITE_REC

    page: int
    ba: int
    db: int
    overwrite: bool
    words: tuple[int, ...]


class ReadRecord(msgspec.Struct, frozen=True):
    function: ClassVar[int] = READ_REC

    page: int
    ba: int
    db: int
    bcd: bool


class Delete(msgspec.Struct, frozen=True):
    function: ClassVar[int] = DELETE_REC

    page: int
    ba: int
    db: int


class Malformed(msgspec.Struct, frozen=True):
    """Wrong length or a field out of range: ack 82H, nothing executed (spec §3.6.5)."""

    function: int
    page: int = 0
    ba: int = 0


Request = Operate | Observe | WriteRecord | ReadRecord | Delete | Malformed
#: A function's parser: (function code, page, BA, the parameter bytes) → the request.
Parser = Callable[[int, int, int, bytes], Request]


def parse_request(function: int, data: bytes) -> Request:
    """The request of one transaction's parameter block (spec §3.6.3)."""
    page, ba = (data[0] if data else 0), (data[1] if len(data) > 1 else 0)
    if len(data) > MAX_PARAMETERS or not 1 <= page <= 4:
        return Malformed(function, page, ba)
    parser = FUNCTIONS.get(function_token(function))
    if parser is None:
        return Malformed(function, page, ba)
    return parser(function, page, ba, data)


def _operate(function: int, page: int, ba: int, data: bytes) -> Request:
    if len(data) != 10:
        return Malformed(function, page, ba)
    _, _, cmd, b, w, dd = struct.unpack(">BBBBHi", data)
    if cmd not in COMMANDS:
        return Malformed(function, page, ba)
    return Operate(page, ba, cmd, b, w, dd)


def _observe(function: int, page: int, ba: int, data: bytes) -> Request:
    return Observe(page) if len(data) == 1 else Malformed(function, page, ba)


def _write_record(function: int, page: int, ba: int, data: bytes) -> Request:
    if len(data) < 4 or len(data) % 2:
        return Malformed(function, page, ba)
    words = struct.unpack(f">{(len(data) - 4) // 2}H", data[4:])
    return WriteRecord(page, ba, data[2], bool(data[3] & 1), words)


def _read_record(function: int, page: int, ba: int, data: bytes) -> Request:
    return ReadRecord(page, ba, data[2], bool(data[3] & 1)) if len(data) == 4 else Malformed(function, page, ba)


def _delete(function: int, page: int, ba: int, data: bytes) -> Request:
    return Delete(page, ba, data[2]) if len(data) == 3 else Malformed(function, page, ba)


#: The profile's functions (spec §3.6.1), by token (``61H``): each parses its parameters.
FUNCTIONS: Table[Parser] = Table([
    Command(function_token(OPERATE), _operate, "spec §3.6.1", "OPERATE: an operator job (page, BA, command, B, W, DD)"),
    Command(function_token(OBSERVE), _observe, "spec §3.6.1", "OBSERVE: actual value, residual, errors (page)"),
    Command(function_token(WRITE_REC), _write_record, "spec §3.6.1",
            "WRITE_REC: BA20/22/24 (page, BA, DB, overwrite, the record's words)"),
    Command(function_token(READ_REC), _read_record, "spec §3.6.1", "READ_REC: BA64 … BA70 (page, BA, DB, BCD)"),
    Command(function_token(DELETE_REC), _delete, "spec §3.6.1", "DELETE_REC: BA21/23 (page, BA, DB)"),
])


class Header(msgspec.Struct, frozen=True):
    """The common 8 bytes of every response (spec §3.6.4)."""

    ack: int
    page: int
    ba: int
    cmd: int
    err: int
    btr: int  # the page's current mode (0 on page 4)
    rmld: int  # axis attributes (0 on page 4)
    mfkt: int  # current M function, 255 before the first, 2 outside BA8/BA9

    def pack(self) -> bytes:
        return bytes((self.ack, self.page, self.ba, self.cmd, self.err, self.btr, self.rmld, self.mfkt))


class Observation(msgspec.Struct, frozen=True):
    """OBSERVE's continuation (spec §3.6.4): 14 more bytes."""

    position: int
    residual: int
    errors: tuple[int, int, int, int]  # axes 1 … 3 and the data channel
    last_command: int
    flags: int  # 1 external start, 2 interrupted, 4 teach-in, 8 waiting for Übernahme

    def pack(self) -> bytes:
        return struct.pack(">ii4BBB", self.position, self.residual, *self.errors, self.last_command, self.flags)


def command_code(command: int | str) -> int | None:
    """A command as its code: 1 … 5 as they are, a name (Start, Stopp … or English) looked up."""
    if isinstance(command, int) and not isinstance(command, bool):  # (True is no command)
        return command
    return COMMAND_NAMES.get(str(command).lower())


def pack_words(words: tuple[int, ...] | list[int]) -> bytes:
    """Record words as the profile sends them: big-endian 16-bit."""
    return struct.pack(f">{len(words)}H", *words)


def response(header: Header, body: bytes | Observation | tuple[int, ...] = b"") -> bytes:
    """Header and continuation: OBSERVE's 14 bytes, a READ_REC record (words), a WRITE_REC
    result (words) or nothing."""
    if isinstance(body, Observation):
        return header.pack() + body.pack()
    if isinstance(body, tuple):
        return header.pack() + pack_words(body)
    return header.pack() + body
