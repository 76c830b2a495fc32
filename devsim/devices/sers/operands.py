"""Operands, conditions and arithmetic of the SERS's statements (manual §4.2, §4.6.1, §4.6.10;
spec G-ARITH, G-COUNTER).

An operand is a number or an address: a parameter by number or alias, an output O1..O16, an
input I1..I16, a switch J1..J5 or the input byte IN; each kind of address is read through
:data:`OPERANDS`.  The accumulator X takes the results of the operators in :data:`ARITHMETIC`.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from devsim.core.kit import Command, Table
from devsim.devices.sers import statements as st
from devsim.devices.sers.access import ParameterAccess, address_number
from devsim.devices.sers.errors import SersError
from devsim.devices.sers.inputs import Inputs
from devsim.devices.sers.parameters import ALIASES
from devsim.devices.sers.params import SersParameters
from devsim.devices.sers.power import PowerStage
from devsim.devices.sers.units import quantize

__all__ = ["ARITHMETIC", "OPERANDS", "Operands", "UNARY"]

X_LIMIT = 2147483.647  # the accumulator's range (spec G-ARITH)


class Operands:
    """The values of operands and conditions, and the accumulator X (§4.6.1, §4.6.10).
    ``decrement_first``: a counter in IF is decremented before it is compared, the manual's rule
    in §4.6.1 (spec G-COUNTER ⚙ ``counter_decrement_first``); by default the old value is
    compared, as the manual's loop examples (§4.6.1 example 3, §4.8.5.2, §4.6.12) count."""

    def __init__(self, access: ParameterAccess, inputs: Inputs, params: SersParameters, power: PowerStage,
                 decrement_first: bool = False) -> None:
        self.access = access
        self.inputs = inputs
        self.params = params
        self.power = power
        self.decrement_first = decrement_first

    def operand_value(self, operand: st.Operand) -> Any:
        if isinstance(operand, st.Number):
            return operand.value
        return _OPERAND.get(operand.kind, Operands.parameter)(self, operand)

    def parameter(self, address: st.Address) -> Any:
        """A parameter (by number or alias) or an output as an operand."""
        value = self.access.param_value(address_number(address))
        if value == "*":
            raise SersError(19)  # Z=* names a broadcast, not a number ('*' only with P1 or Z)
        return value

    def output(self, address: st.Address) -> Any:
        if not 1 <= int(address.ref) <= 16:
            raise SersError(4)
        return self.parameter(address)

    def input(self, address: st.Address) -> int:
        """I1..I16: the input's bit of P1300 / P1301."""
        n = int(address.ref)
        if not 1 <= n <= 16:
            raise SersError(13)
        if n <= 8:
            return (self.inputs.inputs_byte(1) >> (n - 1)) & 1
        return (self.access.param_value(1301) >> (n - 9)) & 1  # type: ignore[no-any-return]

    def evaluate(self, cond: st.Condition | None, counters: bool = True) -> bool:
        """A condition (§4.6.1); a counter C1..C3 compared is decremented (G-COUNTER)."""
        if cond is None:
            return False
        left = cond.left
        counter = counters and left.kind == "alias" and left.ref in ("C1", "C2", "C3")
        if counter and self.decrement_first:  # G-COUNTER ⚙: decrement, then compare the new value
            self._decrement(str(left.ref))
        value = self.operand_value(left)
        if cond.op is None:
            result = value != 0
        else:
            right = self.operand_value(cond.right) if cond.right is not None else 0
            result = st.compare(value, cond.op, right)
        if counter and not self.decrement_first:  # G-COUNTER: compare the old value, then decrement
            self._decrement(str(left.ref))
        return result != cond.negate

    def _decrement(self, alias: str) -> None:
        """A counter C1..C3 one down, saturating at 0 (C1 in positioning mode 3 is signed, G-COUNTER)."""
        values = self.params.values
        number = ALIASES[alias]
        old = int(values.get(number, 0))
        values[number] = old - 1 if (old > 0 or (number == 100 and self.params.positioning_mode == 3)) else 0

    def arithmetic(self, op: str, operand: st.Operand | None) -> None:
        """X := X (op) operand, left to right (§4.6.10, spec G-ARITH): 3 decimals, ±2147483.647."""
        x = float(self.params.accumulator)
        unary = UNARY.get(op)
        if unary is not None:
            result = unary(x)
        else:
            y = self.operand_value(operand) if operand is not None else 0.0
            try:
                result = ARITHMETIC[op](x, y)
            except SersError:
                self.power.warn(256)
                raise
        self.set_x(result)

    def set_x(self, value: float) -> None:
        if value > X_LIMIT:
            self.power.warn(256)
            raise SersError(98)
        if value < -X_LIMIT:
            self.power.warn(256)
            raise SersError(99)
        self.params.accumulator = quantize(value, 3)


#: Each kind of address (statements.Address.kind) as an operand (§4.2).
OPERANDS: Table[Callable[[Operands, st.Address], Any]] = Table(
    [
        Command("P", Operands.parameter, "§4.2", "a parameter by number: P91"),
        Command("alias", Operands.parameter, "§4.2", "a parameter by its alias: V, W, X, C1 …"),
        Command("O", Operands.output, "§4.8.1.2", "an output O1..O16 (P1201..P1216)"),
        Command("I", Operands.input, "§4.6.1", "an input I1..I16 (a bit of P1300 / P1301)"),
        Command("J", lambda o, a: o.inputs.j_value(int(a.ref)), "§4.6.1", "a switch J1..J5 (1 = 24 V)"),
        Command("IN", lambda o, a: o.access.param_value(1300), "§4.6.1", "the input byte (P1300)"),
    ]
)
_OPERAND = {row.token: row.handler for row in OPERANDS}


def _divide(x: float, y: float) -> float:
    if y == 0:
        raise SersError(102)  # (and warning 256)
    return x / y


#: X op operand (§4.6.10).
ARITHMETIC: Table[Callable[[float, float], float]] = Table(
    [
        Command("+", lambda x, y: x + y, "§4.6.10", "add"),
        Command("-", lambda x, y: x - y, "§4.6.10", "subtract"),
        Command("*", lambda x, y: x * y, "§4.6.10", "multiply"),
        Command("/", _divide, "§4.6.10", "divide (by 0: errno 102)"),
        Command("&", lambda x, y: float(int(x) & int(y)), "§4.6.10", "bitwise and"),
        Command("|", lambda x, y: float(int(x) | int(y)), "§4.6.10", "bitwise or"),
        Command("^", lambda x, y: float(int(x) ^ int(y)), "§4.6.10", "bitwise exclusive or"),
    ]
)

#: op X (§4.6.10).
UNARY: Table[Callable[[float], float]] = Table(
    [
        Command("NOT", lambda x: float(~int(x)), "§4.6.10", "bitwise not"),
        Command("NEG", lambda x: -x, "§4.6.10", "negate"),
    ]
)
