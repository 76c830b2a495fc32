"""The tape code of the POSELESTA: the read-in vectors R1–R16 and output vectors O1–O3 of spec
§6.7/§6.8, the manual's example listing of §2.6.2.3 (spec §6.6) and the character codes (§6.1)."""

from __future__ import annotations

import pytest

from devsim.devices.poselesta.codes import KEY_CODES, encode, iso_byte, parity_ok
from devsim.devices.poselesta.tape import Block, BlockRead, Ended, Failed, Formats, Notice, TapeReader, render

# spec §6.6: the manual's listing as OCR'd (the lost "%" restored)
LISTING = """%
N 1 X 0.000 Y, 43.144 F 1002
N 2 X- 20.000 F 750 G 42
N 3 X 0.000 Y 23.144 I 0.000 J 43.144 G 02
N 4 G 12 L 1.100
N 5 X 20.000 Y- 43.144 I 0.000 J- 43.144 G 02
N 6 X 0.000 Z 01 G 40 M 02
N 100 G 10
N 101 I 5.000 J 37.000 G 03 G 25
N 102 G 13 L 5.101
N 103 I 5.000 J 13.000 G 25
N 104 G 13 L 11.103
N 105 I 5.000 J 37.000 G 25
N 106 G 13 L 11.105
N 107 I 5.000 J 13.000 G 25
N 108 G 13 L 11.107
N 109 I 5.000 J 37.000 G 25
N 110 G 13 L 11.109
N 111 I 5.000 J 13.000 G 25
N 112 G 13 L 11.111
N 113 I 5.000 J 37.000 G 25
N 114 G 13 L 5.113
N 115 G 11
M 30
"""


def read(data: bytes, *, iso: bool = False, **options: object) -> tuple[dict[int, Block], list[object]]:
    reader = TapeReader(iso=iso, **options)  # type: ignore[arg-type]
    events = reader.feed(data)
    blocks = {e.block.number: e.block for e in events if isinstance(e, BlockRead)}
    return blocks, events


def ascii_tape(text: str) -> bytes:
    return ("%\r\n" + text.replace("\n", "\r\n")).encode()


def test_character_codes() -> None:
    """§6.1: % A5, CR 8D, LF 0A, DEL FF, # A3; key "P" 48 has parity 0."""
    assert [iso_byte(ord(c)) for c in "%\r\n\x7f#H"] == [0xA5, 0x8D, 0x0A, 0xFF, 0xA3, 0x48]
    assert encode("N 1", iso=True) == bytes.fromhex("4E A0 B1")
    assert all(parity_ok(iso_byte(c)) for c in range(128))
    assert len(KEY_CODES) == 45 and 0x48 in KEY_CODES


def test_r1_iso_read_in_with_leader() -> None:
    data = bytes.fromhex(
        "00000000 A58D0A 4EB1D8B1302E35592D338D0A 4EB2A0473030A0D830A05930A04D30B28D0A 4D33308D0A"
    )
    blocks, events = read(data, iso=True)
    assert blocks == {
        1: Block(1, (("X", 10500), ("Y", -3000))),
        2: Block(2, (("G", 0), ("X", 0), ("Y", 0), ("M", 2))),
    }
    assert isinstance(events[-1], Ended)


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("garbage N1 X9\r%\rN1 X1\r", {1: (("X", 1000),)}),  # R2: before % ignored
        ("N 01 X .5\r", {1: (("X", 500),)}),  # R3
        ("N3X12C13\r", {3: (("X", 13000),)}),  # R4: C erases the value
        ("N4X1\x7f2\r", {4: (("X", 12000),)}),  # R5: DEL skipped
        ("N6X5\rN7X6\r", {6: (("X", 5000),), 7: (("X", 6000),)}),  # R7: LF optional
        ("N7 M02\rN8 X1\rM30\rN9 X2\r", {7: (("M", 2),), 8: (("X", 1000),)}),  # R8: M02 does not end
        ("n3x5\r", {}),  # R10: lower case is undefined
        ("X5\r", {}),  # R13: no N: skipped
    ],
)
def test_read_in_vectors(text: str, expected: dict[int, tuple[tuple[str, int], ...]]) -> None:
    data = text.encode() if text.startswith("garbage") else ("%\r" + text).encode()
    blocks, events = read(data)
    assert {n: b.words for n, b in blocks.items()} == expected
    assert not any(isinstance(e, Failed) for e in events)


def test_r6_block_skip_and_r9_m30_with_number() -> None:
    blocks, events = read(b"%\rN5 X5 #\rN99 M30\rN10 X1\r")
    assert blocks == {5: Block(5, (("X", 5000),), skip=True)}
    assert isinstance(events[-1], Ended)  # R9: the M30 block ends it; N10 is never read


@pytest.mark.parametrize(
    "text",
    [
        "N9 X12345.678\r",  # R11: beyond xxxx.xxx
        "N10 X1 Y2 Z3\r",  # R12: three coordinates
        "N11 G1 G2 G3 G4 G17\r",  # R16: five G words
        "N12 F-5\r",  # a sign on F
        "N1000 X1\r",  # N beyond 999
        "N13 X1.2.3\r",  # a second point
    ],
)
def test_value_range_overflow(text: str) -> None:
    blocks, events = read(("%\r" + text + "N20 X1\r").encode())
    assert isinstance(events[-1], Failed) and events[-1].message == "WERTBEREICHES-UEBERLAUF"
    assert 20 not in blocks  # the transfer stopped


