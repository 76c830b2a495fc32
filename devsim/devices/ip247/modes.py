"""The operating modes of an IP247 axis page, BA1 … BA16 (manual §4.1.1, §4.2, §4.3.1–§4.3.15;
spec ip247.md §4.2, §5.4–§5.12): what a job the checks let through (:func:`.jobs.refusal`) does
to the axis.

Each mode is a row of :data:`AXIS_MODES`, looked up by its token (``BA6``); the handler gets the
modes part, the axis page and the job's command and FB164 parameters B, W, DD, and returns the
module error it leaves (None: none).  Programs and teach-in (BA8 … BA11) belong to the programs
part (:class:`.programs.ProgramJobs`).
"""

from __future__ import annotations

from collections.abc import Callable

from devsim.core.kit import Command, Table
from devsim.devices.ip247.axis_unit import AxisUnit
from devsim.devices.ip247.jobs import BACKWARD, FORWARD, START, STOP, TAKE_OVER
from devsim.devices.ip247.programs import ProgramJobs
from devsim.devices.ip247.reference import ReferenceRun
from devsim.devices.ip247.tables import MODES, mode_token

__all__ = ["AXIS_MODES", "AxisModes", "ModeHandler"]

MAX_RELATIVE = 200_000_000  # base units: BA7 on a rotary axis (spec §5.5)

#: A mode's handler: (the modes part, the page, cmd, B, W, DD) → the module error it leaves.
ModeHandler = Callable[["AxisModes", AxisUnit, int, int, int, int], "int | None"]


