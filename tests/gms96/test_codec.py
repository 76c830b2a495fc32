"""GMS96 link codec: the computed test vectors of spec §3.11, the §6.1 session, framing errors,
timeouts, resynchronisation, and property-based fuzzing."""

from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from devsim.devices.gms96.codec import (
    ACK,
    FrameDecoder,
    FrameError,
    LongFrame,
    ShortFrame,
    SingleChar,
    checksum,
    control_host,
    encode,
    from_s24,
    k_frame,
    letter,
    parse_letter,
    short_command,
    short_command_number,
    short_extension_device,
    short_extension_host,
    t_reply,
    to_s24,
)


def h(text: str) -> bytes:
    return bytes.fromhex(text)


def device_decoder(**kw: object) -> FrameDecoder:
    return FrameDecoder(short_extension=short_extension_device, **kw)  # type: ignore[arg-type]


def host_decoder(**kw: object) -> FrameDecoder:
    return FrameDecoder(short_extension=short_extension_host, accept_single=True, **kw)  # type: ignore[arg-type]


def frames_of(items: list) -> list:
    return [x for x in items if not isinstance(x, FrameError)]


def errors_of(items: list) -> list[FrameError]:
    return [x for x in items if isinstance(x, FrameError)]


# -- spec §3.11: letter commands (host → card) --------------------------------------------------
# (name, command, params, address, FCB, wire bytes); every one is answered with E5h.
LETTER_VECTORS = [
    ("A10000", "A", (10000,), 3, 0, "68 06 06 68 53 03 41 10 27 00 CE 16"),
    ("A10000 FCB=1", "A", (10000,), 3, 1, "68 06 06 68 73 03 41 10 27 00 EE 16"),
    ("A-10000", "A", (-10000,), 3, 0, "68 06 06 68 53 03 41 F0 D8 FF 5E 16"),
    ("A8388607 (max)", "A", (8388607,), 3, 0, "68 06 06 68 53 03 41 FF FF 7F 14 16"),
    ("A-8388352 (min)", "A", (-8388352,), 3, 0, "68 06 06 68 53 03 41 00 01 80 18 16"),
    ("A0 to address 0", "A", (0,), 0, 0, "68 06 06 68 53 00 41 00 00 00 94 16"),
    ("A0 to address 17", "A", (0,), 17, 0, "68 06 06 68 53 11 41 00 00 00 A5 16"),
    ("+1000 FCB=1", "+", (1000,), 3, 1, "68 06 06 68 73 03 2B E8 03 00 8C 16"),
    ("+-500", "+", (-500,), 3, 0, "68 06 06 68 53 03 2B 0C FE FF 8A 16"),
    ("B100", "B", (100,), 3, 0, "68 06 06 68 53 03 42 64 00 00 FC 16"),
    ("M50000", "M", (50000,), 3, 0, "68 06 06 68 53 03 4D 50 C3 00 B6 16"),
    ("M2000000", "M", (2000000,), 3, 0, "68 06 06 68 53 03 4D 80 84 1E C5 16"),
    ("f12000", "f", (12000,), 3, 0, "68 06 06 68 53 03 66 E0 2E 00 CA 16"),
    ("f1000;128", "f", (1000, 128), 3, 0, "68 09 09 68 53 03 66 E8 03 00 80 00 00 27 16"),
    ("S200", "S", (200,), 3, 0, "68 06 06 68 53 03 53 C8 00 00 71 16"),
    ("G0", "G", (0,), 3, 0, "68 06 06 68 53 03 47 00 00 00 9D 16"),
    ("G90", "G", (90,), 3, 0, "68 06 06 68 53 03 47 5A 00 00 F7 16"),
    ("G91", "G", (91,), 3, 0, "68 06 06 68 53 03 47 5B 00 00 F8 16"),
    ("G94", "G", (94,), 3, 0, "68 06 06 68 53 03 47 5E 00 00 FB 16"),
    ("G95", "G", (95,), 3, 0, "68 06 06 68 53 03 47 5F 00 00 FC 16"),
    ("G53;1", "G", (53, 1), 3, 0, "68 09 09 68 53 03 47 35 00 00 01 00 00 D3 16"),
    ("G54", "G", (54,), 3, 0, "68 06 06 68 53 03 47 36 00 00 D3 16"),
    ("G54;1", "G", (54, 1), 3, 0, "68 09 09 68 53 03 47 36 00 00 01 00 00 D4 16"),
    ("G54;5000;1", "G", (54, 5000, 1), 3, 0, "68 0C 0C 68 53 03 47 36 00 00 88 13 00 01 00 00 6F 16"),
    ("G0x000336", "G", (0x000336,), 3, 0, "68 06 06 68 53 03 47 36 03 00 D6 16"),
    ("H2", "H", (2,), 3, 0, "68 06 06 68 53 03 48 02 00 00 A0 16"),
    ("H7;50", "H", (7, 50), 3, 0, "68 09 09 68 53 03 48 07 00 00 32 00 00 D7 16"),
    ("H22;1", "H", (22, 1), 3, 0, "68 09 09 68 53 03 48 16 00 00 01 00 00 B5 16"),
    ("M1", "M", (1,), 3, 0, "68 06 06 68 53 03 4D 01 00 00 A4 16"),
    ("O0", "O", (0,), 3, 0, "68 06 06 68 53 03 4F 00 00 00 A5 16"),
    ("o0", "o", (0,), 3, 0, "68 06 06 68 53 03 6F 00 00 00 C5 16"),
    ("o1", "o", (1,), 3, 0, "68 06 06 68 53 03 6F 01 00 00 C6 16"),
    ("o2;80", "o", (2, 80), 3, 0, "68 09 09 68 53 03 6F 02 00 00 50 00 00 17 16"),
    ("Q0", "Q", (0,), 3, 0, "68 06 06 68 53 03 51 00 00 00 A7 16"),
    ("Q3", "Q", (3,), 3, 0, "68 06 06 68 53 03 51 03 00 00 AA 16"),
    ("Q3;64", "Q", (3, 64), 3, 0, "68 09 09 68 53 03 51 03 00 00 40 00 00 EA 16"),
    ("Q-1", "Q", (-1,), 3, 0, "68 06 06 68 53 03 51 FF FF FF A4 16"),
    ("Q0;2;100000", "Q", (0, 2, 100000), 3, 0, "68 0C 0C 68 53 03 51 00 00 00 02 00 00 A0 86 01 D0 16"),
    ("Q6;0x81;50000", "Q", (6, 0x81, 50000), 3, 0, "68 0C 0C 68 53 03 51 06 00 00 81 00 00 50 C3 00 41 16"),
    ("Q8;3;20000", "Q", (8, 3, 20000), 3, 0, "68 0C 0C 68 53 03 51 08 00 00 03 00 00 20 4E 00 20 16"),
    ("s85;170", "s", (85, 170), 3, 0, "68 09 09 68 53 03 73 55 00 00 AA 00 00 C8 16"),
    ("r0;0;0", "r", (0, 0, 0), 3, 0, "68 0C 0C 68 53 03 72 00 00 00 00 00 00 00 00 00 C8 16"),
    ("r0;0;1", "r", (0, 0, 1), 3, 0, "68 0C 0C 68 53 03 72 00 00 00 00 00 00 01 00 00 C9 16"),
    ("N300;10", "N", (300, 10), 3, 0, "68 09 09 68 53 03 4E 2C 01 00 0A 00 00 DB 16"),
    ("N2000;20", "N", (2000, 20), 3, 0, "68 09 09 68 53 03 4E D0 07 00 14 00 00 8F 16"),
    ("N5;27", "N", (5, 27), 3, 0, "68 09 09 68 53 03 4E 05 00 00 1B 00 00 C4 16"),
    ("N-5;27", "N", (-5, 27), 3, 0, "68 09 09 68 53 03 4E FB FF FF 1B 00 00 B8 16"),
    ("N20;28", "N", (20, 28), 3, 0, "68 09 09 68 53 03 4E 14 00 00 1C 00 00 D4 16"),
    ("N-100;8;0", "N", (-100, 8, 0), 3, 0, "68 0C 0C 68 53 03 4E 9C FF FF 08 00 00 00 00 00 46 16"),
    ("N0x0301;19", "N", (0x0301, 19), 3, 0, "68 09 09 68 53 03 4E 01 03 00 13 00 00 BB 16"),
    ("N1;17", "N", (1, 17), 3, 0, "68 09 09 68 53 03 4E 01 00 00 11 00 00 B6 16"),
    ("N1;51", "N", (1, 51), 3, 0, "68 09 09 68 53 03 4E 01 00 00 33 00 00 D8 16"),
    ("c-1;2", "c", (-1, 2), 3, 0, "68 09 09 68 53 03 63 FF FF FF 02 00 00 B8 16"),
    ("c123456;2", "c", (123456, 2), 3, 0, "68 09 09 68 53 03 63 40 E2 01 02 00 00 DE 16"),
    ("d0x1234;10", "d", (0x1234, 10), 3, 0, "68 09 09 68 53 03 64 34 12 00 0A 00 00 0A 16"),
    ("m50;7", "m", (50, 7), 3, 0, "68 09 09 68 53 03 6D 32 00 00 07 00 00 FC 16"),
    ("m100;1;1500", "m", (100, 1, 1500), 3, 0, "68 0C 0C 68 53 03 6D 64 00 00 01 00 00 DC 05 00 09 16"),
    ("m101;5;2", "m", (101, 5, 2), 3, 0, "68 0C 0C 68 53 03 6D 65 00 00 05 00 00 02 00 00 2F 16"),
    ("p1;1;0", "p", (1, 1, 0), 3, 0, "68 0C 0C 68 53 03 70 01 00 00 01 00 00 00 00 00 C8 16"),
    ("p1;2;0", "p", (1, 2, 0), 3, 0, "68 0C 0C 68 53 03 70 01 00 00 02 00 00 00 00 00 C9 16"),
    ("p3;100;5", "p", (3, 100, 5), 3, 0, "68 0C 0C 68 53 03 70 03 00 00 64 00 00 05 00 00 32 16"),
    ("p3;101;0", "p", (3, 101, 0), 3, 0, "68 0C 0C 68 53 03 70 03 00 00 65 00 00 00 00 00 2E 16"),
    ("p3;1;5", "p", (3, 1, 5), 3, 0, "68 0C 0C 68 53 03 70 03 00 00 01 00 00 05 00 00 CF 16"),
    ("p10;16;3", "p", (10, 16, 3), 3, 0, "68 0C 0C 68 53 03 70 0A 00 00 10 00 00 03 00 00 E3 16"),
    ("p10;17;3", "p", (10, 17, 3), 3, 0, "68 0C 0C 68 53 03 70 0A 00 00 11 00 00 03 00 00 E4 16"),
    ("p10;2;1", "p", (10, 2, 1), 3, 0, "68 0C 0C 68 53 03 70 0A 00 00 02 00 00 01 00 00 D3 16"),
    ("p10;14;20", "p", (10, 14, 20), 3, 0, "68 0C 0C 68 53 03 70 0A 00 00 0E 00 00 14 00 00 F2 16"),
    ("p10;26;0", "p", (10, 26, 0), 3, 0, "68 0C 0C 68 53 03 70 0A 00 00 1A 00 00 00 00 00 EA 16"),
    ("p10;29;42", "p", (10, 29, 42), 3, 0, "68 0C 0C 68 53 03 70 0A 00 00 1D 00 00 2A 00 00 17 16"),
    ("p10;31;0", "p", (10, 31, 0), 3, 0, "68 0C 0C 68 53 03 70 0A 00 00 1F 00 00 00 00 00 EF 16"),
    ("p11;13;1", "p", (11, 13, 1), 3, 0, "68 0C 0C 68 53 03 70 0B 00 00 0D 00 00 01 00 00 DF 16"),
    ("p12;128", "p", (12, 128), 3, 0, "68 09 09 68 53 03 70 0C 00 00 80 00 00 52 16"),
    ("q", "q", (), 3, 0, "68 03 03 68 53 03 71 C7 16"),
    ("v5000", "v", (5000,), 3, 0, "68 06 06 68 53 03 76 88 13 00 67 16"),
    ("w250", "w", (250,), 3, 0, "68 06 06 68 53 03 77 FA 00 00 C7 16"),
    # read-back requests
    ("T0", "T", (0,), 3, 0, "68 06 06 68 53 03 54 00 00 00 AA 16"),
    ("T0 to address 5", "T", (0,), 5, 0, "68 06 06 68 53 05 54 00 00 00 AC 16"),
    ("T1;0", "T", (1, 0), 3, 0, "68 09 09 68 53 03 54 01 00 00 00 00 00 AB 16"),
    ("T1;1;0", "T", (1, 1, 0), 3, 0, "68 0C 0C 68 53 03 54 01 00 00 01 00 00 00 00 00 AC 16"),
    ("T1;1;4", "T", (1, 1, 4), 3, 0, "68 0C 0C 68 53 03 54 01 00 00 01 00 00 04 00 00 B0 16"),
    ("T1;3;4", "T", (1, 3, 4), 3, 0, "68 0C 0C 68 53 03 54 01 00 00 03 00 00 04 00 00 B2 16"),
    ("T1;4", "T", (1, 4), 3, 0, "68 09 09 68 53 03 54 01 00 00 04 00 00 AF 16"),
    ("T1;5", "T", (1, 5), 3, 0, "68 09 09 68 53 03 54 01 00 00 05 00 00 B0 16"),
    ("T1;6;8", "T", (1, 6, 8), 3, 0, "68 0C 0C 68 53 03 54 01 00 00 06 00 00 08 00 00 B9 16"),
    ("T3;0", "T", (3, 0), 3, 0, "68 09 09 68 53 03 54 03 00 00 00 00 00 AD 16"),
    ("T3;4", "T", (3, 4), 3, 0, "68 09 09 68 53 03 54 03 00 00 04 00 00 B1 16"),
    ("T5;10", "T", (5, 10), 3, 0, "68 09 09 68 53 03 54 05 00 00 0A 00 00 B9 16"),
    ("T5;8;1", "T", (5, 8, 1), 3, 0, "68 0C 0C 68 53 03 54 05 00 00 08 00 00 01 00 00 B8 16"),
    ("T0 FCB=1", "T", (0,), 3, 1, "68 06 06 68 73 03 54 00 00 00 CA 16"),
    # §6 worked examples not in §3.11
    ("E1 A1234", "A", (1234,), 3, 0, "68 06 06 68 53 03 41 D2 04 00 6D 16"),
    ("E3 T1;3;13", "T", (1, 3, 13), 3, 0, "68 0C 0C 68 53 03 54 01 00 00 03 00 00 0D 00 00 BB 16"),
    ("E13 m58;0", "m", (58, 0), 3, 0, "68 09 09 68 53 03 6D 3A 00 00 00 00 00 FD 16"),
    ("E14 N127;15", "N", (127, 15), 3, 0, "68 09 09 68 53 03 4E 7F 00 00 0F 00 00 32 16"),
    ("E15 T5;15", "T", (5, 15), 3, 0, "68 09 09 68 53 03 54 05 00 00 0F 00 00 BE 16"),
    (
        "E17 Q8;3;0x3F0064",
        "Q",
        (8, 3, 0x3F0064),
        3,
        0,
        "68 0C 0C 68 53 03 51 08 00 00 03 00 00 64 00 3F 55 16",
    ),
]