def test_r14_ascii_into_iso_fails_at_the_cr() -> None:
    blocks, events = read(bytes.fromhex("25 0D 0A 4E 31 58 31 0D"), iso=True)
    assert blocks == {} and isinstance(events[0], Failed)
    assert "0D" in events[0].reason


def test_parity_skip_option_and_ascii_bit7() -> None:
    blocks, _ = read(bytes.fromhex("A5 8D 4E B1 D8 31 B1 8D"), iso=True, parity_error="skip")
    assert blocks == {1: Block(1, (("X", 1000),))}  # the plain "1" (31, odd) was dropped
    blocks, _ = read(encode("%\rN1X2\r", iso=True))  # an ISO image into ASCII: bit 7 masked
    assert blocks == {1: Block(1, (("X", 2000),))}
    _, events = read(encode("%\rN1X2\r", iso=True), ascii_bit7="abort")
    assert isinstance(events[-1], Failed)


def test_notices_for_the_host_developer() -> None:
    blocks, events = read(b"%\rN1 X Y2 X3 X4 (note)\rX4\r", strict_block_numbers=False)
    whats = [e.what for e in events if isinstance(e, Notice)]
    assert whats == ["empty_word", "comment_characters_seen", "duplicate_word", "block_without_number"]
    assert blocks[1].words == (("Y", 2000), ("X", 4000))  # the later X replaces the earlier
    _, events = read(b"%\rX4\r", strict_block_numbers=True)
    assert isinstance(events[-1], Failed)


def test_the_manuals_listing_reads_in() -> None:
    """Spec §6.6: 22 blocks, no error; 'Y, 43.144' is Y 43.144 and 'Z 01' is Z 1.000."""
    blocks, events = read(LISTING.replace("\n", "\r\n").encode())
    assert len(blocks) == 22 and isinstance(events[-1], Ended)
    assert blocks[1].value("Y") == 43144 and blocks[6].value("Z") == 1000
    assert blocks[101].values("G") == [3, 25] and blocks[114].value("L") == 5113


def test_formatted_output_of_the_listing() -> None:
    """Spec §6.6: the reconstructed tape, formatted (V6 modes 7/8), ISO and ASCII bytes."""
    blocks = [
        Block(1, (("X", 0), ("Y", -43144), ("F", 1002))),
        Block(2, (("X", -20000), ("F", 750), ("G", 42))),
        Block(4, (("G", 12), ("L", 1100))),
        Block(6, (("X", 0), ("Z", 1000), ("G", 40), ("M", 2))),
    ]
    iso = render(blocks, iso=True, formatted=True)
    lines = iso.split(b"\x8d\x0a")
    assert lines[0] == b"\xa5"
    assert lines[1] == bytes.fromhex("4E A0 B1 A0 D8 A0 30 2E 30 30 30 A0 59 2D A0 B4 33 2E B1 B4 B4 A0 C6 A0 B1 30 30 B2")
    assert lines[2] == bytes.fromhex("4E A0 B2 A0 D8 2D A0 B2 30 2E 30 30 30 A0 C6 A0 B7 35 30 A0 47 A0 B4 B2")
    assert lines[-2] == bytes.fromhex("4D A0 33 30")
    text = render(blocks, iso=False, formatted=True).decode()
    assert text.splitlines()[1:4] == ["N 1 X 0.000 Y- 43.144 F 1002", "N 2 X- 20.000 F 750 G 42", "N 4 G 12 L 1.100"]
    assert text.splitlines()[4] == "N 6 X 0.000 Z 1.000 G 40 M 02"
    dnc = render(blocks, iso=True, formatted=False)
    assert dnc.split(b"\x8d\x0a")[1] == bytes.fromhex("4E B1 D8 30 2E 30 30 30 59 2D B4 33 2E B1 B4 B4 C6 B1 30 30 B2")
    assert dnc.split(b"\x8d\x0a")[2] == bytes.fromhex("4E B2 D8 2D B2 30 2E 30 30 30 C6 B7 35 30 47 B4 B2")


def test_output_vectors_o1_to_o3() -> None:
    blocks, _ = read(bytes.fromhex("A58D0A 4EB1D8B1302E35592D338D0A 4EB2A0473030A0D830A05930A04D30B28D0A 4D33308D0A"),
                     iso=True)
    o1 = bytes.fromhex(
        "25 0D 0A 4E 31 58 31 30 2E 35 30 30 59 2D 33 2E 30 30 30 0D 0A"
        "4E 32 58 30 2E 30 30 30 59 30 2E 30 30 30 47 30 30 4D 30 32 0D 0A 4D 33 30 0D 0A"
    )
    assert render(blocks.values(), iso=False, formatted=False) == o1
    assert render(blocks.values(), iso=True, formatted=False) == bytes(iso_byte(b) for b in o1)  # O2
    assert render([], iso=False, formatted=False) == b"%\r\nM30\r\n"  # O3


def test_round_trip_with_other_resolutions() -> None:
    formats = Formats({"X": 2, "Y": 3, "Z": 5, "D": 3})
    blocks, _ = read(b"%\rN1 X12345.67 Z-12.34567 K1.5\r", formats=formats)
    assert blocks[1].words == (("X", 1234567), ("Z", -1234567), ("K", 150000))
    again, _ = read(render(blocks.values(), iso=False, formatted=True, formats=formats), formats=formats)
    assert again == blocks
