"""Parameter access of the SERS by the number the host sent: reads, writes with their range
checks and their effects, and the values as the drive shows them (manual §4.7, §4.8, §4.8.4.6;
spec §4.8, G-QUERYFMT).

A parameter whose value is the drive's state rather than a stored number is read through
:data:`READS`; one whose write does something is written through :data:`WRITES`; both are
tables of :class:`~devsim.core.kit.Command` rows keyed by ``P<n>``, each citing its section.
Every other parameter is a value of :class:`~.params.SersParameters`, converted by its weighting.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from operator import attrgetter
from typing import Any, Protocol

from devsim.core.kit import Command, Table
from devsim.core.parameters import Param
from devsim.core.signals import SignalBank
from devsim.devices.sers import statements as st
from devsim.devices.sers.constants import FIRMWARE, INC_PER_REV, WEIGHTED_KINDS
from devsim.devices.sers.errors import SersError
from devsim.devices.sers.inputs import Inputs
from devsim.devices.sers.memory import ParameterMemory
from devsim.devices.sers.motion import Motion
from devsim.devices.sers.paramdef import below_exclusive_minimum
from devsim.devices.sers.parameters import ALIASES, CURRENT_MAX_MA, KIND, PARAMETERS
from devsim.devices.sers.params import SersParameters
from devsim.devices.sers.power import PowerStage
from devsim.devices.sers.program import ProgramMemory
from devsim.devices.sers.units import Scaling, format_query, quantize

__all__ = ["READS", "TIMELESS", "WRITES", "ParameterAccess", "ProgramControl", "address_number", "plain_reader",
           "weighted_reader"]


class ProgramControl(Protocol):
    """What P0 and P1099 (§4.8.2.1, §4.8.6.16) need of the program execution
    (:class:`~.execution.Execution`)."""

    @property
    def running(self) -> bool: ...

    def run_program(self, label: int | None) -> None: ...

    def new_program(self) -> None: ...


#: How an address names a parameter (§4.2): by number, by alias, as output O1..O16 (P1201..).
_NUMBERS: dict[str, Callable[[str | int], int]] = {
    "P": int,
    "alias": lambda ref: ALIASES[str(ref)],
    "O": lambda ref: 1200 + int(ref),
}


def address_number(address: st.Address) -> int:
    """The P number an address names (``V`` → 91, ``O2`` → 1202); errno 13 for I, J, IN."""
    number = _NUMBERS.get(address.kind)
    if number is None:
        raise SersError(13)
    return number(address.ref)


class ParameterAccess:
    """Reads and writes of one SERS's parameters by number (§4.7, §4.8)."""

    #: (Slots: a host's repeated poll reads this part: one block of memory instead of an object and its values)
    __slots__ = ("params", "memory", "power", "motion", "inputs", "program", "signals", "_config",
                 "_programs", "_changed", "_recheck_warnings", "_rotation_changed", "firmware", "_format_query")

    def __init__(
        self,
        params: SersParameters,
        memory: ParameterMemory,
        power: PowerStage,
        motion: Motion,
        inputs: Inputs,
        program: ProgramMemory,
        signals: SignalBank,
        *,
        config: Callable[[], Any],
        programs: Callable[[], ProgramControl],
        changed: Callable[[], None],
        recheck_warnings: Callable[[], None],
        rotation_changed: Callable[[], None],
        query_format: Callable[[float, int, str], str] = format_query,
    ) -> None:
        self.params = params
        self.memory = memory
        self.power = power
        self.motion = motion
        self.inputs = inputs
        self.program = program
        self.signals = signals
        self._config = config
        self._programs = programs  # (the program execution, made after the access)
        self._changed = changed  # outputs that follow a state (P1125 …) follow a new selector
        self._recheck_warnings = recheck_warnings  # P12=0: the warnings whose causes remain
        self._rotation_changed = rotation_changed  # P1134: the motor turns the other way from now on
        self.firmware = FIRMWARE
        self._format_query = query_format  # G-QUERYFMT ⚙ (:func:`.units.query_formatter`)

    @property
    def scaling(self) -> Scaling:
        return self.params.scaling

    # -- reading ----------------------------------------------------------------------------------
    def param_value(self, number: int) -> Any:
        """Value of parameter ``number`` in user units (raises SersError 13/106)."""
        row = PARAMETERS.get(number)
        if row is None:
            raise SersError(13)
        reader = _READ.get(number)
        if reader is not None:
            return reader(self)
        if number in _WRITE_ONLY:
            raise SersError(106)
        value = self.params.values.get(number, 0)
        return self.in_user_units(number, float(value)) if KIND[number] in WEIGHTED_KINDS else value

    def in_user_units(self, number: int, value: float) -> float:
        """An internal value (inc, inc/s, inc/s²) of weighted parameter ``number`` as a read gives it."""
        scaling, kind = self.params.scaling, KIND[number]
        return quantize(scaling.from_internal(kind, value), scaling.decimals(kind))

    def p51(self) -> float:
        """P51 in the user unit."""
        scaling = self.params.scaling
        return quantize(scaling.inc_to_pos(round(self.motion.p51_inc())), scaling.pos_decimals)

    def program_state(self) -> int:
        """P0: 2 in programming mode, 1 while a program runs, else 0."""
        return 2 if self.program.editing else 1 if self._programs().running else 0

    def format_value(self, number: int, value: Any) -> str:
        """A value as a query and LISTP answer it: weighted ones with the decimals and the unit of
        their weighting, ``fixed`` ones with their decimals (G-QUERYFMT, as the configured
        ``query_fixed_decimals`` / ``query_units`` render them)."""
        kind = KIND[number]
        if kind in WEIGHTED_KINDS:
            scaling = self.params.scaling
            return self._format_query(value, scaling.decimals(kind), scaling.unit(kind))
        if kind == "fixed":
            row = PARAMETERS[number]
            # §4.7: "bei Parametern mit einer Einheit - Wichtung - wie z.B. die Vorschubkonstante
            # wird die Einheit mitgesendet" (the example answer: 'P…=150mm')
            unit = self.params.scaling.length_unit if row.extra["length_unit"] else ""
            return self._format_query(value, row.decimals, unit)
        if isinstance(value, float) and value.is_integer():
            return str(int(value))
        return str(value)

    def plain_value(self, number: int) -> str:
        """Parameter ``number`` as a bare number (no unit), as a slave answers a master."""
        if number in (1300, 1301, 1013) or number in PARAMETERS:
            value = self.param_value(number)
            if value == "*":
                return "*"  # P1 = Z=* (a broadcast target), as its query answers it
            kind = KIND.get(number)
            if kind in WEIGHTED_KINDS:
                return format_query(float(value), self.params.scaling.decimals(kind))
            if kind == "fixed":
                return format_query(float(value), PARAMETERS[number].decimals)
            return str(int(value)) if float(value).is_integer() else str(value)
        raise SersError(13)

    # -- writing ----------------------------------------------------------------------------------
    def write_param(self, number: int, value: float | str) -> None:
        row = PARAMETERS.get(number)
        if row is None:
            raise SersError(13)
        if value == "*":
            if number != 1:
                raise SersError(19)
            self.params.target_address = "*"
            return
        assert isinstance(value, int | float)
        if not row.writable:
            raise SersError(row.extra["write_errno"])
        if row.choices is not None and value not in row.choices:
            raise SersError(row.extra["invalid_errno"])
        writer = _WRITE.get(number)
        if writer is not None:
            writer(self, value)
            return
        if 1205 <= number <= 1216 and "IO" not in self._config().options:
            raise SersError(4)
        self.check_range(row, value)
        kind = KIND[number]
        values = self.params.values
        if kind in WEIGHTED_KINDS:
            values[number] = self.params.scaling.to_internal(kind, float(value))
        elif kind == "int" and float(value).is_integer():
            values[number] = int(value)
        elif kind == "fixed":
            values[number] = quantize(float(value), row.decimals)
        else:
            values[number] = value
        if 1201 <= number <= 1216:
            self.signals.set(f"O{number - 1200}", bool(value))
        if number in (1125, 1126, 1131, 1132, 1036):
            self._changed()

    def check_range(self, row: Param, value: float) -> None:
        """The drive's range check of a write (§4.7): choices, then the range, weighted ranges
        after conversion (V ≤ 10000 rpm, A ≤ 100000 rad/s², positions within ±2^31 increments);
        C1 in positioning mode 3 is signed (§4.8.5.2: "Wenn P1014=3 ..., dann ist dieser Zähler
        vorzeichenbehaftet", the row's ``mode3_range``)."""
        extra = row.extra
        if row.choices is not None and value not in row.choices:
            raise SersError(extra["invalid_errno"])
        kind = extra["kind"]
        if below_exclusive_minimum(row, value):  # a range "> minimum" (V, P103, P123), as kept
            raise SersError(extra["too_small_errno"])
        scaling = self.params.scaling
        if kind == "velocity":
            rpm = scaling.vel_to_incps(float(value)) * 60 / INC_PER_REV
            if rpm <= 0 and row.key == 91:
                raise SersError(extra["too_small_errno"])
            if _beyond(rpm, 10000):
                raise SersError(extra["too_large_errno"])
            if rpm < 0:
                raise SersError(extra["too_small_errno"])
            return
        if kind == "acceleration":
            rads = scaling.acc_to_incps2(float(value)) * 2 * math.pi / INC_PER_REV
            if _beyond(rads, 100000):
                raise SersError(extra["too_large_errno"])
            if _beyond(-rads, -(2 if row.key in (138, 1096) else 0)):
                raise SersError(extra["too_small_errno"])
            return
        if kind == "position":
            lo, hi = scaling.pos_range()
            if value > hi:
                raise SersError(extra["too_large_errno"])
            if value < lo:
                raise SersError(extra["too_small_errno"])
            return
        minimum, maximum = row.minimum, row.maximum
        if extra["mode3_range"] is not None and int(self.params.positioning_mode) == 3:
            minimum, maximum = extra["mode3_range"]  # C1 signed in mode 3 (§4.8.5.2)
        if maximum is not None and value > maximum:
            raise SersError(extra["too_large_errno"])
        if minimum is not None and value < minimum:
            raise SersError(extra["too_small_errno"])

    def _position(self, number: int, value: float) -> float:
        """A position parameter's value checked and in increments."""
        self.check_range(PARAMETERS[number], value)
        return self.params.scaling.pos_to_inc(float(value))

    def write_p0(self, value: float) -> None:
        """P0 (§4.8.2.1): 0 leaves programming mode, 1 starts the program, 2 starts programming
        mode deleting the program (NEW)."""
        _P0[value](self)  # (the row's choices are checked before: errno 82)

    def write_w(self, value: float) -> None:
        """W (P47): free while standing; while moving only in the constant phase (§4.6.6)."""
        self.motion.positioning.write_w(self._position(47, value))

    def write_w_mode(self, value: float, mode: int) -> None:
        """WR / WA (P1051 / P1052): W, and the positioning mode relative (0) or absolute (2)."""
        if self.motion.kind is not None and self.params.positioning_mode != mode:
            raise SersError(93)
        self.write_w(value)
        self.params.positioning_mode = mode

    def write_p1004(self, value: float) -> None:
        """P1004 (§4.8.6.10): 2 PSAVE, 3 factory defaults, 4 POSSAVE, 5 R0..R5 and W."""
        _P1004[int(value)](self.memory)  # (the row's choices are checked before: errno 82)
        self._rotation_changed()  # factory defaults may set P1134 back

    def write_p1014(self, value: float) -> None:
        """P1014 (§4.8.4.1): the positioning mode (the row's choices are checked before: errno 80
        "unbekannter Positioniermodus"), not while the drive moves."""
        if self.motion.kind is not None:
            raise SersError(93)
        self.params.positioning_mode = int(value)

    def write_p1043(self, value: float) -> None:
        """P1043 (§4.8.4.2): 1 POS0, 2 POSR, 3 POSR also without a step loss."""
        action = _P1043.get(value)
        if action is None:
            raise SersError(3)
        action(self.motion)

    def write_p1134(self, value: float) -> None:
        """P1134 (§4.8.2.3): the motor's sense of rotation; not while the drive moves [SIM-CHOICE:
        errno 93 "nicht schreibbar, während der Antrieb positioniert"]."""
        self.check_range(PARAMETERS[1134], value)
        if self.motion.kind is not None:
            raise SersError(93)
        self.params.direction_inverted = int(value)
        self._rotation_changed()

    def write_p1136(self, value: float) -> None:
        """P1136 (§4.8.2.4): "Bei Versionen bis 6A kann P1136 nicht verändert werden" -- only a
        12 A version takes it (a smaller one: the row's write errno, 105)."""
        row = PARAMETERS[1136]
        self.check_range(row, value)
        if self._config().current_class != "12":
            raise SersError(row.extra["write_errno"])
        self.params.values[1136] = int(value)

    def write_phase_current(self, value: float) -> None:
        """P1010 (§4.8.6.1): "Der gültige Wertebereich bzw. der max. einstellbare Phasenstrom hängt
        von der Version ab" -- the version's maximum (CURRENT_MAX_MA), above it errno 1."""
        row = PARAMETERS[1010]
        self.check_range(row, value)
        if value > CURRENT_MAX_MA[self._config().current_class]:
            raise SersError(row.extra["too_large_errno"])
        self.params.values[1010] = int(value) if float(value).is_integer() else value

    def write_pulse_weight(self, number: int, value: float) -> None:
        """P1054 / P1144 (§4.8.6.6): "Intern werden nur 16 Bit abgespeichert. Bei Zahlen außerhalb
        -0.32768 bis 0.32767 wird die Auflösung vermindert indem die letzten beiden
        Nachkommastellen 0 werden" -- five decimals inside that range, three outside (cut off)."""
        row = PARAMETERS[number]
        self.check_range(row, value)
        weight = quantize(float(value), row.decimals)
        if not -0.32768 <= weight <= 0.32767:
            weight = math.trunc(round(weight * 100000) / 100) / 1000
        self.params.values[number] = weight

    def write_soft_limit(self, number: int, value: float) -> None:
        """P1040 / P1041 (§4.8.6.12): the lower limit may not lie above the upper one."""
        internal = self._position(number, value)
        params = self.params
        lower = internal if number == 1040 else params.limit_negative
        upper = internal if number == 1041 else params.limit_positive
        if lower > upper:
            raise SersError(95)
        params.values[number] = internal

    def write_opcode(self, value: float) -> None:
        """P1099 (§4.8.6.16): execute a program opcode, e.g. 62213 (0xF305) = ``RUN 5``,
        63235 (0xF703) = ``E``.  Only the opcodes the manual documents are known."""
        code = int(value)
        if code >> 8 == 0xF3:
            self._programs().run_program(code & 0xFF or None)
        elif code == 0xF703:
            self.motion.start_positioning()
        elif code >> 8 == 0xF7:
            raise SersError(77)
        else:
            raise SersError(75)