@pytest.mark.parametrize(
    ("command", "params", "address", "fcb", "wire"),
    [pytest.param(*v[1:], id=v[0]) for v in LETTER_VECTORS],
)
def test_letter_vector_build_and_parse(
    command: str, params: tuple, address: int, fcb: int, wire: str
) -> None:
    expected = h(wire)
    frame = LongFrame(control_host(fcb), address, letter(command, *params))
    assert encode(frame) == expected
    assert device_decoder().feed(expected, 0.0) == [frame]
    padded = tuple(params) + (0,) * (3 - len(params))
    assert parse_letter(frame.data) == (command, padded, len(params))


# -- spec §3.11: read-back answers (card → host) -------------------------------------------------
# (name, wire bytes, control, address, identifier, value bytes, value decoded)
T_ANSWERS = [
    ("T0 10000", "68 06 06 68 08 03 40 10 27 00 82 16", 0x08, 3, 0x40, "10 27 00", 10000),
    ("T0 -10000", "68 06 06 68 08 03 40 F0 D8 FF 12 16", 0x08, 3, 0x40, "F0 D8 FF", -10000),
    ("T0 address 5", "68 06 06 68 08 05 40 00 00 00 4D 16", 0x08, 5, 0x40, "00 00 00", 0),
    ("T1;0 version 404", "68 05 05 68 08 03 56 94 01 F6 16", 0x08, 3, 0x56, "94 01", 404),
    ("T1;1;0 EB0 EB1", "68 05 05 68 08 03 49 05 00 59 16", 0x08, 3, 0x49, "05 00", 5),
    ("T1;1;4 EB4 EB5", "68 05 05 68 08 03 49 00 00 54 16", 0x08, 3, 0x49, "00 00", 0),
    ("T1;3;4 MB4=23", "68 05 05 68 08 03 49 17 00 6B 16", 0x08, 3, 0x49, "17 00", 23),
    ("T1;4 following error -12", "68 05 05 68 08 03 49 F4 FF 47 16", 0x08, 3, 0x49, "F4 FF", -12),
    ("T1;5 current 84", "68 04 04 68 08 03 49 54 A8 16", 0x08, 3, 0x49, "54", 84),
    ("T1;6;8 R02 123456", "68 06 06 68 08 03 44 40 E2 01 72 16", 0x08, 3, 0x44, "40 E2 01", 123456),
    ("T1;6;8 R02 -1", "68 06 06 68 08 03 44 FF FF FF 4C 16", 0x08, 3, 0x44, "FF FF FF", -1),
    ("T3;0 IDXOFF", "68 03 03 68 08 03 08 13 16", 0x08, 3, 0x08, "", 0),
    ("T3;0 motion+BUSY", "68 03 03 68 08 03 12 1D 16", 0x08, 3, 0x12, "", 0),
    ("T3;0 E-version ACD", "68 03 03 68 28 03 80 AB 16", 0x28, 3, 0x80, "", 0),
    ("T3;4 memory OK", "68 03 03 68 08 03 00 0B 16", 0x08, 3, 0x00, "", 0),
    ("T5;10 N10=300", "68 06 06 68 08 03 4E 2C 01 00 86 16", 0x08, 3, 0x4E, "2C 01 00", 300),
    ("T0 E-version DFC", "68 06 06 68 18 03 40 10 27 00 92 16", 0x18, 3, 0x40, "10 27 00", 10000),
    # §6 / §8 answers
    ("E3 T1;3;13 MB13=1", "68 05 05 68 08 03 49 01 00 55 16", 0x08, 3, 0x49, "01 00", 1),
    ("E13 T1;3;6 MB7=1", "68 05 05 68 08 03 49 00 01 55 16", 0x08, 3, 0x49, "00 01", 256),
    ("E14 T3;0 I.3+I.5+I.6", "68 03 03 68 08 03 68 73 16", 0x08, 3, 0x68, "", 0),
    ("E15 T5;15 84", "68 06 06 68 08 03 4E 54 00 00 AD 16", 0x08, 3, 0x4E, "54 00 00", 84),
    ("E16 #1 reply", "10 40 11 51 16", None, 17, 0x40, "", 0),
    ("§8 T1;5 126", "68 04 04 68 08 03 49 7E D2 16", 0x08, 3, 0x49, "7E", 126),
]


