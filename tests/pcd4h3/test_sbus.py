"""S-Bus framing of the PCD4.H3 simulator (spec pcd4h3.md §9.2–§9.4) with the byte-exact vectors
V1–V21 and EV1–EV14 of §9.4."""

from __future__ import annotations

import hypothesis.strategies as hs
import pytest
from hypothesis import given, settings

from devsim.devices.pcd4h3.sbus import (
    Bad,
    EtherReceiver,
    Read,
    Request,
    SerialReceiver,
    Simple,
    Write,
    crc16,
    decode_command,
    ether_ack,
    ether_reply,
    pack_bits,
    parse_ether,
    serial_ack,
    serial_reply,
    stuff,
    unstuff,
)
from devsim.devices.pcd4h3.services import telegram as telegram_of


def h(text: str) -> bytes:
    return bytes.fromhex(text)


REQUESTS = [  # (vector, raw telegram, wire form, decoded)
    ("V1", "B5 00 01 0E 05 00 CF 00 00 03 E8 8C 42", None, Write("register", 207, (1000,))),
    ("V2", "B5 00 01 0B 03 00 CF 00 01 B3 8A", None, Write("flag", 207, (1,))),
    ("V3", "B5 00 01 0B 03 00 E4 00 01 C5 BD", "B5 00 01 0B 03 00 E4 00 01 C5 01 BD", Write("flag", 228, (1,))),
    ("V4", "B5 00 01 02 04 00 C8 48 6E", None, Read("flag", 200, 5)),
    ("V5", "B5 00 01 02 22 00 C8 7C 08", None, Read("flag", 200, 35)),
    ("V6", "B5 00 01 06 00 00 D5 9D C3", None, Read("register", 213, 1)),
    ("V7", "B5 00 01 06 06 00 D5 2F 63", None, Read("register", 213, 7)),
    ("V8", "B5 00 01 0E 05 00 D4 00 00 04 1B 22 0C", None, Write("register", 212, (0x41B,))),
    ("V9", "B5 00 01 06 00 00 D4 8D E2", None, Read("register", 212, 1)),
    ("V10", "B5 00 01 0E 05 00 CD C8 00 00 47 EF F0", None, Write("register", 205, (0xC8000047 - (1 << 32),))),
    ("V11", "B5 00 01 0E 15 00 C8 00 00 00 96 00 00 00 32 00 00 00 32 00 00 01 F4 00 00 00 0F F9 49", None,
     Write("register", 200, (150, 50, 50, 500, 15))),
    ("V12", "B5 00 01 06 00 00 DB 7C 0D", None, Read("register", 219, 1)),
    ("V13", "B5 00 01 03 0F 00 30 A0 3C", None, Read("input", 48, 16)),
    ("V14", "B5 00 01 1B DD FF", None, Simple("read status")),
    ("V15", "B5 00 01 1D BD 39", None, Simple("read station")),
    ("V16", "B5 00 01 38 C9 FE", None, Simple("restart cold")),
    ("V18", "B5 00 01 0E 05 00 B5 00 00 00 C5 77 F6", "B5 00 01 0E 05 00 C5 00 00 00 00 C5 01 77 F6",
     Write("register", 181, (197,))),
    ("V19", "B5 00 01 06 00 00 1A B5 60", "B5 00 01 06 00 00 1A C5 00 60", Read("register", 26, 1)),
    ("V20", "B5 00 01 0E 05 07 D7 00 00 03 E8 42 74", None, Write("register", 2007, (1000,))),
    ("V21", "B5 00 01 0B 03 07 D7 00 01 08 65", None, Write("flag", 2007, (1,))),
]


def test_crc_check_value() -> None:
    assert crc16(b"123456789") == 0x31C3


