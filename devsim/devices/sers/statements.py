"""The SERS statement language: parsing a line's text into statements (manual §4.2).

Pure functions, no I/O.  :func:`parse` reads the text of one line (after ``#`` and the drive
address) and returns the statements found so far.  It is meant to be called again as each
character arrives: with ``final=False`` a statement that might still grow (``W=50`` could
become ``W=500``, ``E`` could become ``ELSE``, ``P11?`` could become ``P11??``) is reported as
pending instead of complete, which is how the device executes statements "before the CR"
(§4.1) without executing them too early.

Tokenisation follows spec G-TOKEN: keywords are case-insensitive, statements may abut
(``GT1``, ``X=V*ADC+100``, ``W=5000E``), and the longest keyword wins (``WAIT`` before ``WA``,
``ELSE`` before ``E``, ``ADC`` before ``A`` ...).
"""

from __future__ import annotations

import functools
import re
from collections.abc import Callable

import msgspec

from devsim.core.kit import Command as KitCommand
from devsim.core.kit import Table
from devsim.core.points import ascii_digits, ascii_upper

__all__ = [
    "LABEL_MAX",
    "LABEL_MIN",
    "compare",
    "Address",
    "Arith",
    "Assign",
    "Command",
    "Comment",
    "Condition",
    "Else",
    "End",
    "Goto",
    "If",
    "Jog",
    "Label",
    "ListCmd",
    "ParseResult",
    "Query",
    "Run",
    "Statement",
    "Text",
    "Unary",
    "Wait",
    "parse",
]

SEPARATORS = " ,;\t"
OPERATORS = "+-*/&|^"
COMPARISONS = ("<=", ">=", "<>", "<", ">", "=")

# Simple aliases that name a parameter (spec §3.4); bit-type operands (I, J, O) are separate.
ALIAS_WORDS = (
    "ADC", "A", "B", "C1", "C2", "C3", "D2", "DB", "D", "M1", "M2", "M3", "IN", "POS", "V", "W",
    "WA", "WR", "WP", "WRP", "WAP", "WPT", "WRPT", "WAPT", "X", "Z", "R0", "R1", "R2", "R3", "R4",
    "R5", "LP",
)
# Keyword statements without arguments.
COMMAND_WORDS = (
    "E", "H", "S", "ON", "OFF", "PSAVE", "POSSAVE", "POS0", "POSR", "NEW", "PGM", "QUIT", "DEL",
    "PE", "VER", "TRON", "TROFF", "NOT", "NEG", "RETURN", "RT",
)
ARG_WORDS = ("IF", "THEN", "ELSE", "END", "WAIT", "GOTO", "GT", "GOSUB", "GS", "RUN", "LIST", "LISTP",
             "TR", "RS", "RF", "LS", "LF")
ALL_WORDS = tuple(sorted(set(ALIAS_WORDS + COMMAND_WORDS + ARG_WORDS), key=len, reverse=True))
_WORD_SET = frozenset(ALL_WORDS)
_PROPER_PREFIXES = frozenset(w[:i] for w in ALL_WORDS for i in range(1, len(w)))
_LONGEST = len(ALL_WORDS[0])


#: The label numbers a program may define (§4.6.2: "ein Wert von 1 bis 128").
LABEL_MIN, LABEL_MAX = 1, 128
#: The largest fixed-point constant a condition compares with (§4.6.1 "festkommakonstante:
#: - 2147483.639 bis +2147483.639", the bound of IF, WAIT and ":") and a calculation takes
#: (§4.6.10 "Es können alle Parameter und 32-Bit Konstanten in Rechenoperationen verwendet
#: werden"; the same 32-bit fixed-point number [SIM-CHOICE]).  A larger one is refused when the
#: statement is read: errno 10 "Dezimalkonstante zu groß" (§4.8.3.1).
FIXED_CONSTANT_MAX = 2147483.639
#: The inputs a condition may name (§4.6.1: "Es sind alle SERS-Parameter und digitalen Eingänge
#: (I1 bis I16, und J1 bis J5) erlaubt"); another input (``IF I17``, ``WAIT J6``, ``RS:I0``) is an
#: event the drive does not know: errno 11 "unbekanntes if Ereignis" (§4.8.3.1) [SIM-CHOICE: the
#: manual gives only the text; elsewhere such an input stays errno 13].
EVENT_INPUTS = {"I": range(1, 17), "J": range(1, 6)}