def _signed(value: bytes) -> int:
    return int.from_bytes(value, "little", signed=True) if value else 0


@pytest.mark.parametrize(
    ("wire", "control", "address", "identifier", "value", "decoded"),
    [pytest.param(*v[1:], id=v[0]) for v in T_ANSWERS],
)
def test_answer_vector_build_and_parse(
    wire: str, control: int | None, address: int, identifier: int, value: str, decoded: int
) -> None:
    expected = h(wire)
    if control is None:  # a Kurzsatz status answer
        frame: ShortFrame | LongFrame = k_frame(identifier, address, None)
    else:
        frame = t_reply(address, identifier, h(value), control)
        raw = h(value)
        assert _signed(raw) == decoded or int.from_bytes(raw, "little") == decoded
    assert encode(frame) == expected
    assert host_decoder().feed(expected, 0.0) == [frame]


# -- spec §3.11: Kurzsatz commands and answers ------------------------------------------------------
SHORT_COMMANDS = [
    ("#0 abort", 0, 3, b"", "10 00 03 03 16"),
    ("#1 status", 1, 3, b"", "10 01 03 04 16"),
    ("#1 address 0", 1, 0, b"", "10 01 00 01 16"),
    ("#1 address 17", 1, 17, b"", "10 01 11 12 16"),
    ("#1 address 31", 1, 31, b"", "10 01 1F 20 16"),
    ("#8 1500 rpm", 8, 3, (1500).to_bytes(2, "little"), "10 0A 03 DC 05 EE 16"),
    ("#8 750 rpm (§8)", 8, 3, (750).to_bytes(2, "little"), "10 0A 03 EE 02 FD 16"),
    ("#9 80 %", 9, 3, bytes([80]), "10 0B 03 50 5E 16"),
    ("#9 125 %", 9, 3, bytes([125]), "10 0B 03 7D 8B 16"),
]


