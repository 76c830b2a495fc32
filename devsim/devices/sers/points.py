"""The SERS's control names and faults, declared once (spec sers.md §7, manual sections per row).

Every name the control API, scenarios, plants and fixtures use is a row here; the parameters
``param.P<n>`` are generated from the parameter table (aliases such as ``param.V`` resolve to
their number).  Values are checked by type and range before they take effect; a parameter write
also gets the drive's own range check and error text.
"""

from __future__ import annotations

from typing import Any

import msgspec

from devsim.core.kit import Fault, FaultTable, signal_points
from devsim.core.parameters import Param, alias_hook, parameter_points
from devsim.core.points import BadValue, Point, PointTable
from devsim.devices.sers import statements as st
from devsim.devices.sers.errors import SersError, message
from devsim.devices.sers.parameters import PARAMETER_TABLE
from devsim.devices.sers.program import defined_once, refusal
from devsim.devices.sers.signals import SIGNALS

__all__ = ["FAULTS", "POINTS", "load_program"]


def load_program(model: Any, program: Any) -> None:
    """Store a program (lines as typed, without ``#``) in the EEPROM as if downloaded with
    NEW … QUIT; a bad line is refused with its error text and nothing is stored."""
    lines = [program] if isinstance(program, str) else program
    if not isinstance(lines, list) or not all(isinstance(text, str) for text in lines):
        raise BadValue("a program is its lines: text, or a list of texts")
    parsed = []
    for text in lines:
        try:
            text.encode("latin-1")  # (the characters a byte on the line carries; not '€', not a lone surrogate)
        except UnicodeEncodeError as exc:
            raise BadValue(f"program line {text!r}: {exc.object[exc.start:exc.end]!r} is no character the drive's "
                           "line carries (latin-1)") from None
        result = st.parse(text, final=True)
        if result.errno is not None:
            raise BadValue(f"program line {text!r}: {message(result.errno)}")
        # what programming mode stores of the line (not its comments), or the statement it refuses
        stored = [stmt.text for stmt, _end in result.statements if not isinstance(stmt, st.Comment)]
        for statement in stored:
            if (problem := refusal(statement)) is not None:
                raise BadValue(f"program line {text!r}: {statement!r}: {problem}")
        parsed.append(stored)
    try:
        defined_once([], [statement for stored in parsed for statement in stored])
    except SersError as exc:
        raise BadValue(f"program: {message(exc.errno, detail=exc.detail)}") from None
    model.program.new()
    for stored in parsed:
        for index, statement in enumerate(stored):
            model.program.add(statement, new_line=index == 0)
    model.program.quit()


def _write_param(model: Any, row: Param, value: Any) -> None:
    number = row.key
    if number == 1 and value != "*" and (isinstance(value, bool) or not isinstance(value, int | float)):
        raise BadValue("P1: a number, or '*'")  # (the only parameter that is not just a number)
    try:
        model.access.write_param(number, value)
    except SersError as exc:
        raise BadValue(f"P{number}: {exc}") from None


def _read_param(model: Any, row: Param) -> Any:
    return model.access.param_value(row.key)


def _example(row: Param) -> Any:
    """A value a write-only parameter accepts (its default, its first choice, or 0 in range)."""
    if row.readable:
        return None
    if row.default is not None:
        return row.default
    if row.choices:
        return min(row.choices)
    return 0


def _as_the_drive_takes_it(point: Point) -> Point:
    """A parameter's point takes any number (P1 also ``*``) and leaves the range to the drive:
    its errnos, and the weighted ranges that follow P76 / P44 / P160 (§4.8.4.6)."""
    return msgspec.structs.replace(point, type="json" if point.name == "param.P1" else "float", minimum=None, maximum=None,
                   choices=None)


def _set_dip(field: str) -> Any:
    def put(model: Any, value: Any) -> None:
        model.cfg = model.cfg.replace(**{field: value})

    return put


