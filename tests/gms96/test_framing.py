"""The GMS96 port's framing (devsim.devices.gms96.framing), what record, replay, the telegram tap
and the plot cut and describe FT1.2 frames with (spec §3.2, §3.3, §3.5, §3.6).

Frames are generated from their fields (Langsätze of L = 2 up to the letters of 0 to 3
parameters, Kurzsätze with 0 to 2 AE octets, E5h), and what the framing says of them is compared
with an oracle written from those fields, not from the codec: the description, the label, the
message cut, and the replay tolerances' keys (the CS octet, the FCB bit 20h of C)."""

from __future__ import annotations

from typing import Any

import hypothesis.strategies as hs
import pytest
from hypothesis import example, given

from devsim.devices.gms96 import codec as ft12
from devsim.devices.gms96.device import Gms96Device
from devsim.devices.gms96.framing import FT12

S24 = hs.integers(min_value=-(2**23), max_value=2**23 - 1)
OCTET = hs.integers(min_value=0, max_value=255)
LETTERS = hs.sampled_from("AMQTHRab")  # "a", the PLC download, may have any length
TOLERANCES = {t.name: t for t in FT12.tolerances}


def _long(control: int, address: int, data: bytes) -> bytes:
    body = bytes((control, address)) + data
    return bytes((0x68, len(body), len(body), 0x68)) + body + bytes((sum(body) & 0xFF, 0x16))


def _short(control: int, address: int, extension: bytes = b"") -> bytes:
    body = bytes((control, address)) + extension
    return bytes((0x10,)) + body + bytes((sum(body) & 0xFF, 0x16))


@hs.composite
def letters(draw: hs.DrawFn) -> tuple[bytes, dict[str, Any]]:
    """A host's letter Langsatz (M §2.3) and its description, from the fields."""
    fcb = draw(hs.integers(0, 1))
    control, address = 0x53 | (0x20 * fcb), draw(OCTET)
    command = draw(LETTERS)
    params = draw(hs.lists(S24, max_size=3))
    data = command.encode() + b"".join((p & 0xFFFFFF).to_bytes(3, "little") for p in params)
    described = {"frame": "long", "C": f"{control:02X}", "A": address, "data": data.hex(" "),
                 "letter": command, "params": params, "fcb": fcb}
    return _long(control, address, data), described


@hs.composite
def short_commands(draw: hs.DrawFn) -> tuple[bytes, dict[str, Any]]:
    """A host's Kurzsatz #0, #1, #8 (2 AE octets), #9 (1 AE octet) (spec §3.6)."""
    number = draw(hs.sampled_from([0, 1, 8, 9]))
    extension = draw(hs.binary(min_size={8: 2, 9: 1}.get(number, 0), max_size={8: 2, 9: 1}.get(number, 0)))
    control = number | (ft12.AE_FLAG if extension else 0) | draw(hs.sampled_from([0, 0x40, 0x70]))
    address = draw(OCTET)
    described: dict[str, Any] = {"frame": "short", "C": f"{control:02X}", "A": address}
    if extension:
        described["AE"] = extension.hex(" ")
    described["command"] = f"#{number}"
    return _short(control, address, extension), described


HOST_FRAMES = hs.one_of(letters(), short_commands())


def _describe(direction: str, *chunks: bytes) -> list[Any]:
    describer = FT12.decoder(direction)
    out: list[Any] = []
    for chunk in chunks:
        got = describer.feed(chunk)
        assert got is not None
        out += got
    return out


def test_the_port_declares_the_ft12_framing() -> None:
    assert Gms96Device.ports[0].framing is FT12
    assert [t.name for t in FT12.tolerances] == ["checksum", "fcb"]
    assert all(t.adapt is None for t in FT12.tolerances)  # the recorded answer is sent as recorded
    assert FT12.decoder("host").direction == "host" and FT12.decoder("device").direction == "device"


@pytest.mark.manual("§2.3", "commands go in the Langsatz as <address><command>[P1[P2[P3]]]")
@given(hs.lists(HOST_FRAMES, min_size=1, max_size=4), hs.integers(min_value=0, max_value=60))
def test_host_frames_are_described_field_by_field_however_cut(frames: list[tuple[bytes, dict[str, Any]]],
                                                               cut: int) -> None:
    stream = b"".join(raw for raw, _ in frames)
    assert _describe("host", stream[:cut], stream[cut:]) == [described for _, described in frames]


