"""The IP247-SIM/PG v1 profile's requests and responses (spec ip247.md §3.6; vectors §3.6.7)."""

from __future__ import annotations

from hypothesis import given
from hypothesis import strategies as hs

from devsim.devices.ip247.pg_profile import (
    Delete,
    Header,
    Malformed,
    Observation,
    Observe,
    Operate,
    ReadRecord,
    WriteRecord,
    parse_request,
    response,
)


def test_vector_b_start_automatic_program_5_on_axis_1() -> None:
    request = parse_request(0x61, bytes.fromhex("01 08 01 05 00 00 00 00 00 00"))
    assert request == Operate(page=1, ba=8, cmd=1, b=5, w=0, dd=0)
    answer = response(Header(0x00, 1, 8, 1, 0, 8, 0x02, 0xFF))
    assert answer == bytes.fromhex("00 01 08 01 00 08 02 FF")


def test_vector_c_actual_values_and_vector_d_e() -> None:
    """(c) BA66 on axis 1: 47.287 mm, residual 12.602 mm; (d) program 16 read; (e) BA13 on axis
    2, 10.000 mm forward."""
    assert parse_request(0x64, bytes.fromhex("01 42 00 00")) == ReadRecord(1, 0x42, 0, False)
    record = (0x0000, 0xB8B7, 0, 0, 0x0000, 0x313A)
    assert response(Header(0, 1, 0x42, 0, 0, 6, 0x86, 2), record) == bytes.fromhex(
        "00 01 42 00 00 06 86 02 00 00 B8 B7 00 00 00 00 00 00 31 3A")
    assert parse_request(0x64, bytes.fromhex("01 45 10 00")) == ReadRecord(1, 0x45, 16, False)
    assert parse_request(0x61, bytes.fromhex("02 0D 03 00 00 00 00 00 27 10")) == Operate(2, 13, 3, 0, 0, 10_000)


def test_records_observation_and_malformed_requests() -> None:
    write = parse_request(0x63, bytes.fromhex("04 16 05 01 00 07 00 44 42 05"))
    assert write == WriteRecord(4, 0x16, 5, True, (0x0007, 0x0044, 0x4205))
    assert parse_request(0x65, bytes.fromhex("04 17 05")) == Delete(4, 0x17, 5)
    observed = response(Header(0, 1, 8, 0, 10, 8, 0x02, 0xFF),
                        Observation(-1, 12_602, (10, 0, 0, 0), 1, 0b1000))
    assert len(observed) == 22 and observed[8:12] == b"\xff\xff\xff\xff" and observed[16] == 10
    assert isinstance(parse_request(0x61, bytes.fromhex("05 08 01")), Malformed)  # page 5
    assert isinstance(parse_request(0x61, bytes.fromhex("01 08 09 00 00 00 00 00 00 00")), Malformed)  # cmd 9
    assert isinstance(parse_request(0x62, b""), Malformed)
    assert isinstance(parse_request(0x63, bytes.fromhex("04 16 05 00 01")), Malformed)  # odd record


@given(function=hs.integers(min_value=0, max_value=255), data=hs.binary(max_size=1200))
def test_any_parameters_parse_to_a_request_or_malformed(function: int, data: bytes) -> None:
    request = parse_request(function, data)
    assert isinstance(request, Operate | Observe | WriteRecord | ReadRecord | Delete | Malformed)