@pytest.mark.parametrize(
    ("number", "address", "extension", "wire"), [pytest.param(*v[1:], id=v[0]) for v in SHORT_COMMANDS]
)
def test_short_command_vectors(number: int, address: int, extension: bytes, wire: str) -> None:
    frame = short_command(number, address, extension)
    assert encode(frame) == h(wire)
    [decoded] = device_decoder().feed(h(wire), 0.0)
    assert decoded == frame
    assert isinstance(decoded, ShortFrame)
    assert short_command_number(decoded.control) == number
    assert decoded.extension == extension


K_ANSWERS = [
    ("IDXOFF", 0x40, None, "10 40 03 43 16"),
    ("all clear", 0x00, None, "10 00 03 03 16"),
    ("BUSY + motion", 0x90, None, "10 90 03 93 16"),
    ("IDXOFF + message 23", 0x40, 23, "10 42 03 17 5C 16"),
    ("e-stop + IDXOFF", 0x48, None, "10 48 03 4B 16"),
    ("monitoring + IDXOFF + I2t", 0x61, None, "10 61 03 64 16"),
    ("BUSY + IDXOFF + motion", 0xD0, None, "10 D0 03 D3 16"),
    ("message 23, indexer active (§8)", 0x00, 23, "10 02 03 17 1C 16"),
]


