"""Statement execution of the SERS: what the drive does with a statement, interactive or from its
program, and with each command keyword; starting, stopping and tracing the program (manual
§4.2, §4.4.1, §4.5.3, §4.5.4, §4.6; spec §3.3, §4.4).

Statements are looked up by type in :data:`STATEMENTS`, commands by keyword in :data:`COMMANDS`;
in a running program the motions that the program waits for are :data:`PROGRAM_MOTIONS`.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from devsim.core.kit import Command, Table
from devsim.devices.sers import statements as st
from devsim.devices.sers.access import ParameterAccess, address_number
from devsim.devices.sers.errors import SersError
from devsim.devices.sers.inputs import Inputs
from devsim.devices.sers.interpreter import Interpreter
from devsim.devices.sers.interruption import JogInterruption
from devsim.devices.sers.memory import ParameterMemory
from devsim.devices.sers.motion import Motion
from devsim.devices.sers.operands import Operands
from devsim.devices.sers.params import SersParameters
from devsim.devices.sers.power import PowerStage
from devsim.devices.sers.program import ProgramMemory

__all__ = ["COMMANDS", "PROGRAM_MOTIONS", "STATEMENTS", "Execution"]


class Execution:
    """The statements, commands and program control of one SERS (§4.2, §4.4)."""

    def __init__(
        self,
        params: SersParameters,
        memory: ParameterMemory,
        power: PowerStage,
        motion: Motion,
        inputs: Inputs,
        program: ProgramMemory,
        interpreter: Interpreter,
        access: ParameterAccess,
        operands: Operands,
        *,
        config: Callable[[], Any],
        changed: Callable[[], None],
    ) -> None:
        self.params = params
        self.memory = memory
        self.power = power
        self.motion = motion
        self.inputs = inputs
        self.program = program
        self.interpreter = interpreter
        self.access = access
        self.operands = operands
        self._config = config
        self._changed = changed  # the output P1126 follows the program
        self.interruption = JogInterruption(interpreter, motion, params)  # P1093 (§4.8.6.3)

    # -- statements -------------------------------------------------------------------------------
    def execute(self, stmt: st.Statement) -> None:
        """One statement, interactive or from a program: looked up by its type in
        :data:`STATEMENTS` (spec §3.3)."""
        handler = _STATEMENT.get(type(stmt).__name__)
        if handler is None:
            raise SersError(21)
        handler(self, stmt)

    def assign(self, stmt: st.Assign) -> None:
        target = stmt.target
        if target.kind in ("I", "J", "IN"):
            raise SersError(105)
        if target.kind == "O" and not 1 <= int(target.ref) <= 16:
            raise SersError(4)
        number = address_number(target)
        value = stmt.value
        if number == 1047 and not isinstance(value, str):  # (X=*: errno 19 in write_param, §4.8.3.1)
            self.operands.set_x(self.operands.operand_value(value))
            return
        self.access.write_param(number, value if isinstance(value, str) else self.operands.operand_value(value))

    def command(self, name: str) -> None:
        handler = _COMMAND.get(name)
        if handler is None:
            raise SersError(21)
        handler(self)

    # -- the running program (the host of :class:`.interpreter.Interpreter`) --------------------
    def statement(self, stmt: st.Statement) -> str | None:
        """Execute a statement of a running program; returns what the program must wait for
        (``position``: until the drive stands, §4.6.6) or None to go on at once."""
        key = stmt.name if isinstance(stmt, st.Command) else type(stmt).__name__
        motion = _PROGRAM_MOTION.get(key)
        if motion is not None:
            return motion(self, stmt)
        self.execute(stmt)
        return None

    def positioning(self, stmt: st.Command) -> str | None:
        """E in a program: the program waits until the drive stands, unless a master with
        P1110=0 (§4.8.5.5); E closing a polynomial segment waits for the segment (§4.6.7)."""
        motion = self.motion
        master_goes_on = self._config().address == 0 and int(self.params.wait_until_positioned) == 0
        if motion.poly.definition is not None:
            last = motion.poly.definition[2]
            started = motion.poly.execute() == "started"
            if last:
                return None if (master_goes_on or motion.kind is None) else "position"
            return None if started else "segment"
        self.execute(stmt)
        if motion.kind is None or master_goes_on:
            return None
        return "position"

    def move(self, stmt: st.Command) -> str | None:
        """H, POS0, POSR in a program: it waits until the drive stands."""
        self.execute(stmt)
        return None if self.motion.kind is None else "position"

    def jog(self, stmt: st.Jog) -> str | None:
        """With ':' the statement lasts until standstill; without, it just starts (G-JOGPROG)."""
        self.motion.jog.start(stmt.name, stmt.until, serial=False)
        return "position" if stmt.until is not None and self.motion.kind is not None else None

    def master_target(self) -> int | str | None:
        """In a master (address 0) after ``Z=n`` (P1): the slave statements go to."""
        if self._config().address != 0:
            return None
        target = self.params.target_address
        if target == "*":
            return "*"
        return int(target) if target else None

    def continue_positioning(self) -> None:
        """P1033=1: a program stopped during ``E`` continues the interrupted move."""
        if not self.motion.continue_positioning():
            self.interpreter.on_motion_end()

    def state_changed(self) -> None:
        """The program started or stopped: outputs (P1126) follow."""
        self._changed()

    def ended(self) -> None:
        self.inputs.program_ended()

    def motion_ended(self) -> None:
        """The motion ended: a program waiting for it goes on, one a jog input interrupted may
        continue (§4.8.6.3)."""
        self.interpreter.on_motion_end()
        self.interruption.motion_ended()

    def came_while_interrupted(self, what: str) -> None:
        self.interruption.came(what)

    def jog_input_activated(self) -> None:
        self.interruption.activated()

    def jog_inputs_released(self) -> None:
        self.interruption.released()

    # -- program control --------------------------------------------------------------------------
    @property
    def running(self) -> bool:
        return self.interpreter.running

    @property
    def cycle(self) -> float:
        return self.interpreter.cycle

    def run_program(self, label: int | None) -> None:
        """Starting a stored program (RUN, P0=1): preconditions of §4.4.1."""
        if self.interpreter.running:
            raise SersError(44)
        self.inputs.check_start()
        if self.program.editing:
            self.program.quit()
        self.interpreter.start(label)

    def run_subroutine(self, label: int) -> None:
        """A dispatcher (start input in parallel mode, an event input) calls L``label``."""
        self.inputs.check_start()
        self.interpreter.start(label, subroutine=True)

    def autostart(self) -> None:
        """DIP switch 2 bit 8 (§3.1.2): start a valid program after power-on, unless the
        service switch is on."""
        cfg = self._config()
        if cfg.autostart and not cfg.service_switch and self.program.valid:
            try:
                self.run_program(None)
            except SersError as exc:
                self.power.record_error(exc.errno)

    def stop_program(self) -> None:
        self.interruption.restore()
        self.interpreter.stop()

    def new_program(self) -> None:
        if self.interpreter.running:
            raise SersError(44)
        self.program.new()

    def edit_program(self) -> None:
        if self.interpreter.running:
            raise SersError(44)
        self.program.edit()

    def quit_program(self) -> None:
        if not self.program.editing:
            raise SersError(22)
        self.program.quit()

    def delete(self) -> None:
        """DEL outside programming mode (in it, the serial face deletes the line)."""
        raise SersError(22 if not self.program.editing else 21)

    def stop_all(self) -> None:
        self.interruption.restore()
        self.interpreter.stop()
        self.motion.stop_command()

    def trace_on(self) -> None:
        self.interpreter.trace_mode = True

    def trace_off(self) -> None:
        interpreter = self.interpreter
        interpreter.trace_mode = False
        if interpreter.running and interpreter.waiting is None:
            interpreter.continue_cycle()

    def trace_step(self) -> None:
        self.interpreter.trace_mode = True
        self.interpreter.trace_step()

    def program_end(self) -> None:
        if not self.interpreter.running:
            raise SersError(54)


def _refuse(errno: int) -> Callable[..., None]:
    def handler(*_args: Any) -> None:
        raise SersError(errno)

    return handler


def _nothing(execution: Execution, stmt: st.Statement) -> None:
    return None


#: Statement types (spec §3.3) → what the drive does with them.
STATEMENTS: Table[Callable[[Execution, Any], None]] = Table(
    [
        Command("Assign", Execution.assign, "§4.2", "write a parameter or alias (X: the accumulator)"),
        Command("Arith", lambda d, s: d.operands.arithmetic(s.op, s.operand), "§4.6.10", "X := X op operand"),
        Command("Unary", lambda d, s: d.operands.arithmetic(s.op, None), "§4.6.10", "NOT, NEG on X"),
        Command("Jog", lambda d, s: d.motion.jog.start(s.name, s.until), "§4.5.1", "RS, RF, LS, LF [:condition]"),
        Command("Command", lambda d, s: d.command(s.name), "§4.2", "a keyword command (see below)"),
        Command("Text", _refuse(16), "§4.6.11", "text for the SERS-Programmer: stored in programming mode only"),
        Command("Run", lambda d, s: d.run_program(s.label), "§4.8.6.16", "RUN / RUN n: start the program"),
        Command("Change", _refuse(22), "§4.2", "C n: only in programming mode"),
        Command("Trace", lambda d, s: d.trace_step(), "§4.5.4", "TR: one program step"),
        Command("Goto", _refuse(54), "§4.6.3", "GOTO/GOSUB: only in a program"),
        Command("Wait", _nothing, "§4.6.8", "WAIT: only blocks a program"),
        Command("Label", _nothing, "§4.6.2", "L n: a jump target"),
        Command("Comment", _nothing, "§4.2", "// comment"),
    ]
)
_STATEMENT = {row.token: row.handler for row in STATEMENTS}

#: Keyword commands (spec §3.3) → what the drive does.
COMMANDS: Table[Callable[[Execution], None]] = Table(
    [
        Command("E", lambda d: d.motion.start_positioning(), "§4.6.6", "start positioning to W at V with A"),
        Command("H", lambda d: d.motion.home(), "§4.8.4.5", "start homing (reference run)"),
        Command("S", Execution.stop_all, "§4.8.6.2", "stop: the program and the motion"),
        Command("ON", lambda d: d.power.switch_on(), "§4.8.2.2", "energise the motor (P134=7)"),
        Command("OFF", lambda d: d.power.switch_off(), "§4.8.2.2", "de-energise the motor (P134=0)"),
        Command("PSAVE", lambda d: d.memory.psave(), "§4.8.6.10", "save the RAM parameters in the EEPROM (P1004=2)"),
        Command("POSSAVE", lambda d: d.memory.possave(), "§4.8.4.2", "save P51 in the EEPROM (P1004=4)"),
        Command("POS0", lambda d: d.motion.pos0(), "§4.8.4.2", "move to the next electrical zero, then P51=0"),
        Command("POSR", lambda d: d.motion.posr(force=False), "§4.8.4.2", "after step loss: back to the set-point W"),
        Command("NEW", Execution.new_program, "§4.5.3", "programming mode, deleting the program (P0=2)"),
        Command("PGM", Execution.edit_program, "§4.5.3", "programming mode, editing the program"),
        Command("QUIT", Execution.quit_program, "§4.2", "leave programming mode (P0=0)"),
        Command("DEL", Execution.delete, "§4.2", "delete the current line (programming mode)"),
        Command("TRON", Execution.trace_on, "§4.5.4", "trace (single-step) mode on"),
        Command("TROFF", Execution.trace_off, "§4.5.4", "trace mode off"),
        Command("PE", Execution.program_end, "§4.2", "program end (in a program)"),
        Command("RETURN", Execution.program_end, "§4.6.5", "return from a subroutine (in a program)"),
    ]
)
_COMMAND = {row.token: row.handler for row in COMMANDS}

#: Statements of a running program that move the drive and what the program waits for.
PROGRAM_MOTIONS: Table[Callable[[Execution, Any], str | None]] = Table(
    [
        Command("E", Execution.positioning, "§4.6.6", "until the drive is in position (or the segment ran)"),
        Command("H", Execution.move, "§4.8.4.5", "until the homing run has ended"),
        Command("POS0", Execution.move, "§4.8.4.2", "until the drive stands at the electrical zero"),
        Command("POSR", Execution.move, "§4.8.4.2", "until the drive stands at the setpoint"),
        Command("Jog", Execution.jog, "§4.6.9", "with ':' until the drive stands"),
    ]
)
_PROGRAM_MOTION = {row.token: row.handler for row in PROGRAM_MOTIONS}
