"""S-Bus at its limits, by property (spec pcd4h3.md §9.2–§9.4).

Each test generates telegrams at and around one declared limit — at most 32 registers and 128
flags per read or write, the flag bits packed eight to a byte, 32-bit two's complement values
(the int32 minimum and maximum), the 16-bit address (0 and 65535), the station (own, other,
broadcast 255), byte stuffing of B5h/C5h, the CRC, the Ether-S-Bus length (13 to 4096), version
and attribute — in both directions, and compares the codec with the rule written here.
"""

from __future__ import annotations

import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as hs

from devsim.devices.pcd4h3.sbus import (
    Bad,
    EtherReceiver,
    Read,
    Request,
    SerialReceiver,
    Write,
    crc16,
    decode_command,
    ether_ack,
    ether_frame,
    pack_bits,
    parse_ether,
    serial_ack,
    serial_reply,
    stuff,
    unstuff,
)
from devsim.devices.pcd4h3.services import telegram as telegram_of

READS = {0x00: ("counter", 32), 0x02: ("flag", 128), 0x03: ("input", 128), 0x05: ("output", 128),
         0x06: ("register", 32), 0x07: ("timer", 32)}
WRITES = {0x0B: ("flag", 128), 0x0D: ("output", 128), 0x0E: ("register", 32)}
ADDRESS = hs.one_of(hs.sampled_from([0, 1, 255, 256, 65534, 65535]), hs.integers(0, 65535))
INT32 = hs.one_of(hs.sampled_from([-(1 << 31), -(1 << 31) + 1, -1, 0, 1, (1 << 31) - 1]),
                  hs.integers(-(1 << 31), (1 << 31) - 1))


def _near(limit: int) -> hs.SearchStrategy[int]:
    return hs.one_of(hs.integers(max(1, limit - 2), limit + 2), hs.integers(1, 256))


def _crc_xmodem(data: bytes) -> int:
    """CRC-16/XMODEM, bit by bit from its definition (polynomial 1021h, initial 0, MSB first)."""
    crc = 0
    for byte in data:
        for bit in range(7, -1, -1):
            top = (crc >> 15) ^ (byte >> bit & 1)
            crc = (crc << 1) & 0xFFFF
            if top:
                crc ^= 0x1021
    return crc


@settings(max_examples=100, deadline=None)
@given(hs.binary(max_size=40))
@example(b"123456789")
def test_crc_is_crc16_xmodem(data: bytes) -> None:
    assert crc16(data) == _crc_xmodem(data)


@settings(max_examples=300, deadline=None)
@given(hs.sampled_from(sorted(READS)), hs.data(), ADDRESS)
def test_reads_at_the_count_limit(command: int, data: hs.DataObject, address: int) -> None:
    """§9.4: n − 1, address high, low; at most 32 registers/counters/timers, 128 flags/inputs/outputs."""
    medium, most = READS[command]
    count = data.draw(_near(most))
    parameters = bytes((count - 1, address >> 8, address & 0xFF))
    decoded = decode_command(Request(1, command, parameters), telegram_of)
    # (a Bad's reason goes to the station's event log with its NAK)
    assert decoded == (Read(medium, address, count) if count <= most else Bad(f"at most {most} {medium}s per telegram"))
    for wrong in (parameters[:2], parameters + b"\x00"):
        assert decode_command(Request(1, command, wrong), telegram_of) == Bad("wrong parameter count")


