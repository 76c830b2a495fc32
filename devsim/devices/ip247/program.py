"""The IP247's traverse programs: the record that carries one (manual §6.3.8.2; spec ip247.md
§3.4.2) and the language check at input, with the syntax error numbers (manual §2.6, §7.2; spec
§4.5, §4.11; vectors §6.4, §6.5).

Pure: :func:`record_words` / :func:`record_text` are the record, :func:`parse` reads a program
text into blocks or raises :class:`SyntaxFault` with the error number and the faulty block's
ordinal (1 = the first block after the header line, 0 = the header line).
"""

from __future__ import annotations

import re
from collections.abc import Callable

import msgspec

from devsim.core.kit import Command, Table

__all__ = ["MAX_TEXT", "Block", "Program", "SyntaxFault", "parse", "record_text", "record_words"]

MAX_TEXT = 1023  # characters of one program, header line included (§2.6.1)
MAX_BLOCK = 50  # characters of one block including its LF (§2.6.3)
#: G functions the module knows (spec §4.11.3); any other number is syntax error 37.
G_FUNCTIONS = frozenset((0, 4, 10, 20, 24, 25, 26, 27, 40, 43, 44, 53, 54, 55, 56, 57, 70, 71, 74, 90, 91))
ORDER = "NLGXFM"


class SyntaxFault(ValueError):
    """A program the module stores as faulty: ``errno`` (spec §4.5) and the block's ordinal."""

    def __init__(self, errno: int, block: int) -> None:
        super().__init__(f"syntax error {errno} in block {block}")
        self.errno, self.block = errno, block


class Block(msgspec.Struct, frozen=True):
    """One block: its ordinal, number, type and functions (absent: None).  X is in thousandths
    of the unit (base units); F and M as written."""

    ordinal: int
    number: int
    kind: str  # "N", "/N" or ":N" (all executed as N)
    call: int | None = None  # L progno
    g: int | None = None
    x: int | None = None
    f: int | None = None
    m: int | None = None


class Program(msgspec.Struct, frozen=True):
    number: int  # the header's number (documentary)
    main: bool  # "%" (main program) or "L" (subprogram), documentary
    comment: str
    blocks: tuple[Block, ...]


# -- the record ---------------------------------------------------------------------------------
def record_words(db: int, text: str, error: int = 0, faulty: int = 0) -> list[int]:
    """The program record: length, 00 'D', 'B' DB, error, faulty block, the text two
    characters per word, first in the high byte, an odd length padded with 00H."""
    data = text.encode("latin-1")
    if len(data) % 2:
        data += b"\x00"
    body = [data[i] << 8 | data[i + 1] for i in range(0, len(data), 2)]
    return [5 + len(body), 0x0044, 0x4200 | db, error, faulty, *body]


def record_text(words: list[int]) -> tuple[int, int, int, str]:
    """``(db, error, faulty block, text)`` of a record; the length word bounds the text."""
    if len(words) < 5 or words[1] != 0x0044 or words[2] >> 8 != 0x42:
        raise ValueError("not a program record (00 'D', 'B' DB expected in DW n+1, n+2)")
    length = min(words[0], len(words))
    data = bytes(b for w in words[5:length] for b in (w >> 8, w & 0xFF))
    return words[2] & 0xFF, words[3], words[4], data.rstrip(b"\x00").decode("latin-1")


# -- the language -------------------------------------------------------------------------------
_HEADER = re.compile(r"([%L])( *)(\d*)(.*)")
_BLOCK = re.compile(r" *(/N|:N|N)(\d*)(.*)")
_WORD = re.compile(r"([A-Z])([+-]?[0-9.]*)")


def parse(text: str) -> Program:
    """The program a text is, or :class:`SyntaxFault` (spec §4.5, first fault wins)."""
    if len(text) > MAX_TEXT:
        raise SyntaxFault(1, 0)
    lines = text.split("\n")
    terminated = text.endswith("\n")
    if terminated:
        lines.pop()
    header = _HEADER.fullmatch(lines[0]) if lines else None
    if header is None or not header[3]:
        raise SyntaxFault(2, 0)
    if len(header[3]) > 3 or int(header[3]) > 255:
        raise SyntaxFault(4, 0)
    if len(header[4].strip(" ")) > 58 or (len(lines) == 1 and not terminated):  # (not strip(): FS, NBSP)
        raise SyntaxFault(1, 0)
    blocks: list[Block] = []
    loops = 0
    ended = False
    for ordinal, line in enumerate(lines[1:], start=1):
        last = ordinal == len(lines) - 1
        if ended:
            raise SyntaxFault(18, ordinal)
        block = _block(ordinal, line)
        if len(line) + 1 > MAX_BLOCK:
            raise SyntaxFault(19, ordinal)
        if block.g == 24:
            loops += 1
        elif block.g == 20:
            if loops == 0:
                raise SyntaxFault(14, ordinal)
            loops -= 1
        if block.m == 2:
            if last and not terminated:
                raise SyntaxFault(8, ordinal)
            if loops:
                raise SyntaxFault(13, ordinal)
            ended = True
        elif last and not terminated:
            raise SyntaxFault(1, ordinal)
        blocks.append(block)
    if not ended:
        raise SyntaxFault(15, len(lines) - 1)
    return Program(int(header[3]), header[1] == "%", header[4].strip(" "), tuple(blocks))