def _beyond(value: float, limit: float) -> bool:
    """``value`` above ``limit`` by more than the rounding of the unit conversion (V=10000 rpm
    and A=100000 rad/s², the manual's maxima, are allowed exactly)."""
    return value > limit and not math.isclose(value, limit, rel_tol=1e-9, abs_tol=1e-9)


#: P0's values (§4.8.2.1): leave programming mode, start the program, NEW.
_P0: dict[float, Callable[[ParameterAccess], None]] = {
    0: lambda a: a.program.quit(),
    1: lambda a: a._programs().run_program(None),
    2: lambda a: a._programs().new_program(),
}
#: P1004's values (§4.8.6.10): PSAVE, factory defaults, POSSAVE, R0..R5 and W.
_P1004: dict[int, Callable[[ParameterMemory], None]] = {
    2: ParameterMemory.psave,
    3: ParameterMemory.factory_defaults,
    4: ParameterMemory.possave,
    5: ParameterMemory.save_registers,
}
#: P1043's values (§4.8.4.2): nothing, POS0, POSR, POSR also without a step loss.
_P1043: dict[float, Callable[[Motion], None]] = {
    0: lambda m: None,
    1: Motion.pos0,
    2: lambda m: m.posr(force=False),
    3: lambda m: m.posr(force=True),
}


