"""The Modbus application layer in the test's own process (issue 35): request PDUs at and around
every limit of the Modbus Application Protocol Specification V1.1b3 go to
:func:`devsim.facades.modbus_pdu.answer`, and its response — data or exception — is compared with
the standard's rule written here as a small oracle.

The limits (§6.1–§6.4, §6.11, §6.12, §6.17): a read of 1 … 2000 bits or 1 … 125 registers, a write
of 1 … 1968 coils or 1 … 123 registers, function 23 reading 1 … 125 and writing 1 … 121; the byte
count of a write is ceil(N / 8) for coils and 2 × N for registers; the 16-bit address, a request
whose last item would lie beyond 65535 being exception 02; the request's exact length; the
exception response is the function code with its high bit set and the exception code 1 … 4 (§7).
The device behind the tables is a small store of the test's own (:class:`Store`), with a map that
may end before 65535, a register value it refuses and a failure mode.  The examples of §6 and §7
are checked byte for byte.  The same application layer behind real sockets and ptys, with
pymodbus's and modbus-tk's clients, is tests/facades/test_modbus_conformance.py and
test_modbus_differential.py.
"""

from __future__ import annotations

import math
import struct
from collections.abc import Sequence
from dataclasses import dataclass, field

import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as hs
from pymodbus.framer import FramerRTU

from devsim.facades import modbus_pdu
from devsim.facades.modbus_pdu import FUNCTIONS, Refused, answer, exception

#: §6.1–§6.4: function code -> the table it reads, the most items one request may carry, bits or not.
READS = {0x01: ("coil", 2000, True), 0x02: ("discrete", 2000, True), 0x03: ("holding", 125, False),
         0x04: ("input", 125, False)}
#: §6.11, §6.12: function code -> the most items one request may write, bits or not.
WRITES = {0x0F: (1968, True), 0x10: (123, False)}
#: §6.17: the most registers function 23 reads and writes.
RW_READ, RW_WRITE = 125, 121
#: §7: the exception codes.
ILLEGAL_FUNCTION, ILLEGAL_ADDRESS, ILLEGAL_VALUE, DEVICE_FAILURE = 1, 2, 3, 4
#: A register value the store refuses (its device's exception 03).
REFUSED = 0xDEAD


# -- the device behind the tables --------------------------------------------------------------------
@dataclass
class Store:
    """The four tables of §4.3, each with the addresses ``first`` … ``last``; values not written
    come from the address.  A request that reaches the store outside 0 … 65535 or with a table name
    it does not know is a bug of the application layer (it raises AssertionError: answered 04)."""

    first: int = 0
    last: int = 0xFFFF
    failing: bool = False  # every access fails (OSError): the device's failure, 04
    coils: dict[int, bool] = field(default_factory=dict)
    discretes: dict[int, bool] = field(default_factory=dict)
    holding: dict[int, int] = field(default_factory=dict)
    inputs: dict[int, int] = field(default_factory=dict)
    reads: list[tuple[str, int, int]] = field(default_factory=list)

    def copy(self) -> Store:
        return Store(self.first, self.last, self.failing, dict(self.coils), dict(self.discretes),
                     dict(self.holding), dict(self.inputs))

    def bit(self, table: str, address: int) -> bool:
        stored = {"coil": self.coils, "discrete": self.discretes}[table]
        return stored.get(address, bool((address * 2654435761 >> (5 if table == "coil" else 11)) & 1))

    def word(self, table: str, address: int) -> int:
        stored = {"holding": self.holding, "input": self.inputs}[table]
        return stored.get(address, (address * 40503 + (7 if table == "holding" else 99)) & 0xFFFF)

    def _touch(self, address: int, count: int) -> None:
        assert 0 <= address and count >= 1 and address + count <= 0x10000, (address, count)
        if address < self.first or address + count - 1 > self.last:
            raise Refused(ILLEGAL_ADDRESS)
        if self.failing:
            raise OSError("the device failed")

    def read_bits(self, table: str, address: int, count: int) -> list[bool]:
        assert table in ("coil", "discrete"), table
        self._touch(address, count)
        return [self.bit(table, address + i) for i in range(count)]

    def write_bits(self, address: int, values: Sequence[bool]) -> None:
        self._touch(address, len(values))
        self.coils.update((address + i, bool(value)) for i, value in enumerate(values))

    def read_words(self, table: str, address: int, count: int) -> list[int]:
        assert table in ("holding", "input"), table
        self.reads.append((table, address, count))
        self._touch(address, count)
        return [self.word(table, address + i) for i in range(count)]

    def write_words(self, address: int, values: Sequence[int]) -> None:
        self._touch(address, len(values))
        if REFUSED in values:
            raise Refused(ILLEGAL_VALUE)
        self.holding.update((address + i, int(value)) for i, value in enumerate(values))

    def identification(self) -> dict[int, bytes]:
        return {0: b"devsim", 1: b"store", 2: b"0.1"}