_PLAIN: list[Point] = [
    # -- the shared vocabulary -------------------------------------------------------------
    Point("axis.position", "float", "actual position of the stator field, motor increments as the motor "
          "physically turns (P1134=1: against the drive's count)", "§4.8.2.3", "inc",
          get=lambda m: m.wiring.position(), in_state=True, shared=True),
    Point("axis.velocity", "float", "actual velocity (physical, as axis.position)", "§4.8.2.3", "inc/s",
          get=lambda m: m.wiring.velocity(),
          in_state=True, shared=True),
    Point("motion", "bool", "the drive moves (positioning, jog, homing, POS0/POSR)", "§4.6.6",
          get=lambda m: m.motion.kind is not None, in_state=True, shared=True),
    Point("energized", "bool", "the motor phases are energised (ON)", "§4.8.2.2", get=lambda m: m.power_stage.energized,
          in_state=True, shared=True),
    Point("ready", "bool", "the ready relay is closed and no drive error is active", "§2.1.3",
          get=lambda m: bool(m.power_stage.relay and not m.power_stage.errors), in_state=True, shared=True),
    Point("fault", "bool", "a drive error is active (P11 ≠ 0)", "§4.8.3.1", get=lambda m: bool(m.power_stage.errors),
          in_state=True, shared=True),
    # -- the drive --------------------------------------------------------------------------
    Point("axis.acceleration", "float", "actual acceleration (physical, as axis.position)", "§4.8.2.3", "inc/s²",
          get=lambda m: m.wiring.acceleration()),
    Point("axis.moving", "bool", "the stator field moves", "§5.1", get=lambda m: m.axis.moving),
    Point("axis.phase", "str", "the ramp phase of the motion (accelerate, constant, brake, idle)", "§5.2",
          get=lambda m: m.axis.phase()),
    Point("motion.kind", "str", "what moves the drive: position, jog, homing, pos0, posr (null at rest)",
          "§4.6.6", get=lambda m: m.motion.kind),
    Point("display", "json", "the 7-segment display: character and blinking", "§3.5", get=lambda m: m.outputs.display(),
          in_state=True),
    Point("display.char", "str", "the character the display shows", "§3.5", get=lambda m: m.outputs.display()["char"]),
    Point("display.blinking", "bool", "the display blinks (a warning)", "§3.5",
          get=lambda m: m.outputs.display()["blinking"]),
    Point("P11", "int", "drive errors (bit field)", "§4.8.3.1", get=lambda m: m.power_stage.errors, in_state=True),
    Point("P12", "int", "warnings (bit field)", "§4.8.3.1", get=lambda m: m.power_stage.warnings, in_state=True),
    Point("errno", "int", "number of the last error message", "§4.8.3.1", get=lambda m: m.power_stage.errno, in_state=True),
    Point("homed", "bool", "a homing run (H) completed since power-on", "§4.8.4.5", get=lambda m: m.motion.homing.homed),
    Point("homing", "str", "the homing phase (null when not homing)", "§4.8.4.5",
          get=lambda m: m.motion.homing.phase),
    Point("encoder.position", "float", "where the rotor physically is (encoder), motor increments", "§4.8.6.6", "inc",
          get=lambda m: m.wiring.physical(m.motion.encoder.encoder_position())),
    Point("encoder.pulses", "int", "count pulses at the encoder / pulse input (as if they arrived)", "§4.8.6.6",
          put=lambda m, v: m.motion.pulses(v), example=0),
    Point("phase_current", "float", "commanded phase current", "§4.8.6.1", "mA", get=lambda m: m.motion.phase_current()),
    Point("load_angle", "float", "stator field ahead of the rotor", "§4.8.6.6", "inc",
          get=lambda m: m.motion.encoder.load_angle()),
    Point("booting", "bool", "initialising after power-on (input is discarded for 2 s)", "§3.5",
          get=lambda m: m.booting),
    Point("powered", "bool", "the logic supply is on", "§2.1.4", get=lambda m: m.logic_alive, in_state=True),
    Point("position", "float", "actual position P51 in the user unit (P123)", "§4.7 P51",
          get=lambda m: m.params.scaling.inc_to_pos(round(m.motion.p51_inc())), in_state=True),
    Point("address", "int", "the drive address (DIP switch 2 bits 1-7)", "§3.1.1", get=lambda m: m.cfg.address,
          in_state=True),
    Point("selected", "bool", "statements without an address are for this drive", "§3.6.2",
          get=lambda m: m.selected, in_state=True),
    Point("dip.service_switch", "bool", "the service switch (DIP 1 bit 6; may change while powered)", "§3.1.4",
          get=lambda m: m.cfg.service_switch, put=_set_dip("service_switch")),
    Point("dip.input_level", "str", "the input level (DIP 1 bits 4-5; may change while powered)", "§3.1.5",
          get=lambda m: m.cfg.input_level, put=_set_dip("input_level"),
          choices=("plc", "ttl", "low_active", "invalid")),
    Point("program", "json", "the stored program: lines as typed (set: stored as by NEW … QUIT)", "§4.6",
          get=lambda m: m.program.lines(), put=load_program, in_state=True),
]

POINTS = PointTable.of(
    _PLAIN,
    signal_points(SIGNALS),
    map(_as_the_drive_takes_it, parameter_points(PARAMETER_TABLE, _read_param, _write_param, example=_example)),
    alias=alias_hook(PARAMETER_TABLE),
)


def _stall(model: Any, active: bool) -> None:
    model.signals.set("stall", active)


def _stop(model: Any, active: bool) -> None:
    model.signals.set("stop", active)


def _power(model: Any, active: bool) -> None:
    model.switch_supply(not active)


FAULTS = FaultTable(
    [
        Fault("blocked_axis", "the load stalls the rotor: step loss / load-angle error, in SERVO mode the "
              "field waits at the rotor", "§4.8.6.6", _stall),
        Fault("emergency_stop", "the STOP input opens: the motion stops, the display blinks", "§2.1.2", _stop),
        Fault("power", "the supply is off while active; on again afterwards (a power-on)", "§2.1.4", _power),
    ]
)
