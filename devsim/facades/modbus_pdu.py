"""The Modbus application layer of the facade (Modbus Application Protocol Specification V1.1b3):
a request PDU in, its response PDU out, whatever the transport (TCP's MBAP header or RTU's address
and CRC are :mod:`devsim.facades.modbus`'s business).

One table, :data:`FUNCTIONS`, keyed by function code: each row names the function, cites its
section, answers a request and says how long its RTU frame is.  A code not in the table gets
exception 01 (§7).  Every answer follows the state diagrams of §6: the quantity and the length the
request implies are checked first (exception 03), then every address it touches (02), then the
device acts (03 if it refuses a value, 04 if it fails).  An exception response repeats the
request's function code with its high bit set (§7: ``83 02``, ``D5 01``).  Function 43 answers
Read Device Identification (§6.21, MEI type 14) from :mod:`devsim.facades.modbus_ident`'s objects.

Pure: no I/O; the device is reached through a :class:`Tables` (the facade).
"""

from __future__ import annotations

import struct
from collections.abc import Callable, Mapping, Sequence
from functools import partial
from typing import Protocol

import msgspec

from devsim.facades import modbus_ident

__all__ = ["CRC_ENDED", "DEVICE_FAILURE", "FUNCTIONS", "ILLEGAL_ADDRESS", "ILLEGAL_FUNCTION", "ILLEGAL_VALUE", "Function",
           "Refused", "Tables", "answer", "exception"]

#: §7, the exception codes the facade answers with.
ILLEGAL_FUNCTION, ILLEGAL_ADDRESS, ILLEGAL_VALUE, DEVICE_FAILURE = 1, 2, 3, 4
#: §6.1/6.2, §6.3/6.4, §6.11, §6.12, §6.17: the quantities one request may carry.
MAX_READ_BITS, MAX_READ_WORDS, MAX_WRITE_BITS, MAX_WRITE_WORDS, MAX_READ_WRITE_WORDS = 2000, 125, 1968, 123, 121
#: §6.5: the only two values of Write Single Coil.
COIL_ON, COIL_OFF = 0xFF00, 0x0000
#: An RTU frame length that says: not this function's own frame (function 43 with an MEI type
#: other than 14): it ends where its CRC first holds, as an unknown function's.
CRC_ENDED = -1


class Refused(Exception):
    """A request the server answers with an exception response (§7); ``code`` is its exception code."""

    def __init__(self, code: int) -> None:
        super().__init__(code)
        self.code = code


class Tables(Protocol):
    """The four tables of §4.3 as the device holds them; an address outside the map raises
    :class:`Refused` (02), a value the device refuses :class:`Refused` (03)."""

    def read_bits(self, table: str, address: int, count: int) -> list[bool]: ...

    def write_bits(self, address: int, values: Sequence[bool]) -> None: ...

    def read_words(self, table: str, address: int, count: int) -> list[int]: ...

    def write_words(self, address: int, values: Sequence[int]) -> None: ...

    def identification(self) -> Mapping[int, bytes]:
        """The Read Device Identification objects (§6.21): object id -> its value."""
        ...


class Function(msgspec.Struct, frozen=True):
    """One public function code (§6): its name, section, answer and RTU request length."""

    name: str
    section: str
    answer: Callable[[Tables, bytes], bytes]  # the request's data (after the code) -> the response's
    rtu_length: Callable[[bytes], int]  # an RTU frame's first bytes -> its length (0: not known yet; CRC_ENDED)


def exception(function: int, code: int) -> bytes:
    """An exception response PDU (§7): the function code plus 80h, then the exception code."""
    return bytes((function | 0x80, code))