# -- the standard's rule -----------------------------------------------------------------------------
class Refusal(Exception):
    """The oracle's exception response (§7), with its exception code."""

    def __init__(self, code: int) -> None:
        super().__init__(code)
        self.code = code


def _in_map(store: Store, address: int, count: int) -> None:
    """§6 diagrams: "Starting Address == OK AND Starting Address + Quantity == OK" (02), then
    the device: the store's map (02) and its failure (04)."""
    if address + count - 1 > 0xFFFF or address < store.first or address + count - 1 > store.last:
        raise Refusal(ILLEGAL_ADDRESS)


def _device(store: Store) -> None:
    if store.failing:
        raise Refusal(DEVICE_FAILURE)


def _bits_of(data: bytes, count: int) -> list[bool]:
    """§6.11: the first coil in the least significant bit of the first byte."""
    as_number = int.from_bytes(data, "little")
    return [bool(as_number >> i & 1) for i in range(count)]


def _bytes_of(bits: list[bool]) -> bytes:
    """§6.1: the first bit in the least significant bit of the first byte, the rest zero."""
    return sum(int(bit) << i for i, bit in enumerate(bits)).to_bytes(math.ceil(len(bits) / 8), "little")


def _oracle_read(function: int, data: bytes, store: Store) -> bytes:
    table, most, bits = READS[function]
    if len(data) != 4:
        raise Refusal(ILLEGAL_VALUE)
    address, quantity = int.from_bytes(data[:2], "big"), int.from_bytes(data[2:], "big")
    if quantity < 1 or quantity > most:
        raise Refusal(ILLEGAL_VALUE)
    _in_map(store, address, quantity)
    _device(store)
    if bits:
        packed = _bytes_of([store.bit(table, address + i) for i in range(quantity)])
        return bytes([len(packed)]) + packed
    words = b"".join(store.word(table, address + i).to_bytes(2, "big") for i in range(quantity))
    return bytes([2 * quantity]) + words


def _oracle_write_single(function: int, data: bytes, store: Store) -> bytes:
    if len(data) != 4:
        raise Refusal(ILLEGAL_VALUE)
    address, value = int.from_bytes(data[:2], "big"), int.from_bytes(data[2:], "big")
    if function == 0x05 and value not in (0xFF00, 0x0000):  # §6.5
        raise Refusal(ILLEGAL_VALUE)
    _in_map(store, address, 1)
    _device(store)
    if function == 0x05:
        store.coils[address] = value == 0xFF00
    elif value == REFUSED:
        raise Refusal(ILLEGAL_VALUE)
    else:
        store.holding[address] = value
    return data  # §6.5, §6.6: the echo of the request


def _oracle_write_multiple(function: int, data: bytes, store: Store) -> bytes:
    most, bits = WRITES[function]
    if len(data) < 5:
        raise Refusal(ILLEGAL_VALUE)
    address, quantity, count = int.from_bytes(data[:2], "big"), int.from_bytes(data[2:4], "big"), data[4]
    size = math.ceil(quantity / 8) if bits else 2 * quantity
    if not 1 <= quantity <= most or count != size or len(data) != 5 + count:
        raise Refusal(ILLEGAL_VALUE)
    _in_map(store, address, quantity)
    _device(store)
    if bits:
        store.coils.update(zip(range(address, address + quantity), _bits_of(data[5:], quantity), strict=True))
    else:
        values = [int.from_bytes(data[5 + 2 * i:7 + 2 * i], "big") for i in range(quantity)]
        if REFUSED in values:
            raise Refusal(ILLEGAL_VALUE)
        store.holding.update(zip(range(address, address + quantity), values, strict=True))
    return data[:4]  # §6.11, §6.12: the address and the quantity


