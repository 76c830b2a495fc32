"""What the SERS answers on the serial line: the acknowledgement, query answers, LISTP and the
statements as LIST shows them (manual §4.1, §4.2, §4.3, §4.7; spec G-LIST, G-QUERYFMT).
"""

from __future__ import annotations

import re
from collections.abc import Callable
from typing import Any

from devsim.devices.sers import statements as st
from devsim.devices.sers.access import ParameterAccess, address_number
from devsim.devices.sers.constants import WEIGHTED_KINDS
from devsim.devices.sers.errors import SersError
from devsim.devices.sers.motion import Motion
from devsim.devices.sers.operands import Operands
from devsim.devices.sers.parameters import KIND, PARAMETERS
from devsim.devices.sers.params import SersParameters
from devsim.devices.sers.power import PowerStage
from devsim.devices.sers.program import ProgramMemory
from devsim.devices.sers.units import format_fixed

__all__ = ["Answers", "ack_line"]

#: Address kinds that name a parameter (a query answers its value with the parameter's format).
_PARAMETER_KINDS = ("P", "alias", "O")
_READABLE = [n for n in sorted(PARAMETERS) if PARAMETERS[n].readable]
#: How a query's answer names the parameter asked (G-QUERYFMT ⚙ ``query_name_style``): as asked
#: (``V?`` → ``V=…``, ``P91?`` → ``P91=…``), or by its number (``V?`` → ``P91=…``; outputs as asked).
_NAMES: dict[str, Callable[[st.Address, int], str]] = {
    "as_asked": lambda target, number: target.text,
    "number": lambda target, number: target.text if target.kind == "O" else f"P{number}",
}
#: A plain parameter's answer line as it leaves, by what makes it (the text as asked, the value and
#: its type, the encoding): shared by every drive, made once per value (a poll asks again and again).
_PLAIN_LINES: dict[tuple[str, type, object, str], bytes] = {}
_PLAIN_LINES_MAX = 4096
#: The acknowledgements ``ok0`` … ``ok4`` and ``pgm`` as they leave (§4.1).
#: ``ok<d>`` on its own line for each digit (§4.1), as :func:`ack_line` answers outside programming mode.
OK_LINES = tuple(b"\nok%d\n\r" % digit for digit in range(5))
_PGM_LINE = b"\npgm\n\r"


