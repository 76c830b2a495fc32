"""POSELESTA tape images at their limits, by property (manual §2.6, §2.6.3; spec poselesta.md
§3.4–§3.6).

Words are generated at and around their format (N three digits, G/M/T two, F/S four, L 2.3,
coordinates seven significant digits with the axis's decimals), blocks at and around the most
words of a kind (2 coordinates, 2 centres, 4 G, 2 M), bytes around the codes' rules (ISO even
parity, ASCII bit 7, control characters before ``%``), and compared with the rules written here.
"""

from __future__ import annotations

import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as hs

from devsim.devices.poselesta.tape import Block, BlockRead, Ended, Failed, Formats, Notice, TapeReader, render

#: Digits before and after the point (manual §2.6.3, 3 decimals on every axis).
FORMAT = {"N": (3, 0), "G": (2, 0), "M": (2, 0), "T": (2, 0), "F": (4, 0), "S": (4, 0), "L": (2, 3),
          "X": (4, 3), "Y": (4, 3), "Z": (4, 3), "D": (4, 3), "I": (4, 3), "J": (4, 3), "K": (4, 3)}
MOST = {"XYZD": 2, "IJK": 2, "G": 4, "M": 2}


def _even(byte: int) -> int:
    """ISO code: bit 7 makes the number of ones even."""
    return byte | 0x80 if bin(byte).count("1") % 2 else byte


def _read(text: str, iso: bool = False, **options: object) -> list[object]:
    data = bytes(_even(b) for b in text.encode()) if iso else text.encode()
    return TapeReader(iso=iso, **options).feed(data)  # type: ignore[arg-type]


@settings(max_examples=300, deadline=None)
@given(hs.sampled_from(sorted(FORMAT)), hs.data())
def test_a_word_at_the_edge_of_its_format(letter: str, data: hs.DataObject) -> None:
    before, after = FORMAT[letter]
    whole = data.draw(hs.integers(0, before + 1))  # significant digits before the point
    fraction = data.draw(hs.integers(0, after + 1))
    zeros = data.draw(hs.integers(0, 2))  # leading zeros and trailing zeros do not count
    digits = "0" * zeros + "9" * whole + ("." + "5" * fraction + "0" * zeros if fraction or zeros else "")
    if not whole and not fraction and not zeros:
        digits = "0"
    text = f"%\rN1 {letter}{digits}\r" if letter != "N" else f"%\rN{digits}\r"
    events = _read(text)
    if whole > before or fraction > after:
        assert [type(e) for e in events] == [Failed] and "beyond the format" in events[0].reason
        return
    value = int("9" * whole or "0") * 10**after + int(("5" * fraction).ljust(after, "0") or "0")
    if letter == "N":
        assert events == [BlockRead(Block(value))]
    elif letter == "M" and value == 30:
        assert events == [Ended()]
    else:
        assert events == [BlockRead(Block(1, ((letter, value),)))]


@settings(max_examples=200, deadline=None)
@given(hs.sampled_from(sorted(MOST)), hs.integers(0, 2))
@example("G", 1)
@example("XYZD", 0)
def test_a_block_holds_at_most_so_many_words_of_a_kind(kinds: str, over: int) -> None:
    """§2.6.3: at most 2 coordinates, 2 centre coordinates, 4 G and 2 M functions a block;
    one more is WERTBEREICHES-UEBERLAUF."""
    count = MOST[kinds] + over
    if kinds in ("G", "M"):
        words = [f"{kinds}{n}" for n in (1, 2, 3, 4, 5, 6)[:count]]
    else:
        words = [f"{kinds[i % len(kinds)]}{i + 1}" for i in range(count)]
        if count > len(kinds):
            return  # a letter repeated is a duplicate word, not one more of the kind
    events = _read("%\rN1 " + " ".join(words) + "\r")
    if over:
        assert events and isinstance(events[-1], Failed) and f"more than {MOST[kinds]} words" in events[-1].reason
    else:
        assert [type(e) for e in events] == [BlockRead] and len(events[0].block.words) == count


@pytest.mark.parametrize(("letter", "signed"), [("X", True), ("I", True), ("K", True), ("D", True), ("F", False),
                                                 ("N", False), ("G", False), ("S", False)])
def test_only_coordinates_take_a_sign(letter: str, signed: bool) -> None:
    events = _read(f"%\rN1 {letter}-12\r" if letter != "N" else "%\rN-12\r")
    if signed:
        assert events == [BlockRead(Block(1, ((letter, -12000),)))]
    else:
        assert isinstance(events[-1], Failed) and "a sign is not allowed" in events[-1].reason