def _block(ordinal: int, line: str) -> Block:
    match = _BLOCK.fullmatch(line.rstrip(" "))
    if match is None:
        raise SyntaxFault(2, ordinal)  # not N, /N or :N
    kind, digits, rest = match[1], match[2], match[3]
    if not digits:
        raise SyntaxFault(2, ordinal)
    if len(digits) > 3:
        raise SyntaxFault(3, ordinal)
    if rest and not rest.startswith(" "):
        raise SyntaxFault(9, ordinal)
    words: list[tuple[str, str]] = []
    for token in rest.split(" "):  # (blanks only: str.split() also splits at TAB, FS … US, NEL, NBSP)
        if not token:
            continue
        word = _WORD.fullmatch(token)
        if word is None:
            raise SyntaxFault(16, ordinal)
        if word[1] not in ORDER:
            raise SyntaxFault(16, ordinal)
        words.append((word[1], word[2]))
    values: dict[str, int] = {}
    seen: list[str] = []
    for letter, digits_text in words:
        if letter in seen or (seen and ORDER.index(letter) < ORDER.index(seen[-1])) or letter == "N":
            raise SyntaxFault(9, ordinal)  # twice, or out of the order N L G X F M
        seen.append(letter)
        values[letter] = _value(letter, digits_text, ordinal)
    _combination(values, seen, ordinal)
    return Block(ordinal, int(digits), kind, values.get("L"), values.get("G"), values.get("X"), values.get("F"),
                 values.get("M"))


def _value(letter: str, text: str, ordinal: int) -> int:
    return WORDS[letter](text, ordinal)


def _program_number(text: str, ordinal: int) -> int:
    if not text.isdigit():
        raise SyntaxFault(16, ordinal)
    if len(text) > 3 or int(text) > 255:
        raise SyntaxFault(4, ordinal)
    return int(text)


def _g_function(text: str, ordinal: int) -> int:
    if len(text) != 2 or not text.isdigit():
        raise SyntaxFault(16, ordinal)
    if int(text) not in G_FUNCTIONS:
        raise SyntaxFault(37, ordinal)
    return int(text)


def _path(text: str, ordinal: int) -> int:
    sign = -1 if text.startswith("-") else 1
    body = text.lstrip("+-")
    whole, point, fraction = body.partition(".")
    if not (whole or fraction) or not (whole + fraction).isdigit() or "." in fraction:
        raise SyntaxFault(16, ordinal)
    if len(whole.lstrip("0")) > 5:
        raise SyntaxFault(10, ordinal)
    if len(fraction) > 3:
        raise SyntaxFault(12, ordinal)
    return sign * (int(whole or "0") * 1000 + int(fraction.ljust(3, "0") or "0"))


def _feed(text: str, ordinal: int) -> int:
    if not text.isdigit():
        raise SyntaxFault(16, ordinal)
    if len(text) > 5 or int(text) > 65_000:
        raise SyntaxFault(11, ordinal)
    return int(text)


def _m_function(text: str, ordinal: int) -> int:
    if not text.isdigit():
        raise SyntaxFault(16, ordinal)
    if len(text) > 2:
        raise SyntaxFault(17, ordinal)
    return int(text)


#: A word's reader: (its digits, the block's ordinal) → its value, or :class:`SyntaxFault`.
WordReader = Callable[[str, int], int]

#: The words of a block after N, in their order (manual §2.6.4–§2.6.9; spec §4.11.2): each reads its value.
WORDS: Table[WordReader] = Table([
    Command("L", _program_number, "§2.6.5", "subprogram call: program 0 … 255 (syntax error 4)"),
    Command("G", _g_function, "§2.6.6", "G function, two digits, one the module knows (syntax error 37)"),
    Command("X", _path, "§2.6.7", "path in the axis unit, at most 5 + 3 places (syntax errors 10, 12)"),
    Command("F", _feed, "§2.6.8", "velocity, dwell or repetitions, at most 65000 (syntax error 11)"),
    Command("M", _m_function, "§2.6.9", "M function, two digits (syntax error 17)"),
])


def _combination(values: dict[str, int], seen: list[str], ordinal: int) -> None:
    """The rules of spec §4.11.4 / the decisions of §4.5 (codes 5, 6, 9, 11)."""
    after = seen[seen.index("G") + 1 :] if "G" in seen else []
    g = values.get("G")
    if "L" in seen and seen[-1] != "L":
        raise SyntaxFault(9, ordinal)  # nothing after L
    if g == 0 and (after[:1] != ["X"] or "F" in after):
        raise SyntaxFault(5, ordinal)
    if g == 4 and ("X" in after or "F" not in after):
        raise SyntaxFault(5, ordinal)
    if g == 20 and after:
        raise SyntaxFault(5, ordinal)
    if g == 24 and (after[:1] != ["F"] or [w for w in after if w not in ("F", "M")]):
        raise SyntaxFault(5, ordinal)
    if g == 24 and "M" in after:
        raise SyntaxFault(9, ordinal)
    if g == 74 and "X" in after:
        raise SyntaxFault(5, ordinal)
    if "X" in seen and g != 0 and "F" not in seen:
        raise SyntaxFault(6, ordinal)
    if "F" in seen and "X" not in seen and g not in (4, 24, 74):
        raise SyntaxFault(9, ordinal)
    if values.get("F") == 0 and g != 24:
        raise SyntaxFault(11, ordinal)  # F0 as a velocity or a dwell
