"""The IP247-SIM/PG v1 profile's requests at their limits, by property, against spec ip247.md
§3.6.2/§3.6.3 written as an oracle: page 1 … 4, OPERATE 10 bytes with command 1 … 5 (B and W
unsigned, DD signed), OBSERVE 1, WRITE_REC 4 + 2·N, READ_REC 4, DELETE_REC 3 bytes, flags bit 0
only, at most 1100 parameter bytes (§3.6.5); anything else is ack 82H, echoing page and BA."""

from __future__ import annotations

import hypothesis.strategies as hs
import pytest
from hypothesis import example, given

from devsim.devices.ip247.pg_profile import (
    Delete,
    Header,
    Malformed,
    Observation,
    Observe,
    Operate,
    ReadRecord,
    Request,
    WriteRecord,
    command_code,
    parse_request,
    response,
)

FUNCTIONS = [0x00, 0x60, 0x61, 0x62, 0x63, 0x64, 0x65, 0x66, 0xFF]


def _oracle(function: int, data: bytes) -> Request:
    page = data[0] if data else 0
    ba = data[1] if len(data) > 1 else 0
    bad = Malformed(function, page, ba)
    if len(data) > 1100 or page not in (1, 2, 3, 4):
        return bad
    if function == 0x61:
        if len(data) != 10 or data[2] not in (1, 2, 3, 4, 5):
            return bad
        return Operate(page, ba, data[2], data[3], int.from_bytes(data[4:6], "big"),
                       int.from_bytes(data[6:10], "big", signed=True))
    if function == 0x62:
        return Observe(page) if len(data) == 1 else bad
    if function == 0x63:
        if len(data) < 4 or len(data) % 2:
            return bad
        words = tuple(int.from_bytes(data[i : i + 2], "big") for i in range(4, len(data), 2))
        return WriteRecord(page, ba, data[2], data[3] % 2 == 1, words)
    if function == 0x64:
        return ReadRecord(page, ba, data[2], data[3] % 2 == 1) if len(data) == 4 else bad
    if function == 0x65:
        return Delete(page, ba, data[2]) if len(data) == 3 else bad
    return bad


@hs.composite
def blocks(draw: hs.DrawFn) -> bytes:
    """A parameter block of about the right length, pages 0 … 5, commands 0 … 6, any flags."""
    size = draw(hs.sampled_from([0, 1, 2, 3, 4, 5, 6, 9, 10, 11, 12]))
    head = bytes((draw(hs.integers(0, 5)), draw(hs.integers(0, 255)), draw(hs.integers(0, 6)),
                  draw(hs.integers(0, 255))))
    return (head + draw(hs.binary(min_size=8, max_size=8)))[:size]


@given(hs.sampled_from(FUNCTIONS), blocks())
@example(0x61, bytes.fromhex("01 08 05 c8 9c 40 ff ff ff ff"))  # B 200, W 40000, DD -1
@example(0x61, bytes.fromhex("04 08 01 00 00 00 7f ff ff ff"))
@example(0x63, bytes.fromhex("01 14 05 00"))  # no words, not overwriting
@example(0x63, bytes.fromhex("01 14 05 02 00 01"))  # flags bit 1 is not bit 0
@example(0x64, bytes.fromhex("01 42 00 02"))
@example(0x64, bytes.fromhex("01 42 00 ff"))
@example(0x62, bytes.fromhex("04 00"))
@example(0x61, bytes.fromhex("01 08"))  # too short: page and BA echoed
@example(0x61, b"")
@example(0x63, bytes.fromhex("05 14 05 00"))
def test_each_request_as_the_spec_lays_it_out(function: int, data: bytes) -> None:
    assert parse_request(function, data) == _oracle(function, data)


@pytest.mark.parametrize("function", FUNCTIONS)
def test_every_length_and_page_around_the_limits(function: int) -> None:
    for page in (0, 1, 2, 3, 4, 5, 255):
        for command in (0, 1, 5, 6):  # OPERATE's command 1 … 5 (the record functions' DB number)
            for size in range(13):
                data = (bytes((page, 0x08, command)) + bytes.fromhex("c8 9c 40 ff ff ff fe 00 01 02"))[:size]
                assert parse_request(function, data) == _oracle(function, data), (page, command, size)


@pytest.mark.parametrize("size, accepted", [(1098, True), (1100, True), (1102, False)])
def test_a_parameter_block_of_at_most_1100_bytes(size: int, accepted: bool) -> None:
    data = bytes.fromhex("04 16 05 01") + bytes(size - 4)
    request = parse_request(0x63, data)
    assert request == (WriteRecord(4, 0x16, 5, True, (0,) * ((size - 4) // 2)) if accepted
                       else Malformed(0x63, 4, 0x16))


def test_commands_by_code_or_name() -> None:
    assert [command_code(c) for c in (3, "Start", "STOPP", "vorwärts", "Rückwärts", "übernahme")] == [3, 1, 2, 3, 4, 5]
    assert [command_code(c) for c in ("stop", "Forward", "BACKWARD", "take_over", "halt")] == [2, 3, 4, 5, None]


def test_responses() -> None:
    header = Header(0x82, 5, 0x42, 0, 0, 0, 0, 0)
    assert response(header) == bytes.fromhex("82 05 42 00 00 00 00 00")
    assert response(header, (0x1234, 0xFFFF)) == bytes.fromhex("82 05 42 00 00 00 00 00 12 34 ff ff")
    observed = response(header, Observation(-2, 2**31 - 1, (67, 1, 2, 3), 5, 0b1111))
    assert observed[8:] == bytes.fromhex("ff ff ff fe 7f ff ff ff 43 01 02 03 05 0f")
