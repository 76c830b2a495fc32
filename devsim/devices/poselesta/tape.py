"""NC tape images: reading a program in (T3, T5, T7) and writing one out (T2, T4, T6), manual
§2.6.2.3 and §2.6.3; spec poselesta.md §3.3–§3.6 (state machine, word assembly, block commit,
parity errors, output format) and the vectors of §6.6–§6.8.

Pure and incremental: :class:`TapeReader` takes the bytes as they arrive and returns what they
mean (blocks, the end, a failure); :func:`render` turns stored blocks into the bytes a transfer
sends.  No clock, no I/O.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping
from typing import Any, Literal

import msgspec

from devsim.core.kit import Command, Table
from devsim.devices.poselesta.codes import WERTBEREICHES_UEBERLAUF, encode, parity_ok

__all__ = [
    "BLOCK_FORMAT",
    "Block",
    "BlockRead",
    "Ended",
    "Failed",
    "Formats",
    "Notice",
    "TapeReader",
    "block_words",
    "parse_blocks",
    "render",
]

COORDINATES = "XYZD"
CENTRES = "IJK"  # I ↔ X, J ↔ Y, K ↔ Z (absolute centre coordinates, spec §6.6)
#: The most words of a kind one block holds (manual §2.6.3, spec §3.4: "maximal ... 2 Koordinaten,
#: 2 Hilfskoordinaten, 4 G-Funktionen, 2 M-Funktionen"); beyond: WERTBEREICHES-UEBERLAUF.  The
#: one-per-block words (N, F, S, T, L) are replaced by a repeat (a ``duplicate_word`` notice).
BLOCK_FORMAT: tuple[tuple[str, int], ...] = ((COORDINATES, 2), (CENTRES, 2), ("G", 4), ("M", 2))
ADDRESS_LETTERS_ORDER = "NXYZDIJKFSGMTL"
ADDRESS_LETTERS = frozenset(ADDRESS_LETTERS_ORDER)
SIGNED = frozenset(COORDINATES + CENTRES + "P")
#: Output order inside a block (spec §3.6, G-ORDER): N X Y Z D I J K F S T G M L #; P is the
#: value word of the parameter catalogue P99 (spec §3.9, simulator-defined).
ORDER = "NPXYZDIJKFSTGML"
#: The catalogue's value word: signed, 5 digits before the point and 3 after (spec §3.9).
CATALOGUE_VALUE = "P"
#: the letters a stored block's words may have (N is the block's number, not a word; P only the
#: catalogue's, which is no stored program)
_WORD_LETTERS = frozenset(ORDER[2:])
CR, LF, NUL, DEL, SP = 0x0D, 0x0A, 0x00, 0x7F, 0x20


class Formats(msgspec.Struct, frozen=True):
    """Digits before and after the point per address (§2.6.3: 7 significant digits, the point
    placed by each axis's resolution; N xxx, G/M/T xx, F/S xxxx, L xx.xxx)."""

    decimals: Mapping[str, int] = msgspec.field(default_factory=lambda: dict.fromkeys(COORDINATES, 3))
    #: Catalogue parameters whose value word keeps its three decimals on output, whole or not
    #: (``N9 P250.000``: "decimals as the parameter's unit requires", spec §3.9); the others' whole
    #: values are written without them (``N44 P6000``).
    fractional: frozenset[int] = frozenset()

    def of(self, letter: str) -> tuple[int, int]:
        if letter in COORDINATES:
            d = self.decimals[letter]
            return 7 - d, d
        if letter in CENTRES:
            d = self.decimals["XYZ"[CENTRES.index(letter)]]
            return 7 - d, d
        return {"N": (3, 0), "G": (2, 0), "M": (2, 0), "T": (2, 0), "F": (4, 0), "S": (4, 0), "L": (2, 3),
                "P": (5, 3)}[letter]


#: The digits of each word (a coordinate's seven, whatever its decimals): what a stored word may have.
_DIGITS = Formats()


class Block(msgspec.Struct, frozen=True):
    """One NC block: its number and its words.  Coordinates and L are integers in units of the
    last decimal (``X 10.500`` with 3 decimals is 10500); G and M keep their order of arrival."""

    number: int
    words: tuple[tuple[str, int], ...] = ()
    skip: bool = False

    def value(self, letter: str) -> int | None:
        for key, value in self.words:
            if key == letter:
                return value
        return None

    def values(self, letter: str) -> list[int]:
        return [value for key, value in self.words if key == letter]

    def to_json(self) -> dict[str, Any]:
        return {"N": self.number, "words": [list(w) for w in self.words], "skip": self.skip}

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> Block:
        """A stored block; one a read-in or program entry never stores (a hand-edited state file)
        is a ValueError (the start refuses the memory): a word whose letter no block has, which
        failed every output of the program, or what the control served as a program it cannot
        read back (a value beyond its word's digits, a sign where none is allowed, more words of
        a kind than a block holds, a word twice but G and M, the M30 that ends a tape)."""
        number, words = data["N"], tuple((str(k), v) for k, v in data["words"])
        for letter, value in (("N", number), *words):
            if letter not in _WORD_LETTERS | {"N"}:
                raise ValueError(f"block N{number}: {letter!r} is no address letter ({ORDER[1:]})")
            if type(value) is not int or abs(value) >= 10 ** sum(_DIGITS.of(letter)) or \
                    value < 0 and letter not in SIGNED:
                raise ValueError(f"block N{number}: {letter}{value!r} is beyond the format")
        letters = [letter for letter, _ in words]
        if any(letters.count(letter) > 1 for letter in letters if letter not in "GM") or ("M", 30) in words or any(
                sum(letter in kinds for letter in letters) > most for kinds, most in BLOCK_FORMAT):
            raise ValueError(f"block N{number}: {' '.join(letters)} is no block a read-in stores")
        skip = data.get("skip", False)
        if type(skip) is not bool:
            raise ValueError(f"block N{number}: skip {skip!r} is no yes or no")
        return cls(number, words, skip)


# -- what the reader reports ------------------------------------------------------------------
class BlockRead(msgspec.Struct, frozen=True):
    block: Block


class Ended(msgspec.Struct, frozen=True):
    """The ``M30`` block arrived: the transfer is complete."""


class Failed(msgspec.Struct, frozen=True):
    """The transfer stops with the screen message (``WERTBEREICHES-UEBERLAUF``)."""

    reason: str
    message: str = WERTBEREICHES_UEBERLAUF


class Notice(msgspec.Struct, frozen=True):
    """Something a host developer may want to know that changes nothing (an empty word, a
    block without number, a duplicate word, comment characters)."""

    what: str
    detail: str = ""


Event = BlockRead | Ended | Failed | Notice


class _Word(msgspec.Struct):
    letter: str
    digits: str = ""
    negative: bool = False
    sign_invalid: bool = False


class TapeReader:
    """Program read-in after the start of a transfer (spec §3.5): wait for ``%``, then words,
    blocks and the ``M30`` end.  ``iso`` selects ISO code (parity checked after ``%``) or
    ASCII (bit 7 masked, or refused with ``ascii_bit7="abort"``)."""

    def __init__(
        self,
        *,
        iso: bool,
        formats: Formats | None = None,
        parity_error: Literal["abort", "skip"] = "abort",
        ascii_bit7: Literal["ignore", "abort"] = "ignore",
        strict_block_numbers: bool = False,
        catalogue: bool = False,
    ) -> None:
        self.iso = iso
        self._characters = CATALOGUE_CHARACTERS if catalogue else CHARACTERS
        self.formats = formats or Formats()
        self.parity_error = parity_error
        self.ascii_bit7 = ascii_bit7
        self.strict_block_numbers = strict_block_numbers
        self.started = False
        self.finished = False
        self._word: _Word | None = None
        self._words: list[tuple[str, int]] = []
        self._skip = False
        self._comment_seen = False

    def feed(self, data: bytes) -> list[Event]:
        events: list[Event] = []
        for byte in data:
            if self.finished:
                break
            if not self.started:
                if byte & 0x7F == 0x25:  # '%' recognised on its 7 bits (§3.5.1)
                    self.started = True
                    continue
                problem = self._line_error(byte)
                if problem is not None:
                    self._fail(events, f"before %: {problem} (wrong baud rate or code?)")
                continue
            char = self._character(byte, events)
            if char is not None:
                self._interpret(char, events)
        return events

    def _line_error(self, byte: int) -> str | None:
        """Why a byte before ``%`` cannot have come from a sender with the control's baud rate and
        code (manual §2.6: "Wird vor dem Einlesen eines Programmes eine falsche Baud-Rate oder ein
        falscher Code gewählt, erscheint am Bildschirm: WERTBEREICHES-UEBERLAUF"), or None for a
        character of the code, which is ignored (§2.6.3: "Alle vorgängig eintreffenden Zeichen
        werden nicht berücksichtigt").  ISO: a parity error.  ASCII: a byte with bit 7 set that is
        no ISO character either (odd parity; ``ascii_bit7="abort"``: any).  Every 7-bit character
        is one a sender set to ASCII sends (a DNC host's DC2 or DC4 for the tape, a label, CR LF)
        and is ignored.  The pty cannot carry the framing errors a real UART sees at a wrong baud
        rate, and these bytes are what such a line delivers in their place (see the deviations)."""
        if self.iso:
            if not parity_ok(byte) and self.parity_error == "abort":
                return f"parity error in byte {byte:02X}"
            return None
        if byte & 0x80 and (self.ascii_bit7 == "abort" or not parity_ok(byte)):
            return f"byte {byte:02X} is no character of ASCII code"
        return None

    def _character(self, byte: int, events: list[Event]) -> int | None:
        """The 7-bit character of a byte after ``%`` (§3.5.4), None if it is dropped."""
        if self.iso:
            if not parity_ok(byte):
                if self.parity_error == "skip":
                    events.append(Notice("parity_error", f"{byte:02X}"))
                    return None
                self._fail(events, f"parity error in byte {byte:02X} (ISO code expected)")
                return None
        elif byte & 0x80 and (self.ascii_bit7 == "abort" or not parity_ok(byte)):
            # bit 7 is masked only where the byte is an ISO character (even parity): a byte
            # that is neither ASCII nor ISO comes from a wrong baud rate (§2.6)
            self._fail(events, f"byte {byte:02X} has bit 7 set (ASCII code expected)")
            return None
        return byte & 0x7F

    def _fail(self, events: list[Event], reason: str) -> None:
        self.finished = True
        events.append(Failed(reason))

    def _interpret(self, char: int, events: list[Event]) -> None:
        c = chr(char)
        handler = self._characters.get(c)
        if handler is not None:
            handler(self, c, events)  # anything else (LF, NUL, DEL, SP, …) is dropped

    # -- the characters of a tape (spec §3.5.2–§3.5.4) ----------------------------------------------
    def _letter(self, c: str, events: list[Event]) -> None:
        self._finish_word(events)
        self._word = _Word(c)

    def _sign(self, c: str, _events: list[Event]) -> None:
        word = self._word
        if word is None or word.digits:
            return  # a sign in an undefined position: skipped
        if word.letter in SIGNED:
            word.negative = c == "-"
        else:
            word.sign_invalid = True

    def _digit(self, c: str, events: list[Event]) -> None:
        word = self._word
        if word is None:
            return
        if c == "." and "." in word.digits:
            self._fail(events, f"{word.letter}: a second decimal point")
            return
        word.digits += c

    def _clear(self, _c: str, _events: list[Event]) -> None:
        word = self._word
        if word is not None:
            word.digits, word.negative, word.sign_invalid = "", False, False

    def _skip_mark(self, _c: str, _events: list[Event]) -> None:
        self._skip = True

    def _end_of_block(self, _c: str, events: list[Event]) -> None:
        self._finish_word(events)
        if not self.finished:
            self._commit(events)

    def _comment(self, c: str, events: list[Event]) -> None:
        if not self._comment_seen:
            self._comment_seen = True
            events.append(Notice("comment_characters_seen", c))

    def _finish_word(self, events: list[Event]) -> None:
        word, self._word = self._word, None
        if word is None or self.finished:
            return
        if not word.digits or word.digits == ".":
            events.append(Notice("empty_word", word.letter))
            return
        if word.sign_invalid:
            self._fail(events, f"{word.letter}: a sign is not allowed")
            return
        whole, _, fraction = word.digits.partition(".")
        whole, fraction = whole.lstrip("0"), fraction.rstrip("0")
        before, after = self.formats.of(word.letter)
        if len(whole) > before or len(fraction) > after:
            self._fail(events, f"{word.letter}{'-' if word.negative else ''}{word.digits}: beyond the format")
            return
        value = int(whole or "0") * 10**after + int((fraction or "0").ljust(after, "0")[:after] or "0")
        if word.negative:
            value = -value
        if word.letter not in "GM":
            if any(k == word.letter for k, _ in self._words):
                events.append(Notice("duplicate_word", word.letter))
                self._words = [(k, v) for k, v in self._words if k != word.letter]
        self._words.append((word.letter, value))

    def _commit(self, events: list[Event]) -> None:
        words, skip = self._words, self._skip
        self._words, self._skip = [], False
        if not words:
            return  # an empty block: ignored
        letters = [k for k, _ in words]
        if ("M", 30) in words:
            self.finished = True
            events.append(Ended())
            return
        for kinds, most in BLOCK_FORMAT:
            if sum(letter in kinds for letter in letters) > most:
                self._fail(events, f"more than {most} words of {kinds} in a block")
                return
        number = next((v for k, v in words if k == "N"), None)
        if number is None:
            if self.strict_block_numbers:
                self._fail(events, "a block without number")
            else:
                events.append(Notice("block_without_number"))
            return
        rest = tuple((k, v) for k, v in words if k != "N")
        events.append(BlockRead(Block(number, rest, skip)))


CharacterHandler = Callable[[TapeReader, str, list[Event]], None]


#: What each character after ``%`` does (spec §3.5.2–§3.5.4, manual §2.6.3).  Anything not in
#: the table (LF, NUL, DEL, SP, lower case, a later ``%``, …) is dropped.
CHARACTERS: Table[CharacterHandler] = Table([
    *(Command(letter, TapeReader._letter, "§2.6.3", f"address {letter}: starts a word")
      for letter in ADDRESS_LETTERS_ORDER),
    *(Command(sign, TapeReader._sign, "§2.6.3", "sign of the word (X Y Z D I J K P only)") for sign in "-+"),
    *(Command(digit, TapeReader._digit, "§2.6.3", "a digit or the decimal point of the word")
      for digit in "0123456789."),
    Command("C", TapeReader._clear, "§2.6.3", "clears the word being read"),
    Command("#", TapeReader._skip_mark, "§2.3.13", "marks the block as skippable (/ on the screen)"),
    Command("\r", TapeReader._end_of_block, "§2.6.3", "CR: end of block"),
    *(Command(c, TapeReader._comment, "§2.6.3", "a comment character: noticed once, dropped") for c in "();:/"),
])
#: The characters of the parameter catalogue P99: those of a program and its value word P
#: (spec §3.9, simulator-defined).
CATALOGUE_CHARACTERS: Table[CharacterHandler] = Table([
    *CHARACTERS,
    Command(CATALOGUE_VALUE, TapeReader._letter, "§2.6.2.3", "the value word of a catalogue block (spec §3.9)"),
])


# -- output -----------------------------------------------------------------------------------
def _value_text(letter: str, value: int, formats: Formats, number: int) -> tuple[str, str]:
    """(sign, digits) of a word of block ``number`` on output (spec §3.6)."""
    before, after = formats.of(letter)
    sign = "-" if value < 0 else ""
    value = abs(value)
    if letter in "GMT":
        return sign, f"{value:02d}"
    if after == 0 or letter == CATALOGUE_VALUE and value % 10**after == 0 and number not in formats.fractional:
        return sign, str(value // 10**after)
    whole, fraction = divmod(value, 10**after)
    return sign, f"{whole}.{fraction:0{after}d}"


def block_words(block: Block, formats: Formats, *, formatted: bool) -> list[str]:
    """The words of a block on output, in the order of spec §3.6 (``X- 20.000`` formatted,
    ``X-20.000`` not)."""
    gap = " " if formatted else ""
    items = [("N", block.number), *block.words]
    rank = {letter: i for i, letter in enumerate(ORDER)}
    ordered = sorted(items, key=lambda kv: (rank[kv[0]], kv[1] if kv[0] in "GM" else 0))
    words = []
    for letter, value in ordered:
        sign, digits = _value_text(letter, value, formats, block.number)
        words.append(f"{letter}{sign}{gap}{digits}")
    if block.skip:
        words.append("#")
    return words


def render(
    blocks: Iterable[Block],
    *,
    iso: bool,
    formatted: bool,
    formats: Formats | None = None,
    eob: str = "\r\n",
    leader_nul: int = 0,
    trailer_nul: int = 0,
) -> bytes:
    """A program as a transfer sends it: ``%``, the blocks in ascending N, the generated
    ``M30`` block (manual §2.6.3: "M 30 wird automatisch … ausgegeben"), each ended by ``eob``."""
    formats = formats or Formats()
    gap = " " if formatted else ""
    lines = ["%"]
    for block in sorted(blocks, key=lambda b: b.number):
        lines.append(gap.join(block_words(block, formats, formatted=formatted)))
    lines.append(f"M{gap}30")
    text = "".join(line + eob for line in lines)
    return b"\x00" * leader_nul + encode(text, iso) + b"\x00" * trailer_nul


def parse_blocks(text: str, formats: Formats | None = None) -> list[Block]:
    """Blocks typed as text (program entry, a plant file): the read-in rules of §3.5 on
    ``% text M30``, in ASCII, a line a block; raises ValueError with the screen message on an
    error.  A character beyond ASCII is one the control does not know: skipped like any other
    (manual §2.6.3: "Falsche oder nicht definierte Zeichen werden überlesen"), not read as the
    byte of some 8-bit code (where bit 7 would end the read-in, or be masked into a letter)."""
    reader = TapeReader(iso=False, formats=formats)
    body = text.replace("\r\n", "\n").replace("\n", "\r")
    events = reader.feed(("%\r" + body + "\rM30\r").encode("ascii", errors="replace"))
    blocks: dict[int, Block] = {}
    for event in events:
        if isinstance(event, Failed):
            raise ValueError(f"{event.message}: {event.reason}")
        if isinstance(event, BlockRead):
            blocks[event.block.number] = event.block
    return [block for _, block in sorted(blocks.items())]