@pytest.mark.parametrize(("vector", "raw", "wire", "decoded"), REQUESTS, ids=[r[0] for r in REQUESTS])
def test_request_vectors(vector: str, raw: str, wire: str | None, decoded: object) -> None:
    telegram = h(raw)
    assert crc16(telegram[:-2]) == int.from_bytes(telegram[-2:], "big")  # the vector's CRC
    on_wire = stuff(telegram)
    assert on_wire == h(wire or raw)
    assert unstuff(on_wire) == telegram
    for size in (1, 3, len(on_wire)):
        receiver = SerialReceiver(1, telegram_of)
        requests = [r for start in range(0, len(on_wire), size) for r in receiver.feed(on_wire[start : start + size])]
        assert len(requests) == 1 and decode_command(requests[0], telegram_of) == decoded


@pytest.mark.parametrize(("data", "wire"), [
    (h("01"), "B5 01 01 36 1F"),  # V4 (OnDest), V15 (station 1)
    (h("00 00 03 E8"), "B5 01 00 00 03 E8 3B 89"),  # V6
    (h("00 00 04 1B"), "B5 01 00 00 04 1B 7D 62"),  # V9
    (h("00 00 40 84"), "B5 01 00 00 40 84 CE 3C"),  # V12
    (h("00 66"), "B5 01 00 66 76 C4"),  # V13
    (b"R", "B5 01 52 5C 89"), (b"H", "B5 01 48 EF F2"),  # V14
    (h("01 00 00 00 00"), "B5 01 01 00 00 00 00 64 22"),  # V5
])
def test_reply_vectors(data: bytes, wire: str) -> None:
    assert serial_reply(data) == h(wire)


def test_ack_nak_vectors() -> None:
    assert serial_ack(0) == h("B5 02 00 00 23 F4")
    assert serial_ack(1) == h("B5 02 00 01 33 D5")  # V17


def test_flags_pack_bit_0_first() -> None:
    assert pack_bits([1, 0, 0, 0, 0]) == b"\x01"
    assert pack_bits([0] * 9 + [1]) == b"\x00\x02"


def test_other_stations_crc_and_framing_errors_are_dropped() -> None:
    receiver = SerialReceiver(2, telegram_of)
    assert receiver.feed(h("B5 00 01 1B DD FF")) == []  # station 1
    receiver = SerialReceiver(1, telegram_of)
    assert receiver.feed(h("B5 00 01 1B DD FE")) == [] and receiver.errors["crc"] == 1
    assert receiver.feed(h("B5 00 01 0E 05 00 C5 07")) == [] and receiver.errors["framing"] == 1
    assert receiver.feed(h("B5 00 01 06 B5 00 01 1B DD FF")) == [Request(1, 0x1B, b"")]  # B5 resynchronises
    assert receiver.feed(h("B5 00 FF 1B")) == []  # broadcast: in progress
    broadcast = bytes.fromhex("B5 00 FF 38")
    broadcast += crc16(broadcast).to_bytes(2, "big")
    assert SerialReceiver(1, telegram_of).feed(stuff(broadcast)) == [Request(255, 0x38, b"")]


def test_unsupported_commands_and_counts_are_bad() -> None:
    telegram = h("B5 00 01 55")
    telegram += crc16(telegram).to_bytes(2, "big")
    (request,) = SerialReceiver(1, telegram_of).feed(stuff(telegram))
    assert isinstance(decode_command(request, telegram_of), Bad)
    assert isinstance(decode_command(Request(1, 0x06, h("20 00 00")), telegram_of), Bad)  # 33 registers
    for command, parameters in ((0x0E, h("00 00")), (0x0B, h("00 00 01")), (0x06, h("00")), (0x0E, h("02 00 00 00 00"))):
        assert isinstance(decode_command(Request(1, command, parameters), telegram_of), Bad)


@settings(max_examples=500, deadline=None)
@given(hs.sampled_from([0x00, 0x02, 0x03, 0x05, 0x06, 0x07, 0x0B, 0x0D, 0x0E, 0x1B, 0x55]), hs.binary(max_size=40))
def test_any_parameters_decode_or_are_bad(command: int, parameters: bytes) -> None:
    assert isinstance(decode_command(Request(1, command, parameters), telegram_of), Read | Write | Simple | Bad)


