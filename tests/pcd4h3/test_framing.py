"""The PCD4.H3's Ether-S-Bus framing on TCP (devsim.devices.pcd4h3.framing), what record, replay
and the telegram tap cut and describe its telegrams with (spec §9.3): back to back, each
delimited by its length field (13 … 4096 bytes), a 9-byte header (length, version, type,
sequence, attribute), the payload and a CRC-16 over everything before it.

Telegrams are built here from their fields, and what the framing says of them is compared with
those fields: the description, the cut, and the replay tolerance ``sequence`` (another sequence
number is the same request; the recorded answer gets the host's, and its CRC anew)."""

from __future__ import annotations

import struct
from typing import Any

import hypothesis.strategies as hs
import pytest
from hypothesis import example, given

from devsim.devices.pcd4h3 import sbus
from devsim.devices.pcd4h3.device import Pcd4h3Device
from devsim.devices.pcd4h3.framing import ETHER_TCP

ATTRIBUTES = {0: "request", 1: "response", 2: "ack/nak"}
[SEQUENCE] = ETHER_TCP.tolerances


def _frame(sequence: int, attribute: int, payload: bytes, version: int = 1, good_crc: bool = True) -> bytes:
    """An Ether-S-Bus telegram from its fields (spec §9.3)."""
    body = struct.pack(">IBBHB", 9 + len(payload) + 2, version, 0, sequence, attribute) + payload
    crc = sbus.crc16(body) ^ (0 if good_crc else 0x0101)
    return body + struct.pack(">H", crc)


@hs.composite
def telegrams(draw: hs.DrawFn) -> tuple[bytes, dict[str, Any]]:
    sequence = draw(hs.integers(0, 0xFFFF))
    attribute = draw(hs.sampled_from([0, 1, 2, 3, 0xFF]))
    payload = draw(hs.binary(min_size=2, max_size=24))
    good = draw(hs.booleans())
    described: dict[str, Any] = {"sequence": sequence, "attribute": ATTRIBUTES.get(attribute, attribute),
                                 "payload": payload.hex(" ")}
    if attribute == 0:
        described.update(station=payload[0], command=f"{payload[1]:02X}")
    described["crc_ok"] = good
    return _frame(sequence, attribute, payload, good_crc=good), described


def _describe(direction: str, *chunks: bytes) -> list[Any]:
    describer = ETHER_TCP.decoder(direction)
    out: list[Any] = []
    for chunk in chunks:
        got = describer.feed(chunk)
        assert got is not None
        out += got
    return out


def test_the_tcp_port_declares_the_ether_framing() -> None:
    [port] = [p for p in Pcd4h3Device.ports if p.name == "ether_tcp"]
    assert port.framing is ETHER_TCP and ETHER_TCP.label is None and SEQUENCE.name == "sequence"
    assert ETHER_TCP.decoder("device").direction == "device"


@given(hs.lists(telegrams(), min_size=1, max_size=4), hs.integers(min_value=0, max_value=120),
       hs.sampled_from(["host", "device"]))
def test_telegrams_are_described_field_by_field_however_cut(frames: list[tuple[bytes, dict[str, Any]]], cut: int,
                                                             direction: str) -> None:
    stream = b"".join(raw for raw, _ in frames)
    assert _describe(direction, stream[:cut], stream[cut:]) == [described for _, described in frames]


def test_descriptions_at_the_limits() -> None:
    shortest = _frame(0xFFFF, 0, b"\x01\x1b")  # 13 bytes: station 1, read PCD status, no parameters
    assert _describe("host", shortest) == [{"sequence": 0xFFFF, "attribute": "request", "payload": "01 1b",
                                            "station": 1, "command": "1B", "crc_ok": True}]
    assert _describe("device", _frame(0x8000, 2, b"\x00\x00")) == [
        {"sequence": 0x8000, "attribute": "ack/nak", "payload": "00 00", "crc_ok": True}]  # no station
    assert _describe("host", _frame(1, 7, b"\x01\x06", good_crc=False))[0]["attribute"] == 7
    ev14 = bytes.fromhex("00 00 00 0C 01 00 00 01 01 52 69 7D")  # 12 bytes: the station's 'R' (spec §9.4 EV14)
    assert _describe("device", ev14, _frame(2, 1, b"\x00")) == [
        {"sequence": 1, "attribute": "response", "payload": "52", "crc_ok": True},
        {"sequence": 2, "attribute": "response", "payload": "00", "crc_ok": True}]  # and what follows it