Read = Callable[[ParameterAccess], Any]
Write = Callable[[ParameterAccess, float], None]


def _output(n: int) -> Read:
    return lambda a: int(a.signals.get(f"O{n}"))


#: Parameters whose value is the drive's state rather than a stored number (§4.8.3).
READS: Table[Read] = Table(
    [
        Command("P0", ParameterAccess.program_state, "§4.8.2.1", "EEPROM mode: programming 2, running 1"),
        Command("P11", attrgetter("power.errors"), "§4.8.3.1", "drive errors"),
        Command("P12", attrgetter("power.warnings"), "§4.8.3.1", "warnings"),
        Command("P51", ParameterAccess.p51, "§4.8.4.2", "actual position"),
        Command("P134", lambda a: 7 if a.power.energized else 0, "§4.8.2.2", "motor ON (7) or OFF (0)"),
        Command("P336", lambda a: int(a.motion.pos_ok), "§4.8.3.3", "in position"),
        Command("P403", lambda a: 0 if a.motion.homing.homed else 3, "§4.8.4.5", "homed (0) or not (3)"),
        Command("P1013", lambda a: a.inputs.status_word(), "§4.8.3.2", "switches open"),
        Command("P1015", lambda a: int(a.motion.axis.phase() in ("accel", "decel")), "§4.8.3.3", "ramping"),
        Command("P1016", lambda a: int(a.motion.axis.phase() == "const"), "§4.8.3.3", "at constant speed"),
        Command("P1042", lambda a: int(a.motion.watches.outside_soft_limits(a.motion.p51_inc())), "§4.8.6.12",
                "outside the software limits"),
        Command("P1046", lambda a: a.inputs.adc(), "§4.8.1.3", "the analog input"),
        Command("P1050", lambda a: a._config().address, "§3.1.2", "the DIP address"),
        Command("P1057", lambda a: round(max(a.motion.encoder.max_load_angle, abs(a.motion.encoder.load_angle()))),
                "§4.8.6.6", "the largest load angle"),
        Command("P1122", lambda a: a.program.free_words(), "§4.8.6.10", "free program memory (words)"),
        Command("P1123", lambda a: int(a.motion.poly.slot_free), "§4.6.7", "a polynomial segment may be sent"),
        Command("P1124", lambda a: a.inputs.pulses_in_window(1124), "§4.8.6.6", "pulses in the window P1055 (P1053=9 I3, 10 ENC)"),
        Command("P1133", lambda a: a.firmware, "§4.8.2.5", "firmware version"),
        Command("P1137", attrgetter("power.errno"), "§4.8.3.1", "the last error message"),
        Command("P1146", lambda a: a.inputs.pulses_in_window(1146), "§4.8.6.6", "pulses in the window P1145 (P1143=5, I3)"),
        Command("P1156", lambda a: a.in_user_units(1156, a.motion.ramp_acceleration()), "§4.8.6.7",
                "SERVO: the mean acceleration of the last ramp"),
        *(Command(f"P{1200 + n}", _output(n), "§4.8.1.2", f"output O{n}") for n in range(1, 17)),
        Command("P1300", lambda a: a.inputs.inputs_byte(1), "§4.8.1.1", "inputs I1..I8"),
        Command("P1301", lambda a: a.inputs.inputs_byte(9) if "IO" in a._config().options else 0, "§4.8.1.1",
                "inputs I9..I16 (option IO)"),
    ]
)