@pytest.mark.parametrize(("k", "mb4", "wire"), [pytest.param(*v[1:], id=v[0]) for v in K_ANSWERS])
def test_k_answer_vectors(k: int, mb4: int | None, wire: str) -> None:
    frame = k_frame(k, 3, mb4)
    assert encode(frame) == h(wire)
    assert host_decoder().feed(h(wire), 0.0) == [frame]
    assert frame.extension == (b"" if mb4 is None else bytes([mb4]))
    assert bool(frame.control & 0x02) == (mb4 is not None)


def test_single_char_ack() -> None:
    assert encode(SingleChar(ACK)) == b"\xe5"
    assert host_decoder().feed(b"\xe5", 0.0) == [SingleChar(0xE5)]
    assert host_decoder().feed(b"\xa2", 0.0) == [SingleChar(0xA2)]
    # On the card side E5h is not a frame: a byte outside any frame.
    assert device_decoder().feed(b"\xe5", 0.0) == [FrameError("garbage", b"\xe5")]


def test_tolerant_short_command_decoding() -> None:
    """Spec §3.6 rule 1/2: cmd = F & 0x0D, AE count from the command table, not from bit 1."""
    for control in (0x01, 0x41):
        assert short_command_number(control) == 1
    for control in (0x08, 0x0A, 0x48, 0x4A):
        assert short_command_number(control) == 8
        wire = encode(ShortFrame(control, 3, b"\xdc\x05"))
        assert device_decoder().feed(wire, 0.0) == [ShortFrame(control, 3, b"\xdc\x05")]
    assert short_extension_device(0x09) == short_extension_device(0x0B) == 1
    # 10 40 A CS 16 (IEC reset of remote link) is #0 Abbruch (rule 4).
    [reset] = device_decoder().feed(h("10 40 03 43 16"), 0.0)
    assert isinstance(reset, ShortFrame) and short_command_number(reset.control) == 0
    assert control_host(0, fcv=0, fc=0) == 0x40


def test_control_field_defaults() -> None:
    assert control_host(0) == 0x53
    assert control_host(1) == 0x73
    assert short_command(8, 3, b"\x00\x00").control == 0x0A
    assert short_command(9, 3, b"\x00").control == 0x0B
    assert short_command(0, 3).control == 0x00


# -- spec §6.1: complete session ----------------------------------------------------------------
SESSION = [
    ("10 01 03 04 16", "10 40 03 43 16"),
    ("68 09 09 68 53 03 54 01 00 00 00 00 00 AB 16", "68 05 05 68 08 03 56 94 01 F6 16"),
    ("68 09 09 68 53 03 54 03 00 00 00 00 00 AD 16", "68 03 03 68 08 03 08 13 16"),
    ("68 0C 0C 68 53 03 54 01 00 00 03 00 00 00 00 00 AE 16", "68 05 05 68 08 03 49 B0 04 08 16"),
    ("68 06 06 68 53 03 42 32 00 00 CA 16", "E5"),
    ("68 06 06 68 53 03 4D 20 4E 00 11 16", "E5"),
    ("68 06 06 68 53 03 66 10 27 00 F3 16", "E5"),
    ("68 06 06 68 53 03 53 C8 00 00 71 16", "E5"),
    ("68 06 06 68 53 03 51 00 00 00 A7 16", "E5"),
    ("10 01 03 04 16", "10 D0 03 D3 16"),
    ("10 01 03 04 16", "10 00 03 03 16"),
    ("68 06 06 68 53 03 41 10 27 00 CE 16", "E5"),
    ("10 01 03 04 16", "10 90 03 93 16"),
    ("10 01 03 04 16", "10 00 03 03 16"),
    ("68 06 06 68 53 03 54 00 00 00 AA 16", "68 06 06 68 08 03 40 10 27 00 82 16"),
]

