"""The SERS sequence-program interpreter (manual §4.5, §4.6; spec §4.4, §4.10).

The stored program is compiled into a flat list of statements with a label table and the
jumps of the IF…THEN…ELSE…END blocks.  One statement runs per control cycle – 0.5 ms, or 2 ms
with P1127=1 (§1.2, §4.8.6.10) – scheduled on the device clock, so a program never starves the
serial interface.  Statements that wait (``E`` until the drive is in position, ``D`` delays,
``WAIT`` and ``:`` conditions, ``H``, ``POS0``) park the program until their event; conditions
are looked at again whenever the drive's state changes and, while the axis moves, every cycle.

Starting (``RUN``, ``P0=1``, autostart, start input I8, the parallel and event dispatchers),
errors (program errors stop the program with P12 value 128; drive errors jump to L65 with
P1033=2/3), stops and continuation (P1033), the non-blocking timer ``D2`` with its timed jump,
trace mode and the ``@nP0=0`` message are handled here.  A jog input that interrupts the
program (P1093=0, §4.8.6.3) parks it as waiting ``jog``; :mod:`.interruption` keeps what it
waited for and decides when it goes on.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, Protocol

import msgspec

from devsim.core.clock import Clock, Timer
from devsim.core.kit import Command, Table
from devsim.devices.sers import statements as st
from devsim.devices.sers.errors import SersError
from devsim.devices.sers.master import MasterLink
from devsim.devices.sers.motion import Motion
from devsim.devices.sers.operands import Operands
from devsim.devices.sers.params import SersParameters
from devsim.devices.sers.power import PowerStage
from devsim.devices.sers.program import ProgramMemory
from devsim.devices.sers.remote import RemoteStatements

#: Statements a program passes over (a tuple: ``isinstance`` checks it faster than a union).
_PASSIVE = (st.Label, st.Comment, st.Text)


class ProgramHost(Protocol):
    """What the interpreter (§4.5, §4.6) needs of the program execution
    (:class:`~.execution.Execution`)."""

    def statement(self, stmt: st.Statement) -> str | None:
        """Execute a statement of the program; what the program waits for (``position`` …)."""

    def master_target(self) -> int | str | None:
        """The slave statements go to after ``Z=n`` (a master only), or None."""

    def continue_positioning(self) -> None: ...

    def state_changed(self) -> None:
        """The program started or stopped (P0, the output P1126)."""

    def ended(self) -> None:
        """The program ended normally (the dispatchers may start the next one)."""

    def came_while_interrupted(self, what: str) -> None:
        """What the program waited for came while a jog input interrupted it (P1093=0, §4.8.6.3)."""


__all__ = ["FLOW", "Interpreter", "Program", "ProgramHost"]


MAX_NESTING = 4  # GOSUB depth (§4.6.4)
L65 = 65  # error / stop handler label (§4.6.2)


class Program(msgspec.Struct):
    """A compiled program: statements in order, labels (§4.6.2) and block jumps (§4.6.1)."""

    statements: list[st.Statement] = msgspec.field(default_factory=list)
    texts: list[str] = msgspec.field(default_factory=list)
    labels: dict[int, int] = msgspec.field(default_factory=dict)  # label number -> statement index
    block_end: dict[int, int] = msgspec.field(default_factory=dict)  # IF..THEN index -> ELSE/END index; ELSE -> END
    #: Per statement, what the program itself does with it (its row of :data:`FLOW`, looked up
    #: once): ``_passed_over`` for a statement passed over, None for one the drive executes.
    flow: list[Any] = msgspec.field(default_factory=list)

    @classmethod
    def compile(cls, texts: list[str]) -> Program:
        program = cls()
        open_blocks: list[int] = []
        for text in texts:
            result = st.parse(text, final=True)
            if result.errno is not None or len(result.statements) != 1:
                stmt: st.Statement = st.Comment(text)  # unreadable: skipped (never stored normally)
            else:
                stmt = result.statements[0][0]
            index = len(program.statements)
            program.statements.append(stmt)
            program.texts.append(text)
            program.flow.append(_passed_over if isinstance(stmt, _PASSIVE) else _FLOW.get(_flow_token(stmt)))
            if isinstance(stmt, st.Label) and stmt.number not in program.labels:
                program.labels[stmt.number] = index
            elif isinstance(stmt, st.If) and stmt.then:
                open_blocks.append(index)
            elif isinstance(stmt, st.Else) and open_blocks:
                program.block_end[open_blocks[-1]] = index
                open_blocks[-1] = index
            elif isinstance(stmt, st.End) and open_blocks:
                program.block_end[open_blocks.pop()] = index
        return program

    def label_index(self, label: int) -> int:
        """The statement a jump to L``label`` goes to (errno 72: no label number, 71: not in the program)."""
        if not st.LABEL_MIN <= label <= st.LABEL_MAX:
            raise SersError(72)
        index = self.labels.get(label)
        if index is None:
            raise SersError(71)
        return index


class Passes(Protocol):
    """What hears the passes of a loop (:class:`~.runahead.RunAhead`)."""

    def looped(self) -> None: ...


class Interpreter:
    """Runs the stored program of one SERS (§4.5, §4.6)."""

    not_state = frozenset({"runahead"})  # (what it knows of the passes is not the drive's state)

    def __init__(
        self,
        clock: Clock,
        params: SersParameters,
        memory: ProgramMemory,
        operands: Operands,
        power: PowerStage,
        motion: Motion,
        master: MasterLink,
        *,
        host: Callable[[], ProgramHost],
        render: Callable[[str], str],
        spontaneous: Callable[[str], None],
        address: Callable[[], int],
        runahead: Passes,
    ) -> None:
        self.clock = clock
        self.params = params
        self.memory = memory  # the stored program
        self.operands = operands
        self.power = power
        self.motion = motion
        self._host = host  # (the program execution, made after the interpreter)
        self._render = render  # a statement as LIST shows it (TR)
        self._spontaneous = spontaneous
        self._address = address
        self.runahead = runahead  # hears each jump back (a pass of a loop may have ended, §4.6.3)
        self.remote = RemoteStatements(master, operands, self)
        #: Trace mode (TRON, TR): one statement per TR (§4.5.4).
        self.trace_mode = False
        self.program = Program()
        self.running = False
        self.pc = 0
        self.stack: list[int] = []
        self.subroutine = False  # started at a label (RUN n, dispatchers): RETURN on empty stack ends it
        self.waiting: str | None = None  # what a parked program waits for
        self._wait_cond: st.Condition | None = None
        self._timer: Timer | None = None
        self._delay: Timer | None = None
        self._d2: Timer | None = None
        self._d2_jump: st.Goto | None = None
        self.d2_pending = False
        self.stops = 0  # consecutive stops (P1033=1: the second one restarts)
        self.resume_pc: int | None = None
        self._resume_move = False
        self._poll: Timer | None = None

    # -- state ----------------------------------------------------------------------------------
    @property
    def cycle(self) -> float:
        return 0.002 if int(self.params.slow_program_cycle) == 1 else 0.0005

    def reset(self) -> None:
        """Power-on: nothing runs."""
        self._cancel()
        self.running = False
        self.waiting = None
        self.stack.clear()
        self.stops = 0
        self.resume_pc = None
        self.params.l65_flag = 0  # (the L65 error-handling flag is P1118)
        self.trace_mode = False

    def _cancel(self) -> None:
        for timer in (self._timer, self._delay, self._d2, self._poll):
            if timer is not None:
                timer.cancel()
        self._timer = self._delay = self._d2 = self._poll = None
        self._d2_jump = None
        self.d2_pending = False

    # -- starting and ending ------------------------------------------------------------------------
    def start(self, label: int | None = None, *, subroutine: bool | None = None) -> None:
        """Start at line 1 or at label ``label`` (preconditions are the caller's)."""
        self.program = Program.compile(self.memory.statements())
        self._cancel()
        self.stack.clear()
        self.waiting = None
        self.params.l65_flag = 0  # (the L65 error-handling flag is P1118)
        if label is not None:
            if not st.LABEL_MIN <= label <= st.LABEL_MAX:
                raise SersError(72)
            if label not in self.program.labels:
                raise SersError(71)
            self.pc = self.program.labels[label]
            self.subroutine = True if subroutine is None else subroutine
        elif self.resume_pc is not None and int(self.params.continuation_after_stop) == 1 and self.stops == 1:
            self.pc = self.resume_pc  # P1033=1: continue where the stop happened
            self.subroutine = False
        else:
            self.pc = 0
            self.subroutine = False
            self.stops = 0
        self.resume_pc = None
        self.running = True
        self._host().state_changed()
        if self._resume_move:
            self._resume_move = False
            self.waiting = "position"
            try:
                self._host().continue_positioning()
            except SersError as exc:
                self.program_error(exc.errno)
                return
            return
        self._schedule(self.cycle)

    def end(self) -> None:
        """Normal end (PE, end of the program, RETURN of a dispatched subroutine)."""
        was = self.running
        self.params.l65_flag = 0  # (the L65 error-handling flag is P1118)
        self._halt()
        if was and self.params.report_program_end:
            self._spontaneous(f"@{self._address()}P0=0")
        self._host().ended()

    def stop(self) -> None:
        """A stop command (S) or the STOP input while the program runs (P1033, §4.8.6.2)."""
        if not self.running:
            return
        mode = int(self.params.continuation_after_stop)
        if mode in (2, 3) and not (mode == 3 and self.params.l65_flag) and L65 in self.program.labels:
            self._jump_l65()
            return
        self.stops += 1
        # pc is already past a parked statement: after an interrupted E the program goes on
        # with the next one once the move itself is continued; a WAIT, a ':' jog, H, POS0 …
        # are executed again
        self.resume_pc = self.pc if self.stops == 1 else None
        parked = self.program.statements[self.pc - 1] if 0 < self.pc <= len(self.program.statements) else None
        is_move = isinstance(parked, st.Command) and parked.name == "E"
        if self.resume_pc is not None and self.waiting in ("wait", "position") and not is_move:
            self.resume_pc = self.pc - 1
        self._resume_move = mode == 1 and self.stops == 1 and self.waiting == "position" and is_move
        self._cancel()
        self.running = False
        self.waiting = None
        self._host().state_changed()

    def on_drive_error(self) -> None:
        """A drive error (P11) stops the program, or jumps to L65 with P1033=2/3 (§4.6.2)."""
        if not self.running:
            return
        mode = int(self.params.continuation_after_stop)
        if mode == 3 and self.params.l65_flag:
            return  # P1033=3: during the L65 handling further errors neither stop nor jump
        if mode in (2, 3) and L65 in self.program.labels:
            self._jump_l65()
            return
        self._halt()

    def abort(self) -> None:
        """P1093=1 (§4.8.6.3): a jog input aborts the program; a start begins at line 1 again."""
        self._halt()

    def _halt(self) -> None:
        """The program stops for good (an error, or its end): the next start begins at line 1."""
        self._cancel()
        self.running = False
        self.waiting = None
        self.stops = 0
        self.resume_pc = None
        self._host().state_changed()

    def _jump_l65(self) -> None:
        self._cancel()
        self.waiting = None
        self.stack.clear()
        self.pc = self.program.labels[L65]
        self.params.l65_flag = 1  # the L65 error handling runs (P1118)
        self.subroutine = False
        self._schedule(self.cycle)

    def program_error(self, errno: int, detail: str = "") -> None:
        """Unknown jump target, stack overflow, arithmetic error …: the program stops with
        P12 value 128 (display 'H' blinking) and the errno (§4.8.3.1)."""
        self.power.record_error(errno)
        self.power.warn(128)
        self._halt()  # (nothing is sent, G-FAULTMSG)

    # -- the cycle ------------------------------------------------------------------------------------
    def continue_cycle(self) -> None:
        """Go on at the next control cycle (after trace mode was switched off)."""
        self._schedule(self.cycle)

    def _schedule(self, delay: float) -> None:
        if self.trace_mode:
            return  # single step: TR executes the next statement
        if self._timer is not None:
            self._timer.cancel()
        self._timer = self.clock.call_later(delay, self._tick)

    def _tick(self) -> None:
        self._timer = None
        if not self.running or self.waiting is not None:
            return
        if self.d2_pending and not self._position_blocks():
            self._fire_d2_jump()
            return
        self.step()

    def trace_step(self) -> str | None:
        """TR: execute one statement (starting the program at the current position if it does
        not run, G-TRACE); returns the listed statement."""
        if not self.running:
            self.program = Program.compile(self.memory.statements())
            # the current program position is a statement number (LIST n, 0 = before the first)
            self.pc = min(max(0, self.memory.position - 1), max(0, len(self.program.statements) - 1))
            self.running = True
            self.subroutine = False
            self._host().state_changed()
        if self.waiting is not None or self.pc >= len(self.program.statements):
            return None
        text = f"{self.pc + 1}: {self._render(self.program.texts[self.pc])}"
        self.step()
        return text

    def step(self) -> None:
        """Execute the statement at ``pc``."""
        program = self.program
        if self.pc >= len(program.statements):
            self.end()  # the end of the stored program ends it (G-PROGEND)
            return
        stmt = program.statements[self.pc]
        self.memory.position = self.pc + 1  # LIST . shows the line being executed
        flow, before = program.flow[self.pc], self.pc
        try:
            advance = self._execute(stmt, flow)
        except SersError as exc:
            self.program_error(exc.errno, exc.detail)
            return
        if not self.running:
            return
        if advance:
            self.pc += 1
        if self.waiting is None:
            self._schedule(self.cycle)
            if flow is _goto and self.pc <= before and self._timer is not None:
                self.runahead.looped()  # (a pass of a loop may have ended: its next cycle is scheduled)

    # -- statements -------------------------------------------------------------------------------------
    def _execute(self, stmt: st.Statement, flow: Callable[[Interpreter, Any], bool] | None) -> bool:
        """Run one statement; True if the program goes on with the next one.  ``flow`` is its row
        of :data:`FLOW`; the drive does the rest and says what the program waits for."""
        if flow is _passed_over:
            return True
        host = self._host()
        target = host.master_target()
        if target is not None and self.remote.send(stmt, target):
            return False  # sent to a slave; the answer moves the program on
        if flow is not None:
            return flow(self, stmt)
        self.waiting = host.statement(stmt)
        return True

    def branch(self, stmt: st.If, true: bool) -> None:
        """IF: without THEN skip the next statement when false; with THEN go to ELSE/END."""
        if stmt.then:
            if not true:
                self.pc = self.program.block_end.get(self.pc, len(self.program.statements) - 1)
        elif not true:
            self.pc += 1

    def start_delay(self, stmt: st.Assign) -> None:
        """D (§4.8.5.1): wait D × 0.1 s (× 1.2 unless P1141 = 1)."""
        value = self.operands.operand_value(stmt.value) if not isinstance(stmt.value, str) else 0.0
        factor = 1.0 if int(self.params.delay_correction) == 1 else 1.2
        self.waiting = "delay"
        self._delay = self.clock.call_later(max(0.0, float(value)) * 0.1 * factor, self._delay_done)

    # -- master mode (§3.6.2, §4.8.5.5; the parked program of :class:`.remote.RemoteStatements`) -----
    def park_for_master(self) -> None:
        self.waiting = "master"

    def awaiting_master(self) -> bool:
        return self.running and self.waiting == "master"

    def master_answered(self, branch: st.If | None = None, true: bool = False) -> None:
        if branch is not None:
            self.branch(branch, true)
        self.pc += 1
        self.resume("master")

    def master_failed(self) -> None:
        self.program_error(64)

    def later(self, delay: float, action: Callable[[], None]) -> None:  # (the master's retries)
        self._timer = self.clock.call_later(delay, action)

    # -- waiting ----------------------------------------------------------------------------------------
    def park(self, what: str, cond: st.Condition | None) -> None:
        self.waiting = what
        self._wait_cond = cond
        self.poke()

    def poke(self) -> None:
        """The drive's state changed: a parked WAIT may go on."""
        if self.waiting != "wait" or not self.running:
            return
        if self.operands.evaluate(self._wait_cond, counters=False):
            self.waiting = None
            self._wait_cond = None
            if self._poll is not None:
                self._poll.cancel()
                self._poll = None
            self._schedule(self.cycle)
        elif self.motion.axis.moving and self._poll is None:
            # positions change continuously: look again every cycle while the axis moves
            self._poll = self.clock.call_later(self.cycle, self._poll_tick)

    def _poll_tick(self) -> None:
        self._poll = None
        self.poke()

    def on_motion_end(self) -> None:
        if self.waiting == "position" and self.running:
            self.resume("position")
        else:
            self.poke()

    def resume(self, what: str) -> None:
        """What the parked program waited for (``position``, ``segment``, ``master`` …) came."""
        if self.waiting == "jog":
            self._host().came_while_interrupted(what)  # (it goes on once the interruption ends)
        if self.waiting != what or not self.running:
            return
        self.waiting = None
        if self.d2_pending:
            self._fire_d2_jump()
            return
        self._schedule(self.cycle)

    def _delay_done(self) -> None:
        self._delay = None
        self.resume("delay")

    def _position_blocks(self) -> bool:
        """A D2 jump waits: for the position (P1110=1), or while a jog input interrupts (§4.8.6.3)."""
        return self.waiting == "jog" or (self.waiting == "position" and int(self.params.wait_until_positioned) == 1)

    # -- D2 (§4.8.5.1) ---------------------------------------------------------------------------------
    def start_d2(self, stmt: st.Assign) -> None:
        """D2 (§4.8.5.1): the non-blocking timer; a GT/GS right after it is its timed jump."""
        value = self.operands.operand_value(stmt.value) if not isinstance(stmt.value, str) else 0.0
        self.params.d2_time = float(value)
        self.params.d2_bit = 0
        # "D2=Wert" reloads (extends) the time of a jump not yet executed (§4.8.5.1)
        pending = self._d2_jump if self._d2 is not None else None
        if self._d2 is not None:
            self._d2.cancel()
        nxt = self.program.statements[self.pc + 1] if self.pc + 1 < len(self.program.statements) else None
        self._d2_jump = pending
        if isinstance(nxt, st.Goto):
            self._d2_jump = nxt
            self.pc += 1  # the GT/GS belongs to the timer: it is not executed now
        self._d2 = self.clock.call_later(max(0.0, float(value)) * 0.1, self._d2_expired)

    def _d2_expired(self) -> None:
        self._d2 = None
        self.params.d2_bit = 1
        if self._d2_jump is not None and self.running:
            if self._position_blocks():
                self.d2_pending = True  # P1110=1: the jump waits until the drive is in position
            else:
                self._fire_d2_jump()
        self.poke()

    def _fire_d2_jump(self) -> None:
        """The timed jump: aborts a running D, WAIT or ':' (§4.8.5.1)."""
        jump = self._d2_jump
        self.d2_pending = False
        self._d2_jump = None
        if jump is None or not self.running:
            return
        if self._delay is not None:
            self._delay.cancel()
            self._delay = None
        if self.waiting == "position" and self.motion.kind == "jog":
            self.motion.stop_motion()
        self.waiting = None
        self._wait_cond = None
        try:
            target = self.program.label_index(jump.label)
            if jump.sub:
                if len(self.stack) >= MAX_NESTING:
                    raise SersError(73)
                self.stack.append(self.pc)  # pc is the statement not yet executed
        except SersError as exc:
            self.program_error(exc.errno)
            return
        self.pc = target
        self._schedule(self.cycle)


def _going_on(interpreter: Interpreter, stmt: st.Statement) -> bool:
    return True


def _passed_over(interpreter: Interpreter, stmt: st.Statement) -> bool:
    """A label, comment or text: the program passes over it (its own control cycle, §1.2)."""
    return True


def _if(interpreter: Interpreter, stmt: st.If) -> bool:
    interpreter.branch(stmt, interpreter.operands.evaluate(stmt.cond))
    return True


def _else(interpreter: Interpreter, stmt: st.Else) -> bool:
    pc = interpreter.pc
    interpreter.pc = interpreter.program.block_end.get(pc, pc)  # the THEN part ran: skip to END
    return True


def _goto(interpreter: Interpreter, stmt: st.Goto) -> bool:
    target = interpreter.program.label_index(stmt.label)
    if stmt.sub:
        if len(interpreter.stack) >= MAX_NESTING:
            raise SersError(73)
        interpreter.stack.append(interpreter.pc + 1)
    interpreter.pc = target
    return False


def _return(interpreter: Interpreter, stmt: st.Command) -> bool:
    if interpreter.stack:
        interpreter.pc = interpreter.stack.pop()
        return False
    if interpreter.subroutine:
        interpreter.end()
        return False
    raise SersError(72)  # G-RETURN: RETURN without GOSUB in a program from line 1


def _program_end(interpreter: Interpreter, stmt: st.Command) -> bool:
    interpreter.end()
    return False


def _wait(interpreter: Interpreter, stmt: st.Wait) -> bool:
    interpreter.park("wait", stmt.cond)
    return True


def _run(interpreter: Interpreter, stmt: st.Run) -> bool:
    interpreter.start(stmt.label)
    return False


def _delay(interpreter: Interpreter, stmt: st.Assign) -> bool:
    interpreter.start_delay(stmt)
    return True


def _d2(interpreter: Interpreter, stmt: st.Assign) -> bool:
    interpreter.start_d2(stmt)
    return True


def _flow_token(stmt: st.Statement) -> str:
    """A statement's row in :data:`FLOW`: a command by its keyword, ``D`` / ``D2`` by the alias
    assigned, anything else by its type."""
    if isinstance(stmt, st.Command):
        return stmt.name
    if isinstance(stmt, st.Assign) and stmt.target.kind == "alias" and stmt.target.ref in ("D", "D2"):
        return str(stmt.target.ref)
    return type(stmt).__name__


#: What the program itself does with a statement (§4.6); every other one the drive executes.
FLOW: Table[Callable[[Any, Any], bool]] = Table(
    [
        Command("If", _if, "§4.6.1", "IF condition [THEN … ELSE … END]"),
        Command("Else", _else, "§4.6.1", "ELSE: the THEN part ran, skip to END"),
        Command("End", _going_on, "§4.6.1", "END of an IF block"),
        Command("Goto", _goto, "§4.6.3", "GOTO/GT, GOSUB/GS n (4 levels)"),
        Command("RETURN", _return, "§4.6.5", "back from a subroutine"),
        Command("PE", _program_end, "§4.2", "program end"),
        Command("Wait", _wait, "§4.6.8", "WAIT condition"),
        Command("Run", _run, "§4.8.6.16", "RUN [n]: start again"),
        Command("D", _delay, "§4.8.5.1", "D=n: wait n × 0.1 s"),
        Command("D2", _d2, "§4.8.5.1", "D2=n [GT/GS m]: the non-blocking timer and its jump"),
        *(Command(name, _going_on, "§4.2", "means nothing inside a program")
          for name in ("NEW", "PGM", "QUIT", "DEL", "VER", "TRON", "TROFF")),
        *(Command(name, _going_on, "§4.2", "answers only interactively")
          for name in ("Query", "ListCmd", "Trace", "Change")),
    ]
)
_FLOW = {row.token: row.handler for row in FLOW}