@settings(max_examples=200, deadline=None)
@given(hs.integers(0, 255), hs.sampled_from(["abort", "skip"]))
def test_iso_parity_after_the_percent(byte: int, mode: str) -> None:
    """ISO code: even parity; a byte with odd parity after ``%`` ends the transfer or (skip)
    is reported and dropped."""
    events = TapeReader(iso=True, parity_error=mode).feed(bytes((_even(0x25), byte)))  # type: ignore[arg-type]
    if bin(byte).count("1") % 2 == 0:
        assert not any(isinstance(e, Failed | Notice) and "parity" in str(e) for e in events)
    elif mode == "abort":
        assert events == [Failed(f"parity error in byte {byte:02X} (ISO code expected)")]
    else:
        assert events == [Notice("parity_error", f"{byte:02X}")]


@settings(max_examples=200, deadline=None)
@given(hs.integers(0, 255), hs.booleans(), hs.sampled_from(["ignore", "abort"]))
def test_bytes_before_the_percent(byte: int, iso: bool, bit7: str) -> None:
    """§2.6.3: characters before ``%`` are not considered; §2.6: a wrong baud rate or code is
    WERTBEREICHES-UEBERLAUF: ISO a parity error, ASCII a byte with bit 7 set that is no ISO
    character (any, with abort) or a control character a tape does not carry."""
    if byte & 0x7F == 0x25:
        return  # the '%' itself
    events = TapeReader(iso=iso, ascii_bit7=bit7).feed(bytes((byte,)))  # type: ignore[arg-type]
    even = bin(byte).count("1") % 2 == 0
    if iso:
        wrong = not even
    else:
        char = byte & 0x7F
        wrong = bool(byte & 0x80 and (bit7 == "abort" or not even)) or (char < 0x20 and char not in (0, 10, 13))
    assert [type(e) for e in events] == ([Failed] if wrong else [])


@settings(max_examples=200, deadline=None)
@given(hs.integers(0x80, 0xFF), hs.sampled_from(["ignore", "abort"]))
def test_ascii_bit_7_after_the_percent(byte: int, bit7: str) -> None:
    """ASCII code: bit 7 is masked where the byte is an ISO character (even parity), unless
    ``abort``; any other byte with bit 7 ends the transfer."""
    events = TapeReader(iso=False, ascii_bit7=bit7).feed(b"%N1" + bytes((byte,)) + b"\r")  # type: ignore[arg-type]
    if bit7 == "abort" or bin(byte).count("1") % 2:
        assert events == [Failed(f"byte {byte:02X} has bit 7 set (ASCII code expected)")]
    else:
        assert not any(isinstance(e, Failed) for e in events)


WORDS = {"X": hs.integers(-9_999_999, 9_999_999), "Y": hs.integers(-9_999_999, 9_999_999),
         "F": hs.integers(0, 9999), "S": hs.integers(0, 9999), "T": hs.integers(0, 99), "L": hs.integers(0, 99_999)}


@hs.composite
def _blocks(draw: hs.DrawFn) -> list[Block]:
    numbers = draw(hs.lists(hs.integers(0, 999), unique=True, max_size=5))
    blocks = []
    for number in numbers:
        letters = draw(hs.lists(hs.sampled_from(sorted(WORDS)), unique=True, max_size=4))
        words = [(letter, draw(WORDS[letter])) for letter in letters]
        words += [("G", g) for g in draw(hs.lists(hs.integers(0, 99), max_size=4))]
        words += [("M", m) for m in draw(hs.lists(hs.integers(0, 99).filter(lambda m: m != 30), max_size=2))]
        blocks.append(Block(number, tuple(words), draw(hs.booleans())))
    return blocks


def _canonical(block: Block) -> tuple[int, list[tuple[str, int]], list[int], list[int], bool]:
    others = sorted((k, v) for k, v in block.words if k not in "GM")
    return block.number, others, sorted(block.values("G")), sorted(block.values("M")), block.skip


@settings(max_examples=200, deadline=None)
@given(_blocks(), hs.booleans(), hs.booleans(), hs.sampled_from(["\r\n", "\r"]))
def test_what_a_transfer_sends_reads_back(blocks: list[Block], iso: bool, formatted: bool, eob: str) -> None:
    """§3.6 output read in by §3.5: ``%``, the blocks in ascending N, the M30 end; values at
    the limits of their formats survive (seven digits, signs, leading zeros of G/M/T)."""
    wire = render(blocks, iso=iso, formatted=formatted, formats=Formats(), eob=eob, leader_nul=2)
    assert wire[:2] == b"\x00\x00"
    events = TapeReader(iso=iso).feed(wire)
    assert events[-1] == Ended()
    read = [e.block for e in events if isinstance(e, BlockRead)]
    assert [_canonical(b) for b in read] == [_canonical(b) for b in sorted(blocks, key=lambda b: b.number)]