SESSION_BUILT = [
    (short_command(1, 3), k_frame(0x40, 3, None)),
    (LongFrame(0x53, 3, letter("T", 1, 0)), t_reply(3, ord("V"), (404).to_bytes(2, "little"))),
    (LongFrame(0x53, 3, letter("T", 3, 0)), t_reply(3, 0x08, b"")),
    (LongFrame(0x53, 3, letter("T", 1, 3, 0)), t_reply(3, ord("I"), b"\xb0\x04")),
    (LongFrame(0x53, 3, letter("B", 50)), SingleChar(ACK)),
    (LongFrame(0x53, 3, letter("M", 20000)), SingleChar(ACK)),
    (LongFrame(0x53, 3, letter("f", 10000)), SingleChar(ACK)),
    (LongFrame(0x53, 3, letter("S", 200)), SingleChar(ACK)),
    (LongFrame(0x53, 3, letter("Q", 0)), SingleChar(ACK)),
    (short_command(1, 3), k_frame(0xD0, 3, None)),
    (short_command(1, 3), k_frame(0x00, 3, None)),
    (LongFrame(0x53, 3, letter("A", 10000)), SingleChar(ACK)),
    (short_command(1, 3), k_frame(0x90, 3, None)),
    (short_command(1, 3), k_frame(0x00, 3, None)),
    (LongFrame(0x53, 3, letter("T", 0)), t_reply(3, ord("@"), to_s24(10000))),
]


def test_session_example_6_1() -> None:
    card, host = device_decoder(), host_decoder()
    for t, ((request, reply), (built_request, built_reply)) in enumerate(
        zip(SESSION, SESSION_BUILT, strict=True)
    ):
        assert encode(built_request) == h(request)
        assert encode(built_reply) == h(reply)
        assert card.feed(h(request), float(t)) == [built_request]
        assert host.feed(h(reply), float(t) + 0.5) == [built_reply]
    assert card.pending == host.pending == 0


# -- framing errors (spec §3.2 R6, §3.10, §8 link_errors_no_reply) --------------------------------
GOOD = "10 01 03 04 16"


@pytest.mark.parametrize(
    ("bad", "reason"),
    [
        ("68 06 06 68 53 03 41 10 27 00 CF 16", "checksum"),
        ("68 06 07 68 53 03 41 10 27 00 CE 16", "length_mismatch"),
        ("68 06 06 68 53 03 41 10 27 00 CE 17", "end_byte"),
        ("68 01 01 68 53 54 16", "length"),
        ("68 06 06 69 53 03 41 10 27 00 CE 16", "start_byte"),
        ("10 01 03 05 16", "checksum"),
        ("10 01 03 04 17", "end_byte"),
        ("10 0A 03 DC 05 EF 16", "checksum"),
    ],
)
def test_framing_errors_are_reported_and_discarded(bad: str, reason: str) -> None:
    decoder = device_decoder()
    out = decoder.feed(h(bad), 0.0)
    assert frames_of(out) == []
    assert out and isinstance(out[0], FrameError) and out[0].reason == reason
    # Every byte is accounted for: discarded, or held as a partial frame.
    assert b"".join(e.discarded for e in errors_of(out)) + h(bad)[len(h(bad)) - decoder.pending :] == h(bad)
    # The line recovers: a good frame after the line went idle decodes.
    later = decoder.feed(h(GOOD), 1.0)
    assert frames_of(later) == [short_command(1, 3)]


def test_bad_frame_then_good_frame_in_one_chunk() -> None:
    decoder = device_decoder()
    out = decoder.feed(h("68 06 06 68 53 03 41 10 27 00 CF 16") + h(GOOD), 0.0)
    assert frames_of(out) == [short_command(1, 3)]
    assert errors_of(out)[0].reason == "checksum"
    assert decoder.pending == 0


def test_other_address_is_a_valid_frame() -> None:
    """The §8 "other address" frame is valid FT1.2; ignoring it is the device's business."""
    [frame] = device_decoder().feed(h("68 06 06 68 53 04 41 10 27 00 CF 16"), 0.0)
    assert frame == LongFrame(0x53, 4, letter("A", 10000))


# -- timeouts --------------------------------------------------------------------------------------
def test_partial_frame_discarded_after_timeout_not_glued() -> None:
    decoder = device_decoder(char_timeout=0.05)
    first = h("68 06 06 68 53 03 41 10 27 00 CE 16")
    second = h("68 09 09 68 53 03 54 01 00 00 00 00 00 AB 16")
    assert decoder.feed(first[:6], 0.0) == []
    assert decoder.pending == 6
    out = decoder.feed(second, 1.0)
    assert out == [FrameError("timeout", first[:6]), LongFrame(0x53, 3, letter("T", 1, 0))]
    assert decoder.pending == 0


