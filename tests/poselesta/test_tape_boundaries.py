"""POSELESTA tape images at their limits, by property (manual §2.6, §2.6.3; spec poselesta.md
§3.4–§3.6).

Words are generated at and around their format (N three digits, G/M/T two, F/S four, L 2.3,
coordinates seven significant digits with the axis's decimals), blocks at and around the most
words of a kind (2 coordinates, 2 centres, 4 G, 2 M), bytes around the codes' rules (ISO even
parity, ASCII bit 7, bytes before ``%``), and compared with the rules written here.
"""

from __future__ import annotations

import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as hs

from devsim.devices.poselesta.tape import (
    Block,
    BlockRead,
    Ended,
    Failed,
    Formats,
    Notice,
    TapeReader,
    block_words,
    render,
)

#: Digits before and after the point (manual §2.6.3, 3 decimals on every axis).
FORMAT = {"N": (3, 0), "G": (2, 0), "M": (2, 0), "T": (2, 0), "F": (4, 0), "S": (4, 0), "L": (2, 3),
          "X": (4, 3), "Y": (4, 3), "Z": (4, 3), "D": (4, 3), "I": (4, 3), "J": (4, 3), "K": (4, 3),
          "P": (5, 3)}  # P: the value word of the catalogue P99 (spec §3.9), read with catalogue=True
#: Only coordinates, centres and the catalogue's value take a sign (spec §3.4).
SIGNED = "XYZDIJKP"
MOST = {"XYZD": 2, "IJK": 2, "G": 4, "M": 2}


def _even(byte: int) -> int:
    """ISO code: bit 7 makes the number of ones even."""
    return byte | 0x80 if bin(byte).count("1") % 2 else byte


def _read(text: str, iso: bool = False, **options: object) -> list[object]:
    data = bytes(_even(b) for b in text.encode()) if iso else text.encode()
    return TapeReader(iso=iso, **options).feed(data)  # type: ignore[arg-type]


@settings(max_examples=400, deadline=None)
@given(hs.sampled_from(sorted(FORMAT)), hs.data())
def test_a_word_at_the_edge_of_its_format(letter: str, data: hs.DataObject) -> None:
    """§2.6.3: the digits a word may have before and after the point, leading zeros and zeros
    after the point not counted; one more is WERTBEREICHES-UEBERLAUF, and the failure names the
    word as it came (P: the catalogue's value word, 5.3 digits, spec §3.9)."""
    before, after = FORMAT[letter]
    whole = data.draw(hs.integers(0, before + 1))  # significant digits before the point
    fraction = data.draw(hs.integers(0, after + 1))
    zeros = data.draw(hs.integers(0, 2))  # leading zeros and trailing zeros do not count
    negative = letter in SIGNED and data.draw(hs.booleans())
    _check_word(letter, whole, fraction, zeros, negative)


@pytest.mark.parametrize("letter", sorted(FORMAT))
def test_every_word_at_its_edges(letter: str) -> None:
    """Each word with as many digits as its format holds and one more, before the point and
    after, with leading and trailing zeros that do not count, with and without a sign."""
    before, after = FORMAT[letter]
    for whole in (before - 1, before, before + 1):
        for fraction in sorted({0, after, after + 1}):
            for zeros in (0, 2):
                for negative in ({False, True} if letter in SIGNED else {False}):
                    _check_word(letter, whole, fraction, zeros, negative)


def _check_word(letter: str, whole: int, fraction: int, zeros: int, negative: bool) -> None:
    before, after = FORMAT[letter]
    digits = "0" * zeros + "9" * whole + ("." + "5" * fraction + "0" * zeros if fraction or zeros else "")
    if not whole and not fraction and not zeros:
        digits = "0"
    sign = "-" if negative else ""
    text = f"%\rN1 {letter}{sign}{digits}\r" if letter != "N" else f"%\rN{digits}\r"
    events = _read(text, catalogue=letter == "P")
    if whole > before or fraction > after:
        assert events == [Failed(f"{letter}{sign}{digits}: beyond the format")]
        return
    value = int("9" * whole or "0") * 10**after + int(("5" * fraction).ljust(after, "0") or "0")
    if letter == "N":
        assert events == [BlockRead(Block(value))]
    elif letter == "M" and value == 30:
        assert events == [Ended()]
    else:
        assert events == [BlockRead(Block(1, ((letter, -value if negative else value),)))]


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


@pytest.mark.parametrize("sign", ["-", "+"])
@pytest.mark.parametrize(("letter", "signed"), [("X", True), ("I", True), ("K", True), ("D", True), ("F", False),
                                                 ("N", False), ("G", False), ("S", False), ("T", False), ("L", False)])
