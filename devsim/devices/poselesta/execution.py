"""Program execution: the block cycle of the automatic modes and Hand-Einzelsatz (manual §2.3.1–
§2.3.3, §2.3.13–§2.3.19, §2.3.22, §2.4.2–§2.4.8, §2.4.10; spec poselesta.md §4.3, §4.4.5–§4.4.9,
§5.2, §5.3, §6.3).

A block runs as: its block-start M functions, S1, S2 and T on the data bus (:class:`MstBus`);
M06 and a non-self-holding M10 wait for their acknowledge; the travel commands and the axis
enable; the motion on the closed-form axes (G00 each axis at its rapid speed, G01 a straight line
at F × override); exact positioning with "Position erreicht" and "Programm fortsetzen"; then the
block-end M functions (M05, M09, M11, M15, odd free codes, then M00/M01/M02).  NC-Stop brakes to
``HOLD``, NC-Start continues; Not-Stop stops at once, gives up the handshake and the program.

G01 lines, G02/G03 arcs and the continuous path between them run in
:mod:`~devsim.devices.poselesta.contour`.  Subroutines and repeats (G10–G13), dwell (G04) and
block abort (P90) change the flow.  Not simulated: G25 (its blocks run as no motion, event
``unsupported_g``) and cutter compensation G41/G42 (accepted, no offset).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from typing import TYPE_CHECKING, Any

from devsim.devices.poselesta.contour import PLANES, PathMotion
from devsim.devices.poselesta.signals import AXES
from devsim.devices.poselesta.tape import Block, parse_blocks

if TYPE_CHECKING:
    from devsim.devices.poselesta.cnc import PoselestaCnc

__all__ = ["EXECUTION_MODES", "STATES", "Executor", "block_end_function"]

STATES = ("IDLE", "BLOCK_START", "MST_OUTPUT", "WAIT_TOOL_CHANGE", "WAIT_M10_PULSE", "WAIT_AXIS_ENABLE",
          "MOVING", "WAIT_PROGRAM_CONTINUE", "HOLD", "STOPPED", "LIMIT_STOP", "END")
#: States in which a block is being worked on: the "Start" symbol, V16/8 H (spec §4.3.1).
RUNNING = frozenset(("BLOCK_START", "MST_OUTPUT", "WAIT_TOOL_CHANGE", "WAIT_M10_PULSE", "WAIT_AXIS_ENABLE",
                     "MOVING", "WAIT_PROGRAM_CONTINUE"))
EXECUTION_MODES = ("AUTO_CONTINUOUS", "AUTO_SINGLE_BLOCK", "MANUAL_SINGLE_BLOCK")
#: Decoded M outputs V15 (§2.4.7).
DECODED = {0: "m00", 1: "m01", 2: "m02", 3: "m03", 4: "m04", 6: "m06", 8: "m08", 10: "m10"}
#: What a function switches off (§2.4.7; M03/M04 cancel each other, spec §4.4.7).
CANCELS = {5: ("m03", "m04"), 9: ("m08",), 11: ("m10",), 3: ("m04",), 4: ("m03",)}
_FIXED = frozenset((*range(12), 13, 14, 15, 30))
#: G functions with a meaning here (spec §4.12.1); the others are stored and run as no-ops.
KNOWN_G = frozenset((0, 1, 2, 3, 4, 9, 10, 11, 12, 13, 17, 18, 19, 25, 40, 41, 42, 60, 90, 91))
POSITION_REACHED_PULSE = 60e-6  # §2.4.2: with "Programm fortsetzen" already H


def block_end_function(m: int) -> bool:
    """M00, M01, M02, M05, M09, M11, M15 and the odd free codes act at the end of the block
    (§2.4.8; spec §4.4.5); the others at its start."""
    return m in (0, 1, 2, 5, 9, 11, 15) or (m not in _FIXED and m % 2 == 1)


class Executor:
    """The block cycle of one control (spec §4.3.2) on its clock, axes, signals and MST bus."""

    def __init__(self, cnc: PoselestaCnc) -> None:
        self.cnc = cnc
        self.signals = cnc.signals
        self.state = "IDLE"
        self.blocks: list[Block] = []
        self.pointer = 0
        self.block: Block | None = None
        self.inch = False  # V22/2 sampled at the start of the block (spec §5.1)
        self.typed_inch = False  # the running program was typed in inch (two more decimals)
        self.motion = 0  # modal G00 … G03
        self.plane = 17  # modal G17 / G18 / G19
        self.compensation = 40  # modal G40 / G41 / G42 (no offset: spec §5.8 phase 1)
        self.tool = 0  # the last T programmed
        self.contour: PathMotion | None = None
        self.carry: float | None = None  # path speed handed on to the next block (mm/s)
        self._v0: float | None = None
        self.absolute = True  # G90 / G91
        self.feed = 0  # modal F, mm/min
        self.targets: dict[str, float] = {}
        self.stop_pending = False  # NC-Stop during M/S/T output: the motion waits for NC-Start
        self._resume: Callable[[], None] | None = None
        self.calls: list[list[int]] = []  # [return index, calls left, subroutine index] (G12)
        self.loops: dict[int, int] = {}  # G13 block index → jumps left
        self.abort_pending = False
        self._m10_waits = False
        self._arriving: set[str] = set()
        self._timer: Any = None
        self.mdi = ""
        for name, handler in (("nc_start", self._nc_start_input), ("nc_stop", self._nc_stop_input),
                              ("emergency_stop", self._emergency_input), ("axis_enable", self._wait_input),
                              ("program_continue", self._wait_input), ("tool_change_ack", self._wait_input),
                              ("m10_ack", self._m10_ack_input), ("override_pot_v", self._override_input),
                              ("block_abort", self._block_abort_input)):
            self.signals.subscribe(name, handler)

    # -- state ------------------------------------------------------------------------------------
    def _enter(self, state: str) -> None:
        self.state = state
        self.signals.set("start_stop_status", state in RUNNING)

    @property
    def running(self) -> bool:
        """A block is being worked on: the mode cannot change (spec §4.1)."""
        return self.state in RUNNING or self.cnc.mst.busy and self.state != "IDLE"

    @property
    def block_number(self) -> int:
        return self.block.number if self.block is not None else -1

    def reset(self) -> None:
        """Back to the first block (a mode change abandons a stopped program, spec §4.1): its
        travel commands end."""
        self._cancel_timer()
        if self.state != "IDLE":
            for a in AXES:
                self.signals.set(f"travel_{a}", False)
            self.signals.set("position_reached", False)
        self.contour = None
        self._resume = None
        self.stop_pending = self.abort_pending = False
        self.carry = self._v0 = None
        self.pointer = 0
        self.block = None
        self.calls.clear()
        self.loops.clear()
        self._enter("IDLE")

    # -- NC-Start, NC-Stop, Not-Stop ----------------------------------------------------------------
    def _nc_start_input(self, _name: str, old: Any, new: Any) -> None:
        if new and not old:
            self.nc_start("external")

    def nc_start(self, source: str = "panel") -> None:
        """NC-Start (§2.3.3): starts from the first block, continues a stop or a hold; P75 says
        which source counts (0 both, 1 the panel, 2 the external button V19/3)."""
        cnc = self.cnc
        allowed = {0: ("panel", "external"), 1: ("panel",), 2: ("external",)}.get(int(cnc.params.nc_start_source), ())
        if source not in allowed or cnc.booting or not self.signals.get("emergency_stop"):
            return
        if cnc.mode not in EXECUTION_MODES or not self.signals.get("nc_stop") or not cnc.field.inside:
            cnc.record_event("nc_start_ignored")  # (also while outside the working field, spec §5.5)
            return
        for output in ("m00", "m01", "m02", "m06"):
            self.signals.set(output, False)  # reset by NC-Start (§2.4.7)
        if self.state in ("IDLE", "END"):
            if not self._load():
                return
            self.pointer = 0
            self.calls.clear()
            self.loops.clear()
            self._next_block()
        elif self.state in ("STOPPED", "HOLD", "LIMIT_STOP") or self.stop_pending:
            self.stop_pending = False
            resume, self._resume = self._resume, None
            if resume is not None:
                resume()

    def _load(self) -> bool:
        cnc = self.cnc
        if cnc.mode == "MANUAL_SINGLE_BLOCK":
            self.typed_inch = bool(self.signals.get("inch"))
            try:
                formats = cnc.inch_formats if self.typed_inch else cnc.formats
                self.blocks = parse_blocks(self.mdi, formats) if self.mdi.strip() else []
            except ValueError:
                self.blocks = []
        else:
            self.typed_inch = cnc.program in cnc.inch_programs
            self.blocks = sorted(cnc.programs.get(cnc.program, {}).values(), key=lambda b: b.number)
        if not self.blocks:
            cnc.record_event("no_program")
            return False
        return True

    def _nc_stop_input(self, _name: str, _old: Any, new: Any) -> None:
        if new or self.cnc.mode == "MANUAL":
            return  # NC-Stop is ineffective in MANUAL (§2.3.1)
        if self.state == "MOVING":
            self._brake("HOLD")
        elif self.state in RUNNING:
            self.stop_pending = True  # the output goes on; the motion waits for NC-Start (§2.3.1)

    def _emergency_input(self, _name: str, _old: Any, new: Any) -> None:
        if not new:
            self.emergency_stop()
        else:
            self.cnc.emergency_released()

    def left_field(self) -> None:
        """An axis left the working field: all brake as with NC-Stop, the program stops (§2.4.4)."""
        if self.state == "MOVING":
            self._brake("LIMIT_STOP")

    def emergency_stop(self) -> None:
        """§2.3.2: axes stop at once without ramp, set-points 0 V, the handshake is given up and
        the program aborted (spec §4.3.5); NC ready stays H."""
        for axis in self.cnc.axes.values():
            axis.quick_stop()
        self.cnc.manual.reset()
        self.abort()

    def abort(self) -> None:
        """The program is given up (Not-Stop, a limit switch): handshake abandoned, travel
        commands L, back to the first block; self-holding M outputs stay (spec §4.3.5)."""
        self._cancel_timer()
        self.cnc.mst.abandon()
        for a in AXES:
            self.signals.set(f"travel_{a}", False)
        self.signals.set("position_reached", False)
        self.signals.set("machine_standstill", True)
        self._arriving.clear()
        self.reset()

    # -- the block cycle ----------------------------------------------------------------------------
    def _next_block(self) -> None:
        """BLOCK_START: the next block in ascending N; a block marked ``/`` is skipped while the
        block-skip input is L (sampled now, §2.3.13); past the last block is as M02."""
        while self.pointer < len(self.blocks):
            block = self.blocks[self.pointer]
            if block.skip and not self.signals.get("block_skip_cancel"):
                self.cnc.record_event("block_skipped")
                self.pointer += 1
                continue
            self._run(block)
            return
        self._program_end()

    def unit(self, a: str) -> float:
        """A stored coordinate value in units of the machine's last decimal: a program runs in
        inch while V22/2 is H (spec §5.1: the machine measures in mm; D is not converted), and a
        program typed in inch carries two more decimals."""
        if a == "d":
            return 1.0
        return (25.4 if self.inch else 1.0) / (100.0 if self.typed_inch else 1.0)

    def feed_unit(self) -> float:
        """F in mm/min, or inch/min while V22/2 is H."""
        return 25.4 if self.inch else 1.0

    def _run(self, block: Block) -> None:
        self.block = block
        self.inch = bool(self.signals.get("inch"))
        self._enter("BLOCK_START")
        for g in block.values("G"):
            if g in (0, 1, 2, 3):
                self.motion = g
            elif g in PLANES:
                self.plane = g
            elif g in (40, 41, 42) and g != self.compensation:
                self.compensation = g  # recorded, no path offset (spec §5.8, phase 1)
                self.cnc.record_event("compensation")
                self.cnc.announce("event", "program", "compensation", f"G{g}")
            elif g in (90, 91):
                self.absolute = g == 90
            elif g not in KNOWN_G:
                self._unsupported(g)  # stored and run as no-op (spec §4.12.1)
        feed = block.value("F")
        if feed is not None:
            self.feed = feed
        ms = sorted(block.values("M"))
        functions: list[tuple[str, int]] = [("M", m) for m in ms if not block_end_function(m) and m != 30]
        speed = block.value("S")
        if speed is not None:
            functions += [("S1", speed % 100), ("S2", speed // 100 % 100)]  # units and tens first
        tool = block.value("T")
        if tool is not None:
            functions.append(("T", tool))
            self.tool = tool
        self._m10_waits = False
        self._enter("MST_OUTPUT")
        self.cnc.mst.output(functions, self._after_start_functions)

    def put(self, kind: str, value: int) -> None:
        """A function goes on the bus: decoded M outputs set and cancelled (§2.4.7)."""
        if kind != "M":
            return
        for output in CANCELS.get(value, ()):
            self.signals.set(output, False)
        if value in DECODED:
            self.signals.set(DECODED[value], True)
        if value == 10:
            self._m10_waits = bool(self.signals.get("m10_ack"))  # H at output: not self-holding

    def _after_start_functions(self) -> None:
        block = self.block
        assert block is not None
        if self.abort_pending:
            self._jump_p90()
            return
        if 6 in block.values("M") and not self.signals.get("tool_change_ack"):
            self._enter("WAIT_TOOL_CHANGE")  # §2.3.17: after M06, S and T are taken over
            return
        if 6 in block.values("M"):
            self._tool_changed()
            return
        if self._m10_waits:
            self._enter("WAIT_M10_PULSE")
            return
        self._start_motion()

    def _tool_changed(self) -> None:
        self.signals.set("m06", False)
        if self.cnc.cfg.m06_requires_nc_start:
            self._stop_until_start(self._after_tool_change)
            return
        self._after_tool_change()

    def _after_tool_change(self) -> None:
        if self._m10_waits:
            self._enter("WAIT_M10_PULSE")
            return
        self._start_motion()

    def _wait_input(self, name: str, _old: Any, new: Any) -> None:
        if not new:
            return
        if name == "tool_change_ack" and self.state == "WAIT_TOOL_CHANGE":
            self._tool_changed()
        elif name == "axis_enable" and self.state == "WAIT_AXIS_ENABLE":
            if self.stop_pending:
                self._stop_until_start(self._move, state="HOLD")
            else:
                self._move()
        elif name == "program_continue" and self.state == "WAIT_PROGRAM_CONTINUE":
            self.signals.set("position_reached", False)
            self._end_functions()

    def _m10_ack_input(self, _name: str, old: Any, new: Any) -> None:
        if old and not new and self.state == "WAIT_M10_PULSE":
            self.signals.set("m10", False)  # the negative pulse clears M10 (§2.3.18)
            self._start_motion()

    # -- motion ------------------------------------------------------------------------------------
    def _start_motion(self) -> None:
        block = self.block
        assert block is not None
        cnc = self.cnc
        self._v0, self.carry = self.carry, None  # the path speed the previous block handed on
        if 25 in block.values("G") and not cnc.cfg.g25_full_circle:
            self._unsupported(25)  # no motion (spec §4.12.1)
            self._end_functions()
            return
        self.contour = None
        if self.motion in (2, 3) or 25 in block.values("G"):
            contour = PathMotion.arc(cnc, block, self.plane, self.absolute, -1 if self.motion == 2 else 1, self.unit,
                                     full_circle=25 in block.values("G"))
            if isinstance(contour, str):
                cnc.record_event("circle_endpoint_error")
                cnc.announce("event", "program", "circle_endpoint_error", contour)
                self._stop_until_start(self._end_functions)  # not executed: the program stops (spec §5.3)
                return
            if contour is None:
                self._end_functions()  # I/J only: no motion (spec §5.3)
                return
            self.contour = contour
            self._motion_targets(contour.targets)
            return
        targets: dict[str, float] = {}
        for a in AXES:
            value = block.value(a.upper())
            if value is None:
                continue
            base = 0.0 if self.absolute else cnc.planned_position(a)
            targets[a] = base + value * self.unit(a)
        if not targets:
            self._end_functions()
            return
        if self.motion == 1:
            self.contour = PathMotion.line(cnc, targets)
        self._motion_targets(targets)

    def _motion_targets(self, targets: dict[str, float]) -> None:
        cnc = self.cnc
        self.targets = targets
        travel = set(targets)
        if self.motion in (1, 2, 3) and cnc.mode != "MANUAL":
            travel |= {"x", "y"}  # both axes of the plane get a travel command (§2.4.2)
        for a in travel:
            self.signals.set(f"travel_{a}", True)
        if self.stop_pending:
            self._v0 = None
            self._stop_until_start(self._check_enable, state="HOLD")
            return
        if self._v0 is not None:
            self._move()  # within a contour the axis enable is not checked again (§2.3.15)
            return
        self._check_enable()

    def _continues(self) -> bool:
        """Does the next block continue this block's contour (spec §4.3.3)?  Then this one ends
        at its path speed: no exact positioning, travel commands on, no position reached."""
        block = self.block
        if block is None or self.cnc.mode != "AUTO_CONTINUOUS" or self.motion not in (1, 2, 3):
            return False
        gs = set(block.values("G"))
        if gs & {4, 9, 60, 11, 12, 13} or block.values("M") or self.abort_pending:
            return False
        index = self.pointer + 1
        while index < len(self.blocks) and self.blocks[index].skip and not self.signals.get("block_skip_cancel"):
            index += 1
        if index >= len(self.blocks):
            return False
        following = self.blocks[index]
        motion = next((g for g in reversed(following.values("G")) if g in (0, 1, 2, 3)), self.motion)
        return (motion in (1, 2, 3) and not set(following.values("G")) & {4, 9, 10, 11, 12, 13, 25, 60}
                and not any(following.value(c) is not None for c in "MST")
                and any(following.value(c) is not None for c in "XYZD"))

    def _check_enable(self) -> None:
        if not self.signals.get("axis_enable"):
            self._enter("WAIT_AXIS_ENABLE")  # §2.3.15
            return
        self._move()

    def _move(self) -> None:
        """Plan every axis of the block from where it is (also a resumed hold)."""
        cnc = self.cnc
        self._enter("MOVING")
        self.signals.set("machine_standstill", False)
        self._arriving = set(self.targets)
        for a, target in self.targets.items():
            if cnc.limits.blocked(a, target - cnc.axes[a].position()) or cnc.field.outside_towards(
                    a, target - cnc.axes[a].position()):
                cnc.limits.refuse(a)
                self.abort()
                return
        if self.contour is not None:
            speed = self._path_speed(tuple(self.targets))
            v0, self._v0 = self._v0, None
            if speed is not None:
                for a in self.targets:
                    cnc.check_encoder(a, cnc.from_mm(a, speed))
                self.contour.continues = self._continues()
                self.contour.run(speed, self._arrived, v0)
            return
        speeds = self._speeds()
        if speeds is None:
            return  # override 0 %: the path stands without HOLD until the override rises (spec §5.3)
        for a, target in self.targets.items():
            speed, accel = speeds[a]
            axis = cnc.axes[a]
            if abs(target - axis.position()) < 1e-9 and not axis.moving:
                self._arrived(a)  # (already there: a zero move still reaches its position, §2.4.3)
                continue
            cnc.check_encoder(a, speed)
            axis.move_to(target, speed, accel, on_done=lambda a=a: self._arrived(a))

    def _speeds(self) -> dict[str, tuple[float, float]] | None:
        """G00: each axis at its rapid (P44–P47, × override with P64 = 1) with its own ramps
        (spec §5.3); speeds in inc/s, accelerations in inc/s²."""
        cnc = self.cnc
        if self._zero_rapid(self.targets):
            return None
        factor = cnc.override() if cnc.params.rapid_override == 1 else 1.0
        if factor <= 0:
            return None
        return {a: (cnc.rapid(a) * factor, cnc.accel(a)) for a in self.targets}

    def _zero_rapid(self, axes: Iterable[str]) -> bool:
        """P44–P47 = 0 (after a POS II catalogue read): the axis cannot move (spec §4.8)."""
        if any(self.cnc.rapid(a) <= 0 for a in axes):
            self.cnc.record_event("zero_speed_parameter")
            return True
        return False

    def _path_speed(self, axes: tuple[str, ...]) -> float | None:
        """F × override in mm/s, no faster than the slowest rapid of ``axes``; None at 0."""
        cnc = self.cnc
        if self._zero_rapid(axes):
            return None
        path = min([self.feed * self.feed_unit() * cnc.override() / 60.0, *(cnc.to_mm(a, cnc.rapid(a)) for a in axes)])
        if self.feed <= 0:
            cnc.record_event("zero_feed")
        return path if path > 0 else None

    def _override_input(self, _name: str, _old: Any, _new: Any) -> None:
        if self.state == "MOVING" and self.cnc.mode in EXECUTION_MODES and self.contour is not None:
            speed = self._path_speed(tuple(self.targets))
            if speed is None:
                self.contour.brake(None)
            else:
                self.contour.run(speed, self._arrived)
            return
        if self.state == "MOVING" and self.cnc.mode in EXECUTION_MODES:
            speeds = self._speeds()
            if speeds is None:
                self._brake(None)
                return
            self._move()

    def _arrived(self, axis: str) -> None:
        self._arriving.discard(axis)
        if self._arriving or self.state != "MOVING":
            return
        if self.contour is not None and self.contour.final_speed > 0:
            self.carry = self.contour.final_speed  # the contour goes on in the next block (§2.4.2)
            self._end_functions()
            return
        for a in AXES:  # exact positioning (§2.4.2, §2.4.3)
            self.signals.set(f"travel_{a}", False)
        self.signals.set("position_reached", True)
        self.signals.set("machine_standstill", True)
        self.cnc.record_event("position_reached")
        if self.signals.get("program_continue"):
            self._after(POSITION_REACHED_PULSE, self._continue_after_position)
        else:
            self._enter("WAIT_PROGRAM_CONTINUE")  # §2.3.16

    def _continue_after_position(self) -> None:
        self.signals.set("position_reached", False)
        self._end_functions()

    def _unsupported(self, g: int) -> None:
        self.cnc.record_event("unsupported_g")
        self.cnc.announce("event", "program", "unsupported_g", g)

    def _brake(self, state: str | None, then: Callable[[], None] | None = None) -> None:
        """Brake every axis along its ramp; ``HOLD`` waits for NC-Start (§2.3.1); ``then``
        runs once all stand."""
        cnc = self.cnc
        pending = set(self.targets)

        def settled(a: str) -> None:
            pending.discard(a)
            if not pending and self.state == "HOLD":
                self.signals.set("machine_standstill", True)  # spec G-STANDSTILL
            if not pending and then is not None:
                then()

        if self.contour is not None:
            self.contour.brake(settled)
        else:
            for a in self.targets:
                axis = cnc.axes[a]
                if axis.moving:
                    axis.stop(cnc.accel(a), on_done=lambda a=a: settled(a))
                else:
                    settled(a)
        if state is not None:
            self._stop_until_start(self._move, state=state)

    # -- block end ---------------------------------------------------------------------------------
    def _end_functions(self) -> None:
        block = self.block
        assert block is not None
        dwell = block.value("L") if 4 in block.values("G") else None
        if dwell:
            self._after(dwell / 1000, self._block_end_output)  # G04: L seconds (spec §5.3)
            return
        self._block_end_output()

    def _block_end_output(self) -> None:
        block = self.block
        assert block is not None
        ms = sorted(block.values("M"))
        last = [m for m in ms if m in (0, 1, 2)]
        functions = [("M", m) for m in ms if block_end_function(m) and m not in (0, 1, 2)]
        functions += [("M", m) for m in last]
        self._enter("MST_OUTPUT")
        self.cnc.mst.output(functions, self._block_done)

    def _block_done(self) -> None:
        block = self.block
        assert block is not None
        if self.abort_pending:
            self._jump_p90()
            return
        ms = block.values("M")
        mode = self.cnc.mode
        self.pointer += 1
        if not self._flow(block):
            return
        if 2 in ms:
            self._program_end()
            return
        if mode == "MANUAL_SINGLE_BLOCK":
            for output in DECODED.values():
                self.signals.set(output, False)  # decoded M functions act block-wise (§2.4.7)
            self.block = None
            self._enter("IDLE")
            return
        optional = 1 in ms and self.signals.get("optional_stop")
        if 1 in ms and not optional:
            self.signals.set("m01", False)  # spec G-M01RESET
        if 0 in ms or optional or mode == "AUTO_SINGLE_BLOCK":
            self._stop_until_start(self._next_block)
            return
        self._next_block()

    def _flow(self, block: Block) -> bool:
        """Subroutines and repeats (spec §4.12.1, INFERRED from the manual's example §6.6):
        ``G12 L a.bbb`` calls the subroutine at N bbb a times, ``G11`` returns to the block after
        the call, ``G13 L a.bbb`` jumps back to N bbb a more times.  Returns False when the
        program ended (a jump to a missing block)."""
        gs = block.values("G")
        count, target = divmod(block.value("L") or 0, 1000)
        if 12 in gs:
            index = self._index(target)
            if index is None:
                return False
            if count > 0:
                self.calls.append([self.pointer, count - 1, index])
                self.pointer = index
        elif 11 in gs and self.calls:
            call = self.calls[-1]
            if call[1] > 0:
                call[1] -= 1
                self.pointer = call[2]
            else:
                self.calls.pop()
                self.pointer = call[0]
        elif 13 in gs:
            here = self.pointer - 1
            left = self.loops.get(here, count)
            if left > 0:
                index = self._index(target)
                if index is None:
                    return False
                self.loops[here] = left - 1
                self.pointer = index
            else:
                self.loops.pop(here, None)
        return True

    def _index(self, number: int) -> int | None:
        for index, candidate in enumerate(self.blocks):
            if candidate.number == number:
                return index
        self.cnc.record_event("block_missing")
        self.cnc.announce("event", "program", "block_missing", number)
        self._program_end()
        return None

    # -- block abort (POS III, §2.3.21) --------------------------------------------------------------
    def _block_abort_input(self, _name: str, old: Any, new: Any) -> None:
        """V22/10 H→L: the block is given up (the motion brakes, an M/S/T output finishes
        first) and the program goes on at N = P90 by itself (spec §4.3.6)."""
        if not old or new or self.cnc.cfg.variant != "III" or self.cnc.mode not in EXECUTION_MODES[:2]:
            return
        if self.state == "MST_OUTPUT":
            self.abort_pending = True
        elif self.state == "MOVING":
            self._arriving.clear()
            self._enter("BLOCK_START")  # (braking: no more arrivals, no override re-plan)
            self._brake(None, then=self._jump_p90)
        elif self.state in RUNNING:
            self._jump_p90()

    def _jump_p90(self) -> None:
        self.abort_pending = False
        self._cancel_timer()
        for a in AXES:
            self.signals.set(f"travel_{a}", False)
        self.signals.set("position_reached", False)
        number = int(self.cnc.params.abort_block)
        self.cnc.record_event("block_abort")
        index = next((i for i, b in enumerate(self.blocks) if b.number == number), None)
        if index is None:
            self.cnc.record_event("p90_block_missing")
            self._program_end()
            return
        self.pointer = index
        self._next_block()

    def _program_end(self) -> None:
        """M02 (or past the last block): the pointer back to the first block (spec §4.3.2)."""
        self.pointer = 0
        self.cnc.record_event("program_end")
        self._enter("END")

    def _stop_until_start(self, resume: Callable[[], None], state: str = "STOPPED") -> None:
        self._resume = resume
        self._enter(state)

    # -- timers ------------------------------------------------------------------------------------
    def _after(self, seconds: float, callback: Callable[[], None]) -> None:
        self._cancel_timer()
        self._timer = self.cnc.clock.call_later(seconds, callback)

    def _cancel_timer(self) -> None:
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None