_DIGITS = r"[0-9]+"
_NUMBER = r"[0-9]*\.?[0-9]*"
_SIGNED_NUMBER = r"-?[0-9]*\.?[0-9]*"
# The argument of LIST ('.', '-', '+', n, -n, n.m) and of LISTP (n, n.m), spec §4.2 grammar.
_LIST_ARG = r"-[0-9]+|[0-9]*\.[0-9]*|[0-9]+|[-+]"
_LISTP_ARG = r"[0-9]*\.[0-9]*|[0-9]+"


@functools.cache
def _pattern(text: str) -> re.Pattern[str]:
    """One of the patterns above, compiled at its first use rather than by every start (issue 31)."""
    return re.compile(text)


class NeedMore(Exception):
    """The text ends where more characters could still change its meaning."""


class SyntaxFault(Exception):
    """The text cannot become valid: carries the device's errno."""

    def __init__(self, errno: int, pos: int) -> None:
        super().__init__(errno, pos)
        self.errno = errno
        self.pos = pos


# -- statement classes --------------------------------------------------------------------
class Address(msgspec.Struct, frozen=True):
    """An operand naming device state: ``P91``, ``V``, ``I3``, ``J1``, ``O2``, ``IN``."""

    kind: str  # "P" (parameter by number), "alias", "I", "J", "O", "IN"
    ref: str | int  # P-number, alias word, or bit number
    text: str  # as written, upper-cased (used as the identifier in query answers)


class Number(msgspec.Struct, frozen=True):
    text: str

    @property
    def value(self) -> float:
        return float(self.text)


Operand = Address | Number


class Statement(msgspec.Struct, frozen=True):
    text: str = ""  # the statement as the host wrote it


class Assign(Statement):
    target: Address = Address("P", 0, "P0")
    value: Operand | str = Number("0")  # "*" for Z=* / P1=*


class Query(Statement):
    target: Address = Address("P", 0, "P0")
    name: bool = False  # P?? designation query


class Arith(Statement):
    op: str = "+"
    operand: Operand = Number("0")


class Unary(Statement):
    op: str = "NOT"


class Command(Statement):
    name: str = ""


class Condition(msgspec.Struct, frozen=True):
    left: Address
    op: str | None = None  # None: true when the value is non-zero
    right: Operand | None = None
    negate: bool = False  # legacy "!"


class If(Statement):
    cond: Condition | None = None
    then: bool = False


class Else(Statement):
    pass


class End(Statement):
    pass


class Wait(Statement):
    cond: Condition | None = None


class Jog(Statement):
    name: str = "RS"
    until: Condition | None = None


class Goto(Statement):
    label: int = 0
    sub: bool = False  # GOSUB/GS


class Label(Statement):
    number: int = 0


class Run(Statement):
    label: int | None = None


class ListCmd(Statement):
    params: bool = False  # LISTP
    arg: str = ""


class Trace(Statement):
    query: bool = False  # TR?


class Change(Statement):
    value: Number = Number("0")


class Text(Statement):
    body: str = ""


class Comment(Statement):
    pass


class ParseResult(msgspec.Struct):
    """Statements found in a line's text.

    ``statements`` are complete (``(statement, end_offset)``).  ``pending`` is True when the
    text ends inside a statement that may still grow.  ``errno``/``error_pos`` are set when the
    text cannot become valid; nothing after ``error_pos`` is parsed.
    """

    statements: list[tuple[Statement, int]]
    pending: bool = False
    errno: int | None = None
    error_pos: int | None = None