def test_partial_frame_timeout_then_rest_of_old_frame_is_garbage() -> None:
    """The tail of a stale frame is never glued to its head."""
    decoder = device_decoder(char_timeout=0.05)
    first = h("68 06 06 68 53 03 41 10 27 00 CE 16")
    decoder.feed(first[:5], 0.0)
    out = decoder.feed(first[5:], 0.2)
    assert out[0] == FrameError("timeout", first[:5])
    assert frames_of(out) == []


def test_gap_within_timeout_keeps_the_frame() -> None:
    decoder = device_decoder(char_timeout=0.05)
    wire = h(GOOD)
    assert decoder.feed(wire[:2], 0.0) == []
    assert decoder.feed(wire[2:4], 0.04) == []
    assert decoder.feed(wire[4:], 0.08) == [short_command(1, 3)]  # 40 ms gaps, each < 50 ms


def test_expire_without_new_bytes() -> None:
    decoder = device_decoder(char_timeout=0.05)
    decoder.feed(h("10 01 03"), 1.0)
    assert decoder.expire(1.03) == []
    assert decoder.pending == 3
    assert decoder.expire(1.2) == [FrameError("timeout", h("10 01 03"))]
    assert decoder.pending == 0
    assert decoder.expire(5.0) == []


# -- chunking and garbage --------------------------------------------------------------------------
def test_two_frames_in_one_chunk() -> None:
    a = h("68 06 06 68 53 03 41 10 27 00 CE 16")
    out = device_decoder().feed(a + h(GOOD), 0.0)
    assert out == [LongFrame(0x53, 3, letter("A", 10000)), short_command(1, 3)]


def test_frame_split_byte_by_byte() -> None:
    decoder = device_decoder()
    wire = h("68 0C 0C 68 53 03 51 06 00 00 81 00 00 50 C3 00 41 16")
    out: list = []
    for i, byte in enumerate(wire):
        out += decoder.feed(bytes([byte]), i * 0.001)
        if i < len(wire) - 1:
            assert decoder.pending == i + 1
    assert out == [LongFrame(0x53, 3, letter("Q", 6, 0x81, 50000))]


def test_reply_split_byte_by_byte_on_host_side() -> None:
    decoder = host_decoder()
    wire = h("10 42 03 17 5C 16") + b"\xe5" + h("68 05 05 68 08 03 56 94 01 F6 16")
    out: list = []
    for i, byte in enumerate(wire):
        out += decoder.feed(bytes([byte]), i * 0.001)
    assert out == [k_frame(0x40, 3, 23), SingleChar(ACK), t_reply(3, 0x56, b"\x94\x01")]


def test_garbage_between_frames_reported_once() -> None:
    decoder = device_decoder()
    out = decoder.feed(h(GOOD) + b"\x00\x0d\x0a\xff\xe5" + h(GOOD), 0.0)
    assert out == [short_command(1, 3), FrameError("garbage", b"\x00\x0d\x0a\xff\xe5"), short_command(1, 3)]


def test_empty_feed_and_reset() -> None:
    decoder = device_decoder()
    assert decoder.feed(b"", 0.0) == []
    decoder.feed(h("68 06"), 0.0)
    assert decoder.reset() == h("68 06")
    assert decoder.pending == 0


def test_faulty_extension_callback_does_not_break_decoding() -> None:
    def boom(control: int) -> int:
        raise RuntimeError("bad table")

    assert FrameDecoder(short_extension=boom).feed(h(GOOD), 0.0) == [short_command(1, 3)]
    assert FrameDecoder(short_extension=lambda c: -5).feed(h(GOOD), 0.0) == [short_command(1, 3)]


# -- user data: 24-bit parameters and letters ------------------------------------------------------
def test_s24_limits() -> None:
    assert to_s24(-8388352) == h("00 01 80")
    assert to_s24(8388607) == h("FF FF 7F")
    assert to_s24(-1) == h("FF FF FF")
    assert to_s24(0xFFFFFF) == h("FF FF FF")  # the bit pattern of -1
    assert from_s24(h("00 01 80")) == -8388352
    assert from_s24(h("FF FF 7F")) == 8388607
    assert from_s24(h("00 00 80")) == -8388608
    for bad in (-8388609, 0x1000000):
        with pytest.raises(ValueError):
            to_s24(bad)
    with pytest.raises(ValueError):
        from_s24(b"\x00\x00")


def test_parse_letter_rejects_malformed_counts() -> None:
    assert parse_letter(b"") is None
    assert parse_letter(b"A\x00") is None
    assert parse_letter(b"A\x00\x00\x00\x00") is None
    assert parse_letter(b"N" + bytes(12)) is None  # four parameters
    assert parse_letter(b"q") == ("q", (0, 0, 0), 0)
    # The PLC download command a may have any length (spec §3.8.24).
    assert parse_letter(b"a" + bytes(range(1, 21))) == (
        "a",
        (from_s24(bytes([1, 2, 3])), from_s24(bytes([4, 5, 6])), from_s24(bytes([7, 8, 9]))),
        3,
    )
    assert parse_letter(b"a\x01") == ("a", (0, 0, 0), 0)


def test_letter_rejects_bad_input() -> None:
    with pytest.raises(ValueError):
        letter("AB", 1)
    with pytest.raises(ValueError):
        letter("A", 1, 2, 3, 4)
    with pytest.raises(ValueError):
        letter("A", 1 << 24)