def answer(tables: Tables, pdu: bytes) -> bytes:
    """The response PDU to the request ``pdu`` (function code first)."""
    function = FUNCTIONS.get(pdu[0]) if pdu else None
    if function is None:
        return exception(pdu[0] if pdu else 0, ILLEGAL_FUNCTION)
    try:
        return pdu[:1] + function.answer(tables, pdu[1:])
    except Refused as refused:
        return exception(pdu[0], refused.code)
    except Exception:  # noqa: BLE001 - §7 code 04: the device failed, the server answers
        return exception(pdu[0], DEVICE_FAILURE)


# -- the request fields ----------------------------------------------------------------------------
def _fields(data: bytes, count: int) -> tuple[int, ...]:
    """``count`` 16-bit fields and nothing else; another length is 03 (§7: "the implied length is
    incorrect")."""
    if len(data) != 2 * count:
        raise Refused(ILLEGAL_VALUE)
    return struct.unpack(f">{count}H", data)


def _quantity(quantity: int, most: int) -> None:
    if not 1 <= quantity <= most:
        raise Refused(ILLEGAL_VALUE)


def _span(address: int, quantity: int) -> None:
    """§6 diagrams: "Starting Address + Quantity == OK"."""
    if address + quantity > 0x10000:
        raise Refused(ILLEGAL_ADDRESS)


def _payload(data: bytes, head: int, quantity: int, most: int, size: int) -> bytes:
    """The values of a write of ``quantity`` items, ``size`` bytes of them after a byte count."""
    _quantity(quantity, most)
    if data[head] != size or len(data) != head + 1 + size:
        raise Refused(ILLEGAL_VALUE)
    return data[head + 1:]