def _oracle_read_write(function: int, data: bytes, store: Store) -> bytes:
    """§6.17: both quantities and the byte count (03), both ranges (02), then the write, then the read."""
    if len(data) < 9:
        raise Refusal(ILLEGAL_VALUE)
    read_address, read_quantity, write_address, write_quantity = (
        int.from_bytes(data[i:i + 2], "big") for i in range(0, 8, 2))
    count = data[8]
    if (not 1 <= read_quantity <= RW_READ or not 1 <= write_quantity <= RW_WRITE
            or count != 2 * write_quantity or len(data) != 9 + count):
        raise Refusal(ILLEGAL_VALUE)
    _in_map(store, read_address, read_quantity)
    _in_map(store, write_address, write_quantity)
    _device(store)
    values = [int.from_bytes(data[9 + 2 * i:11 + 2 * i], "big") for i in range(write_quantity)]
    if REFUSED in values:
        raise Refusal(ILLEGAL_VALUE)
    store.holding.update(zip(range(write_address, write_address + write_quantity), values, strict=True))
    return bytes([2 * read_quantity]) + b"".join(
        store.word("holding", read_address + i).to_bytes(2, "big") for i in range(read_quantity))


class JudgedElsewhere(Exception):
    """A request the oracle does not answer itself: a valid Read Device Identification, whose
    objects ``tests/facades/test_modbus_ident.py`` checks."""


def _oracle_identification(function: int, data: bytes, store: Store) -> bytes:
    """§6.21: function 43 with another MEI type is a function the server does not have (01); MEI
    type 14 with a request of another length or a Read Device ID code other than 01–04 is 03
    ("an exception code 03 is sent back in the response if the Read Device ID code is illegal")."""
    if data and data[0] != 0x0E:
        raise Refusal(ILLEGAL_FUNCTION)
    if len(data) != 3 or data[1] not in (1, 2, 3, 4):
        raise Refusal(ILLEGAL_VALUE)
    raise JudgedElsewhere


ORACLE = {**dict.fromkeys(READS, _oracle_read), 0x05: _oracle_write_single, 0x06: _oracle_write_single,
          **dict.fromkeys(WRITES, _oracle_write_multiple), 0x17: _oracle_read_write, 0x2B: _oracle_identification}


def oracle(store: Store, pdu: bytes) -> tuple[bytes, Store]:
    """The standard's response to ``pdu`` and the store as the request leaves it (a refused request
    writes nothing)."""
    after = store.copy()
    if not pdu or pdu[0] not in ORACLE:
        return bytes([(pdu[0] if pdu else 0) | 0x80, ILLEGAL_FUNCTION]), store.copy()
    try:
        return pdu[:1] + ORACLE[pdu[0]](pdu[0], pdu[1:], after), after
    except Refusal as refused:
        return bytes([pdu[0] | 0x80, refused.code]), store.copy()


def check(store: Store, pdu: bytes) -> bytes:
    """``answer`` against the oracle: the same response, the same tables afterwards."""
    try:
        expected, after = oracle(store, pdu)
    except JudgedElsewhere:  # (a valid Read Device Identification: it answers with its MEI type and code)
        assert answer(store, pdu)[:3] == pdu[:3], pdu.hex(" ")
        return b""
    response = answer(store, pdu)
    assert response.hex(" ") == expected.hex(" "), pdu.hex(" ")
    assert (store.coils, store.holding) == (after.coils, after.holding), pdu.hex(" ")
    return response


# -- the strategies: at and around each limit ---------------------------------------------------------
def _quantity(most: int) -> hs.SearchStrategy[int]:
    return hs.one_of(hs.sampled_from([0, 1, 2, 7, 8, 9, 15, 16, 17, most - 1, most, most + 1, 0x8000, 0xFFFF]),
                     hs.integers(0, most + 2))