# -- the scanner --------------------------------------------------------------------------
class _Cursor:
    def __init__(self, text: str, final: bool) -> None:
        self.text = text
        #: Upper case as the drive sees it, ASCII letters only, one character for one: ``str.upper``
        #: made the latin-1 byte DFh, ``ß``, into ``SS`` (garbage ran as the stop S, in programming
        #: mode it was stored as one, and every character after it was read one place off).
        self.upper = ascii_upper(text)
        self.pos = 0
        self.final = final

    def at_end(self) -> bool:
        return self.pos >= len(self.text)

    def peek(self, n: int = 1) -> str:
        """The next ``n`` characters (upper-case); NeedMore if the text ends before them."""
        chunk = self.upper[self.pos : self.pos + n]
        if len(chunk) < n and not self.final:
            raise NeedMore
        return chunk

    def skip_spaces(self) -> None:
        while self.pos < len(self.text) and self.text[self.pos] in " \t":
            self.pos += 1

    def word(self) -> str | None:
        """Longest keyword at the cursor (consumed), or None."""
        rest = self.upper[self.pos : self.pos + _LONGEST]
        if not self.final and rest in _PROPER_PREFIXES and self.pos + len(rest) == len(self.text):
            raise NeedMore
        for size in range(len(rest), 0, -1):
            if rest[:size] in _WORD_SET:
                self.pos += size
                return rest[:size]
        return None

    def number(self, errno: int, signed: bool = False) -> Number:
        start = self.pos
        match = _pattern(_SIGNED_NUMBER if signed else _NUMBER).match(self.text, self.pos)
        if match is not None and match.end() >= len(self.text) and not self.final:
            raise NeedMore
        if match is None or not any(ascii_digits(ch) for ch in match.group()):
            raise SyntaxFault(errno, start)
        self.pos = match.end()
        self.peek()  # a number at the end of the text may still grow
        return Number(match.group())

    def integer(self, errno: int) -> int:
        self.skip_spaces()
        match = _pattern(_DIGITS).match(self.text, self.pos)
        if match is None:
            if self.pos >= len(self.text) and not self.final:
                raise NeedMore
            raise SyntaxFault(errno, self.pos)
        self.pos = match.end()
        self.peek()  # more digits may follow
        return int(match.group())


def _address(cur: _Cursor, errno: int = 61) -> Address:
    """An operand naming state (parameter, alias, input/output bit)."""
    start = cur.pos
    c = cur.peek()
    if c == "P" and ascii_digits(cur.peek(2)[1:]):
        cur.pos += 1
        number = cur.integer(13)
        return Address("P", number, cur.upper[start : cur.pos])
    if c in ("I", "J", "O") and ascii_digits(cur.peek(2)[1:]):
        cur.pos += 1
        bit = cur.integer(errno)
        return Address(c, bit, cur.upper[start : cur.pos])
    word = cur.word()
    if word in ALIAS_WORDS:
        if word == "IN" and ascii_digits(cur.peek()):
            value = cur.integer(errno)  # legacy IN0..IN255 means IN=value
            return Address("IN", value, cur.upper[start : cur.pos])
        return Address("alias", word, word)
    cur.pos = start
    raise SyntaxFault(errno, start)


def _operand(cur: _Cursor, errno: int = 61, signed: bool = True) -> Operand:
    c = cur.peek()
    if ascii_digits(c) or c == "." or (signed and c == "-"):
        return cur.number(errno, signed=signed)
    return _address(cur, errno)


def _condition(cur: _Cursor) -> Condition:
    cur.skip_spaces()
    negate = False
    if cur.peek() == "!":
        negate = True
        cur.pos += 1
        cur.skip_spaces()
    left = _event(_address(cur, 24), cur.pos)
    if left.kind == "IN" and isinstance(left.ref, int) and left.text != "IN":
        # legacy "IF IN5" == "IF IN=5"
        return Condition(Address("alias", "IN", "IN"), "=", Number(str(left.ref)), negate)
    cur.skip_spaces()
    two = cur.peek(2)
    op = None
    for candidate in COMPARISONS:
        if two.startswith(candidate):
            op = candidate
            break
    if op is None:
        return Condition(left, None, None, negate)
    cur.pos += len(op)
    cur.skip_spaces()
    at = cur.pos
    right = _fixed_constant(_event(_operand(cur, 24), at), at)
    return Condition(left, op, right, negate)


def _event(operand: Operand, start: int) -> Operand:
    """``operand``, unless it names an input a condition does not know (errno 11)."""
    if isinstance(operand, Address) and operand.kind in EVENT_INPUTS and operand.ref not in EVENT_INPUTS[operand.kind]:
        raise SyntaxFault(11, start)
    return operand


def _fixed_constant(operand: Operand, start: int) -> Operand:
    """``operand``, unless it is a constant beyond :data:`FIXED_CONSTANT_MAX` (errno 10)."""
    if isinstance(operand, Number) and abs(operand.value) > FIXED_CONSTANT_MAX:
        raise SyntaxFault(10, start)
    return operand