def _poly(number: int) -> Write:
    """WP/WRP/WAP/WPT/WRPT/WAPT (P1111–P1116): a polynomial segment, closed by E."""
    return lambda a, v: a.motion.poly.define(number, a._position(number, v))


#: Parameters whose write does something beyond storing the value.
WRITES: Table[Write] = Table(
    [
        Command("P0", ParameterAccess.write_p0, "§4.8.2.1", "QUIT / RUN / NEW"),
        Command("P11", lambda a, v: a.power.write_p11(v), "§4.8.3.1", "clear the drive errors (0)"),
        Command("P12", lambda a, v: a.power.write_p12(v, a._recheck_warnings), "§4.8.3.1", "clear the warnings (0)"),
        Command("P47", ParameterAccess.write_w, "§4.6.6", "W: also on the move, in the constant phase"),
        Command("P51", lambda a, v: a.motion.set_p51(round(a._position(51, v))), "§4.8.4.2",
                "set the actual position (the drive counts whole increments)"),
        Command("P134", lambda a, v: a.power.write_p134(v), "§4.8.2.2", "ON (7) / OFF (0)"),
        Command("P1004", ParameterAccess.write_p1004, "§4.8.6.10", "PSAVE, factory defaults, POSSAVE"),
        Command("P1014", ParameterAccess.write_p1014, "§4.8.4.1", "positioning mode"),
        Command("P1031", lambda a, v: a.motion.jog.write_p1031(v, a.motion.home), "§4.8.6.3", "jog / home"),
        Command("P1010", ParameterAccess.write_phase_current, "§4.8.6.1", "phase current: the version's maximum"),
        Command("P1136", ParameterAccess.write_p1136, "§4.8.2.4", "chopper frequency: 12 A versions only"),
        Command("P1134", ParameterAccess.write_p1134, "§4.8.2.3", "the motor's sense of rotation"),
        Command("P1040", lambda a, v: a.write_soft_limit(1040, v), "§4.8.6.12", "lower software limit"),
        Command("P1041", lambda a, v: a.write_soft_limit(1041, v), "§4.8.6.12", "upper software limit"),
        Command("P1043", ParameterAccess.write_p1043, "§4.8.4.2", "POS0 / POSR"),
        Command("P1054", lambda a, v: a.write_pulse_weight(1054, v), "§4.8.6.6", "pulse weight: 16 bit"),
        Command("P1144", lambda a, v: a.write_pulse_weight(1144, v), "§4.8.6.6", "pulse weight: 16 bit"),
        Command("P1051", lambda a, v: a.write_w_mode(v, 0), "§4.6.6", "WR: W and relative mode"),
        Command("P1052", lambda a, v: a.write_w_mode(v, 2), "§4.6.6", "WA: W and absolute mode"),
        Command("P1099", ParameterAccess.write_opcode, "§4.8.6.16", "execute an opcode"),
        *(Command(f"P{n}", _poly(n), "§4.6.7", "a polynomial segment") for n in range(1111, 1117)),
    ]
)

