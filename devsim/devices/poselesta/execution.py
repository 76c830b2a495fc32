"""Program execution: the block cycle of the automatic modes and Hand-Einzelsatz (manual §2.3.1–
§2.3.3, §2.3.13–§2.3.19, §2.3.22, §2.4.2–§2.4.8, §2.4.10; spec poselesta.md §4.3, §4.4.5–§4.4.9,
§5.2, §5.3, §6.3).

A block runs as: its block-start M functions, S1, S2 and T on the data bus (:class:`MstBus`);
M06 and a non-self-holding M10 wait for their acknowledge; the travel commands and the axis
enable; the motion on the closed-form axes (:mod:`~devsim.devices.poselesta.block_motion`);
exact positioning with "Position erreicht" and "Programm fortsetzen"; then the block-end M
functions (M05, M09, M11, M15, odd free codes, then M00/M01/M02).  NC-Stop brakes to ``HOLD``,
NC-Start continues; Not-Stop stops at once, gives up the handshake and the program.

What each G, M and address word does is a row of the tables in
:mod:`~devsim.devices.poselesta.functions`.  Subroutines and repeats (G10–G13), dwell (G04) and
block abort (P90) change the flow.  Not simulated: G25 (its blocks run as no motion, event
``unsupported_g``) and cutter compensation G41/G42 (accepted, no offset).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import msgspec

from devsim.core.clock import Clock, Timer
from devsim.core.kit import Command, Table
from devsim.core.signals import SignalBank
from devsim.devices.poselesta.block_motion import BlockMotion
from devsim.devices.poselesta.contour import PLANES
from devsim.devices.poselesta.flow import ProgramFlow
from devsim.devices.poselesta.functions import ADDRESSES, BlockFunctions, block_end_function
from devsim.devices.poselesta.mst import MstBus
from devsim.devices.poselesta.parameters import MachineParameters
from devsim.devices.poselesta.screen import Screen
from devsim.devices.poselesta.signals import AXES
from devsim.devices.poselesta.tape import Block

__all__ = ["EXECUTION_MODES", "STATES", "ExecutionOptions", "Executor"]

STATES = ("IDLE", "BLOCK_START", "MST_OUTPUT", "WAIT_TOOL_CHANGE", "WAIT_M10_PULSE", "WAIT_AXIS_ENABLE",
          "MOVING", "WAIT_PROGRAM_CONTINUE", "HOLD", "STOPPED", "LIMIT_STOP", "END")
#: States in which a block is being worked on: the "Start" symbol, V16/8 H (spec §4.3.1).
RUNNING = frozenset(("BLOCK_START", "MST_OUTPUT", "WAIT_TOOL_CHANGE", "WAIT_M10_PULSE", "WAIT_AXIS_ENABLE",
                     "MOVING", "WAIT_PROGRAM_CONTINUE"))
EXECUTION_MODES = ("AUTO_CONTINUOUS", "AUTO_SINGLE_BLOCK", "MANUAL_SINGLE_BLOCK")
POSITION_REACHED_PULSE = 60e-6  # §2.4.2: with "Programm fortsetzen" already H

Program = Callable[[], tuple[list[Block], bool]]


class BlockChain:
    """The next block, as a loop: blocks that end at once (no motion, no M, S or T to hand over)
    follow one another in the same instant, each asking for the next while it still runs; as
    nested calls a few hundred in a row ran out of Python's stack (RecursionError).  A program that
    runs :data:`LIMIT` blocks in one instant can never go on (a subroutine that calls itself
    without motion): the event ``endless_loop``, and the program ends."""

    LIMIT = 100_000

    def __init__(self, step: Callable[[], None], end: Callable[[], None], screen: Screen) -> None:
        self.step, self.end, self.screen = step, end, screen
        self.running = self.again = False

    def __call__(self) -> None:
        if self.running:
            self.again = True  # (the step that runs now is followed by the next)
            return
        self.running, self.again, count = True, True, 0
        try:
            while self.again and count < self.LIMIT:
                self.again, count = False, count + 1
                self.step()
        finally:
            self.running = False
        if self.again:
            self.screen.record("endless_loop")
            self.end()


class ExecutionOptions(msgspec.Struct, frozen=True):
    """What the variant and the configuration change in the block cycle (spec §4.3.6, G-M06,
    §4.12.1, G-M01): V22/10 block abort (POS III), M06 waiting for NC-Start, G25 as a full circle,
    the start/stop status output V16/8 (POS III, manual §2.4.10), the level of V21/10 that makes
    M01 stop (H by the pin list and the table of contents, "M 01 wahlweisen Halt aktivieren"; L
    with ``invert_optional_stop``, the diagnostic table's "M 01 aufheben")."""

    block_abort: bool = True
    m06_requires_nc_start: bool = False
    g25_full_circle: bool = False
    start_stop_status: bool = True
    invert_optional_stop: bool = False


class Executor:
    """The block cycle of one control (spec §4.3.2) on its clock, signals and MST bus; the
    motion of a block is ``motion``'s, what its words do ``functions``'.

    ``mode()`` is the operating mode, ``booting()`` whether the control starts up,
    ``inside_field()`` whether every axis is inside the working field, ``program()`` the blocks to
    run and whether they were typed in inch; ``stop_manual()`` stops manual motion with Not-Stop
    (the model hears the Not-Stop input and calls :meth:`emergency_stop`)."""

    def __init__(self, clock: Clock, signals: SignalBank, mst: MstBus, motion: BlockMotion,
                 functions: BlockFunctions, flow: ProgramFlow, params: MachineParameters, screen: Screen, *,
                 mode: Callable[[], str], booting: Callable[[], bool], inside_field: Callable[[], bool],
                 program: Program, stop_manual: Callable[[], None], options: ExecutionOptions) -> None:
        self._clock = clock
        self.signals = signals
        self._mst = mst
        self.motion = motion
        self.functions = functions
        self._params = params
        self._screen = screen
        self._mode = mode
        self._booting = booting
        self._inside_field = inside_field
        self._program = program
        self._stop_manual = stop_manual
        self._options = options
        self.state = "IDLE"
        self.flow = flow
        self.block: Block | None = None
        self.stop_pending = False  # NC-Stop during M/S/T output: the motion waits for NC-Start
        self._resume: Callable[[], None] | None = None
        self.abort_pending = False
        self.dwelling = False  # G04: the block waits its L seconds, the axes stand (spec §5.3)
        self._timer: Timer | None = None
        self._next_block = BlockChain(self._block_start, self._program_end, screen)
        for name, handler in (("nc_start", self._nc_start_input), ("nc_stop", self._nc_stop_input),
                              ("axis_enable", self._wait_input),
                              ("program_continue", self._wait_input), ("tool_change_ack", self._wait_input),
                              ("m10_ack", self._m10_ack_input), ("override_pot_v", self._override_input),
                              ("block_abort", self._block_abort_input)):
            self.signals.subscribe(name, handler)

    # -- state ------------------------------------------------------------------------------------
    def _enter(self, state: str) -> None:
        self.state = state
        self.signals.set("start_stop_status", state in RUNNING and self._options.start_stop_status)

    @property
    def running(self) -> bool:
        """A block is being worked on: the mode cannot change (spec §4.1)."""
        return self.state in RUNNING or self._mst.busy and self.state != "IDLE"

    @property
    def block_number(self) -> int:
        return self.block.number if self.block is not None else -1

    def reset(self) -> None:
        """Back to the first block (a mode change abandons a stopped program, spec §4.1): its
        travel commands end."""
        self._cancel_timer()
        if self.state != "IDLE":
            self._travel_off()
            self.functions.block_over(self._mode() == "MANUAL_SINGLE_BLOCK")
        self.motion.reset()
        self._resume = None
        self.stop_pending = self.abort_pending = False
        self.flow.restart()
        self.block = None
        self._enter("IDLE")

    def _travel_off(self) -> None:
        for a in AXES:
            self.signals.set(f"travel_{a}", False)
        self.signals.set("position_reached", False)

    # -- NC-Start, NC-Stop, Not-Stop ----------------------------------------------------------------
    def _nc_start_input(self, _name: str, old: Any, new: Any) -> None:
        if new and not old:
            self.nc_start("external")

    def nc_start(self, source: str = "panel") -> None:
        """NC-Start (§2.3.3): starts from the first block, continues a stop or a hold; P75 says
        which source counts (0 both, 1 the panel, 2 the external button V19/3)."""
        if not self._params.nc_start_counts(source) or self._booting() or not self.signals.get("emergency_stop"):
            return
        if self._mode() not in EXECUTION_MODES or not self.signals.get("nc_stop") or not self._inside_field():
            self._screen.record("nc_start_ignored")  # (also while outside the working field, spec §5.5)
            return
        for output in ("m00", "m01", "m02", "m06"):
            self.signals.set(output, False)  # reset by NC-Start (§2.4.7)
        if self.state in ("IDLE", "END"):
            if not self._load():
                return
            self.flow.restart()
            self._next_block()
        elif self.state in ("STOPPED", "HOLD", "LIMIT_STOP") or self.stop_pending:
            self.stop_pending = False
            resume, self._resume = self._resume, None
            if resume is not None:
                resume()

    def _load(self) -> bool:
        self.flow.blocks, self.motion.typed_inch = self._program()
        if not self.flow.blocks:
            self._screen.record("no_program")
            return False
        return True

    def _nc_stop_input(self, _name: str, _old: Any, new: Any) -> None:
        if new or self._mode() == "MANUAL":
            return  # NC-Stop is ineffective in MANUAL (§2.3.1)
        if self.state == "MOVING" and not self.dwelling:
            self._brake("HOLD")
        elif self.state in RUNNING:
            # the output (or a dwell) goes on; the next motion waits for NC-Start (§2.3.1)
            self.stop_pending = True

    def left_field(self) -> None:
        """An axis left the working field: all brake as with NC-Stop, the program stops (§2.4.4)."""
        if self.state == "MOVING":
            self._brake("LIMIT_STOP")

    def emergency_stop(self) -> None:
        """§2.3.2: axes stop at once without ramp, set-points 0 V, the handshake is given up and
        the program aborted (spec §4.3.5); NC ready stays H."""
        self.motion.quick_stop()
        self._stop_manual()
        self.abort()

    def abort(self) -> None:
        """The program is given up (Not-Stop, a limit switch): handshake abandoned, travel
        commands L, back to the first block; self-holding M outputs stay (spec §4.3.5)."""
        self._cancel_timer()
        self._mst.abandon()
        self._travel_off()
        self.signals.set("machine_standstill", True)
        self.motion.forget_arrivals()
        self.reset()

    # -- the block cycle ----------------------------------------------------------------------------
    def _block_start(self) -> None:
        """BLOCK_START: the next block in ascending N; a block marked ``/`` is skipped while the
        block-skip input is L (sampled now, §2.3.13); past the last block is as M02."""
        block = self.flow.next_block()
        if block is None:
            self._program_end()
            return
        self._run(block)

    def _run(self, block: Block) -> None:
        self.block = block
        self.motion.inch = bool(self.signals.get("inch"))
        self._enter("BLOCK_START")
        self.functions.begin(block)
        functions: list[tuple[str, int]] = []
        for address in ADDRESSES:
            address.handler(self.functions, block, functions)
        self._enter("MST_OUTPUT")
        self._mst.output(functions, self._after_start_functions)

    def _after_start_functions(self) -> None:
        if self.abort_pending:
            self._jump_p90()
            return
        if not self.functions.tool_change:
            self._after_tool_change()
        elif not self.signals.get("tool_change_ack"):
            self._enter("WAIT_TOOL_CHANGE")  # §2.3.17: after M06, S and T are taken over
        else:
            self._tool_changed()

    def _tool_changed(self) -> None:
        self.signals.set("m06", False)
        if self._options.m06_requires_nc_start:
            self._stop_until_start(self._after_tool_change)
            return
        self._after_tool_change()

    def _after_tool_change(self) -> None:
        if self.functions.m10_waits:
            self._enter("WAIT_M10_PULSE")
            return
        self._start_motion()

    def _wait_input(self, name: str, _old: Any, new: Any) -> None:
        """An input the block cycle waits for went H (spec §4.3.2): looked up in :data:`WAITS`."""
        if new and self.state == WAITING_IN[name]:
            WAITS[name](self)

    def _enabled(self) -> None:
        if self.stop_pending:
            self._stop_until_start(self._move, state="HOLD")
        else:
            self._move()

    def _m10_ack_input(self, _name: str, old: Any, new: Any) -> None:
        if old and not new and self.state == "WAIT_M10_PULSE":
            self.signals.set("m10", False)  # the negative pulse clears M10 (§2.3.18)
            self._start_motion()

    # -- motion ------------------------------------------------------------------------------------
    def _start_motion(self) -> None:
        block = self.block
        assert block is not None
        self.motion.take_carry()  # the path speed the previous block handed on
        if self.functions.full_circle and not self._options.g25_full_circle:
            self.functions.unsupported(25)  # no motion (spec §4.12.1)
            self._end_functions()
            return
        targets = self.motion.plan(block)
        if isinstance(targets, str):
            self._screen.record("circle_endpoint_error")
            self._screen.report("program", "circle_endpoint_error", targets)
            self._stop_until_start(self._end_functions)  # not executed: the program stops (spec §5.3)
            return
        if targets is None:
            self._end_functions()  # no axis word, or I/J only: no motion (spec §5.3)
            return
        self._motion_targets(targets)

    def _motion_targets(self, targets: dict[str, float]) -> None:
        self.motion.targets = targets
        travel = set(targets)
        if self.functions.motion in (1, 2, 3) and self._mode() != "MANUAL":
            # both axes of the chosen plane (G17 XY, G18 ZX, G19 YZ) get a travel command (§2.4.2)
            travel |= {axis for axis, _centre in PLANES[self.functions.plane]}
        for a in travel:
            self.signals.set(f"travel_{a}", True)
        if self.stop_pending:
            self.motion.v0 = None
            self._stop_until_start(self._check_enable, state="HOLD")
            return
        if self.motion.v0 is not None:
            self._move()  # within a contour the axis enable is not checked again (§2.3.15)
            return
        self._check_enable()

    def _continues(self) -> bool:
        """Does the next block continue this block's contour (spec §4.3.3)?  Then this one ends
        at its path speed: no exact positioning, travel commands on, no position reached."""
        return (self.block is not None and self._mode() == "AUTO_CONTINUOUS" and not self.abort_pending
                and self.flow.contour_goes_on(self.block, self.functions))

    def _check_enable(self) -> None:
        if self.signals.get("axis_enable"):
            self._move()
        else:
            self._enter("WAIT_AXIS_ENABLE")  # §2.3.15

    def _move(self) -> None:
        self._enter("MOVING")
        self.signals.set("machine_standstill", False)
        if not self.motion.start(self._continues, self._arrived):
            self.abort()  # refused by a limit switch or the working field

    def _override_input(self, _name: str, _old: Any, _new: Any) -> None:
        if self.state != "MOVING" or self.dwelling or self._mode() not in EXECUTION_MODES:
            return  # (a dwell keeps its time: the axes stand)
        if self.motion.contour is not None:
            self.motion.replan(self._arrived)
        elif self.motion.speeds() is None:
            self._brake(None)
        else:
            self._move()

    def _arrived(self, axis: str) -> None:
        if not self.motion.arrived(axis) or self.state != "MOVING":
            return
        if self.motion.hand_on():
            self._end_functions()  # the contour goes on in the next block (§2.4.2)
            return
        for a in AXES:  # exact positioning (§2.4.2, §2.4.3)
            self.signals.set(f"travel_{a}", False)
        self.signals.set("position_reached", True)
        self.signals.set("machine_standstill", True)
        self._screen.record("position_reached")
        if self.signals.get("program_continue"):
            self._after(POSITION_REACHED_PULSE, self._continue_after_position)
        else:
            self._enter("WAIT_PROGRAM_CONTINUE")  # §2.3.16

    def _continue_after_position(self) -> None:
        self.signals.set("position_reached", False)
        self._end_functions()

    def _brake(self, state: str | None, then: Callable[[], None] | None = None) -> None:
        """Brake every axis along its ramp; ``HOLD`` waits for NC-Start (§2.3.1); ``then``
        runs once all stand."""
        pending = set(self.motion.targets)

        def settled(a: str) -> None:
            pending.discard(a)
            if not pending and self.state == "HOLD":
                self.signals.set("machine_standstill", True)  # spec G-STANDSTILL
            if not pending and then is not None:
                then()

        self.motion.brake(settled)
        if state is not None:
            self._stop_until_start(self._move, state=state)

    # -- block end ---------------------------------------------------------------------------------
    def _end_functions(self) -> None:
        block = self.block
        assert block is not None
        dwell = block.value("L") if self.functions.dwell else None
        if dwell:
            self._after(dwell / 1000, self._block_end_output)  # G04: L seconds (spec §5.3)
            self.dwelling = True
            return
        self._block_end_output()

    def _block_end_output(self) -> None:
        self.dwelling = False
        block = self.block
        assert block is not None
        ms = sorted(block.values("M"))
        last = [m for m in ms if m in (0, 1, 2)]
        functions = [("M", m) for m in ms if block_end_function(m) and m not in (0, 1, 2)]
        functions += [("M", m) for m in last]
        self._enter("MST_OUTPUT")
        self._mst.output(functions, self._block_done)

    def _block_done(self) -> None:
        block = self.block
        assert block is not None
        if self.abort_pending:
            self._jump_p90()
            return
        functions = self.functions
        mode = self._mode()
        self.functions.block_over(mode == "MANUAL_SINGLE_BLOCK")
        if not self.flow.after_block(block, functions.flow):
            self._program_end()
            return
        if functions.program_end:
            self._program_end()
            return
        if mode == "MANUAL_SINGLE_BLOCK":
            self.block = None
            self._enter("IDLE")
            return
        optional = functions.optional_stop and (
            bool(self.signals.get("optional_stop")) != self._options.invert_optional_stop)
        if functions.optional_stop and not optional:
            self.signals.set("m01", False)  # spec G-M01RESET
        if functions.program_stop or optional or mode == "AUTO_SINGLE_BLOCK":
            self._stop_until_start(self._next_block)
            return
        self._next_block()

    # -- block abort (POS III, §2.3.21) --------------------------------------------------------------
    def _block_abort_input(self, _name: str, old: Any, new: Any) -> None:
        """V22/10 H→L: the block is given up (the motion brakes, an M/S/T output finishes
        first) and the program goes on at N = P90 by itself (spec §4.3.6)."""
        if not old or new or not self._options.block_abort or self._mode() not in EXECUTION_MODES[:2]:
            return
        if self.state == "MST_OUTPUT":
            self.abort_pending = True
        elif self.state == "MOVING" and not self.dwelling:
            self.motion.forget_arrivals()
            self._enter("BLOCK_START")  # (braking: no more arrivals, no override re-plan)
            self._brake(None, then=self._jump_p90)
        elif self.state in RUNNING:
            self._jump_p90()

    def _jump_p90(self) -> None:
        self.abort_pending = False
        self._cancel_timer()
        self._travel_off()
        number = int(self._params.abort_block)
        self._screen.record("block_abort")
        if not self.flow.jump(number):
            self._screen.record("p90_block_missing")
            self._program_end()
            return
        self._next_block()

    def _program_end(self) -> None:
        """M02 (or past the last block): the pointer back to the first block (spec §4.3.2)."""
        self.flow.pointer = 0
        self._screen.record("program_end")
        self._enter("END")

    def _stop_until_start(self, resume: Callable[[], None], state: str = "STOPPED") -> None:
        self._resume = resume
        self._enter(state)

    # -- timers ------------------------------------------------------------------------------------
    def _after(self, seconds: float, callback: Callable[[], None]) -> None:
        self._cancel_timer()
        self._timer = self._clock.call_later(seconds, callback)

    def _cancel_timer(self) -> None:
        self.dwelling = False
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None


#: The inputs of the PLC a block waits for, with the state it waits in (spec §4.3.2).
WAITING_IN = {"tool_change_ack": "WAIT_TOOL_CHANGE", "axis_enable": "WAIT_AXIS_ENABLE",
              "program_continue": "WAIT_PROGRAM_CONTINUE"}
WAITS: Table[Callable[[Executor], None]] = Table([
    Command("tool_change_ack", Executor._tool_changed, "§2.3.17", "V22/5 H: the tool is changed, the block goes on"),
    Command("axis_enable", Executor._enabled, "§2.3.15", "V22/3 H: the feed is released, the axes move"),
    Command("program_continue", Executor._continue_after_position, "§2.3.16",
            "V22/4 H: after position reached, the block-end functions follow"),
])