def test_descriptions_and_labels_of_both_directions() -> None:
    t_reply = ft12.encode(ft12.t_reply(3, 0x49, b"\x01\x02\x03"))  # reads like a letter I
    k_with_mb4 = ft12.encode(ft12.k_frame(0x20, 3, 0x81))
    described = _describe("device", b"\xe5", t_reply, k_with_mb4, ft12.encode(ft12.k_frame(0x20, 3, None)))
    assert described == [
        {"frame": "single", "value": "E5"},
        {"frame": "long", "C": "08", "A": 3, "data": "49 01 02 03"},  # no letter: the card's answer
        {"frame": "short", "C": "22", "A": 3, "AE": "81"},  # no command: the card's K
        {"frame": "short", "C": "20", "A": 3},
    ]
    assert [FT12.label(d) for d in described] == ["E5", "C=08 49 01 02 03", "C=22", "C=20"]
    assert _describe("host", b"\xe5") == [{"error": "garbage", "hex": "e5"}]  # the card takes no E5h
    host = _describe("host", _long(0x73, 3, b"M" + (20000).to_bytes(3, "little")), _short(0x41, 3),
                     _long(0x53, 3, b"A\x01"), _long(0x53, 3, b"A" + b"\xff" * 3) + b"\x16\x16")
    assert host[0]["letter"] == "M" and host[0]["fcb"] == 1
    assert [FT12.label(d) for d in host] == ["M 20000", "#1", "C=53 41 01", "A -1", "bad frame: garbage"]
    assert "letter" not in host[2]  # a parameter of one octet is no letter (spec §3.5)


@given(hs.lists(HOST_FRAMES, max_size=4), hs.binary(max_size=12))
@example([], b"\x10\x53\x03")
@example([], b"\x68\x02\x02\x68\x53")
def test_split_gives_the_whole_frames_and_keeps_the_unfinished_one(frames: list[tuple[bytes, dict[str, Any]]],
                                                                   tail: bytes) -> None:
    assert FT12.split is not None
    whole = [raw for raw, _ in frames]
    nxt = _long(0x53, 1, b"A" + tail)
    for size in range(len(nxt)):  # every prefix of a frame that is still arriving
        assert FT12.split(b"".join(whole) + nxt[:size]) == (whole, nxt[:size])
    assert FT12.split(b"".join(whole) + nxt) == ([*whole, nxt], b"")


@given(hs.binary(max_size=40))
@example(b"\x55\x55" + bytes.fromhex("10 5b 03 5e 16"))
@example(bytes.fromhex("68 02 02 68 53 03 57 16 e5"))
def test_split_accounts_for_every_byte(buffer: bytes) -> None:
    """Garbage and broken frames are messages too (so that replay reports them), whole."""
    assert FT12.split is not None
    messages, rest = FT12.split(buffer)
    assert b"".join(messages) + rest == buffer
    assert all(messages)


def _key_oracle(message: bytes, clear_fcb: bool) -> bytes:
    """Spec §3.2: Kurzsatz 10 C A [AE] CS 16 (5 octets at least), Langsatz 68 L L 68 C A data CS
    16 (8 at least); the key has CS 0 and, for ``fcb``, bit 20h of C cleared."""
    if len(message) >= 5 and message[0] == 0x10 and message[-1] == 0x16:
        c = 1
    elif len(message) >= 8 and message[0] == message[3] == 0x68 and message[-1] == 0x16:
        c = 4
    else:
        return message
    out = bytearray(message)
    out[-2] = 0
    if clear_fcb:
        out[c] &= 0xDF
    return bytes(out)


FRAMELIKE = hs.one_of(
    HOST_FRAMES.map(lambda f: f[0]),
    hs.binary(min_size=3, max_size=10).map(lambda b: b"\x10" + b + b"\x16"),
    hs.binary(min_size=2, max_size=8).map(lambda b: b"\x68" + b[:2] + b"\x68" + b[2:] + b"\x16"),
    hs.binary(max_size=10),
)


@given(FRAMELIKE)
@example(bytes.fromhex("10 73 03 76 16"))  # the shortest Kurzsatz
@example(bytes.fromhex("10 73 76 16"))  # one octet short: not a frame
@example(bytes.fromhex("68 02 02 68 73 03 76 16"))  # the shortest Langsatz (L = 2)
@example(bytes.fromhex("68 01 01 68 73 76 16"))  # one octet short
@example(bytes.fromhex("68 02 02 69 73 03 76 16"))  # no second 68h
@example(bytes.fromhex("68 02 02 68 73 03 76 17"))  # no 16h at the end
@example(bytes.fromhex("10 73 03 76 17"))
@example(bytes.fromhex("69 02 02 68 73 03 76 16"))
def test_the_replay_tolerances_ignore_the_checksum_and_the_fcb(message: bytes) -> None:
    assert TOLERANCES["checksum"].key(message) == _key_oracle(message, clear_fcb=False)
    assert TOLERANCES["fcb"].key(message) == _key_oracle(message, clear_fcb=True)


@pytest.mark.parametrize("broken, reason", [
    (bytes.fromhex("10 53 03 00 16"), "checksum"),
    (bytes.fromhex("68 01 01 68 53"), "length"),
    (bytes.fromhex("68 03 02 68 53 03 00 16"), "length_mismatch"),
])
def test_a_broken_frame_is_described_by_its_reason_and_bytes(broken: bytes, reason: str) -> None:
    [described] = _describe("host", broken)[:1]
    assert described["error"] == reason and bytes.fromhex(described["hex"]).startswith(broken[:2])
    assert FT12.label(described) == f"bad frame: {reason}"