class Answers:
    """The texts one SERS answers with (§4.1, §4.7, G-LIST).  ``list_decimals``: the decimals
    LIST shows a weighted constant with (spec G-LIST ⚙ ``list_decimals``; the manual's §4.3
    example ``V=500.000`` has 3), None: all of the weighting's.  ``name_style``: how a query's
    answer names the parameter (G-QUERYFMT ⚙ ``query_name_style``, :data:`_NAMES`)."""

    def __init__(
        self,
        access: ParameterAccess,
        operands: Operands,
        params: SersParameters,
        power: PowerStage,
        motion: Motion,
        program: ProgramMemory,
        list_decimals: int | None = None,
        name_style: str = "as_asked",
    ) -> None:
        self.list_decimals = list_decimals
        self._name = _NAMES[name_style]
        self.access = access
        self.operands = operands
        self.params = params
        self.power = power
        self.motion = motion
        self.program = program

    @property
    def english(self) -> bool:
        """P265 = 1: the messages and designations in English."""
        return int(self.params.language) == 1

    @property
    def list_options(self) -> int:
        """P1028 (§4.3)."""
        return int(self.params.list_option)

    def ack_line(self) -> bytes:
        """``ok<d>`` (§4.1) on its own line, as it leaves: 4 error, 0/2 moving, 1/3 standing, +2
        with a warning; ``pgm`` in programming mode (:func:`ack_line`)."""
        return ack_line(self.program, self.power, self.motion)

    def query_text(self, stmt: st.Query) -> str:
        """``P<n>?`` / ``alias?``: ``<as asked>=<value>``; ``P<n>??``: the designation (§4.7)."""
        target = stmt.target
        if stmt.name:
            if target.kind in _PARAMETER_KINDS:
                row = PARAMETERS.get(address_number(target))
                if row is None:
                    raise SersError(13)
                return row.doc if self.english else row.name
            raise SersError(13)
        if target.kind in _PARAMETER_KINDS:
            number = address_number(target)
            if number == 1 and self.params.target_address == "*":
                return f"{self._name(target, number)}=*"
            return f"{self._name(target, number)}={self.access.format_value(number, self.operands.operand_value(target))}"
        return f"{target.text}={int(self.operands.operand_value(target))}"

    def parameter_text(self, target: st.Address, number: int) -> str:
        """What :meth:`query_text` answers for a parameter asked by number or alias (``P``,
        ``alias``), its number already known (a host's poll, parsed once)."""
        if number == 1 and self.params.target_address == "*":
            return f"{self._name(target, number)}=*"
        return self.value_text(target, number, self.access.param_value(number))

    def value_text(self, target: st.Address, number: int, value: Any) -> str:
        """:meth:`parameter_text` of parameter ``number`` holding ``value`` (read already)."""
        if value == "*":
            raise SersError(19)  # as Operands.parameter: Z=* names a broadcast, not a number
        return f"{self._name(target, number)}={self.access.format_value(number, value)}"

    def parameter_line(self, target: st.Address, number: int, encoding: str) -> bytes:
        """:meth:`parameter_text` with its line end, encoded, as a poll's answer leaves: a plain
        parameter's (neither weighted nor ``fixed``: its value as it is) made once per value."""
        kind = KIND.get(number)
        if number == 1 or kind in WEIGHTED_KINDS or kind == "fixed":
            return (self.parameter_text(target, number) + "\n\r").encode(encoding, errors="replace")
        return self.plain_line(target, number, self.access.param_value(number), encoding)

    def plain_line(self, target: st.Address, number: int, value: Any, encoding: str) -> bytes:
        """The answer line of a plain parameter (neither weighted nor ``fixed``, not P1) that
        holds ``value``, as :meth:`parameter_line` makes it: made once per value."""
        key = (self._name(target, number), type(value), value, encoding)
        line = _PLAIN_LINES.get(key)
        if line is None:
            text = self.value_text(target, number, value)  # (its errors as they are: nothing kept)
            if len(_PLAIN_LINES) >= _PLAIN_LINES_MAX:
                _PLAIN_LINES.clear()
            line = _PLAIN_LINES[key] = (text + "\n\r").encode(encoding, errors="replace")
        return line

    def list_parameters(self, arg: str) -> list[str]:
        """LISTP (G-LIST): ``P<n>=<value>`` in ascending order; P1028 bit 4 adds names."""
        numbers = _READABLE
        if arg:
            first, _, count = arg.partition(".")
            start = int(first or 0)
            size = int(count) * 10 if count else 1
            numbers = numbers[start : start + size]
        access = self.access
        rows = []
        for n in numbers:
            try:
                text = f"P{n}={access.format_value(n, access.param_value(n))}"
            except SersError:
                continue
            if self.list_options & 16:
                text += "  " + PARAMETERS[n].name
            rows.append(text)
        return rows

    def render_statement(self, text: str) -> str:
        """A stored statement as LIST shows it (G-LIST): keywords upper-case, constants of
        weighted parameters with all decimals of the weighting, the unit with P1028 bit 1."""
        result = st.parse(text, final=True)
        if result.errno is not None or len(result.statements) != 1:
            return text
        stmt = result.statements[0][0]
        if isinstance(stmt, st.Assign) and isinstance(stmt.value, st.Number) and stmt.target.kind != "I":
            try:
                kind = KIND.get(address_number(stmt.target))
            except (SersError, KeyError):
                kind = None
            if kind in WEIGHTED_KINDS:
                scaling = self.params.scaling
                decimals = scaling.decimals(kind) if self.list_decimals is None else self.list_decimals
                value = format_fixed(stmt.value.value, decimals)
                unit = scaling.unit(kind) if self.list_options & 2 else ""
                return f"{stmt.target.text}={value}{unit}"
        legacy_in = re.search(r"\bIN[0-9]", text.upper()) is not None
        if isinstance(stmt, st.If | st.Wait) and stmt.cond is not None and (stmt.cond.negate or legacy_in):
            keyword = "IF" if isinstance(stmt, st.If) else "WAIT"
            then = " THEN" if isinstance(stmt, st.If) and stmt.then else ""
            return f"{keyword} {_new_syntax(stmt.cond)}{then}"
        return text.upper() if not isinstance(stmt, st.Text | st.Comment) else text


def ack_line(program: ProgramMemory, power: PowerStage, motion: Motion) -> bytes:
    """:meth:`Answers.ack_line` of the drive whose parts these are (a host's repeated poll asks
    the parts it holds: no answers object to read).  :meth:`.polls.KeptPolls.answer_at_once`
    repeats its last two lines inline (a call less per poll): change both, and
    ``tests/sers/test_poll_path.py`` compares them."""
    if program.editing:
        return _PGM_LINE
    if power.errors:
        return OK_LINES[4]
    return OK_LINES[(1 if motion.pos_ok else 0) + (2 if power.warnings else 0)]


_OPPOSITE = {"<": ">=", "<=": ">", "=": "<>", "<>": "=", ">": "<=", ">=": "<"}


def _new_syntax(cond: st.Condition) -> str:
    """A legacy condition (``!I5``, ``IN5``) in the syntax LIST shows (§4.6.1)."""
    left = cond.left.text
    if cond.op is None:
        return f"{left}=0" if cond.negate else f"{left}<>0"
    op = _OPPOSITE[cond.op] if cond.negate else cond.op
    return f"{left}{op}{'0' if cond.right is None else cond.right.text}"