@hs.composite
def _address(draw: hs.DrawFn, quantity: int) -> int:
    """0, the sign bit, 65535, and the addresses where the last item is 65534, 65535, 65536."""
    end = 0x10000 - max(quantity, 1)
    chosen = draw(hs.one_of(hs.sampled_from([0, 1, 0x7FFF, 0x8000, 0xFFFE, 0xFFFF, end - 1, end, end + 1]),
                            hs.integers(0, 0xFFFF)))
    return min(max(chosen, 0), 0xFFFF)


@hs.composite
def stores(draw: hs.DrawFn) -> Store:
    """The whole address space, or a map that starts after 0 or ends before 65535; or a device
    that fails (with the whole address space: which of 02 and 04 comes first where both could is
    the device's business)."""
    if draw(hs.sampled_from([False, False, False, True])):
        return Store(failing=True)
    return Store(first=draw(hs.sampled_from([0, 0, 1, 100])), last=draw(hs.sampled_from([0xFFFF, 0xFFFF, 0xFFFE, 300])))


_WORD = hs.one_of(hs.sampled_from([0, 1, 0x7FFF, 0x8000, 0xFFFE, 0xFFFF, REFUSED]), hs.integers(0, 0xFFFF))


@hs.composite
def _length_skew(draw: hs.DrawFn, pdu: bytes) -> bytes:
    """The request as built, one byte short, or one byte long."""
    skew = draw(hs.sampled_from([0, 0, 0, -1, 1]))
    return pdu[:-1] if skew < 0 else pdu + bytes([draw(hs.integers(0, 255))]) if skew else pdu


@hs.composite
def reads(draw: hs.DrawFn) -> bytes:
    function = draw(hs.sampled_from(sorted(READS)))
    quantity = draw(_quantity(READS[function][1]))
    return draw(_length_skew(struct.pack(">BHH", function, draw(_address(quantity)), quantity)))


@hs.composite
def single_writes(draw: hs.DrawFn) -> bytes:
    function = draw(hs.sampled_from([0x05, 0x06]))
    value = draw(hs.sampled_from([0xFF00, 0x0000, 0x00FF, 0xFF01, 0xFFFF, 0x0001]) if function == 0x05 else _WORD)
    return draw(_length_skew(struct.pack(">BHH", function, draw(_address(1)), value)))


