"""Parameter access of the SERS model: the RAM image, EEPROM, reads, writes with their range
checks and side effects, operands and conditions, and the texts the serial face answers with
(manual §4.7, §4.8; spec §4.8, G-LIST)."""

from __future__ import annotations

import math
import re
from collections.abc import Callable

from devsim.core.parameters import Param as ParamDef
from devsim.devices.sers import statements as st
from devsim.devices.sers.constants import (
    INC_PER_REV,
    WEIGHTED,
)
from devsim.devices.sers.errors import SersError
from devsim.devices.sers.parameters import ALIASES, KIND, PARAMETERS
from devsim.devices.sers.units import Scaling, format_fixed, format_query, quantize

__all__ = ["ParameterAccess"]


class ParameterAccess:
    """Part of :class:`~devsim.devices.sers.drive.SersDrive`: parameters, operands, answer texts."""

    # ======================================================================================
    # parameters
    # ======================================================================================
    @property
    def scaling(self) -> Scaling:
        return self.params.scaling

    # -- reading ---------------------------------------------------------------------------
    def p51_inc(self) -> float:
        return self.motion.p51_inc()

    def param_value(self, number: int) -> float:
        """Value of parameter ``number`` in user units (raises SersError 13/106)."""
        pdef = PARAMETERS.get(number)
        if pdef is None:
            raise SersError(13)
        special = self._special_read(number)
        if special is not None:
            return special
        if not pdef.readable:
            raise SersError(106)
        value = self.params.values.get(number, 0)
        if KIND[pdef.key] in WEIGHTED:
            scaling = self.scaling
            return quantize(scaling.from_internal(KIND[pdef.key], float(value)), scaling.decimals(KIND[pdef.key]))
        return value

    def _special_read(self, n: int) -> float | None:
        """Parameters whose value is the drive's state rather than a stored number (§4.8.3),
        looked up in :meth:`_special_reads`; None for the stored ones."""
        if 1201 <= n <= 1216:
            return int(self.signals.get(f"O{n - 1200}"))
        reads = self.__dict__.get("_reads")
        if reads is None:
            reads = self.__dict__["_reads"] = self._special_reads()
        reader = reads.get(n)
        return None if reader is None else reader()

    def _special_reads(self) -> dict[int, Callable[[], float]]:
        return {
            0: lambda: 2 if self.program_editing else self.program_state,
            11: lambda: self.power_stage.errors,
            12: lambda: self.power_stage.warnings,
            51: self._read_p51,
            134: lambda: 7 if self.power_stage.energized else 0,
            336: lambda: int(self.motion.pos_ok),
            403: lambda: 0 if self.motion.homing.homed else 3,
            1013: self.status_word,
            1015: lambda: int(self.axis.phase() in ("accel", "decel")),
            1016: lambda: int(self.axis.phase() == "const"),
            1042: lambda: int(self.motion.watches.outside_soft_limits(self.motion.p51_inc())),
            1046: self.adc,
            1050: lambda: self.cfg.address,
            1122: lambda: self.program.free_words(),
            1133: lambda: self.firmware,
            1137: lambda: self.power_stage.errno,
            1300: lambda: self.inputs_byte(1),
            1301: lambda: self.inputs_byte(9) if "IO" in self.cfg.options else 0,
            1123: lambda: int(self.motion.poly.slot_free),
            1124: lambda: self._pulses_in_window(1124),
            1146: lambda: self._pulses_in_window(1146),
            1057: lambda: round(max(self.motion.encoder.max_load_angle, abs(self.motion.encoder.load_angle()))),
        }

    def _read_p51(self) -> float:
        scaling = self.scaling
        return quantize(scaling.inc_to_pos(round(self.p51_inc())), scaling.pos_decimals)

    def _pulses_in_window(self, n: int) -> int:
        params = self.params
        window = float(params.frequency_window if n == 1124 else params.frequency_window2) * 0.002
        measuring = int(self.params.pulse_input) in (9, 10) if n == 1124 else int(self.params.pulse_input2) == 5
        return round(float(self.signals.get("pulse_frequency")) * window) if measuring else 0

    @property
    def program_editing(self) -> bool:
        program = getattr(self, "program", None)
        return bool(program is not None and program.editing)

    def inputs_byte(self, first: int) -> int:
        if self.cfg.input_level == "invalid" and first == 1:
            return 0
        return sum(1 << i for i in range(8) if self.signals.get(f"I{first + i}"))

    def status_word(self) -> int:
        """P1013 (§4.8.3.2): bits set when a switch is *open*."""
        s = self.signals
        word = 0
        if s.get("limit_right"):
            word |= 1
        if s.get("limit_left"):
            word |= 2
        if s.get("stop"):
            word |= 4
        if not self.motion.homing.reference_active():
            word |= 8
        if not s.get("service_ext"):
            word |= 128
        return word

    def adc(self) -> float:
        """P1046 (spec G-ADC): fraction of the range above the P1148 offset, 10-bit quantised."""
        volts = max(0.0, min(5.0, float(self.signals.get("adc_volts"))))
        hysteresis = int(self.params.adc_hysteresis)
        bits = max(1, 10 - int(math.log2(hysteresis + 1)))
        raw = round(volts / 5 * 1023)
        raw = (raw >> (10 - bits)) << (10 - bits)
        volts = raw / 1023 * 5
        offset = int(self.params.adc_offset) * 5 / 255
        if offset >= 5:
            return 0.0
        return round(max(0.0, min(1.0, (volts - offset) / (5 - offset))), 3)

    # -- writing ---------------------------------------------------------------------------
    def write_param(self, number: int, value: float | str) -> None:  # noqa: C901
        pdef = PARAMETERS.get(number)
        if pdef is None:
            raise SersError(13)
        if value == "*":
            if number != 1:
                raise SersError(19)
            self.params.target_address = "*"
            return
        assert isinstance(value, int | float)
        handler = self._special_writes().get(number)
        if handler is not None:
            handler(value)
            return
        if not pdef.writable:
            raise SersError(105)
        if 1205 <= number <= 1216 and "IO" not in self.cfg.options:
            raise SersError(4)
        self._check_range(pdef, value)
        if KIND[pdef.key] in WEIGHTED:
            internal = self.scaling.to_internal(KIND[pdef.key], float(value))
            self.params.values[number] = internal
        else:
            self.params.values[number] = _as_number(value, pdef)
        if 1201 <= number <= 1216:
            self.signals.set(f"O{number - 1200}", bool(value))
        self._after_write(number)

    def _check_range(self, pdef: ParamDef, value: float) -> None:
        if pdef.choices is not None and value not in pdef.choices:
            raise SersError(3)
        if pdef.extra["min_exclusive"] and pdef.minimum is not None and value <= pdef.minimum:
            raise SersError(pdef.extra["too_small_errno"])  # a range "> minimum" (V, P103, P123)
        if KIND[pdef.key] == "velocity":
            rpm = self.scaling.vel_to_incps(float(value)) * 60 / INC_PER_REV
            if rpm <= 0 and pdef.key == 91:
                raise SersError(pdef.extra["too_small_errno"])
            if rpm > 10000:
                raise SersError(pdef.extra["too_large_errno"])
            if rpm < 0:
                raise SersError(pdef.extra["too_small_errno"])
            return
        if KIND[pdef.key] == "acceleration":
            rads = self.scaling.acc_to_incps2(float(value)) * 2 * math.pi / INC_PER_REV
            if rads > 100000:
                raise SersError(pdef.extra["too_large_errno"])
            if rads < (2 if pdef.key in (138, 1096) else 0):
                raise SersError(pdef.extra["too_small_errno"])
            return
        if KIND[pdef.key] == "position":
            lo, hi = self.scaling.pos_range()
            if value > hi:
                raise SersError(pdef.extra["too_large_errno"])
            if value < lo:
                raise SersError(pdef.extra["too_small_errno"])
            return
        if pdef.maximum is not None and value > pdef.maximum:
            raise SersError(pdef.extra["too_large_errno"])
        if pdef.minimum is not None and value < pdef.minimum:
            raise SersError(pdef.extra["too_small_errno"])

    def _special_writes(self) -> dict[int, Callable[[float], None]]:
        return {
            0: self._write_p0,
            11: self.power_stage.write_p11,
            12: lambda v: self.power_stage.write_p12(v, self._recheck_warnings),
            47: self._write_w,
            51: self._write_p51,
            134: self.power_stage.write_p134,
            1004: self._write_p1004,
            1014: self._write_p1014,
            1031: self._write_p1031,
            1043: self._write_p1043,
            1051: lambda v: self._write_w_mode(v, 0),
            1052: lambda v: self._write_w_mode(v, 2),
            1040: lambda v: self._write_soft_limit(1040, v),
            1099: self._write_opcode,
            **{n: (lambda v, n=n: self._write_poly(n, v)) for n in range(1111, 1117)},
            1041: lambda v: self._write_soft_limit(1041, v),
        }

    def _after_write(self, number: int) -> None:
        if number in (1125, 1126, 1131, 1132, 1036):
            self.outputs.update()

    def _write_p0(self, value: float) -> None:
        program = getattr(self, "program", None)
        if value == 0:
            if program is not None:
                program.quit()
        elif value == 1:
            self.run_program(None)
        elif value == 2:
            self.new_program()
        else:
            raise SersError(82)

    def new_program(self) -> None:
        if self.program_state == 1:
            raise SersError(44)
        self.program.new()  # type: ignore[attr-defined]

    def run_program(self, label: int | None) -> None:
        """Starting a stored program (RUN, P0=1): preconditions of §4.4.1."""
        if self.program_state == 1:
            raise SersError(44)
        self._check_start()
        program = self.program
        if program.editing:
            program.quit()
        self.interpreter.start(label)

    def on_program_state(self) -> None:
        """The program started or stopped: outputs (P1126) follow."""
        self.outputs.update()

    def on_program_end(self) -> None:
        """After a program: the event dispatcher (P1098) and a level start (P1023=1) may
        start the next one."""
        if not self.logic_alive or self.interpreter.running:
            return
        events = int(self.params.program_jump_enable)
        for n in sorted(self.interpreter.pending_events):
            self.interpreter.pending_events.discard(n)
            if events & (1 << (n - 1)) and self.signals.get(f"I{n}"):
                self._start_subroutine(n)
                return
        if self._functions_enabled(128) and int(self.params.start_enable) == 1 and self.signals.get("I8"):
            self._clock_start = self.clock.call_later(self.interpreter.cycle, self._start_input)

    def report_program_error(self, errno: int, detail: str) -> None:
        """A program error is recorded in P12/P1137; nothing is sent (G-FAULTMSG)."""

    def _write_poly(self, number: int, value: float) -> None:
        """WP/WRP/WAP/WPT/WRPT/WAPT (P1111–P1116): a polynomial segment, closed by E."""
        self._check_range(PARAMETERS[number], value)
        self.motion.poly.define(number, self.scaling.pos_to_inc(float(value)))

    def _write_opcode(self, value: float) -> None:
        """P1099 (§4.8.6.16): execute a program opcode, e.g. 62213 (0xF305) = ``RUN 5``,
        63235 (0xF703) = ``E``.  Only the opcodes the manual documents are known."""
        code = int(value)
        if code >> 8 == 0xF3:
            self.run_program(code & 0xFF or None)
        elif code == 0xF703:
            self.motion.start_positioning()
        elif code >> 8 == 0xF7:
            raise SersError(77)
        else:
            raise SersError(75)

    def _recheck_warnings(self) -> None:
        self.supply.check_supply()
        self.supply.check_temperature()

    def _write_p51(self, value: float) -> None:
        self._check_range(PARAMETERS[51], value)
        self.motion.set_p51(self.scaling.pos_to_inc(float(value)))

    def _write_p1004(self, value: float) -> None:
        actions = {2: self.memory.psave, 3: self.memory.factory_defaults, 4: self.memory.possave, 5: self.memory.save_registers}
        action = actions.get(int(value)) if value == int(value) else None
        if action is None:
            raise SersError(82)
        action()

    def _write_p1014(self, value: float) -> None:
        if value not in (0, 1, 2, 3):
            raise SersError(80)
        if self.motion.kind is not None:
            raise SersError(93)
        self.params.positioning_mode = int(value)

    def _write_p1031(self, value: float) -> None:
        commands = {1: "LS", 2: "RS", 4: "LF", 8: "RF"}
        if value == 16:
            self.motion.home()
        elif value in commands:
            self.motion.jog.start(commands[int(value)])
        else:
            raise SersError(3)

    def _write_p1043(self, value: float) -> None:
        if value == 0:
            return
        if value == 1:
            self.motion.pos0()
        elif value in (2, 3):
            self.motion.posr(force=value == 3)
        else:
            raise SersError(3)

    def _write_soft_limit(self, number: int, value: float) -> None:
        self._check_range(PARAMETERS[number], value)
        internal = self.scaling.pos_to_inc(float(value))
        lower = internal if number == 1040 else self.params.limit_negative
        upper = internal if number == 1041 else self.params.limit_positive
        if lower > upper:
            raise SersError(95)
        self.params.values[number] = internal

    def _write_w_mode(self, value: float, mode: int) -> None:
        if self.motion.kind is not None and self.params.positioning_mode != mode:
            raise SersError(93)
        self._write_w(value)
        self.params.positioning_mode = mode

    def _write_w(self, value: float) -> None:
        """W (P47): free while standing; while moving only in the constant phase (§4.6.6)."""
        self._check_range(PARAMETERS[47], value)
        self.motion.write_w(self.scaling.pos_to_inc(float(value)))

    # ======================================================================================
    # operands, conditions, arithmetic
    # ======================================================================================
    def address_number(self, address: st.Address) -> int:
        if address.kind == "P":
            return int(address.ref)
        if address.kind == "alias":
            return ALIASES[str(address.ref)]
        if address.kind == "O":
            return 1200 + int(address.ref)
        raise SersError(13)

    def operand_value(self, operand: st.Operand) -> float:
        if isinstance(operand, st.Number):
            return operand.value
        a = operand
        if a.kind == "I":
            n = int(a.ref)
            if not 1 <= n <= 16:
                raise SersError(13)
            if n <= 8:
                return (self.inputs_byte(1) >> (n - 1)) & 1
            return (self.param_value(1301) >> (n - 9)) & 1  # type: ignore[operator]
        if a.kind == "J":
            return self.j_value(int(a.ref))
        if a.kind == "IN":
            return self.param_value(1300)
        if a.kind == "O" and not 1 <= int(a.ref) <= 16:
            raise SersError(4)
        value = self.param_value(self.address_number(a))
        if value == "*":
            raise SersError(19)  # Z=* names a broadcast, not a number ('*' only with P1 or Z)
        return value

    def j_value(self, n: int) -> int:
        """J1..J5 (§4.6.1): 1 = 24 V at the input (inverse of the P1013 'open' bits)."""
        bits = {1: 8, 2: 2, 3: 1, 4: 4, 5: 128}
        if n not in bits:
            raise SersError(13)
        return 0 if self.status_word() & bits[n] else 1

    def evaluate(self, cond: st.Condition | None, counters: bool = True) -> bool:
        if cond is None:
            return False
        left = cond.left
        counter = left.kind == "alias" and left.ref in ("C1", "C2", "C3")
        value = self.operand_value(left)
        if cond.op is None:
            result = value != 0
        else:
            right = self.operand_value(cond.right) if cond.right is not None else 0
            result = st.compare(value, cond.op, right)
        if counter and counters:  # G-COUNTER: compare the old value, then decrement (saturating at 0)
            number = ALIASES[str(left.ref)]
            old = int(self.params.values.get(number, 0))
            self.params.values[number] = old - 1 if (old > 0 or (number == 100 and self.params.positioning_mode == 3)) else 0
        return result != cond.negate

    def arithmetic(self, op: str, operand: st.Operand | None) -> None:
        """X := X (op) operand, left to right (§4.6.10, spec G-ARITH): 3 decimals, ±2147483.647."""
        x = float(self.params.accumulator)
        if op in ("NOT", "NEG"):
            result = float(~int(x)) if op == "NOT" else -x
        else:
            y = self.operand_value(operand) if operand is not None else 0.0
            if op == "+":
                result = x + y
            elif op == "-":
                result = x - y
            elif op == "*":
                result = x * y
            elif op == "/":
                if y == 0:
                    self.power_stage.warn(256)
                    raise SersError(102)
                result = x / y
            elif op == "&":
                result = float(int(x) & int(y))
            elif op == "|":
                result = float(int(x) | int(y))
            else:
                result = float(int(x) ^ int(y))
        self.set_x(result)

    def set_x(self, value: float) -> None:
        if value > 2147483.647:
            self.power_stage.warn(256)
            raise SersError(98)
        if value < -2147483.647:
            self.power_stage.warn(256)
            raise SersError(99)
        self.params.accumulator = quantize(value, 3)

    # ======================================================================================
    # serial helpers used by the device
    # ======================================================================================
    @property
    def handshake_mode(self) -> int:
        return int(self.params.handshake_mode)

    @property
    def english(self) -> bool:
        return int(self.params.language) == 1

    @property
    def list_options(self) -> int:
        return int(self.params.list_option)

    def ack_text(self) -> str:
        """``ok<d>`` (§4.1): 4 error, 0/2 moving, 1/3 standing, +2 with a warning; ``pgm``."""
        if self.program_editing:
            return "pgm"
        if self.power_stage.errors:
            return "ok4"
        digit = 1 if self.motion.pos_ok else 0
        if self.power_stage.warnings:
            digit += 2
        return f"ok{digit}"

    def format_value(self, number: int, value: float) -> str:
        pdef = PARAMETERS[number]
        if KIND[pdef.key] in WEIGHTED:
            scaling = self.scaling
            return format_query(value, scaling.decimals(KIND[pdef.key]), scaling.unit(KIND[pdef.key]))
        if KIND[pdef.key] == "fixed":
            return format_query(value, pdef.decimals)
        if isinstance(value, float) and value.is_integer():
            return str(int(value))
        return str(value)

    def render_statement(self, text: str) -> str:
        """A stored statement as LIST shows it (G-LIST): keywords upper-case, constants of
        weighted parameters with all decimals of the weighting, the unit with P1028 bit 1."""
        result = st.parse(text, final=True)
        if result.errno is not None or len(result.statements) != 1:
            return text
        stmt = result.statements[0][0]
        if isinstance(stmt, st.Assign) and isinstance(stmt.value, st.Number) and stmt.target.kind != "I":
            try:
                pdef = PARAMETERS.get(self.address_number(stmt.target))
            except (SersError, KeyError):
                pdef = None
            if pdef is not None and KIND[pdef.key] in WEIGHTED:
                scaling = self.scaling
                value = format_fixed(stmt.value.value, scaling.decimals(KIND[pdef.key]))
                unit = scaling.unit(KIND[pdef.key]) if self.list_options & 2 else ""
                return f"{stmt.target.text}={value}{unit}"
        legacy_in = re.search(r"\bIN[0-9]", text.upper()) is not None
        if isinstance(stmt, st.If | st.Wait) and stmt.cond is not None and (stmt.cond.negate or legacy_in):
            keyword = "IF" if isinstance(stmt, st.If) else "WAIT"
            then = " THEN" if isinstance(stmt, st.If) and stmt.then else ""
            return f"{keyword} {_new_syntax(stmt.cond)}{then}"
        return text.upper() if not isinstance(stmt, st.Text | st.Comment) else text

    def plain_value(self, number: int) -> str:
        """Parameter ``number`` as a bare number (no unit), as a slave answers a master."""
        if number in (1300, 1301, 1013) or number in PARAMETERS:
            value = self.param_value(number)
            if value == "*":
                return "*"  # P1 = Z=* (a broadcast target), as its query answers it
            pdef = PARAMETERS.get(number)
            if pdef is not None and KIND[pdef.key] in WEIGHTED:
                return format_query(float(value), self.scaling.decimals(KIND[pdef.key]))
            if pdef is not None and KIND[pdef.key] == "fixed":
                return format_query(float(value), pdef.decimals)
            return str(int(value)) if float(value).is_integer() else str(value)
        raise SersError(13)

    def query_text(self, stmt: st.Query) -> str:
        target = stmt.target
        if stmt.name:
            if target.kind in ("P", "alias", "O"):
                pdef = PARAMETERS.get(self.address_number(target))
                if pdef is None:
                    raise SersError(13)
                return pdef.doc if self.english else pdef.name
            raise SersError(13)
        if target.kind in ("P", "alias", "O"):
            number = self.address_number(target)
            if number == 1 and self.params.target_address == "*":
                return f"{target.text}=*"
            return f"{target.text}={self.format_value(number, self.operand_value(target))}"
        return f"{target.text}={int(self.operand_value(target))}"

    def list_parameters(self, arg: str) -> list[str]:
        """LISTP (G-LIST): ``P<n>=<value>`` in ascending order; P1028 bit 4 adds names."""
        numbers = [n for n in sorted(PARAMETERS) if PARAMETERS[n].readable]
        if arg:
            first, _, count = arg.partition(".")
            start = int(first or 0)
            size = int(count) * 10 if count else 1
            numbers = numbers[start : start + size]
        rows = []
        for n in numbers:
            try:
                text = f"P{n}={self.format_value(n, self.param_value(n))}"
            except SersError:
                continue
            if self.list_options & 16:
                text += "  " + PARAMETERS[n].name
            rows.append(text)
        return rows




def _as_number(value: float, pdef: ParamDef) -> float | int:
    if KIND[pdef.key] == "int" and float(value).is_integer():
        return int(value)
    if KIND[pdef.key] == "fixed":
        return quantize(float(value), pdef.decimals)
    return value


_OPPOSITE = {"<": ">=", "<=": ">", "=": "<>", "<>": "=", ">": "<=", ">=": "<"}


def _operand_text(operand: st.Operand | None) -> str:
    if operand is None:
        return "0"
    return operand.text if isinstance(operand, st.Number) else operand.text


def _new_syntax(cond: st.Condition) -> str:
    """A legacy condition (``!I5``, ``IN5``) in the syntax LIST shows (§4.6.1)."""
    left = cond.left.text
    if cond.op is None:
        return f"{left}=0" if cond.negate else f"{left}<>0"
    op = _OPPOSITE[cond.op] if cond.negate else cond.op
    return f"{left}{op}{_operand_text(cond.right)}"




def _sign(x: float) -> int:
    return (x > 0) - (x < 0)


def _raise(errno: int) -> None:
    raise SersError(errno)

