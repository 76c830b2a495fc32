"""Automatic execution of a traverse program on one IP247 axis, BA8 and BA9 (manual §2.6,
§4.3.1–§4.3.3; spec ip247.md §5.11, §4.11).

The blocks come in the order :func:`.flow.steps` gives them; switches, shifts and corrections
take no time, a traverse (X, G74) moves the axis and a dwell (G04) waits on the device clock,
each setting "position reached" when done.  A halt (M00 before the next traverse or dwell, each
step of BA9) and an interruption (Stopp: error 65) leave the axis "fertig" with the context
kept; Übernahme continues, Start begins again, a Stopp on an interrupted program aborts it.
A flying change (G10) joins its blocks into one motion (:mod:`.flying`).
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from typing import Any

from devsim.core.kit import Command, Table
from devsim.devices.ip247 import program as lang
from devsim.devices.ip247.axis_unit import AxisUnit
from devsim.devices.ip247.flow import M_NONE, FlowError, steps
from devsim.devices.ip247.flying import NotJoinable, chain_pieces, resume_pieces
from devsim.devices.ip247.jobs import STOP
from devsim.devices.ip247.program import Block

__all__ = ["CYCLE_BLOCKS", "SWITCHES", "ChainMotion", "ProgramRun", "g_token"]

#: Blocks the module interprets without a traverse or dwell before it gives up with error 33
#: "Zykluszeit überschritten" (manual §7.2; spec §4.11.5: an endless loop without motion).
CYCLE_BLOCKS = 10_000


class ProgramRun:
    """One program context of an axis (spec §4.1.1 ``program_ctx``)."""

    def __init__(self, unit: AxisUnit, number: int, single: bool, programs: dict[int, lang.Program]) -> None:
        self.unit, self.number, self.single = unit, number, single
        self.calls: list[int] = []  # the programs being executed: this one and the subprograms it is in
        self._steps: Iterator[tuple[int, Block, int]] = steps(programs, number, self.calls)
        self.absolute, self.direction = True, 25
        self.metric = unit.md is None or unit.md.unit != 2  # G71 on metric, G70 on inch axes
        self.feed: int | None = None
        self.halted = False  # waiting for Übernahme (M00, a BA9 step): OBSERVE flag bit 3
        self.interrupted = False  # error 65: OBSERVE flag bit 1
        self._pending: tuple[Block, int] | None = None  # the traverse/dwell the halt holds back
        self._halt_next = False  # the last traverse or dwell had M00: halt before the next
        self._timer = None
        self._last: tuple[Block, int] | None = None  # the traverse or dwell executing
        self._move: tuple[float, float] | None = None  # its holder target and frequency
        self._chain = ChainMotion(unit, self._done)  # a G10 chain's blocks ahead
        self._advancing = self._again = False  # interpreting; a traverse ended at once meanwhile

    # -- from the module -------------------------------------------------------------------------
    def start(self) -> None:
        """Start: the blocks run up to the first traverse or dwell; in BA9 the axis then waits
        for Übernahme before it (manual §4.3.2)."""
        self.unit.m_function = M_NONE
        self.unit.coords.program_shift(0)
        self._advance(halt_before=self.single)

    def take_over(self) -> int | None:
        """Übernahme while "fertig": continue after a halt or an interruption."""
        if not (self.halted or self.interrupted):
            return 2
        self.halted = self.interrupted = False
        if self._last is not None and self._move is not None:  # an interrupted traverse is completed first
            unit = self.unit
            target, f = self._move
            unit.running = True
            self._go(lambda: self._chain.go_on(target) or self._complete(target, f))
            return None
        self._advance(skip_halt=True)
        return None

    def stop_at_rest(self) -> tuple[int | None, bool]:
        """Stopp while "fertig": at a halt it interrupts (65); on an interrupted program it
        aborts the context.  Returns (error, context ended)."""
        if self.interrupted:
            self.abort()
            return None, True
        self.halted, self.interrupted = False, True
        return 65, False

    def command(self, ba: int, cmd: int) -> int | None:
        """A job while the program moves (manual §4.3.3, §4.1.1; spec §4.2, §5.11.5): the axis
        brakes and the program is interrupted, Übernahme continues it.  Stopp (or any command
        with BA4) leaves 65; any other job is a wrong operation ("Fehlbedienung": §4.1.1 names
        "Übernahmebefehl mit einer anderen Betriebsart"), which §4.3.3 names beside the Stopp as
        a cause of the interruption; it is error 2 "Nicht erlaubter Auftrag" (§4.1.1, §7.2.2).
        [SIM-CHOICE] §4.3.3 says 65 is output after such an interruption, §4.1.1 that the wrong
        job gives 2: the simulator shows 2, the OBSERVE flag "interrupted" tells the wait."""
        self.unit.last_cmd = cmd
        self._interrupt()
        return 65 if cmd == STOP or ba == 4 else 2

    def abort(self) -> None:
        """The context ends without its M02: leftover program shifts fold into BA12/13's."""
        self._chain.cancel()
        if self._timer is not None:
            self._timer.cancel()
        coords = self.unit.coords
        coords.zo_mode += coords.zo_prog
        coords.zo_prog = 0
        self.unit.automatic = None
        self.unit.m_function = 2

    # -- the blocks -------------------------------------------------------------------------------
    def _advance(self, skip_halt: bool = False, halt_before: bool = False) -> None:
        """The blocks up to the next traverse or dwell, which runs unless a halt holds it: after
        a block with M00, or at BA9's start (``halt_before``); ``skip_halt`` is the Übernahme
        that releases it.  An M00 alone (or with a switch) is a traverse of length 0 (manual
        §2.6.9, §4.3.1, §4.3.2)."""
        if self._advancing:
            self._again = True  # a traverse that took no time ended inside the loop below: it goes on
            return
        self._advancing = True
        try:
            self._interpret(skip_halt, halt_before)
        finally:
            self._advancing = False

    def _interpret(self, skip_halt: bool, halt_before: bool) -> None:
        """:meth:`_advance`'s loop; :data:`CYCLE_BLOCKS` blocks without a traverse or dwell that
        takes time, a halt or the end: error 33 (manual §7.2)."""
        if self._pending is not None:
            block, m = self._pending
            self._pending = None
            if not self._ran_at_once(block, m):
                return
            skip_halt = halt_before = False
        for _ in range(CYCLE_BLOCKS):
            try:
                _, block, m = next(self._steps)
            except StopIteration:
                if self.interrupted:
                    self._rest()  # the interruption point lies before the end (manual §4.3.3)
                    return
                self._end()
                return
            except FlowError as exc:
                self._fail(exc.error)
                return
            error = self._switches(block)
            if error is not None:
                self._fail(error)
                return
            if not _traverse(block) and block.m != 0:
                continue
            if (self._halt_next or halt_before) and not skip_halt:
                self._pending = (block, m)  # the halt point: directly before the traverse
                self._halt()
                return
            if not self._ran_at_once(block, m):
                return
            skip_halt = halt_before = False
        self._fail(33)  # blocks without end and without time: "Zykluszeit überschritten" (§7.2)

    def _ran_at_once(self, block: Block, m: int) -> bool:
        """Run a traverse or dwell (:meth:`_run`); True when it ended at once (a path of length
        0, an M00 alone) and the program goes on."""
        self._again = False
        self._run(block, m)
        again, self._again = self._again, False
        return again

    def _run(self, block: Block, m: int) -> None:
        """A traverse or dwell runs; after one with M00 the next one waits for Übernahme."""
        self._halt_next = block.m == 0
        if _traverse(block):
            self._execute(block, m)
        else:
            self._advance()  # M00 alone: done at once

    def _switches(self, block: Block) -> int | None:
        """The switch, shift or correction a block's G function makes (:data:`SWITCHES`)."""
        assert self.unit.md is not None
        switch = SWITCHES.get(g_token(block.g)) if block.g is not None else None
        return switch(self, block.g) if switch is not None else None

    def _dimensions(self, g: int) -> int | None:
        self.absolute = g == 90
        return None

    def _units(self, g: int) -> int | None:
        md = self.unit.md
        assert md is not None
        if md.unit != 3:
            self.metric = g == 71
        return None

    def _rotary_direction(self, g: int) -> int | None:
        self.direction = g
        return None

    def _shifts_off(self, g: int) -> int | None:
        self.unit.coords.program_shift(0)
        return None

    def _shift(self, g: int) -> int | None:
        md = self.unit.md
        assert md is not None
        self.unit.coords.program_shift(md.zero_offsets[g - 54])
        return None

    def _tools_off(self, g: int) -> int | None:
        self.unit.coords.to_prog = 0
        return None

    def _tool(self, g: int) -> int | None:
        md = self.unit.md
        assert md is not None
        return self.unit.coords.program_tool(md.tool_length, g == 43)

    def _execute(self, block: Block, m: int) -> None:
        unit, md = self.unit, self.unit.md
        assert md is not None
        unit.m_function = m
        self._last = (block, m)
        self._chain.blocks.clear()
        unit.running = True
        unit.changed()
        if block.g == 4:
            unit.in_position = False
            unit.set_pe()

            def dwell() -> None:
                self._timer = unit.clock.call_later((block.f or 0) * 0.1, lambda: self._done(True))

            self._go(dwell)
            return
        result = self._target(block, unit.actual(), unit.holder)
        if isinstance(result, int):
            self._fail(result)
            return
        if block.g == 10 and block.m != 0:  # (M00 in a G10 block splits the chain)
            self._flying(block, m, result)
            return
        target, f, _ = result
        refused = unit.limit_refusal(1 if target > unit.holder else -1 if target < unit.holder else 0)
        if refused is not None:
            self._fail(refused)  # towards an actuated or locked limit switch (manual §2.5.3.10)
            return
        self._move = (target, f)
        self._go(lambda: unit.position_to(target, f, self._done))

    def _go(self, start: Callable[[], None]) -> None:
        """A traverse or dwell starts, or waits for the external start (6, manual §2.8.4); one
        the module refuses ends the program: 53 without the power unit's BB (§2.8.1, §7.2.2),
        55 under BASP (§2.9)."""
        error = self.unit.held(start)
        if error == 6:
            self.unit.set_error(6)
        elif error is not None:
            self._fail(error)

    def _target(self, block: Block, tip: float, holder: float) -> tuple[float, float, float] | int:
        """Where a traverse takes the holder, at which frequency, and the tip coordinate there;
        or the module error (23 SW limit, 43/58 velocity)."""
        unit, md = self.unit, self.unit.md
        assert md is not None
        if block.g == 74:  # the physical reference point at the step velocity
            target, velocity = float(md.reference), float(md.step_velocity)
            end_tip = float(unit.coords.actual(round(target)))
        else:
            assert block.x is not None
            x = self._convert(block.x)
            if block.f:
                self.feed = round(self._convert(block.f))
            velocity = md.v_max if block.g == 0 else float(self.feed or md.step_velocity)
            if md.rotary and self.absolute:
                begin, end = unit.coords.range()
                span = end - begin
                forward = (x - tip) % span
                if self.direction == 26:  # standing on the target: one turn (manual §2.6.6.5's N60)
                    step = forward or span
                elif self.direction == 27:
                    step = forward - span
                else:  # G25: the shortest way, a tie forward
                    step = forward if forward <= span - forward else forward - span
                target, end_tip = holder + step, x
            else:
                end_tip = x if self.absolute else tip + x
                target = float(unit.coords.holder_for(round(end_tip)))
            if not md.rotary and unit.reference_set:
                low, high = unit.coords.range()
                if not low <= target - unit.coords.zero_offset <= high:
                    return 23
        f = md.frequency(velocity)
        if f > md.f_max * (1 + 1e-9) and block.g != 0:
            return 43
        if f < 1:
            return 58
        return target, min(f, float(md.f_max)), end_tip

    def _flying(self, first: Block, m: int, result: tuple[float, float, float]) -> None:
        """A G10 chain (spec §5.11.4): the following traverses joined into one motion."""
        unit, md = self.unit, self.unit.md
        assert md is not None
        chain = [(first, m, result)]
        while chain[-1][0].g == 10 and chain[-1][0].m != 0:
            try:
                _, block, m_next = next(self._steps)
            except StopIteration:
                self._fail(52)
                return
            except FlowError as exc:
                self._fail(exc.error)
                return
            if block.x is None or block.g not in (None, 0, 10):
                self._fail(52)  # a dwell, M02 alone, a switch, a shift or a correction cannot be joined
                return
            _, _, tip = chain[-1][2]
            following = self._target(block, tip, chain[-1][2][0])
            if isinstance(following, int):
                self._fail(following)
                return
            chain.append((block, m_next, following))
        holders = [unit.holder, *(r[0] for _, _, r in chain)]
        steps = [b - a for a, b in zip(holders, holders[1:], strict=False)]
        direction = 1 if steps[0] > 0 else -1
        if any(step * direction <= 0 for step in steps):
            self._fail(47 if md.rotary else 52)
            return
        refused = unit.limit_refusal(direction)
        if refused is not None:
            self._fail(refused)
            return
        unit.begin(direction)
        ends = [unit.machine(h, direction) for h in holders[1:]]
        try:
            pieces, starts = chain_pieces(md.ramp, md.resolution, unit.axis.position(), direction, ends,
                                          [r[1] for _, _, r in chain])
        except NotJoinable:
            self._fail(52)
            return
        self._last = (chain[-1][0], chain[-1][1])
        self._move = (holders[-1], chain[-1][2][1])
        self._chain.blocks[:] = [(h, f, m_b) for h, (_, m_b, (_, f, _)) in zip(holders[1:], chain, strict=True)]
        self._go(lambda: self._chain.follow(0, pieces, starts, ends[-1]))

    def _complete(self, target: float, f: float) -> None:
        assert self._last is not None
        self.unit.m_function = self._last[1]
        self.unit.position_to(target, f, self._done)

    def _convert(self, value: float) -> float:
        """A program value in the axis unit: G70 (0.1 inch) on a metric axis, G71 (mm) on an
        inch axis (spec §4.11.3: 1 inch = 25.4 mm)."""
        md = self.unit.md
        assert md is not None
        if md.unit == 1 and not self.metric:
            return round(value * 2.54)
        if md.unit == 2 and self.metric:
            return round(value / 2.54)
        return value

    def _done(self, reached: bool) -> None:
        unit = self.unit
        self._timer = None
        if not reached:
            return
        block, _ = self._last or (None, 0)
        self._last = None
        unit.in_position = not (block is not None and block.g == 10)
        unit.set_pe()
        if self.interrupted:
            self._rest()
            return
        if self.single:
            self.halted = True
            self._rest()
            return
        self._advance()

    def _interrupt(self) -> None:
        """Brake; the traverse stays to be completed (the dwell counts as expired)."""
        unit = self.unit
        self._chain.cancel()
        self.interrupted, self.halted = True, False
        if self._timer is not None:  # a dwell: expired
            self._timer.cancel()
            self._timer = None
            self._last = None
            unit.in_position = True
            unit.set_pe()
            self._to_interruption_point()
            return
        unit.brake(self._braked)

    def _braked(self, reached: bool) -> None:
        if reached:
            self._last = None  # (braking onto the target: it was reached)
            self._to_interruption_point()
            return
        self._rest()

    def _to_interruption_point(self) -> None:
        """A dwell or a traverse that ended while interrupted: the shifts, corrections and
        switches up to the next traverse or dwell are still done; that one waits (manual
        §4.3.3)."""
        self._advance(halt_before=True)
        self.halted = False  # (interrupted, not halted: Stopp aborts, Übernahme continues)

    def _halt(self) -> None:
        self.halted = True
        self._rest()

    def _rest(self) -> None:
        unit = self.unit
        unit.running = False
        unit.changed()

    def _end(self) -> None:
        unit = self.unit
        unit.coords.program_end()
        unit.automatic = None
        unit.m_function = 2
        self._rest()

    def _fail(self, error: int) -> None:
        unit = self.unit
        self.abort()
        self._rest()
        unit.set_error(error)