def _values(draw: hs.DrawFn, function: int, quantity: int) -> bytes:
    """The values of a write of ``quantity`` coils or registers (as many as a byte count can say),
    a register now and then one of the edge values or the one the device refuses."""
    if function == 0x0F:
        size = math.ceil(min(quantity, 1976) / 8)
        return draw(hs.binary(min_size=size, max_size=size))
    size = 2 * min(quantity, 127)
    values = bytearray(draw(hs.binary(min_size=size, max_size=size)))
    if size and draw(hs.booleans()):
        at = 2 * draw(hs.integers(0, size // 2 - 1))
        values[at:at + 2] = draw(_WORD).to_bytes(2, "big")
    return bytes(values)


@hs.composite
def multiple_writes(draw: hs.DrawFn) -> bytes:
    """Function 15 or 16 with its quantity near its limit, the byte count right or one off, then
    the values (one byte short or long at times)."""
    function = draw(hs.sampled_from(sorted(WRITES)))
    quantity = draw(_quantity(WRITES[function][0]))
    values = _values(draw, function, quantity)
    count = (len(values) + draw(hs.sampled_from([0, 0, 0, -1, 1]))) % 256
    head = struct.pack(">BHHB", function, draw(_address(quantity)), quantity, count)
    return draw(_length_skew(head + values))


@hs.composite
def read_writes(draw: hs.DrawFn) -> bytes:
    read_quantity, write_quantity = draw(_quantity(RW_READ)), draw(_quantity(RW_WRITE))
    values = _values(draw, 0x10, write_quantity)
    count = (len(values) + draw(hs.sampled_from([0, 0, 0, -1, 1]))) % 256
    head = struct.pack(">BHHHHB", 0x17, draw(_address(read_quantity)), read_quantity, draw(_address(write_quantity)),
                       write_quantity, count)
    return draw(_length_skew(head + values))


# -- the properties ----------------------------------------------------------------------------------
@settings(max_examples=150, deadline=None)
@given(store=stores(), pdu=reads())
@example(store=Store(), pdu=bytes.fromhex("01 0000 07D0")).via("2000 coils: 250 bytes")
@example(store=Store(), pdu=bytes.fromhex("01 0000 07D1")).via("2001 coils: 03")
@example(store=Store(), pdu=bytes.fromhex("02 F830 07D0")).via("2000 inputs ending at 65535")
@example(store=Store(), pdu=bytes.fromhex("02 F831 07D0")).via("2000 inputs, one beyond 65535: 02")
@example(store=Store(), pdu=bytes.fromhex("01 FFFF 0001")).via("coil 65535")
@example(store=Store(), pdu=bytes.fromhex("01 FFFF 0002")).via("coils 65535 and 65536: 02")
@example(store=Store(), pdu=bytes.fromhex("01 0003 0009")).via("9 coils: two bytes")
@example(store=Store(), pdu=bytes.fromhex("03 0000 007D")).via("125 registers")
@example(store=Store(), pdu=bytes.fromhex("04 0000 007E")).via("126 registers: 03")
@example(store=Store(), pdu=bytes.fromhex("03 FF83 007D")).via("125 registers ending at 65535")
@example(store=Store(), pdu=bytes.fromhex("04 FF84 007D")).via("125 registers, one beyond 65535: 02")
@example(store=Store(), pdu=bytes.fromhex("03 FFFF 0001")).via("register 65535")
@example(store=Store(), pdu=bytes.fromhex("03 FFFF 0002")).via("registers 65535 and 65536: 02")
@example(store=Store(), pdu=bytes.fromhex("03 0000 0000")).via("0 registers: 03")
@example(store=Store(), pdu=bytes.fromhex("03 0000 00")).via("a byte short: 03")
@example(store=Store(), pdu=bytes.fromhex("03 0000 0001 00")).via("a byte long: 03")
@example(store=Store(failing=True), pdu=bytes.fromhex("03 0010 0002")).via("the device failed: 04")
def test_reads_answer_as_the_standard(store: Store, pdu: bytes) -> None:
    check(store, pdu)


@settings(max_examples=100, deadline=None)
@given(store=stores(), pdu=single_writes())
@example(store=Store(), pdu=bytes.fromhex("05 FFFF FF00")).via("coil 65535 on")
@example(store=Store(), pdu=bytes.fromhex("05 0007 0000")).via("a coil off")
@example(store=Store(), pdu=bytes.fromhex("05 0007 00FF")).via("00FF: 03")
@example(store=Store(), pdu=bytes.fromhex("05 0007 FF00 00")).via("a byte long: 03")
@example(store=Store(), pdu=bytes.fromhex("06 FFFF 8000")).via("register 65535, the sign bit")
@example(store=Store(), pdu=bytes.fromhex("06 0001 DEAD")).via("a value the device refuses: 03")
@example(store=Store(last=300), pdu=bytes.fromhex("06 012D 0001")).via("beyond the map: 02")
@example(store=Store(failing=True), pdu=bytes.fromhex("05 0001 FF00")).via("the device failed: 04")
def test_single_writes_answer_as_the_standard(store: Store, pdu: bytes) -> None:
    check(store, pdu)


@settings(max_examples=150, deadline=None)
@given(store=stores(), pdu=multiple_writes())
@example(store=Store(), pdu=bytes.fromhex("0F 0000 0008 01 A5")).via("8 coils: one byte")
@example(store=Store(), pdu=bytes.fromhex("0F 0000 0009 02 A5 FF")).via("9 coils: two bytes, the 8 padding bits ignored")
@example(store=Store(), pdu=bytes.fromhex("0F 0000 0009 01 A5")).via("9 coils in one byte: 03")
@example(store=Store(), pdu=bytes.fromhex("0F 0000 0010 02 A5 5A")).via("16 coils")
@example(store=Store(), pdu=bytes.fromhex("0F 0000 0007 01 FF")).via("7 coils, the top bit ignored")
@example(store=Store(), pdu=bytes.fromhex("0F FFFF 0001 01 01")).via("coil 65535")
@example(store=Store(), pdu=bytes.fromhex("0F FFFF 0002 01 03")).via("coils 65535 and 65536: 02")
@example(store=Store(), pdu=bytes.fromhex("0F 0000 07B0 F6" + "C3" * 246)).via("1968 coils")
@example(store=Store(), pdu=bytes.fromhex("0F 0000 07B1 F7" + "C3" * 247)).via("1969 coils: 03")
@example(store=Store(), pdu=bytes.fromhex("0F 0000 0000 00")).via("0 coils: 03")
@example(store=Store(), pdu=bytes.fromhex("0F 0000 0001")).via("no byte count: 03")
@example(store=Store(), pdu=bytes.fromhex("0F 0000 00")).via("cut in the quantity: 03")
@example(store=Store(), pdu=bytes.fromhex("10 0000 0001 02 1234")).via("one register")
@example(store=Store(), pdu=bytes.fromhex("10 FFFF 0001 02 8000")).via("register 65535")
@example(store=Store(), pdu=bytes.fromhex("10 FFFF 0002 04 0001 0002")).via("registers 65535 and 65536: 02")
@example(store=Store(), pdu=bytes.fromhex("10 0000 007B F6" + "0102" * 123)).via("123 registers")
@example(store=Store(), pdu=bytes.fromhex("10 0000 007C F8" + "0102" * 124)).via("124 registers: 03")
@example(store=Store(), pdu=bytes.fromhex("10 0000 0002 04 0001")).via("values short of the byte count: 03")
@example(store=Store(), pdu=bytes.fromhex("10 0000 0001 02 0001 00")).via("a byte beyond the byte count: 03")
@example(store=Store(), pdu=bytes.fromhex("10 0000 0002 04 0001 DEAD")).via("a refused value: 03, none written")
@example(store=Store(), pdu=bytes.fromhex("10 0000 00")).via("cut in the quantity: 03")
@example(store=Store(), pdu=bytes.fromhex("10 0000 0001")).via("no byte count: 03")
@example(store=Store(failing=True), pdu=bytes.fromhex("10 0000 0001 02 0001")).via("the device failed: 04")
def test_multiple_writes_answer_as_the_standard(store: Store, pdu: bytes) -> None:
    check(store, pdu)


@settings(max_examples=150, deadline=None)
@given(store=stores(), pdu=read_writes())
@example(store=Store(), pdu=bytes.fromhex("17 0000 007D 0000 0079 F2" + "0203" * 121)).via("125 read, 121 written")
@example(store=Store(), pdu=bytes.fromhex("17 0000 007E 0000 0001 02 0001")).via("126 read: 03")
@example(store=Store(), pdu=bytes.fromhex("17 0000 0001 0000 007A F4" + "0203" * 122)).via("122 written: 03")
@example(store=Store(), pdu=bytes.fromhex("17 0000 0000 0000 0001 02 0001")).via("0 read: 03")
@example(store=Store(), pdu=bytes.fromhex("17 FFFF 0001 FFFF 0001 02 0001")).via("65535 read and written")
@example(store=Store(), pdu=bytes.fromhex("17 FFFF 0002 0000 0001 02 0001")).via("the read beyond 65535: 02")
@example(store=Store(), pdu=bytes.fromhex("17 0000 0001 FFFF 0002 04 0001 0002")).via("the write beyond: 02")
@example(store=Store(last=300), pdu=bytes.fromhex("17 012D 0001 0000 0001 02 0001")).via("read outside the map: 02")
@example(store=Store(), pdu=bytes.fromhex("17 0010 0001 0010 0001 02 4321")).via("the read sees the write")
@example(store=Store(), pdu=bytes.fromhex("17 0010 0001 0010 0001 02")).via("values missing: 03")
@example(store=Store(), pdu=bytes.fromhex("17 0010 0001 0010 0001")).via("no byte count: 03")
@example(store=Store(), pdu=bytes.fromhex("17 8000 0001 8000 0001 02 0001")).via("the sign bit of both addresses")
def test_read_write_answers_as_the_standard(store: Store, pdu: bytes) -> None:
    check(store, pdu)


@settings(max_examples=100, deadline=None)
@given(pdu=hs.binary(min_size=0, max_size=12))
@example(pdu=b"").via("no function code: 80 01")
@example(pdu=b"\x55").via("55: D5 01")
@example(pdu=b"\x81\x00\x00\x00\x01").via("81: 81 01")
@example(pdu=b"\x07").via("07: 87 01")
@example(pdu=b"\x2b").via("43 without its MEI type: AB 03")
@example(pdu=b"\x2b\x0d\x01\x00").via("43 with MEI type 13: AB 01")
@example(pdu=b"\x2b\x0e\x05\x00").via("43/14 with Read Device ID code 05: AB 03")
@example(pdu=b"\x2b\x0e\x01\x00").via("43/14 basic stream: judged by test_modbus_ident")
def test_any_bytes_get_the_standards_answer(pdu: bytes) -> None:
    """Codes outside the table are exception 01 (§7), whatever follows; a known code with any
    bytes after it is answered as its rule says."""
    check(Store(), pdu)


# -- the examples of the standard --------------------------------------------------------------------
def _examples_store() -> Store:
    """The values the examples of §6 read, in a map of addresses 0 … 1023."""
    store = Store(last=0x3FF)
    store.coils.update(zip(range(0x13, 0x13 + 19), _bits_of(bytes.fromhex("CD 6B 05"), 19), strict=True))
    store.discretes.update(zip(range(0xC4, 0xC4 + 22), _bits_of(bytes.fromhex("AC DB 35"), 22), strict=True))
    store.holding.update({0x6B: 0x022B, 0x6C: 0x0000, 0x6D: 0x0064})
    store.inputs[0x08] = 0x000A
    store.holding.update(zip(range(3, 9), (0x00FE, 0x0ACD, 0x0001, 0x0003, 0x000D, 0x00FF), strict=True))
    return store


@pytest.mark.parametrize(("request_pdu", "expected"), [
    pytest.param("01 0013 0013", "01 03 CD 6B 05", id="§6.1 read coils 20-38"),
    pytest.param("02 00C4 0016", "02 03 AC DB 35", id="§6.2 read discrete inputs 197-218"),
    pytest.param("03 006B 0003", "03 06 022B 0000 0064", id="§6.3 read holding registers 108-110"),
    pytest.param("04 0008 0001", "04 02 000A", id="§6.4 read input register 9"),
    pytest.param("05 00AC FF00", "05 00AC FF00", id="§6.5 write coil 173 ON"),
    pytest.param("06 0001 0003", "06 0001 0003", id="§6.6 write register 2 to 3"),
    pytest.param("0F 0013 000A 02 CD01", "0F 0013 000A", id="§6.11 write coils 20-29"),
    pytest.param("10 0001 0002 04 000A 0102", "10 0001 0002", id="§6.12 write registers 2 and 3"),
    pytest.param("17 0003 0006 000E 0003 06 00FF 00FF 00FF", "17 0C 00FE 0ACD 0001 0003 000D 00FF",
                 id="§6.17 read registers 4-9, write 15-17"),
    pytest.param("01 04A1 0001", "81 02", id="§7 read coil 1186 outside the map: 81 02"),
])
def test_the_examples_of_the_standard(request_pdu: str, expected: str) -> None:
    store = _examples_store()
    assert answer(store, bytes.fromhex(request_pdu)).hex(" ") == bytes.fromhex(expected).hex(" ")


def test_the_writes_of_the_examples_reach_the_tables() -> None:
    """§6.11: CD 01 sets coils 20-29 to 1 0 1 1 0 0 1 1 1 0 (coil 20 in the lowest bit); §6.12 and
    §6.17 write their registers; §6.5 switches coil 173 on."""
    store = _examples_store()
    for pdu in ("05 00AC FF00", "06 0001 0003", "0F 0013 000A 02 CD01", "10 0001 0002 04 000A 0102",
                "17 0003 0006 000E 0003 06 00FF 00FF 00FF"):
        answer(store, bytes.fromhex(pdu))
    assert [int(store.coils[a]) for a in range(0x13, 0x13 + 10)] == [1, 0, 1, 1, 0, 0, 1, 1, 1, 0]
    assert store.coils[0xAC] is True
    assert [store.holding[a] for a in (0x01, 0x02, 0x0E, 0x0F, 0x10)] == [0x000A, 0x0102, 0x00FF, 0x00FF, 0x00FF]


def test_read_write_checks_its_read_range_before_it_writes() -> None:
    """§6.17: the write happens before the read, but a read range outside the map is 02 with
    nothing written (the read range is tried first)."""
    store = Store(last=300)
    assert answer(store, bytes.fromhex("17 0120 0010 0000 0001 02 1234")).hex(" ") == "97 02"
    assert store.holding == {}
    assert store.reads == [("holding", 0x120, 0x10)]


def test_read_write_reads_after_it_writes() -> None:
    store = Store()
    assert answer(store, bytes.fromhex("17 0005 0002 0006 0001 02 BEEF")).hex(" ") == "17 04 " + (
        store.word("holding", 5).to_bytes(2, "big") + b"\xbe\xef").hex(" ")
    assert store.reads[-1] == ("holding", 5, 2)


def test_exception_responses_set_the_high_bit() -> None:
    """§7: the function code plus 80h, then the exception code, for each of 01 … 04."""
    for function in (0x01, 0x03, 0x10, 0x17, 0x55):
        for code in (ILLEGAL_FUNCTION, ILLEGAL_ADDRESS, ILLEGAL_VALUE, DEVICE_FAILURE):
            assert exception(function, code) == bytes((function + 0x80, code))
    assert (modbus_pdu.ILLEGAL_FUNCTION, modbus_pdu.ILLEGAL_ADDRESS, modbus_pdu.ILLEGAL_VALUE,
            modbus_pdu.DEVICE_FAILURE) == (1, 2, 3, 4)


def test_a_refusal_carries_its_code() -> None:
    assert Refused(3).code == 3
    assert answer(Store(), bytes.fromhex("06 0000 DEAD")) == b"\x86\x03"


# -- the RTU frame lengths ----------------------------------------------------------------------------
def _crc(frame: bytes) -> bytes:
    return FramerRTU.compute_CRC(frame).to_bytes(2, "big")


@settings(max_examples=100, deadline=None)
@given(pdu=hs.one_of(reads(), single_writes(), multiple_writes(), read_writes()), unit=hs.integers(0, 247))
@example(pdu=bytes.fromhex("0F 0013 000A 02 CD01"), unit=1).via("§6.11's example")
@example(pdu=bytes.fromhex("17 0003 0006 000E 0003 06 00FF 00FF 00FF"), unit=1).via("§6.17's example")
@example(pdu=bytes.fromhex("10 0000 0000 00"), unit=1).via("a byte count of 0")
def test_rtu_frames_are_as_long_as_their_function_says(pdu: bytes, unit: int) -> None:
    """Modbus over Serial Line §2.5.1: address, PDU, CRC.  Reads and single writes are 8 bytes;
    functions 15, 16 and 23 are as long as the byte count at offset 6 (or 10) says, not known (0)
    before it arrives."""
    at = {0x0F: 6, 0x10: 6, 0x17: 10}.get(pdu[0])  # the byte count's offset in the RTU frame
    length = FUNCTIONS[pdu[0]].rtu_length
    if at is None:
        frame = bytes([unit]) + pdu[:5].ljust(5, b"\0")
        assert length(frame + _crc(frame)) == 8
        assert length(frame[:2]) == 8  # known from the function code
        return
    if len(pdu) < at:
        return  # cut before its byte count
    count = pdu[at - 1]
    frame = bytes([unit]) + pdu[:at] + pdu[at:at + count].ljust(count, b"\0")
    frame += _crc(frame)
    for cut in range(2, at + 1):
        assert length(frame[:cut]) == 0, cut
    for cut in range(at + 1, len(frame) + 1):
        assert length(frame[:cut]) == len(frame) == at + 1 + count + 2, cut