# (the tables by number, for the parameter access of every query and write)
_READ: dict[int, Read] = {int(row.token[1:]): row.handler for row in READS}
_WRITE: dict[int, Write] = {int(row.token[1:]): row.handler for row in WRITES}
_WRITE_ONLY = frozenset(n for n, row in PARAMETERS.items() if not row.readable)


def _stored(number: int) -> Read:
    def read(access: ParameterAccess) -> Any:
        return access.params.values.get(number, 0)

    return read


#: Parameters answered with their value as it is (neither weighted nor ``fixed``; not P1, whose
#: ``Z=*`` answers ``*``) that can be read: what reads each, as :meth:`ParameterAccess.param_value`.
_PLAIN_READERS: dict[int, Read] = {
    n: _READ.get(n) or _stored(n)
    for n in PARAMETERS
    if n != 1 and KIND[n] not in WEIGHTED_KINDS and KIND[n] != "fixed" and (n in _READ or n not in _WRITE_ONLY)
}


#: Weighted parameters a query answers (readable; P51 the actual position): what their answer is
#: made of besides the weighting (:attr:`SersParameters.scaling`), before :meth:`ParameterAccess.param_value`
#: converts and rounds it: P51's increments (as :meth:`ParameterAccess.p51` rounds them), the others'
#: stored values.
_WEIGHTED_READERS: dict[int, Read] = {
    51: lambda a: round(a.motion.p51_inc()),
    **{n: _stored(n) for n in PARAMETERS if KIND[n] in WEIGHTED_KINDS and n not in _READ and n not in _WRITE_ONLY},
}