def _pack(bits: Sequence[bool]) -> bytes:
    """§6.1: the first bit in the low-order bit of the first byte, the last byte padded with 0."""
    packed = bytearray((len(bits) + 7) // 8)
    for i, bit in enumerate(bits):
        if bit:
            packed[i // 8] |= 1 << (i % 8)
    return bytes(packed)


def _unpack(data: bytes, count: int) -> list[bool]:
    return [bool(data[i // 8] >> (i % 8) & 1) for i in range(count)]


# -- the functions ---------------------------------------------------------------------------------
# (The table's rows bind their arguments with functools.partial, not closures made at import:
# the function that answers runs when the request comes.)
def _read_bits(table: str, tables: Tables, data: bytes) -> bytes:
    address, quantity = _fields(data, 2)
    _quantity(quantity, MAX_READ_BITS)
    _span(address, quantity)
    packed = _pack(tables.read_bits(table, address, quantity))
    return bytes((len(packed),)) + packed


def _read_words(table: str, tables: Tables, data: bytes) -> bytes:
    address, quantity = _fields(data, 2)
    _quantity(quantity, MAX_READ_WORDS)
    _span(address, quantity)
    return _words(tables.read_words(table, address, quantity))


def _words(words: Sequence[int]) -> bytes:
    return bytes((2 * len(words),)) + struct.pack(f">{len(words)}H", *words)


def _write_coil(tables: Tables, data: bytes) -> bytes:
    address, value = _fields(data, 2)
    if value not in (COIL_ON, COIL_OFF):
        raise Refused(ILLEGAL_VALUE)
    tables.write_bits(address, [value == COIL_ON])
    return data


def _write_register(tables: Tables, data: bytes) -> bytes:
    address, value = _fields(data, 2)
    tables.write_words(address, [value])
    return data


def _write_coils(tables: Tables, data: bytes) -> bytes:
    if len(data) < 5:
        raise Refused(ILLEGAL_VALUE)
    address, quantity = struct.unpack(">HH", data[:4])
    values = _payload(data, 4, quantity, MAX_WRITE_BITS, (quantity + 7) // 8)
    _span(address, quantity)
    tables.write_bits(address, _unpack(values, quantity))
    return data[:4]


def _write_registers(tables: Tables, data: bytes) -> bytes:
    if len(data) < 5:
        raise Refused(ILLEGAL_VALUE)
    address, quantity = struct.unpack(">HH", data[:4])
    values = _payload(data, 4, quantity, MAX_WRITE_WORDS, 2 * quantity)
    _span(address, quantity)
    tables.write_words(address, struct.unpack(f">{quantity}H", values))
    return data[:4]


def _read_write_registers(tables: Tables, data: bytes) -> bytes:
    """§6.17: the write is carried out before the read; both ranges are checked before either."""
    if len(data) < 9:
        raise Refused(ILLEGAL_VALUE)
    read_address, read_quantity, write_address, write_quantity = struct.unpack(">4H", data[:8])
    _quantity(read_quantity, MAX_READ_WORDS)
    values = _payload(data, 8, write_quantity, MAX_READ_WRITE_WORDS, 2 * write_quantity)
    _span(read_address, read_quantity)
    _span(write_address, write_quantity)
    tables.read_words("holding", read_address, read_quantity)  # (02 before anything is written)
    tables.write_words(write_address, struct.unpack(f">{write_quantity}H", values))
    return _words(tables.read_words("holding", read_address, read_quantity))


def _read_device_identification(tables: Tables, data: bytes) -> bytes:
    """§6.21, function 43 with MEI type 14: ``0E code object``.  Another MEI type is a function
    the facade does not have (01: 13 is the CANopen General Reference, §6.20, the others are
    reserved); a request of another length 03; "an exception code 03 is sent back in the response
    if the Read Device ID code is illegal"; with code 04, an object that is not there 02 ("if the
    Object Id doesn't match to any known object, the server returns an exception response with
    exception code = 02"); a stream from an object that is not there starts at object 0."""
    if data[:1] and data[0] != modbus_ident.READ_DEVICE_ID:
        raise Refused(ILLEGAL_FUNCTION)
    if len(data) != 3 or data[1] not in modbus_ident.CODES:
        raise Refused(ILLEGAL_VALUE)
    code, first = data[1], data[2]
    objects = tables.identification()
    if code != modbus_ident.SPECIFIC:
        return modbus_ident.stream(objects, code, first)
    if first not in objects:
        raise Refused(ILLEGAL_ADDRESS)
    return modbus_ident.individual(objects, first)


def _mei_length(frame: bytes) -> int:
    """Function 43's RTU request: address, 2B, 0E, code, object, CRC; another MEI type's frame
    is cut where its CRC holds."""
    if len(frame) < 3:
        return 0
    return 7 if frame[2] == modbus_ident.READ_DEVICE_ID else CRC_ENDED


def _fixed(length: int, frame: bytes) -> int:
    return length


def _counted(at: int, frame: bytes) -> int:
    """An RTU request whose byte count is at ``at``: that many bytes follow it, then the CRC."""
    return at + 1 + frame[at] + 2 if len(frame) > at else 0


FUNCTIONS: dict[int, Function] = {
    0x01: Function("Read Coils", "§6.1", partial(_read_bits, "coil"), partial(_fixed, 8)),
    0x02: Function("Read Discrete Inputs", "§6.2", partial(_read_bits, "discrete"), partial(_fixed, 8)),
    0x03: Function("Read Holding Registers", "§6.3", partial(_read_words, "holding"), partial(_fixed, 8)),
    0x04: Function("Read Input Registers", "§6.4", partial(_read_words, "input"), partial(_fixed, 8)),
    0x05: Function("Write Single Coil", "§6.5", _write_coil, partial(_fixed, 8)),
    0x06: Function("Write Single Register", "§6.6", _write_register, partial(_fixed, 8)),
    0x0F: Function("Write Multiple Coils", "§6.11", _write_coils, partial(_counted, 6)),
    0x10: Function("Write Multiple Registers", "§6.12", _write_registers, partial(_counted, 6)),
    0x17: Function("Read/Write Multiple Registers", "§6.17", _read_write_registers, partial(_counted, 10)),
    0x2B: Function("Read Device Identification", "§6.21", _read_device_identification, _mei_length),
}
