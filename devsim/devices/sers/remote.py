"""A master's program statements for a slave (manual §3.6.2, §4.8.5.5; spec §3.8, G-MASTER).

After ``Z=n`` a master (address 0) sends the statements of its program to slave n instead of
executing them, with its own operands already substituted (``V=X`` → ``V=1000``), and its program
waits for the answer; values come back through the slave's P3 (``X=V``) and, for IF and WAIT,
P2.  Which statements go and how is :data:`REMOTE`.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Protocol

from devsim.core.kit import Command, Table
from devsim.devices.sers import statements as st
from devsim.devices.sers.access import address_number
from devsim.devices.sers.master import MasterLink
from devsim.devices.sers.operands import Operands

__all__ = ["REMOTE", "ParkedProgram", "RemoteStatements"]

#: J1..J5 as bits of the slave's P1013 (§4.8.3.2).
_J_BITS = {1: 3, 2: 1, 3: 0, 4: 2, 5: 7}
Target = int | str

#: Where a slave's input or switch is read (P1300 bit, P1013 bit); a parameter is read by number.
_SLAVE_SOURCES: dict[str, Callable[[st.Address], tuple[int, int]]] = {
    "I": lambda address: (1300, int(address.ref) - 1),
    "J": lambda address: (1013, _J_BITS[int(address.ref)]),
}


class ParkedProgram(Protocol):
    """What a statement sent to a slave (§4.8.5.5) needs of the program that waits for it (the
    :class:`~.interpreter.Interpreter`)."""

    def park_for_master(self) -> None: ...

    def awaiting_master(self) -> bool: ...

    def master_answered(self, branch: st.If | None = None, true: bool = False) -> None:
        """The slave answered: (an IF branches on ``true``), the program goes on."""

    def master_failed(self) -> None:
        """No answer, or an error: a program error (errno 64)."""

    def later(self, delay: float, action: Callable[[], None]) -> None: ...


def _wire(operands: Operands, operand: st.Operand) -> str:
    """A master-side operand as the decimal number sent to a slave (``V=X`` → ``V=1000``)."""
    if isinstance(operand, st.Number):
        return operand.text
    value = float(operands.operand_value(operand))
    return str(int(value)) if value.is_integer() else f"{value:.4f}".rstrip("0").rstrip(".")


class RemoteStatements:
    """The statements a master's program sends to a slave (§3.6.2, §4.8.5.5)."""

    def __init__(self, master: MasterLink, operands: Operands, program: ParkedProgram) -> None:
        self.master = master
        self.operands = operands
        self.program = program

    def send(self, stmt: st.Statement, target: Target) -> bool:
        """Send ``stmt`` to slave ``target``; True if it was sent (the program waits)."""
        handler = _REMOTE.get(type(stmt).__name__)
        return handler is not None and handler(self, stmt, target)

    def assign(self, stmt: st.Assign, target: Target) -> bool:
        if stmt.target.kind in ("P", "alias"):
            number = address_number(stmt.target)
            if number == 1:
                return False  # Z=… is the master's own business
            if number == 1047 and isinstance(stmt.value, st.Address):
                asked = address_number(stmt.value)  # Z=1 X=V: read V of slave 1 into X
                self._request(target, f"P3={asked}", "P3", lambda value: self.operands.set_x(value or 0.0))
                return True
            value = stmt.value if isinstance(stmt.value, str) else _wire(self.operands, stmt.value)
            self._request(target, f"{stmt.target.text}={value}")
            return True
        self._request(target, f"{stmt.target.text}={_wire(self.operands, stmt.value)}")  # type: ignore[arg-type]
        return True  # O1=1 and the like

    def command(self, stmt: st.Command | st.Run | st.Jog, target: Target) -> bool:
        if isinstance(stmt, st.Command) and stmt.name in ("RETURN", "PE"):
            return False
        if isinstance(stmt, st.Run):
            text = "RUN" if stmt.label is None else f"RUN {stmt.label}"
        elif isinstance(stmt, st.Command):
            text = stmt.name
        else:
            text = stmt.text.upper()
        self._request(target, text)
        return True

    def _request(self, target: Target, text: str, want: str | None = None,
                 got: Callable[[float | None], None] | None = None) -> None:
        """Send to the slave and park until it answered; no answer (100 ms) is a program error."""
        program = self.program
        program.park_for_master()

        def done(ok: bool, value: float | None, message: str) -> None:
            if not program.awaiting_master():
                return
            if not ok:
                program.master_failed()
                return
            if got is not None:
                got(value)
            program.master_answered()

        self.master.request(target, text, done, want)

    def condition(self, stmt: st.If | st.Wait, target: Target) -> bool:
        """IF/WAIT on slave data: ``P2=<n>`` returns the value (inputs via P1300, J via P1013)."""
        cond = stmt.cond
        if cond is None:
            return False
        left = cond.left
        source = _SLAVE_SOURCES.get(left.kind)
        number, bit = source(left) if source is not None else (address_number(left), None)
        program = self.program
        program.park_for_master()

        def done(ok: bool, value: float | None, message: str) -> None:
            if not program.awaiting_master():
                return
            if not ok or value is None:
                program.master_failed()
                return
            if bit is not None:
                level = (int(value) >> bit) & 1
                value = float(1 - level if left.kind == "J" else level)
            right = self.operands.operand_value(cond.right) if cond.right is not None else 0.0
            true = (value != 0) if cond.op is None else st.compare(value, cond.op, right)
            true = true != cond.negate
            if isinstance(stmt, st.If):
                program.master_answered(stmt, true)
            elif true:
                program.master_answered()
            else:  # WAIT polls the slave every 10 ms (G-MASTER)
                program.later(0.01, lambda: self.condition(stmt, target))

        self.master.request(target, f"P2={number}", done, "P2")
        return True


#: Statement types a master sends to its slave (§3.6.2); the others it executes itself.
REMOTE: Table[Callable[[RemoteStatements, st.Statement, Target], bool]] = Table(
    [
        Command("Assign", RemoteStatements.assign, "§4.8.5.5", "P<n>=, alias=, O<n>= (X=V asks P3)"),
        Command("If", RemoteStatements.condition, "§4.8.5.5", "IF on the slave's data (asks P2)"),
        Command("Wait", RemoteStatements.condition, "§4.8.5.5", "WAIT on the slave's data (asks P2 every 10 ms)"),
        Command("Command", RemoteStatements.command, "§3.6.2", "E, H, ON … (not RETURN, PE)"),
        Command("Run", RemoteStatements.command, "§3.6.2", "RUN [n]"),
        Command("Jog", RemoteStatements.command, "§3.6.2", "RS, RF, LS, LF"),
    ]
)
_REMOTE = {row.token: row.handler for row in REMOTE}