def _statement(cur: _Cursor) -> Statement:  # noqa: C901 - one branch per statement form
    start = cur.pos
    c = cur.peek()
    if c == "/":
        if cur.peek(2) == "//":
            cur.pos = len(cur.text)
            if not cur.final:
                raise NeedMore
            return Comment(cur.text[start:])
    if c == '"':
        end = cur.text.find('"', start + 1)
        if end < 0:
            if not cur.final:
                raise NeedMore
            raise SyntaxFault(15, start)
        cur.pos = end + 1
        return Text(cur.text[start : cur.pos], cur.text[start + 1 : end])
    if c in OPERATORS:
        cur.pos += 1
        operand = _fixed_constant(_operand(cur, 61, signed=False), start)
        return Arith(cur.text[start : cur.pos], c, operand)
    if c == "C" and cur.peek(2) in ("C ", "C\t"):
        cur.pos += 1
        cur.skip_spaces()
        value = cur.number(49, signed=True)
        return Change(cur.text[start : cur.pos], value)
    if c == "L" and (ascii_digits(cur.peek(2)[1:]) or cur.peek(2) == "L "):
        if cur.peek(2) == "L ":
            cur.pos += 1
            cur.skip_spaces()
            if not ascii_digits(cur.peek()):
                raise SyntaxFault(21, start)
        else:
            cur.pos += 1
        number = cur.integer(37)
        if not LABEL_MIN <= number <= LABEL_MAX:
            raise SyntaxFault(72, start)  # §4.6.2: a label is a jump target L1..L128 ("Sprungziel ungültig")
        return Label(cur.text[start : cur.pos], number)
    if c == "O" and cur.peek(2) == "O=":
        raise SyntaxFault(4, start)  # "O=1" (manual §4.1 example): no such output (spec §7.3)
    if c == "T" and cur.peek(3) == "TR?":
        cur.pos += 3
        return Trace(cur.text[start : cur.pos], query=True)

    if c in ("P", "I", "J", "O") and ascii_digits(cur.peek(2)[1:]):
        return _assign_or_query(cur, start, _address(cur))
    word = cur.word()
    if word is None:
        raise SyntaxFault(21, start)
    keyword = _KEYWORD.get(word)
    if keyword is None:
        raise SyntaxFault(21, start)
    return keyword(cur, start, word)


# -- the statements a keyword begins (the table KEYWORDS) ---------------------------------------
def _alias(cur: _Cursor, start: int, word: str) -> Statement:
    cur.pos = start
    return _assign_or_query(cur, start, _address(cur))


def _unary(cur: _Cursor, start: int, word: str) -> Statement:
    return Unary(cur.text[start : cur.pos], word)


def _trace(cur: _Cursor, start: int, word: str) -> Statement:
    return Trace(cur.text[start : cur.pos])


def _command(cur: _Cursor, start: int, word: str) -> Statement:
    return Command(cur.text[start : cur.pos], "RETURN" if word == "RT" else word)


def _if(cur: _Cursor, start: int, word: str) -> Statement:
    cond = _condition(cur)
    save = cur.pos
    cur.skip_spaces()
    then = False
    if cur.peek(4) == "THEN":
        cur.pos += 4
        then = True
    else:
        cur.pos = save
    return If(cur.text[start : cur.pos], cond, then)


def _then(cur: _Cursor, start: int, word: str) -> Statement:
    raise SyntaxFault(23, start)  # THEN without IF


def _else(cur: _Cursor, start: int, word: str) -> Statement:
    return Else(cur.text[start : cur.pos])


def _end(cur: _Cursor, start: int, word: str) -> Statement:
    return End(cur.text[start : cur.pos])


def _wait(cur: _Cursor, start: int, word: str) -> Statement:
    cond = _condition(cur)
    return Wait(cur.text[start : cur.pos], cond)


def _goto(cur: _Cursor, start: int, word: str) -> Statement:
    label = cur.integer(28 if word == "GOTO" else 25)
    return Goto(cur.text[start : cur.pos], label, sub=False)


def _gosub(cur: _Cursor, start: int, word: str) -> Statement:
    label = cur.integer(30)
    return Goto(cur.text[start : cur.pos], label, sub=True)


def _run(cur: _Cursor, start: int, word: str) -> Statement:
    save = cur.pos
    cur.skip_spaces()
    if ascii_digits(cur.peek()):
        label = cur.integer(37)
        if label < LABEL_MIN:
            raise SyntaxFault(9, start)  # §4.8.3.1 errno 9 "run Dezimalkonstante zu klein": RUN 0
        return Run(cur.text[start : cur.pos], label)
    cur.pos = save
    return Run(cur.text[start : cur.pos], None)


