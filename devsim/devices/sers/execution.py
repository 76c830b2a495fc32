"""Statement execution and motor power of the SERS model: assignments, commands, program
statements, ON/OFF, SERVO mode, drive errors and warnings (manual §4.2, §4.8.2, §4.8.3;
spec §4.3, §4.6)."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from devsim.core.kit import Command, Table
from devsim.devices.sers import statements as st
from devsim.devices.sers.errors import SersError

__all__ = ["COMMANDS", "STATEMENTS", "Execution"]


class Execution:
    """Part of :class:`~devsim.devices.sers.drive.SersDrive`: statements, commands, power stage, errors."""

    # ======================================================================================
    # statements
    # ======================================================================================
    def execute(self, stmt: st.Statement) -> None:
        """One statement, interactive or from a program: looked up by its type in
        :data:`STATEMENTS` (spec §3.3)."""
        handler = STATEMENTS.get(type(stmt).__name__)
        if handler is None:
            raise SersError(21)
        handler(self, stmt)

    def assign(self, stmt: st.Assign) -> None:
        target = stmt.target
        if target.kind in ("I", "J", "IN"):
            raise SersError(105)
        if target.kind == "O" and not 1 <= int(target.ref) <= 16:
            raise SersError(4)
        number = self.address_number(target)
        if number == 1047:
            value = stmt.value
            self.set_x(self.operand_value(value) if not isinstance(value, str) else 0.0)
            return
        value = stmt.value if isinstance(stmt.value, str) else self.operand_value(stmt.value)
        self.write_param(number, value)

    def master_target(self) -> int | str | None:
        """In a master (address 0) after ``Z=n`` (P1): the slave statements go to."""
        if self.cfg.address != 0:
            return None
        target = self.params.target_address
        if target == "*":
            return "*"
        return int(target) if target else None

    def program_statement(self, stmt: st.Statement) -> str | None:
        """Execute a statement of a running program; returns what the program must wait for
        (``position``: until the drive stands, §4.6.6) or None to go on at once."""
        if isinstance(stmt, st.Command) and stmt.name == "E" and self.motion.poly.definition is not None:
            last = self.motion.poly.definition[2]
            started = self.motion.poly.execute() == "started"
            master_goes_on = self.cfg.address == 0 and int(self.params.wait_until_positioned) == 0
            if last:
                return None if (master_goes_on or self.motion.kind is None) else "position"
            return None if started else "segment"
        if isinstance(stmt, st.Command) and stmt.name in ("E", "H", "POS0", "POSR"):
            self.execute(stmt)
            if self.motion.kind is None:
                return None
            if stmt.name == "E" and self.cfg.address == 0 and int(self.params.wait_until_positioned) == 0:
                return None  # master with P1110=0 goes on while it moves (§4.8.5.5)
            return "position"
        if isinstance(stmt, st.Jog):
            self.motion.jog.start(stmt.name, stmt.until, serial=False)
            # with ':' the statement lasts until standstill; without, it just starts (G-JOGPROG)
            return "position" if stmt.until is not None and self.motion.kind is not None else None
        self.execute(stmt)
        return None

    def continue_positioning(self) -> None:
        """P1033=1: a program stopped during ``E`` continues the interrupted move."""
        if not self.motion.continue_positioning():
            self.interpreter.on_motion_end()

    def _command(self, name: str) -> None:
        handler = COMMANDS.get(name)
        if handler is None:
            raise SersError(21)
        handler(self)

    def edit_program(self) -> None:
        if self.program_state == 1:
            raise SersError(44)
        self.program.edit()

    def quit_program(self) -> None:
        if not self.program_editing:
            raise SersError(22)
        self.program.quit()

    def stop_all(self) -> None:
        self.interpreter.stop()
        self.motion.stop_motion()

    def trace_off(self) -> None:
        self.trace_mode = False
        if self.interpreter.running and self.interpreter.waiting is None:
            self.interpreter.continue_cycle()

    def trace_step(self) -> None:
        self.trace_mode = True
        self.interpreter.trace_step()

    def program_end(self) -> None:
        if self.program_state != 1:
            raise SersError(54)



def _refuse(errno: int) -> Callable[..., None]:
    def handler(*_args: Any) -> None:
        raise SersError(errno)

    return handler


def _delete(drive: Any) -> None:
    raise SersError(22 if not drive.program_editing else 21)


#: Statement types (spec §3.3) → what the drive does with them.
STATEMENTS: Table[Callable[[Any, Any], None]] = Table(
    [
        Command("Assign", lambda d, s: d.assign(s), "§4.2", "write a parameter or alias (X: the accumulator)"),
        Command("Arith", lambda d, s: d.arithmetic(s.op, s.operand), "§4.6.10", "X := X op operand"),
        Command("Unary", lambda d, s: d.arithmetic(s.op, None), "§4.6.10", "NOT, NEG on X"),
        Command("Jog", lambda d, s: d.motion.jog.start(s.name, s.until), "§4.5.1", "RS, RF, LS, LF [:condition]"),
        Command("Command", lambda d, s: d._command(s.name), "§4.2", "a keyword command (see below)"),
        Command("Text", _refuse(16), "§4.6.11", "text for the SERS-Programmer: stored in programming mode only"),
        Command("Run", lambda d, s: d.run_program(s.label), "§4.8.6.16", "RUN / RUN n: start the program"),
        Command("Change", _refuse(22), "§4.2", "C n: only in programming mode"),
        Command("Trace", lambda d, s: d.trace_step(), "§4.5.4", "TR: one program step"),
        Command("Goto", _refuse(54), "§4.6.3", "GOTO/GOSUB: only in a program"),
        Command("Wait", lambda d, s: None, "§4.6.8", "WAIT: only blocks a program"),
        Command("Label", lambda d, s: None, "§4.6.2", "L n: a jump target"),
        Command("Comment", lambda d, s: None, "§4.2", "// comment"),
    ]
)

#: Keyword commands (spec §3.3) → what the drive does.
COMMANDS: Table[Callable[[Any], None]] = Table(
    [
        Command("E", lambda d: d.motion.start_positioning(), "§4.6.6", "start positioning to W at V with A"),
        Command("H", lambda d: d.motion.home(), "§4.8.4.5", "start homing (reference run)"),
        Command("S", lambda d: d.stop_all(), "§4.8.6.2", "stop: the program and the motion"),
        Command("ON", lambda d: d.power_stage.switch_on(), "§4.8.2.2", "energise the motor (P134=7)"),
        Command("OFF", lambda d: d.power_stage.switch_off(), "§4.8.2.2", "de-energise the motor (P134=0)"),
        Command("PSAVE", lambda d: d.memory.psave(), "§4.8.6.10", "save the RAM parameters in the EEPROM (P1004=2)"),
        Command("POSSAVE", lambda d: d.memory.possave(), "§4.8.4.2", "save P51 in the EEPROM (P1004=4)"),
        Command("POS0", lambda d: d.motion.pos0(), "§4.8.4.2", "move to the next electrical zero, then P51=0"),
        Command("POSR", lambda d: d.motion.posr(force=False), "§4.8.4.2", "after step loss: back to the set-point W"),
        Command("NEW", lambda d: d.new_program(), "§4.5.3", "programming mode, deleting the program (P0=2)"),
        Command("PGM", lambda d: d.edit_program(), "§4.5.3", "programming mode, editing the program"),
        Command("QUIT", lambda d: d.quit_program(), "§4.2", "leave programming mode (P0=0)"),
        Command("DEL", _delete, "§4.2", "delete the current line (programming mode)"),
        Command("TRON", lambda d: setattr(d, "trace_mode", True), "§4.5.4", "trace (single-step) mode on"),
        Command("TROFF", lambda d: d.trace_off(), "§4.5.4", "trace mode off"),
        Command("PE", lambda d: d.program_end(), "§4.2", "program end (in a program)"),
        Command("RETURN", lambda d: d.program_end(), "§4.6.5", "return from a subroutine (in a program)"),
    ]
)