@settings(max_examples=300, deadline=None)
@given(hs.lists(INT32, max_size=34), ADDRESS, hs.integers(0, 3))
@example([-(1 << 31)], 65535, 0)  # the int32 minimum at the last address
@example([0] * 32, 0, 0)  # exactly 32 registers
@example([0] * 33, 0, 0)  # one too many
@example([], 0, 0)  # no data
def test_register_writes_at_the_limits(values: list[int], address: int, extra: int) -> None:
    """§9.4: wcount, address, then 4 bytes a register, big-endian two's complement; 1 to 32."""
    data = b"".join(v.to_bytes(4, "big", signed=True) for v in values) + bytes(extra)
    parameters = bytes((len(data) + 1 & 0xFF, address >> 8, address & 0xFF)) + data
    decoded = decode_command(Request(1, 0x0E, parameters), telegram_of)
    if values and not extra and len(values) <= 32:
        assert decoded == Write("register", address, tuple(values))
    elif values and not extra:
        assert decoded == Bad("at most 32 registers per telegram")
    else:  # (no data at all leaves the parameters shorter than 4 bytes)
        assert decoded == (Bad("register data come in 4 bytes") if data else Bad("wrong parameter count"))


@settings(max_examples=300, deadline=None)
@given(hs.sampled_from([0x0B, 0x0D]), hs.data(), ADDRESS, hs.integers(-1, 1))
@example(0x0B, None, 0, 0)
def test_flag_writes_at_the_limits(command: int, data: hs.DataObject | None, address: int, off: int) -> None:
    """§9.4: wcount, address, n − 1, then ⌈n/8⌉ bytes, the first flag in bit 0; 1 to 128."""
    medium, most = WRITES[command]
    count = 8 if data is None else data.draw(_near(most) | hs.integers(1, 17))
    bits = [1 if data is None else data.draw(hs.integers(0, 1)) for _ in range(count)]
    packed = bytearray((count + 7) // 8 + off)
    for i, bit in enumerate(bits[: 8 * len(packed)]):
        packed[i // 8] |= bit << (i % 8)
    parameters = bytes((len(packed) + 2 & 0xFF, address >> 8, address & 0xFF, count - 1 & 0xFF)) + bytes(packed)
    decoded = decode_command(Request(1, command, parameters), telegram_of)
    if off == 0 and count <= most:
        assert decoded == Write(medium, address, tuple(bits))
    elif count > most:
        assert decoded == Bad(f"at most {most} {medium}s per telegram")
    else:
        assert decoded == Bad("the byte count does not match the flag count")


def test_a_command_the_station_does_not_know_is_bad() -> None:
    assert decode_command(Request(1, 0x47, b""), telegram_of) == Bad("command 47h is not supported")


@pytest.mark.parametrize("parameters", [b"", b"\x01", b"\x02\x00", b"\x03\x00\x00"])
def test_writes_shorter_than_four_bytes_are_bad(parameters: bytes) -> None:
    for command in WRITES:
        assert decode_command(Request(1, command, parameters), telegram_of) == Bad("wrong parameter count")


@settings(max_examples=200, deadline=None)
@given(hs.lists(hs.integers(0, 1), max_size=40))
def test_pack_bits_first_in_bit_0(values: list[int]) -> None:
    packed = pack_bits(values)
    assert len(packed) == (len(values) + 7) // 8
    assert [packed[i // 8] >> (i % 8) & 1 for i in range(len(values))] == values
    assert all(byte >> (len(values) - 8 * i) == 0 for i, byte in enumerate(packed) if len(values) - 8 * i < 8)


# -- the serial link (§9.2) --------------------------------------------------------------------
def _wire(station: int, command: int, parameters: bytes, crc_error: int = 0) -> bytes:
    raw = bytes((0xB5, 0x00, station, command)) + parameters
    crc = (_crc_xmodem(raw) + crc_error) & 0xFFFF
    raw += crc.to_bytes(2, "big")
    return raw[:1] + raw[1:].replace(b"\xc5", b"\xc5\x01").replace(b"\xb5", b"\xc5\x00")


@hs.composite
def _telegram(draw: hs.DrawFn) -> tuple[int, int, bytes]:
    command = draw(hs.sampled_from([*READS, *WRITES, 0x1B, 0x1D, 0x20, 0x2F, 0x38, 0x43]))
    if command in READS:
        parameters = draw(hs.binary(min_size=3, max_size=3))
    elif command in WRITES:
        data = draw(hs.binary(min_size=1, max_size=20))
        parameters = bytes((len(data) + 1,)) + draw(hs.binary(min_size=2, max_size=2)) + data
    else:
        parameters = b""
    return draw(hs.sampled_from([1, 2, 255, 0xB5, 0xC5])), command, parameters


@settings(max_examples=300, deadline=None)
@given(hs.lists(hs.tuples(_telegram(), hs.sampled_from([0, 0, 0, 1, -1, 0x100]))), hs.integers(1, 9))
def test_the_station_takes_its_own_and_broadcast_telegrams_with_a_good_crc(
        telegrams: list[tuple[tuple[int, int, bytes], int]], size: int) -> None:
    """Stuffed B5h/C5h anywhere (station, parameters, CRC), split anywhere: a telegram for
    station 1 or 255 with a good CRC is a request; a bad CRC or another station is dropped."""
    wire = b"".join(_wire(station, command, parameters, error) for (station, command, parameters), error in telegrams)
    receiver = SerialReceiver(1, telegram_of)
    got = [r for start in range(0, len(wire), size) for r in receiver.feed(wire[start : start + size])]
    assert got == [Request(station, command, parameters) for (station, command, parameters), error in telegrams
                   if error == 0 and station in (1, 255)]
    assert receiver.errors["crc"] == sum(1 for _t, error in telegrams if error)


@settings(max_examples=200, deadline=None)
@given(hs.binary(max_size=30))
@example(b"\xb5\xc5")
def test_stuffing_round_trip(telegram: bytes) -> None:
    telegram = b"\xb5" + telegram
    wire = stuff(telegram)
    assert wire[0] == 0xB5 and 0xB5 not in wire[1:]
    assert len(wire) == len(telegram) + telegram[1:].count(0xB5) + telegram[1:].count(0xC5)
    assert unstuff(wire) == telegram


@pytest.mark.parametrize(("wire", "telegram"), [(b"\xb5\xc5\x00", b"\xb5\xb5"), (b"\xb5\xc5\x01", b"\xb5\xc5"),
                                                (b"\xb5\xc5\x02", None), (b"\xb5\xc5", None), (b"\xb5\x01", b"\xb5\x01")])
def test_unstuff_takes_only_c5_00_and_c5_01(wire: bytes, telegram: bytes | None) -> None:
    assert unstuff(wire) == telegram


def test_a_stuffing_error_drops_the_telegram_and_the_next_one_is_taken() -> None:
    receiver = SerialReceiver(1, telegram_of)
    good = _wire(1, 0x1B, b"")
    assert receiver.feed(b"\xb5\x00\x01\xc5\x02\x00" + good) == [Request(1, 0x1B, b"")]
    assert receiver.errors["framing"] == 1


def test_replies_carry_the_crc_of_their_unstuffed_bytes() -> None:
    for wire in (serial_reply(b"\xb5\xc5\x00"), serial_ack(0), serial_ack(1)):
        raw = unstuff(wire)
        assert raw is not None and _crc_xmodem(raw[:-2]) == int.from_bytes(raw[-2:], "big")


# -- Ether-S-Bus (§9.3) ------------------------------------------------------------------------
def _ether(version: int, kind: int, attribute: int, payload: bytes, crc_error: int = 0, length: int | None = None) -> bytes:
    body = (length if length is not None else 9 + len(payload) + 2).to_bytes(4, "big")
    body += bytes((version, kind)) + (7).to_bytes(2, "big") + bytes((attribute,)) + payload
    return body + ((_crc_xmodem(body) + crc_error) & 0xFFFF).to_bytes(2, "big")


@settings(max_examples=300, deadline=None)
@given(hs.integers(0, 3), hs.integers(0, 2), hs.integers(0, 3), hs.binary(min_size=0, max_size=8),
       hs.sampled_from([0, 0, 1]), hs.integers(-1, 1))
@example(1, 0, 0, b"\x01\x1b", 0, 0)  # the shortest frame: 13 bytes
@example(1, 0, 0, b"\x01", 0, 0)  # 12 bytes
def test_ether_frames_by_version_type_attribute_length_and_crc(
        version: int, kind: int, attribute: int, payload: bytes, crc_error: int, length_off: int) -> None:
    frame = _ether(version, kind, attribute, payload, crc_error)
    if length_off:
        frame = _ether(version, kind, attribute, payload, crc_error, len(frame) + length_off)
    good = (len(frame) >= 13 and version in (0, 1) and kind == 0 and attribute == 0 and not crc_error
            and not length_off)
    parsed = parse_ether(frame)
    assert parsed == ((version, 7, Request(payload[0], payload[1], payload[2:])) if good else None)


@pytest.mark.parametrize(("length", "taken"), [(11, False), (12, True), (13, True), (4096, True), (4097, False),
                                               (0, False)])
def test_ether_stream_lengths(length: int, taken: bool) -> None:
    """A TCP stream's length field outside 12…4096 (12: a one-byte answer, spec EV14) is no
    frame: the receiver drops what it holds and resynchronises on the next write."""
    frame = length.to_bytes(4, "big") + bytes(max(0, length - 4))
    receiver = EtherReceiver()
    assert receiver.feed(frame) == ([frame] if taken else [])
    good = ether_frame(1, 1, 0, b"\x01\x1b")
    assert receiver.feed(good) == [good]


@pytest.mark.parametrize("sequence", [0, 0x7FFF, 0x8000, 0xFFFF])
def test_the_ether_sequence_number_is_16_bits_unsigned(sequence: int) -> None:
    """§9.3: the sequence number is a 16-bit word the station copies into its answer; from
    8000h on it is still a plain number (a signed reading would turn FFFFh into -1)."""
    frame = _ether(1, 0, 0, b"\x01\x1b")
    frame = frame[:6] + sequence.to_bytes(2, "big") + frame[8:-2]
    frame += _crc_xmodem(frame).to_bytes(2, "big")
    assert parse_ether(frame) == (1, sequence, Request(1, 0x1B, b""))
    for answer in (ether_frame(1, sequence, 2, b"\x00\x01"), ether_ack(1, sequence, 1)):
        assert answer[6:8] == sequence.to_bytes(2, "big")
        assert int.from_bytes(answer[:4], "big") == len(answer) == 13


def test_a_telegram_with_a_bad_crc_is_dropped_and_what_follows_until_the_next_b5h_is_noise() -> None:
    """§9.2: a telegram whose CRC is wrong gets silence; the bytes after it, up to the next B5h,
    belong to no telegram, and the next telegram is taken."""
    receiver = SerialReceiver(1, telegram_of)
    assert receiver.feed(_wire(1, 0x1B, b"", crc_error=1) + b"\x00\x01\x1b\x12\x34") == []
    assert receiver.feed(_wire(1, 0x1D, b"")) == [Request(1, 0x1D, b"")]
    assert receiver.errors == {"crc": 1, "framing": 0}


def test_each_stuffing_error_is_counted() -> None:
    receiver = SerialReceiver(1, telegram_of)
    assert receiver.feed(b"\xb5\x00\x01\xc5\x02" * 2 + _wire(1, 0x1B, b"")) == [Request(1, 0x1B, b"")]
    assert receiver.errors["framing"] == 2


def test_a_host_that_goes_away_mid_telegram_leaves_nothing_behind() -> None:
    """The face resets its receiver when the host disconnects (a half telegram and a pending
    C5h are forgotten); the next host's first telegram is taken whole."""
    receiver = SerialReceiver(1, telegram_of)
    assert receiver.feed(_wire(1, 0x1B, b"")[:3] + b"\xc5") == []
    receiver.reset()
    assert receiver.feed(b"\x00" + _wire(1, 0x1B, b"")) == [Request(1, 0x1B, b"")]