def _list(cur: _Cursor, start: int, word: str) -> Statement:
    save = cur.pos
    cur.skip_spaces()
    found = _pattern(_LISTP_ARG if word == "LISTP" else _LIST_ARG).match(cur.text, cur.pos)
    end = found.end() if found is not None else cur.pos
    if end == len(cur.text) and not cur.final:
        raise NeedMore  # the argument may go on
    arg = cur.text[cur.pos : end]  # (what follows a complete argument is the next statement)
    cur.pos = end if arg else save
    return ListCmd(cur.text[start : cur.pos], params=word == "LISTP", arg=arg)


def _jog(cur: _Cursor, start: int, word: str) -> Statement:
    until = None
    if cur.peek() == ":":
        cur.pos += 1
        until = _condition(cur)
    return Jog(cur.text[start : cur.pos], word, until)


Keyword = Callable[[_Cursor, int, str], Statement]

#: The keywords of the statement language (§4.2) and the statement each one begins.
KEYWORDS: Table[Keyword] = Table(
    [
        *(KitCommand(word, _alias, "§4.2", "an alias: assignment or query") for word in ALIAS_WORDS),
        KitCommand("NOT", _unary, "§4.6.10", "X := NOT X"),
        KitCommand("NEG", _unary, "§4.6.10", "X := -X"),
        KitCommand("TR", _trace, "§4.5.4", "one program step"),
        *(KitCommand(word, _command, "§4.2", "a command without arguments")
          for word in COMMAND_WORDS if word not in ("NOT", "NEG")),
        KitCommand("IF", _if, "§4.6.1", "IF condition [THEN]"),
        KitCommand("THEN", _then, "§4.6.1", "THEN without IF: errno 23"),
        KitCommand("ELSE", _else, "§4.6.1", "ELSE"),
        KitCommand("END", _end, "§4.6.1", "END of an IF block"),
        KitCommand("WAIT", _wait, "§4.6.8", "WAIT condition"),
        KitCommand("GOTO", _goto, "§4.6.3", "GOTO n"),
        KitCommand("GT", _goto, "§4.6.3", "GT n"),
        KitCommand("GOSUB", _gosub, "§4.6.4", "GOSUB n"),
        KitCommand("GS", _gosub, "§4.6.4", "GS n"),
        KitCommand("RUN", _run, "§4.8.6.16", "RUN [n]"),
        KitCommand("LIST", _list, "§4.2", "LIST [range]"),
        KitCommand("LISTP", _list, "§4.2", "LISTP [range]"),
        *(KitCommand(word, _jog, "§4.5.1", "jog [:condition]") for word in ("RS", "RF", "LS", "LF")),
    ]
)
_KEYWORD: dict[str, Keyword] = {row.token: row.handler for row in KEYWORDS}


def _assign_or_query(cur: _Cursor, start: int, target: Address) -> Statement:
    c = cur.peek()
    if c == "?":
        cur.pos += 1
        if cur.peek() == "?":
            cur.pos += 1
            return Query(cur.text[start : cur.pos], target, name=True)
        return Query(cur.text[start : cur.pos], target)
    if c == "=":
        cur.pos += 1
        if cur.peek() == "*":
            cur.pos += 1
            return Assign(cur.text[start : cur.pos], target, "*")
        value = _operand(cur, 48, signed=True)
        return Assign(cur.text[start : cur.pos], target, value)
    raise SyntaxFault(34, cur.pos)


@functools.lru_cache(maxsize=2048)
def parse(text: str, final: bool) -> ParseResult:
    """Parse a line's statement text (without ``#`` and address).

    ``final`` says the line has ended (CR/LF arrived), so nothing at the end is pending.
    Results are cached (a host polls the same lines again and again): callers must not
    change them.
    """
    cur = _Cursor(text, final)
    result = ParseResult([])
    while True:
        while cur.pos < len(text) and text[cur.pos] in SEPARATORS:
            cur.pos += 1
        if cur.pos >= len(text):
            return result
        start = cur.pos
        try:
            stmt = _statement(cur)
        except NeedMore:
            result.pending = True
            return result
        except SyntaxFault as fault:
            result.errno = fault.errno
            result.error_pos = start
            return result
        result.statements.append((stmt, cur.pos))


def compare(left: float, op: str, right: float) -> bool:
    """A condition's comparison (§4.6.1): ``<``, ``<=``, ``=``, ``>``, ``>=``, ``<>``."""
    return {
        "<": left < right,
        "<=": left <= right,
        "=": left == right,
        ">": left > right,
        ">=": left >= right,
        "<>": left != right,
    }[op]
