"""The standard S5 services on the IP247's PG port (devsim.devices.ip247.s5_services; spec ip247.md
§3.5.2): the blocks laid out in 64 KiB from 1000H, each a 5-word header and its words, and the four
services at the limits of their parameters (exact lengths, a read of one byte, the last address
before the first, a block that just fits and one word more)."""

from __future__ import annotations

import struct

import pytest

from devsim.devices.ip247.as511 import Refused
from devsim.devices.ip247.s5_services import DB, DX, S5Memory

BLOCKS = [(DB, 5, [0x0102, 0xFFFF, 3]), (DX, 0x101, [-1]), (DB, 9, [])]


def _header(kind: int, number: int, words: int) -> bytes:
    """70H 70H, type | 40H, number, PG id 0, library 0, length in words with the header."""
    return struct.pack(">BBBBHHH", 0x70, 0x70, 0x40 | kind, number, 0, 0, 5 + words)


def test_the_blocks_are_laid_out_from_1000h() -> None:
    memory = S5Memory(BLOCKS)
    assert bytes(memory.memory[0x1000:0x1010]) == _header(DB, 5, 3) + bytes.fromhex("0102 ffff 0003")
    assert bytes(memory.memory[0x1010:0x101C]) == _header(DX, 1, 1) + b"\xff\xff"  # number and word cut to size
    assert bytes(memory.memory[0x101C:0x1026]) == _header(DB, 9, 0)
    assert memory.info == {(DB, 5): (0x100A, 8), (DX, 1): (0x101A, 6), (DB, 9): (0x1026, 5)}
    assert not any(memory.memory[:0x1000]) and not any(memory.memory[0x1026:])


@pytest.mark.parametrize("words, laid", [(0x10000 // 2 - 0x800 - 5, True), (0x10000 // 2 - 0x800 - 4, False)])
def test_a_block_that_just_fits_and_one_word_more(words: int, laid: bool) -> None:
    memory = S5Memory([(DB, 1, [0xABCD] * words), (DB, 2, [])])
    assert ((DB, 1) in memory.info) is laid and (DB, 2) not in memory.info
    assert memory.memory[0xFFFE:] == (b"\xab\xcd" if laid else b"\0\0")


def test_the_system_parameters() -> None:
    reply = S5Memory(BLOCKS).service(0x18, b"")
    assert reply == bytes(5) + bytes.fromhex("0080 0100 0200 0300 0400 0500") + bytes(28)


def test_block_info() -> None:
    memory = S5Memory(BLOCKS)
    assert memory.service(0x1A, bytes((DB, 5))) == bytes.fromhex("00 100a 70 70 41 05 0000 0000 0008")
    assert memory.service(0x1A, bytes((DX, 1))) == bytes.fromhex("00 101a 70 70 4c 01 0000 0000 0006")
    for parameters in (bytes((DB, 6)), bytes((DX, 5)), bytes((DB,)), bytes((DB, 5, 0)), b""):
        assert memory.service(0x1A, parameters) == Refused("no such block")  # (the why goes to the event log)


def test_the_block_address_list() -> None:
    memory = S5Memory(BLOCKS)
    reply = memory.service(0x1B, bytes((DB,)))
    assert isinstance(reply, bytes) and len(reply) == 1 + 512 and reply[0] == 0
    addresses = struct.unpack(">256H", reply[1:])
    assert addresses[5] == 0x100A and addresses[9] == 0x1026 and sum(1 for a in addresses if a) == 2
    assert struct.unpack(">256H", memory.service(0x1B, bytes((DX,)))[1:])[1] == 0x101A  # type: ignore[index]
    for parameters in (b"", bytes((DB, 0))):
        assert memory.service(0x1B, parameters) == Refused("the block list takes a block type")


def test_read_memory() -> None:
    memory = S5Memory(BLOCKS)
    assert memory.service(0x04, bytes.fromhex("100a 100b")) == bytes(5) + b"\x01\x02"
    assert memory.service(0x04, bytes.fromhex("100a 100a")) == bytes(5) + b"\x01"  # one byte
    assert memory.service(0x04, bytes.fromhex("fffe ffff")) == bytes(7)
    assert memory.service(0x04, bytes.fromhex("100b 100a")) == Refused("the last address lies before the first")
    for parameters in (bytes.fromhex("100a 10"), bytes.fromhex("100a 100b 00")):
        assert memory.service(0x04, parameters) == Refused("read memory takes a first and a last address")


def test_other_functions_are_no_s5_service() -> None:
    assert S5Memory([]).service(0x03, b"") == S5Memory([]).service(0x61, b"") == Refused("not an S5 service")


def test_block_numbers_and_addresses_from_128_and_8000h_are_unsigned() -> None:
    memory = S5Memory([(DB, 200, [0] * 0x4000), (DX, 255, [7])])
    assert memory.info[(DX, 255)] == (0x1000 + 10 + 0x8000 + 10, 6)
    assert memory.service(0x1A, bytes((DB, 200))) == bytes.fromhex("00 100a 70 70 41 c8 0000 0000 4005")
    assert memory.service(0x1A, bytes((DX, 255))) == bytes.fromhex("00 9014 70 70 4c ff 0000 0000 0006")
    assert memory.service(0x1B, bytes((DX,)))[-2:] == b"\x90\x14"  # type: ignore[index]