@given(hs.lists(telegrams().map(lambda t: t[0]), max_size=3), hs.binary(min_size=2, max_size=20))
def test_split_gives_the_whole_telegrams_and_keeps_the_unfinished_one(frames: list[bytes], payload: bytes) -> None:
    assert ETHER_TCP.split is not None
    nxt = _frame(5, 0, payload)
    for size in range(len(nxt)):  # every prefix of a telegram still arriving
        assert ETHER_TCP.split(b"".join(frames) + nxt[:size]) == (frames, nxt[:size])
    assert ETHER_TCP.split(b"".join(frames) + nxt) == ([*frames, nxt], b"")


@pytest.mark.parametrize("length", [0, 11, 4097, 0xFFFFFFFF])
def test_a_length_outside_12_to_4096_is_one_message_with_what_follows(length: int) -> None:
    assert ETHER_TCP.split is not None
    good = _frame(1, 0, b"\x01\x1b")
    bad = struct.pack(">I", length) + b"\x01\x00\x00"
    assert ETHER_TCP.split(good + bad) == ([good, bad], b"")
    assert ETHER_TCP.split(bad[:4]) == ([bad[:4]], b"")  # four bytes tell it already
    assert ETHER_TCP.split(bad[:3]) == ([], bad[:3])  # three do not


@pytest.mark.parametrize("length", [12, 13, 4096])
def test_a_length_of_12_or_4096_is_a_telegram_still_arriving(length: int) -> None:
    assert ETHER_TCP.split is not None
    start = struct.pack(">I", length) + b"\x01\x00"
    assert ETHER_TCP.split(start) == ([], start)


@given(telegrams().map(lambda t: t[0]), hs.integers(0, 0xFFFF))
def test_another_sequence_number_is_the_same_request(frame: bytes, sequence: int) -> None:
    other = frame[:6] + sequence.to_bytes(2, "big") + frame[8:-2]
    other += sbus.crc16(other).to_bytes(2, "big")
    assert SEQUENCE.key(other) == SEQUENCE.key(frame) == frame[:6] + b"\0\0" + frame[8:-2] + b"\0\0"
    changed = frame[:9] + bytes([frame[9] ^ 1]) + frame[10:]
    assert SEQUENCE.key(changed) != SEQUENCE.key(frame)


@pytest.mark.parametrize("message", [
    b"", b"\x00\x00\x00\x0d", _frame(1, 0, b"\x01")[:-1],  # 11 bytes saying 12
    _frame(1, 0, b"\x01\x1b") + b"\x00",  # one byte more than the length says
    _frame(1, 0, b"")])  # 11 bytes, saying so: shorter than any telegram
def test_what_is_no_telegram_is_its_own_key(message: bytes) -> None:
    assert SEQUENCE.key(message) == message
    assert SEQUENCE.adapt is not None and SEQUENCE.adapt(message, b"recorded") == b"recorded"


@given(hs.integers(0, 0xFFFF), hs.lists(telegrams().map(lambda t: t[0]), max_size=3), hs.binary(max_size=3))
@example(0x1234, [_frame(0x0001, 1, b"\x52\x00")], b"")
def test_the_recorded_answer_gets_the_hosts_sequence_and_a_new_crc(sequence: int, answers: list[bytes],
                                                                    rest: bytes) -> None:
    assert SEQUENCE.adapt is not None
    request = _frame(sequence, 0, b"\x01\x1b")
    adapted = SEQUENCE.adapt(request, b"".join(answers) + rest)
    expected = b""
    for answer in answers:
        expected += _frame(sequence, answer[8], answer[9:-2], version=answer[4])
    assert adapted == expected + rest
    assert all(d["crc_ok"] and d["sequence"] == sequence for d in _describe("device", adapted))