class ChainMotion:
    """The blocks of a G10 chain ahead of the axis, as one motion (manual §2.6.6.3, §4.3.3):
    at each joint the next block's M function and target, whose distance is the residual (so
    braking past an intermediate target leaves a negative one), and the chain going on after
    an interruption."""

    def __init__(self, unit: AxisUnit, done: Callable[[bool], None]) -> None:
        self.unit, self._done = unit, done
        self.blocks: list[tuple[float, float, int]] = []  # holder target, frequency, M function
        self._timers: list[Any] = []

    def cancel(self) -> None:
        for timer in self._timers:
            timer.cancel()
        self._timers.clear()

    def follow(self, skip: int, pieces: list[tuple[float, Any]], starts: list[float], end: float) -> None:
        """Along the blocks ahead less ``skip`` done ones, to motor position ``end``."""
        del self.blocks[:skip]
        unit = self.unit
        for at in starts:
            self._timers.append(unit.clock.call_later(at, self._joint))
        unit.follow_path(pieces, self.blocks[-1][0], end, self._done)
        unit.target, _, unit.m_function = self.blocks[0]

    def _joint(self) -> None:
        del self.blocks[0]
        self.unit.target, _, self.unit.m_function = self.blocks[0]

    def go_on(self, target: float) -> bool:
        """Übernahme inside the chain (manual §4.3.3): the flying change goes on as programmed;
        a block the braking passed is done, one too short to reach its velocity again gives
        its rest to the next (:func:`.flying.resume_pieces`).  [SIM-CHOICE] Then the next
        block's M function is output at once.  False: not inside a chain, or nothing joinable."""
        unit, md = self.unit, self.unit.md
        if len(self.blocks) < 2 or md is None:
            return False
        direction = 1 if target > unit.holder else -1
        unit.begin(direction)
        ends = [unit.machine(h, direction) for h, _, _ in self.blocks]
        try:
            skip, pieces, starts = resume_pieces(md.ramp, md.resolution, unit.axis.position(), direction, ends,
                                                 [f for _, f, _ in self.blocks])
        except NotJoinable:
            return False
        self.follow(skip, pieces, starts, ends[-1])
        return True


