"""POSELESTA programs as text (program entry ``program.P20``, a plant file) and as stored in the
state directory: the read-in rules of the tape (manual §2.6.3, spec poselesta.md §3.5) on text
typed a block a line, and the stored form of a block."""

from __future__ import annotations

import json

import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as hs

from devsim.devices.poselesta.tape import Block, Formats, parse_blocks

PROGRAM = ["N2 X-20 F750 G42", "N1 X0 Y43.144 F1002", "N4 G12 L1.1 #", "N2 X5"]
BLOCKS = [
    Block(1, (("X", 0), ("Y", 43144), ("F", 1002))),
    Block(2, (("X", 5000),)),  # the later N2 replaces the earlier (spec §3.5.3)
    Block(4, (("G", 12), ("L", 1100)), skip=True),
]


@pytest.mark.parametrize("eol", ["\n", "\r\n", "\r"])
def test_a_line_is_a_block_whatever_ends_it(eol: str) -> None:
    """§2.6.3: a block ends with CR, LF may follow; typed text ends its lines as it likes. The
    blocks come in ascending N, a repeated number replaces the block."""
    assert parse_blocks(eol.join(PROGRAM)) == BLOCKS
    assert parse_blocks(eol.join(PROGRAM) + eol + eol) == BLOCKS
    assert parse_blocks("") == [] and parse_blocks(eol) == []


@pytest.mark.parametrize("eol", ["\n", "\r\n", "\r"])
def test_a_value_before_any_address_belongs_to_no_word(eol: str) -> None:
    """Spec §3.5.2: a digit or sign with no word being read is skipped, at the start of the
    text as at the start of a line: it joins neither the word before the line end nor the next."""
    text = eol.join(["5 N1 Y1", "N3 X1", "-7 N2 Y2"])
    assert parse_blocks(text) == [Block(1, (("Y", 1000),)), Block(2, (("Y", 2000),)), Block(3, (("X", 1000),))]


@pytest.mark.manual("§2.6.3", "Die Datenein- und Ausgabe wird mit M 02 (Programmende) nicht unterbrochen, sondern erst mit M 30")
def test_m30_in_the_text_ends_it() -> None:
    assert parse_blocks("N1 X1\nN2 M02\nN3 X3") == [Block(1, (("X", 1000),)), Block(2, (("M", 2),)),
                                                    Block(3, (("X", 3000),))]
    assert parse_blocks("N1 X1\nM30\nN2 X2") == [Block(1, (("X", 1000),))]


def test_the_axes_decimals_place_the_point() -> None:
    formats = Formats({"X": 2, "Y": 3, "Z": 5, "D": 3})
    assert parse_blocks("N1 X12345.67 Z-.00001 K1.5", formats) == [
        Block(1, (("X", 1234567), ("Z", -1), ("K", 150000)))]
    with pytest.raises(ValueError, match="^WERTBEREICHES-UEBERLAUF: X1.234: beyond the format$"):
        parse_blocks("N1 X1.234", formats)


@pytest.mark.manual("§2.6", "WERTBEREICHES-UEBERLAUF")
def test_an_error_is_the_screen_message_and_why() -> None:
    with pytest.raises(ValueError) as raised:
        parse_blocks("N1 X1\nN2 Y1.2.3\nN3 X3")
    assert str(raised.value) == "WERTBEREICHES-UEBERLAUF: Y: a second decimal point"


@settings(max_examples=200, deadline=None)
@given(hs.lists(hs.tuples(hs.integers(0, len("\n".join(PROGRAM))), hs.characters(min_codepoint=0x80)), max_size=6))
@example([(4, "é")])  # E9 in latin-1: bit 7 with odd parity
@example([(4, "Ã")])  # C3 in latin-1: even parity, the "C" that erases a word
@example([(0, "€"), (30, "ü")])
@pytest.mark.manual("§2.6.3", "Falsche oder nicht definierte Zeichen werden überlesen")
def test_characters_beyond_ascii_are_skipped(inserted: list[tuple[int, str]]) -> None:
    """A character the control does not know is skipped wherever it stands, also one beyond
    ASCII (not read as an 8-bit byte whose bit 7 would end the read-in or be masked away)."""
    text = "\n".join(PROGRAM)
    for at, char in sorted(inserted, reverse=True):
        text = text[:at] + char + text[at:]
    assert parse_blocks(text) == BLOCKS


#: the values a read-in stores for a word (spec §3.4: 7 digits signed for coordinates and centres)
_VALUES = {**dict.fromkeys("XYZDIJK", (-9_999_999, 9_999_999)), "F": (0, 9_999), "S": (0, 9_999), "T": (0, 99),
           "G": (0, 99), "M": (0, 99), "L": (0, 99_999)}


@hs.composite
def _blocks(draw: hs.DrawFn) -> Block:
    """A block as a read-in stores it: at most 2 coordinates, 2 centres, 4 G and 2 M (not M30, which
    ends the tape), N F S T L once each."""
    letters = [*draw(hs.lists(hs.sampled_from("XYZD"), max_size=2, unique=True)),
               *draw(hs.lists(hs.sampled_from("IJK"), max_size=2, unique=True)),
               *draw(hs.lists(hs.sampled_from("FSTL"), unique=True)), *"G" * draw(hs.integers(0, 4)),
               *"M" * draw(hs.integers(0, 2))]
    words = [(k, draw(hs.integers(*_VALUES[k]).filter(lambda v, k=k: (k, v) != ("M", 30)))) for k in letters]
    return Block(draw(hs.integers(0, 999)), tuple(draw(hs.permutations(words))), draw(hs.booleans()))


@settings(max_examples=100, deadline=None)
@given(_blocks())
def test_a_stored_block_reads_back(block: Block) -> None:
    """The programs persist in the state directory as JSON, a block as {N, words, skip}."""
    stored = json.loads(json.dumps(block.to_json()))
    assert stored == {"N": block.number, "words": [[k, v] for k, v in block.words], "skip": block.skip}
    assert Block.from_json(stored) == block


def test_a_stored_block_without_skip_is_not_skipped() -> None:
    """A stored block without "skip" (a state file written by hand) runs; "skip" is the ``#``."""
    assert Block.from_json({"N": 3, "words": [["X", 1500], ["G", 1]]}) == Block(3, (("X", 1500), ("G", 1)))
    assert Block.from_json({"N": 3, "words": [], "skip": True}) == Block(3, (), True)