def test_only_coordinates_take_a_sign(letter: str, signed: bool, sign: str) -> None:
    """Spec §3.4: a sign (``-``, or ``+`` that changes nothing) belongs to X Y Z D I J K only;
    on N F S G M T L it is WERTBEREICHES-UEBERLAUF."""
    events = _read(f"%\rN1 {letter}{sign}12\r" if letter != "N" else f"%\rN{sign}12\r")
    if signed:
        assert events == [BlockRead(Block(1, ((letter, (-12000 if sign == "-" else 12000)),)))]
    else:
        assert events == [Failed(f"{letter}: a sign is not allowed")]


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
    character (any, with abort); every 7-bit character is ignored on an ASCII port."""
    if byte & 0x7F == 0x25:
        return  # the '%' itself
    events = TapeReader(iso=iso, ascii_bit7=bit7).feed(bytes((byte,)))  # type: ignore[arg-type]
    even = bin(byte).count("1") % 2 == 0
    if iso:
        wrong_byte = not even
    else:
        wrong_byte = bool(byte & 0x80 and (bit7 == "abort" or not even))
    assert [type(e) for e in events] == ([Failed] if wrong_byte else [])
    if wrong_byte:  # the event names the byte
        reason = events[0].reason
        assert reason.startswith("before %: ") and f"{byte:02X}" in reason
        assert reason.endswith("(wrong baud rate or code?)")


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


# -- every character after the % (spec §3.3, manual §2.6.3) ----------------------------------
#: The address letters of a program (§2.6.3); P only in the catalogue P99 (spec §3.9).
LETTERS = "NXYZDIJKFSGMTL"


def _meaning(char: str, catalogue: bool) -> Block:
    """The block ``N1 X2<char>5`` CR is, by the table of spec §3.3: an address letter ends X2
    and starts a word of its own; a digit or the point is part of X's value; C erases X's value
    so far; # marks the block as skippable; CR ends the block (the 5 after it belongs to no
    word); every other character — a sign after digits, lower case, controls, SP, DEL, a later
    %, comment characters, P in a program — is skipped, so 2 and 5 are one value."""
    if char in LETTERS or catalogue and char == "P":
        if char == "N":
            return Block(5, (("X", 2000),))
        if char == "X":
            return Block(1, (("X", 5000),))  # the later X replaces the earlier
        return Block(1, (("X", 2000), (char, 5 * 10 ** FORMAT[char][1])))
    if char.isdigit():
        return Block(1, (("X", int(f"2{char}5") * 1000),))
    meaning = {".": Block(1, (("X", 2500),)), "C": Block(1, (("X", 5000),)), "#": Block(1, (("X", 25000),), True),
               "\r": Block(1, (("X", 2000),))}
    return meaning.get(char, Block(1, (("X", 25000),)))


@pytest.mark.manual("§2.6.3", "Falsche oder nicht definierte Zeichen werden überlesen")
@pytest.mark.parametrize("catalogue", [False, True])
def test_what_every_character_after_the_percent_does(catalogue: bool) -> None:
    for code in range(128):
        char = chr(code)
        events = TapeReader(iso=False, catalogue=catalogue).feed(f"%\rN1 X2{char}5\r".encode())
        blocks = [e.block for e in events if isinstance(e, BlockRead)]
        assert blocks == [_meaning(char, catalogue)], f"{code:02X}"
        notices = [e for e in events if isinstance(e, Notice)]
        if char in "();:/":
            assert notices == [Notice("comment_characters_seen", char)], f"{code:02X}"
        elif char in "NX":
            assert notices == [Notice("duplicate_word", char)], f"{code:02X}"
        else:
            assert notices == [] and not any(isinstance(e, Failed) for e in events), f"{code:02X}"


@pytest.mark.manual("§2.6.3", "Die Datenübertragung beginnt mit einem %-Zeichen")
@pytest.mark.parametrize("iso", [False, True])
def test_the_first_block_may_follow_the_percent_directly(iso: bool) -> None:
    """Nothing but the ``%`` is asked before the first block: one without ``#`` that follows it
    on the same line is no skippable block, and the first comment character is noticed."""
    assert _read("%N1 X1\rN2 X2 #\rN3 X3\r", iso=iso) == [
        BlockRead(Block(1, (("X", 1000),))), BlockRead(Block(2, (("X", 2000),), True)),
        BlockRead(Block(3, (("X", 3000),))),
    ]
    assert _read("%(P20)N1 X1\r", iso=iso) == [Notice("comment_characters_seen", "("),
                                              BlockRead(Block(1, (("X", 1000),)))]


def test_notices_and_failures_name_what_they_saw() -> None:
    """What a host developer sees in the events (spec §3.5.2/§3.5.3): the letter of an empty
    word (also a lone point) and of a repeated one, the comment character, and why the transfer
    stopped."""
    assert _read("%\rN1 X Y2 X. (a)\rN2 Y3 Y4\r") == [
        Notice("empty_word", "X"), Notice("comment_characters_seen", "("), Notice("empty_word", "X"),
        BlockRead(Block(1, (("Y", 2000),))), Notice("duplicate_word", "Y"), BlockRead(Block(2, (("Y", 4000),))),
    ]
    assert _read("%\rN1 Y1.2.3\r") == [Failed("Y: a second decimal point")]
    assert _read("%\rN1 X1\rX4\r", strict_block_numbers=True) == [BlockRead(Block(1, (("X", 1000),))),
                                                                 Failed("a block without number")]
    assert _read("%\rX4\r") == [Notice("block_without_number")]


# -- output (spec §3.6) -------------------------------------------------------------------------
#: The order of the words in a block on output (spec §3.6, from the manual's listing): G and M
#: ascending among themselves, the skip mark last.
OUTPUT_ORDER = "NXYZDIJKFSTGML"


@hs.composite
def _shuffled_block(draw: hs.DrawFn) -> Block:
    others = draw(hs.lists(hs.sampled_from(sorted(WORDS)), unique=True, max_size=len(WORDS)))
    words = [(letter, draw(WORDS[letter])) for letter in others]
    words += [("G", g) for g in draw(hs.lists(hs.integers(0, 99), min_size=0, max_size=4))]
    words += [("M", m) for m in draw(hs.lists(hs.integers(0, 99), max_size=2))]
    return Block(draw(hs.integers(0, 999)), tuple(draw(hs.permutations(words))), draw(hs.booleans()))


@settings(max_examples=200, deadline=None)
@given(_shuffled_block(), hs.booleans())
@example(Block(7, (("M", 8), ("G", 90), ("X", 1), ("G", 1), ("M", 3), ("F", 5))), False)
def test_the_words_of_a_block_go_out_in_the_order_of_the_listing(block: Block, formatted: bool) -> None:
    words = block_words(block, Formats(), formatted=formatted)
    if block.skip:
        assert words[-1] == "#"
        words = words[:-1]
    assert "#" not in words
    letters = [w[0] for w in words]
    assert letters == sorted(letters, key=OUTPUT_ORDER.index) and letters[0] == "N"
    for kind in "GM":
        values = [int(w[1:]) for w in words if w[0] == kind]
        assert values == sorted(block.values(kind))


@pytest.mark.manual("§2.6.2.3", "die Abstände zwischen den einzelnen Funktionen werden mit Leerzeichen (space) ausgefüllt")
def test_a_skippable_block_ends_with_its_mark() -> None:
    """The ``#`` goes out as the last word of its block (spec §3.6, the printer example of
    §2.6.2.1), formatted and not."""
    block = Block(5, (("G", 1), ("X", -5000)), skip=True)
    assert render([block], iso=False, formatted=True) == b"%\r\nN 5 X- 5.000 G 01 #\r\nM 30\r\n"
    assert render([block], iso=False, formatted=False, eob="\r") == b"%\rN5X-5.000G01#\rM30\r"


@settings(max_examples=100, deadline=None)
@given(hs.integers(0, 5), hs.integers(0, 5), hs.booleans())
def test_leader_and_trailer(leader: int, trailer: int, iso: bool) -> None:
    """Blank tape (NUL) before the ``%`` and after the last CR LF, as many as asked (spec §3.6)."""
    wire = render([], iso=iso, formatted=False, leader_nul=leader, trailer_nul=trailer)
    end = b"\x8d\x0a" if iso else b"\r\n"
    percent = b"\xa5" if iso else b"%"  # M, 3 and 0 have even parity: the same bytes in both codes
    assert wire == b"\x00" * leader + percent + end + b"M30" + end + b"\x00" * trailer


@settings(max_examples=300, deadline=None)
@given(hs.integers(-99_999_999, 99_999_999), hs.booleans())
@example(0, False)
@example(6_000_000, False)
@example(1_331, False)
@example(1_500, True)
@example(-250_000, True)
@example(99_999_999, False)
def test_a_catalogue_value_goes_out_whole_or_with_three_decimals(value: int, formatted: bool) -> None:
    """The catalogue P99 (spec §3.9, docs "N44P6000"): a whole value without decimals, any
    other with its three, and the control reads back what it wrote."""
    sign, whole, fraction = "-" if value < 0 else "", abs(value) // 1000, abs(value) % 1000
    text = f"{whole}" if fraction == 0 else f"{whole}.{fraction:03d}"
    gap = " " if formatted else ""
    block = Block(44, (("P", value),))
    assert block_words(block, Formats(), formatted=formatted) == [f"N{gap}44", f"P{sign}{gap}{text}"]
    wire = render([block], iso=False, formatted=formatted)
    assert TapeReader(iso=False, catalogue=True).feed(wire) == [BlockRead(block), Ended()]