def _traverse(block: Block) -> bool:
    """A traverse (X, G74) or a dwell (G04)."""
    return block.x is not None or block.g in (74, 4)


def g_token(g: int) -> str:
    """A G function as the tables name it: ``G54``, ``G04``."""
    return f"G{g:02d}"


Switch = Callable[[ProgramRun, int], "int | None"]


def _g(g: int, handler: Switch, section: str, doc: str) -> Command[Switch]:
    return Command(g_token(g), handler, section, doc)


#: The G functions that switch, shift or correct without moving (manual §2.6.6; spec §4.11.3,
#: §4.11.6, §4.11.7): each returns the module error it gives (63 for G43/G44 out of range).
SWITCHES: Table[Switch] = Table([
    _g(90, ProgramRun._dimensions, "§2.6.6", "Maßangaben absolut: X absolute (default)"),
    _g(91, ProgramRun._dimensions, "§2.6.6", "Maßangaben relativ: X relative"),
    _g(70, ProgramRun._units, "§2.6.6", "Maßangaben in 0,1 inch (no effect on a degree axis)"),
    _g(71, ProgramRun._units, "§2.6.6", "Maßangaben in mm (no effect on a degree axis)"),
    _g(25, ProgramRun._rotary_direction, "§2.6.6", "rotary targets the shortest way (default)"),
    _g(26, ProgramRun._rotary_direction, "§2.6.6", "rotary targets clockwise (forward)"),
    _g(27, ProgramRun._rotary_direction, "§2.6.6", "rotary targets counter-clockwise (backward)"),
    _g(53, ProgramRun._shifts_off, "§2.6.6.7", "Verschiebungen aufheben: program zero offsets off"),
    *(_g(54 + i, ProgramRun._shift, "§2.6.6.7", f"Verschiebung {i + 1} einschalten: MD zero offset {i + 1}")
      for i in range(4)),
    _g(40, ProgramRun._tools_off, "§2.6.6.6", "Werkzeugkorrektur aufheben: program tool offsets off"),
    _g(43, ProgramRun._tool, "§2.6.6.6", "positive Werkzeugkorrektur: add the MD tool length"),
    _g(44, ProgramRun._tool, "§2.6.6.6", "negative Werkzeugkorrektur: subtract the MD tool length"),
])