ETHER = [
    ("EV1", "00 00 00 14 01 00 00 01 00 01 0E 05 00 CF 00 00 03 E8 05 B1", Write("register", 207, (1000,))),
    ("EV2", "00 00 00 12 01 00 00 01 00 01 0B 03 00 CF 00 01 FB D2", Write("flag", 207, (1,))),
    ("EV3", "00 00 00 12 01 00 00 01 00 01 0B 03 00 E4 00 01 8D E5", Write("flag", 228, (1,))),
    ("EV4", "00 00 00 10 01 00 00 01 00 01 02 04 00 C8 41 A4", Read("flag", 200, 5)),
    ("EV6", "00 00 00 10 01 00 00 01 00 01 06 00 00 D5 94 09", Read("register", 213, 1)),
    ("EV14", "00 00 00 0D 01 00 00 01 00 01 1B 08 DA", Simple("read status")),
]


@pytest.mark.parametrize(("vector", "frame", "decoded"), ETHER, ids=[e[0] for e in ETHER])
def test_ether_vectors(vector: str, frame: str, decoded: object) -> None:
    parsed = parse_ether(h(frame))
    assert parsed is not None
    version, sequence, request = parsed
    assert (version, sequence, request.station) == (1, 1, 1) and decode_command(request, telegram_of) == decoded
    receiver = EtherReceiver()
    assert [f for b in h(frame) for f in receiver.feed(bytes((b,)))] == [h(frame)]


def test_ether_reply_vectors() -> None:
    assert ether_ack(1, 1) == h("00 00 00 0D 01 00 00 01 02 00 00 F6 D1")
    assert ether_ack(1, 1, 1) == h("00 00 00 0D 01 00 00 01 02 00 01 E6 F0")
    assert ether_reply(1, 1, b"\x01") == h("00 00 00 0C 01 00 00 01 01 01 03 EB")
    assert ether_reply(1, 1, h("00 00 03 E8")) == h("00 00 00 0F 01 00 00 01 01 00 00 03 E8 7B 16")
    assert ether_reply(1, 1, b"R") == h("00 00 00 0C 01 00 00 01 01 52 69 7D")


#: The vectors' telegrams on the wire, to be mixed into garbage.
WIRES = [h(wire or raw) for _v, raw, wire, _d in REQUESTS]


@settings(max_examples=500, deadline=None)
@given(hs.lists(hs.one_of(hs.binary(max_size=30), hs.sampled_from(WIRES)), max_size=8),
       hs.integers(min_value=1, max_value=40), hs.lists(hs.sampled_from([h(f) for _v, f, _d in ETHER]), max_size=4))
def test_any_bytes_in_any_chunks_never_raise(pieces: list[bytes], size: int, ether_frames: list[bytes]) -> None:
    """Garbage and telegrams, split anywhere: the same requests as in one piece (§9.2: framing
    by FS, length and CRC, not by chunk), each for this station (or the broadcast one) and
    decoded; a telegram followed by no FS before its end is received (FS starts one afresh);
    Ether-S-Bus frames back to back come out one by one, however the writes cut them (§9.3)."""
    data = b"".join(pieces)
    whole = SerialReceiver(1, telegram_of).feed(data)
    receiver = SerialReceiver(1, telegram_of)
    requests = []
    for start in range(0, len(data), size):
        requests += receiver.feed(data[start : start + size])
    assert requests == whole
    for request in requests:
        assert request.station in (1, 255)
        assert isinstance(decode_command(request, telegram_of), Read | Write | Simple | Bad)
    if pieces and pieces[-1] in WIRES:  # the last telegram: nothing after it can cut it
        assert requests and requests[-1] == SerialReceiver(1, telegram_of).feed(pieces[-1])[0]
    ether = EtherReceiver()
    stream = b"".join(ether_frames)
    frames = [frame for start in range(0, len(stream), size) for frame in ether.feed(stream[start : start + size])]
    assert frames == ether_frames
    noise = EtherReceiver()
    for frame in [f for start in range(0, len(data), size) for f in noise.feed(data[start : start + size])]:
        assert len(frame) == int.from_bytes(frame[:4], "big") and 13 <= len(frame) <= 4096
        parsed = parse_ether(frame)
        if parsed is not None:
            assert isinstance(decode_command(parsed[2], telegram_of), Read | Write | Simple | Bad)