def test_encode_rejects_what_does_not_fit() -> None:
    with pytest.raises(ValueError):
        encode(LongFrame(0x53, 3, bytes(254)))
    assert len(encode(LongFrame(0x53, 3, bytes(253)))) == 261
    with pytest.raises(ValueError):
        encode(ShortFrame(0x100, 3))
    with pytest.raises(ValueError):
        encode(SingleChar(-1))
    with pytest.raises(TypeError):
        encode("E5")  # type: ignore[arg-type]


def test_checksum() -> None:
    assert checksum(h("53 03 41 10 27 00")) == 0xCE
    assert checksum(b"") == 0
    assert checksum(bytes([0xFF] * 3)) == 0xFD


# -- property-based --------------------------------------------------------------------------------
s24 = st.integers(min_value=-(1 << 23), max_value=(1 << 23) - 1)
octet = st.integers(min_value=0, max_value=255)
NON_START = bytes(b for b in range(256) if b not in (0x10, 0x68, 0xE5, 0xA2))
non_start_bytes = st.lists(st.sampled_from(NON_START), max_size=40).map(bytes)


@st.composite
def frames(draw: st.DrawFn, host_side: bool = False) -> SingleChar | ShortFrame | LongFrame:
    kind = draw(st.sampled_from(["single", "short", "long"] if host_side else ["short", "long"]))
    if kind == "single":
        return SingleChar(draw(st.sampled_from([0xE5, 0xA2])))
    address = draw(octet)
    if kind == "short":
        control = draw(octet)
        ext_len = short_extension_host(control) if host_side else short_extension_device(control)
        return ShortFrame(control, address, draw(st.binary(min_size=ext_len, max_size=ext_len)))
    return LongFrame(draw(octet), address, draw(st.binary(max_size=253)))


def _decoder(host_side: bool) -> FrameDecoder:
    return host_decoder() if host_side else device_decoder()


@settings(max_examples=300)
@given(chunks=st.lists(st.tuples(st.binary(max_size=64), st.floats(0, 0.2)), max_size=20), host=st.booleans())
def test_fuzz_random_bytes_never_raise_and_every_byte_is_accounted(chunks: list, host: bool) -> None:
    decoder = _decoder(host)
    now = 0.0
    fed = bytearray()
    out: list = []
    for data, gap in chunks:
        now += gap
        fed += data
        out += decoder.feed(data, now)
        assert decoder.pending <= 261
    out += decoder.expire(now + 1.0)
    assert decoder.pending == 0
    rebuilt = b"".join(x.discarded if isinstance(x, FrameError) else encode(x) for x in out)
    assert rebuilt == bytes(fed)
    for x in out:
        if isinstance(x, FrameError):
            assert x.discarded and x.reason in {
                "garbage",
                "timeout",
                "length",
                "length_mismatch",
                "start_byte",
                "checksum",
                "end_byte",
            }


@settings(max_examples=300)
@given(frame=frames(), before=st.binary(max_size=40), after=st.binary(max_size=40))
def test_fuzz_frame_in_garbage_separated_by_timeouts(
    frame: ShortFrame | LongFrame, before: bytes, after: bytes
) -> None:
    decoder = device_decoder(char_timeout=0.05)
    out = decoder.feed(before, 0.0)
    found = decoder.feed(encode(frame), 1.0)
    assert frame in found
    out += found + decoder.feed(after, 2.0) + decoder.expire(3.0)


@settings(max_examples=300)
@given(data=st.data(), before=non_start_bytes, after=non_start_bytes, host=st.booleans())
def test_fuzz_frame_surrounded_by_non_start_bytes(
    data: st.DataObject, before: bytes, after: bytes, host: bool
) -> None:
    frame = data.draw(frames(host_side=host))
    out = _decoder(host).feed(before + encode(frame) + after, 0.0)
    assert frames_of(out) == [frame]
    assert [e.reason for e in errors_of(out)] == ["garbage"] * (bool(before) + bool(after))


@settings(max_examples=300)
@given(items=st.lists(frames(host_side=True), min_size=1, max_size=6), cut=st.integers(1, 8))
def test_round_trip_random_frames(items: list, cut: int) -> None:
    wire = b"".join(encode(f) for f in items)
    decoder = host_decoder()
    assert decoder.feed(wire, 0.0) == items
    # The same stream in arbitrary small chunks, close together in time.
    decoder = host_decoder()
    out: list = []
    for i in range(0, len(wire), cut):
        out += decoder.feed(wire[i : i + cut], i * 1e-4)
    assert out == items


@given(command=st.characters(min_codepoint=0x21, max_codepoint=0x7E), params=st.lists(s24, max_size=3))
def test_letter_round_trip(command: str, params: list[int]) -> None:
    data = letter(command, *params)
    assert len(data) == 1 + 3 * len(params)
    parsed = parse_letter(data)
    assert parsed == (command, tuple(params + [0] * (3 - len(params))), len(params))


@given(value=s24)
def test_s24_round_trip(value: int) -> None:
    assert from_s24(to_s24(value)) == value


@pytest.mark.parametrize("value", [-8388352, 8388607, -8388608, 0, -1, 1])
def test_s24_round_trip_limits(value: int) -> None:
    assert from_s24(to_s24(value)) == value
    assert parse_letter(letter("A", value)) == ("A", (value, 0, 0), 1)