class AxisModes:
    """The modes part: carries out an operator job on an axis page (spec §4.2)."""

    def __init__(self, programs: ProgramJobs) -> None:
        self.programs = programs

    def operate(self, unit: AxisUnit, ba: int, cmd: int, b: int, w: int, dd: int) -> int | None:
        """A job the checks let through; returns the module error it leaves (None: none)."""
        if unit.waiting_start is not None:
            unit.waiting_start = None
            unit.set_running(False)
            if cmd == STOP:
                return None  # Stopp cancels the wait without error (spec §4.2)
            return 2
        if unit.running:
            return self._while_running(unit, ba, cmd, w)
        handler = AXIS_MODES.get(mode_token(ba))
        self.select(unit, ba, cmd)
        if cmd == STOP and ba not in (8, 9):
            return None  # Stopp of a finished axis: nothing to do
        if cmd == TAKE_OVER and ba in (1, 2, 6, 7):
            return self.programs.teach_store(unit)  # store a teach-in block (spec §5.12)
        return handler(self, unit, cmd, b, w, dd) if handler is not None else 2

    @staticmethod
    def select(unit: AxisUnit, ba: int, cmd: int) -> None:
        """A finished axis takes the job's mode, whether the job then runs or not (manual §4.1:
        „Die Achse wechselt dann in die gewünschte Betriebsart. Eine Ausführung findet aber nur
        dann statt, wenn die eingestellte Betriebsart und der Befehl zusammen eine sinnvolle
        Kombination ergeben“)."""
        unit.mode, unit.last_cmd = ba, cmd
        if ba not in (8, 9):
            unit.m_function = 2

    def _while_running(self, unit: AxisUnit, ba: int, cmd: int, w: int) -> int | None:
        if unit.automatic is not None and unit.mode in (8, 9):
            return unit.automatic.command(ba, cmd)
        if ba in (1, 2) and unit.mode in (1, 2) and ba != unit.mode and cmd in (FORWARD, BACKWARD):
            unit.mode, unit.last_cmd = ba, cmd  # stop, then jog on in the other mode (spec §5.4)
            unit.brake(lambda ok: self._jog(unit, cmd, w))
            return None
        unit.last_cmd = STOP
        if unit.reference_run is not None:
            unit.reference_run.cancel()
            unit.reference_set = False  # an aborted reference run leaves none (spec §5.6)
        unit.brake()
        if cmd == STOP or ba == 4:
            return None
        return 2

    @staticmethod
    def _velocity(unit: AxisUnit, w: int, default: int) -> tuple[float, int | None]:
        """The job's travel frequency: W or the MD velocity, clamped (error 7, spec §5.2)."""
        md = unit.md
        assert md is not None
        velocity = w or default
        error = None
        if not 1 <= velocity <= 65000:
            velocity, error = min(max(velocity, 1), 65000), 7
        f = md.frequency(velocity)
        if f > md.f_max or f < 1:
            f, error = min(max(f, 1.0), float(md.f_max)), 7
        return f, error

    def _jog(self, unit: AxisUnit, cmd: int, w: int) -> int | None:
        md = unit.md
        assert md is not None
        if cmd not in (FORWARD, BACKWARD):
            return 2
        direction = 1 if cmd == FORWARD else -1
        refused = unit.limit_refusal(direction)
        if refused is not None:
            return refused
        f, error = self._velocity(unit, w, md.jog1 if unit.mode == 1 else md.jog2)

        def run() -> None:
            unit.jog(direction, f)
            unit.arm_sw_limit(direction)

        return unit.held(run) or error

    def _positioning(self, unit: AxisUnit, holder_target: float, w: int) -> int | None:
        md = unit.md
        assert md is not None
        if not md.rotary and unit.reference_set:
            low, high = unit.coords.range()
            shifted = holder_target - unit.coords.zero_offset
            if not low <= shifted <= high:
                return 23
        direction = 1 if holder_target > unit.holder else -1 if holder_target < unit.holder else 0
        refused = unit.limit_refusal(direction)
        if refused is not None:
            return refused
        f, error = self._velocity(unit, w, md.step_velocity)
        return unit.held(lambda: unit.position_to(holder_target, f)) or error

    # -- the modes ----------------------------------------------------------------------------------
    def jog(self, unit: AxisUnit, cmd: int, b: int, w: int, dd: int) -> int | None:
        """BA1, BA2: jog at W or the MD jog velocity 1 / 2 (spec §5.4)."""
        return self._jog(unit, cmd, w)

    def axis_off(self, unit: AxisUnit, cmd: int, b: int, w: int, dd: int) -> int | None:
        """BA4: the axis is off (and stays "fertig")."""
        return None

    def reference_point(self, unit: AxisUnit, cmd: int, b: int, w: int, dd: int) -> int | None:
        """BA5: B 0 drives to the reference point, any other B sets it here (spec §5.6)."""
        md = unit.md
        assert md is not None
        unit.reference_set = False  # the start deletes an existing reference (spec §5.6)
        if b != 0:
            unit.set_holder(md.reference)  # set: H := x_ref (spec §5.6.1)
            unit.reference_set = True
            unit.target = None
            return None
        return unit.held(ReferenceRun(unit).start)

    def absolute(self, unit: AxisUnit, cmd: int, b: int, w: int, dd: int) -> int | None:
        """BA6: to the absolute target DD; on a rotary axis the shortest way or as commanded."""
        md = unit.md
        assert md is not None
        if not md.rotary:
            return self._positioning(unit, unit.coords.holder_for(dd), w)
        begin, end = unit.coords.range()
        if not begin <= dd <= end:
            return 23
        span = end - begin
        here = unit.actual()
        forward = (dd - here) % span
        if cmd == START:
            step = forward if forward <= span - forward else forward - span  # ties: forward
        elif cmd == FORWARD:
            step = forward or span
        else:
            step = -((here - dd) % span or span)
        return self._positioning(unit, unit.holder + step, w)

    def relative(self, unit: AxisUnit, cmd: int, b: int, w: int, dd: int) -> int | None:
        """BA7: by the distance DD forward or backward (spec §5.5)."""
        md = unit.md
        assert md is not None
        if cmd not in (FORWARD, BACKWARD):
            return 2
        distance = dd if cmd == FORWARD else -dd
        if md.rotary and abs(distance) > MAX_RELATIVE:
            return 62
        if md.rotary:
            refused = unit.limit_refusal(1 if distance > 0 else -1 if distance < 0 else 0)
            if refused is not None:
                return refused  # (the limit switches work on a rotary axis too, §2.8.3)
            f, error = self._velocity(unit, w, md.step_velocity)
            target = unit.holder + distance
            return unit.held(lambda: unit.position_to(target, f)) or error
        return self._positioning(unit, unit.holder + distance, w)

    def program(self, unit: AxisUnit, cmd: int, b: int, w: int, dd: int) -> int | None:
        """BA8, BA9: program B (spec §5.11)."""
        return self.programs.program_job(unit, cmd, b)

    def teach_in(self, unit: AxisUnit, cmd: int, b: int, w: int, dd: int) -> int | None:
        """BA10, BA11: teach-in on for program B, off (spec §5.12)."""
        return self.programs.teach_job(unit, cmd, b)

    def set_actual(self, unit: AxisUnit, cmd: int, b: int, w: int, dd: int) -> int | None:
        """BA12: the current position gets the coordinate DD (spec §5.9)."""
        return unit.coords.set_actual(round(unit.holder), dd)

    def shift(self, unit: AxisUnit, cmd: int, b: int, w: int, dd: int) -> int | None:
        """BA13: the origin moves by DD forward or backward (spec §5.9)."""
        return unit.coords.shift(dd, cmd == FORWARD) if cmd in (FORWARD, BACKWARD) else 2

    def clear_shifts(self, unit: AxisUnit, cmd: int, b: int, w: int, dd: int) -> int | None:
        """BA14 (spec §5.9)."""
        unit.coords.clear_shifts()
        return None

    def tool(self, unit: AxisUnit, cmd: int, b: int, w: int, dd: int) -> int | None:
        """BA15: tool offset ±DD (spec §5.9)."""
        return unit.coords.set_tool(dd, cmd == FORWARD) if cmd in (FORWARD, BACKWARD) else 2

    def clear_tools(self, unit: AxisUnit, cmd: int, b: int, w: int, dd: int) -> int | None:
        """BA16 (spec §5.9)."""
        unit.coords.clear_tools()
        return None


def _row(number: int, handler: ModeHandler) -> Command[ModeHandler]:
    return Command(mode_token(number), handler, "§4.1.1", MODES[number].describe())


#: The modes an axis page runs, by token (spec §3.2, §4.2).
AXIS_MODES: Table[ModeHandler] = Table([
    _row(1, AxisModes.jog),
    _row(2, AxisModes.jog),
    _row(4, AxisModes.axis_off),
    _row(5, AxisModes.reference_point),
    _row(6, AxisModes.absolute),
    _row(7, AxisModes.relative),
    _row(8, AxisModes.program),
    _row(9, AxisModes.program),
    _row(10, AxisModes.teach_in),
    _row(11, AxisModes.teach_in),
    _row(12, AxisModes.set_actual),
    _row(13, AxisModes.shift),
    _row(14, AxisModes.clear_shifts),
    _row(15, AxisModes.tool),
    _row(16, AxisModes.clear_tools),
])