#: Parameters a query answers as they are whose value changes only with the drive's state, never
#: with time alone (devsim.core.changes: nothing changes it while the count of changes stands):
#: every stored value, and of :data:`READS` the errors, warnings, error number, program state,
#: motor ON, in position, homed, DIP address, free memory, firmware and outputs.  Not so: the
#: ramp phase (P1015, P1016), the software limits (P1042), the analog input (P1046), the load
#: angle (P1057), the polynomial slot (P1123), pulses in a window (P1124, P1146), the inputs
#: (P1013, P1300, P1301: a limit switch the axis reaches).
TIMELESS: frozenset[int] = frozenset(
    n for n in _PLAIN_READERS
    if n not in _READ or n in (0, 11, 12, 134, 336, 403, 1050, 1122, 1133, 1137, *range(1201, 1217))
)


def weighted_reader(number: int) -> Read | None:
    """For a weighted parameter ``number`` a query answers: a reader of what its answer depends
    on besides the weighting (the same value and the same :class:`~.units.Scaling` object give
    the same answer line, so a host's repeated poll of a standing axis's position is answered from
    the line kept); None for any other number."""
    return _WEIGHTED_READERS.get(number)


def plain_reader(number: int) -> Read | None:
    """What :meth:`ParameterAccess.param_value` does for parameter ``number`` when a query
    answers its value as it is (a host's poll reads it again and again without looking the
    number up): its reader, or one of the stored value.  None for any other number (weighted,
    ``fixed``, P1, no row, write-only: its answer or error is made the general way)."""
    return _PLAIN_READERS.get(number)
