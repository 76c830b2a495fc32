"""The SERS drive behind the serial line: parameters, motion, I/O and faults.

Implements (manual section → spec section):

* parameters with range checks, units and PSAVE/POSSAVE/P1004 (§4.7, §4.8, §4.8.6.10 → §4.8);
* the motor-power state machine ON/OFF, drive errors P11 and warnings P12 (§2.1.3, §4.8.3.1 →
  §4.3, §4.6) and the 7-segment display (§3.5 → §4.7);
* positioning E with modes P1014 0–3 and W changes during the constant phase (§4.6.6,
  §4.8.4.1 → §3.5.3, §3.5.4, §5.2, §5.12), jog RS/RF/LS/LF with the 500 ms timeout (§4.5.1,
  §4.8.6.4 → §3.5.8, §5.3), homing H (§4.8.4.5 → §5.5), POS0 and P1001 (§4.8.4.2 → §5.13);
* hardware limit switches, STOP input, software limits and compare positions (§2.1.2,
  §4.8.6.12, §4.8.1.2 → §5.6, §5.7), supply voltage and heat-sink temperature faults (§2.1.4,
  §3.5 → §2.7, §5.14), digital inputs with their jog functions (§3.3, §4.8.1.1 → §4.11).

Internally positions are motor increments, speeds inc/s and accelerations inc/s²; the
weighting parameters (P76, P44, P160, P121–P123) only matter at the serial interface.
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable
from typing import Any

from devsim.core.axis import Axis, RampProfile, RegionSwitch, Watch
from devsim.core.clock import Clock, Timer
from devsim.core.device import Device, UnknownName
from devsim.core.nvram import NonVolatileMemory
from devsim.devices.sers import statements as st
from devsim.devices.sers.config import SersConfig
from devsim.devices.sers.errors import SersError
from devsim.devices.sers.parameters import ALIASES, CURRENT_MAX_MA, PARAMETERS, SUPPLY_THRESHOLDS, ParamDef
from devsim.devices.sers.polynomial import PolynomialMove
from devsim.devices.sers.units import Scaling, format_fixed, format_query, quantize

__all__ = ["SersDrive"]

FIRMWARE = 120901
INC_PER_REV = 12800
ELECTRICAL_PERIOD = 256  # increments between phase-zero positions (7.2° on a 1.8° motor)
WEIGHTED = ("position", "velocity", "acceleration")
WEIGHTING_PARAMS = (76, 44, 160, 121, 122, 123)
INPUT_NAMES = ("limit_left", "limit_right", "stop", "reference", "service_ext")

# Display characters of the drive errors, in the spec's priority order (§4.7).
ERROR_DISPLAY = ((128, "E"), (2, "8"), (512, "9"), (32, "F"), (8192, "c"), (2048, "A"))
WARNING_DISPLAY = ((2, "8"), (4, "9"), (32, "F"), (128, "H"), (1, "L"), (8, "A"), (64, "A"))

# P11 bits that P11=0 may clear only once their cause is gone (spec G-P11CLEAR).
OVERTEMP, STEP_LOSS, SHORT, UNDERVOLTAGE, STANDSTILL, LIMIT = 2, 32, 128, 512, 2048, 8192


class SersDrive(Device):
    """Parameters, physics and faults of one SERS; the serial side is :class:`SersDevice`."""

    def __init__(
        self,
        *,
        clock: Clock,
        config: dict[str, Any] | None = None,
        nvram: NonVolatileMemory | None = None,
        name: str | None = None,
    ) -> None:
        super().__init__(clock=clock, config=config, nvram=nvram, name=name)
        self.cfg = SersConfig.model_validate(self.config)
        self.thresholds = SUPPLY_THRESHOLDS[self.cfg.supply_class]
        self.axis = Axis(clock, counts_per_rev=INC_PER_REV, index_offset=self.cfg.axis.index_offset, name=self.name)
        self._timers: list[Timer] = []
        self._watches: list[Watch] = []
        self._define_signals()
        self._switches: list[RegionSwitch] = []
        self._build_switches()
        self.logic_alive = False
        self.booting = False
        self.firmware = FIRMWARE
        self.trace_mode = False
        self.ram: dict[int, Any] = {}
        self.poly = PolynomialMove(self)
        self._power_on()

    # ======================================================================================
    # signals and geometry
    # ======================================================================================
    def _define_signals(self) -> None:
        s = self.signals
        s.define("limit_left", "input", False, "left limit switch actuated (NC contact open)")
        s.define("limit_right", "input", False, "right limit switch actuated (NC contact open)")
        s.define("stop", "input", False, "STOP input actuated (NC contact open)")
        s.define("reference", "input", False, "drive stands on the reference switch")
        s.define("service_ext", "input", False, "external service switch active")
        for n in range(1, 17):
            s.define(f"I{n}", "input", False, f"digital input I{n}")
        for n in range(1, 17):
            s.define(f"O{n}", "output", False, f"digital output O{n}")
        s.define("READY", "output", False, "ready relay closed (§2.1.3)")
        nominal = self.thresholds[0] * 0.8 if self.cfg.supply_voltage is None else self.cfg.supply_voltage
        s.define("supply_voltage", "quantity", float(nominal), "main supply in volts (§2.1.4)")
        s.define("heatsink_temperature", "quantity", float(self.cfg.heatsink_temperature), "°C (§3.5)")
        s.define("short_circuit", "quantity", False, "short circuit in motor or power stage")
        s.define("adc_volts", "quantity", 0.0, "voltage at the analog input ADC, 0..5 V")
        s.define("stall", "quantity", False, "load torque above motor torque: the rotor stands still")
        s.define("pulse_frequency", "quantity", 0.0, "frequency (Hz) of the pulses at I3 / ENC (P1053=9/10, P1143=5)")
        for name in ("limit_left", "limit_right"):
            s.subscribe(name, self._on_limit)
        s.subscribe("stop", self._on_stop_input)
        s.subscribe("reference", self._on_reference)
        for n in range(1, 9):
            s.subscribe(f"I{n}", self._on_digital_input)
        s.subscribe("supply_voltage", lambda *_: self._check_supply())
        s.subscribe("heatsink_temperature", lambda *_: self._check_temperature())
        s.subscribe("short_circuit", lambda *_: self._check_short())
        s.subscribe("stall", self._on_stall)
        for name in s.names():
            s.subscribe(name, lambda *_: self.interpreter.poke())

    def _build_switches(self) -> None:
        geo = self.cfg.axis

        def follow(signal: str) -> Callable[[bool], None]:
            return lambda active: self.signals.set(signal, active)

        if geo.limit_left is not None:
            self._switches.append(RegionSwitch(self.axis, -math.inf, geo.limit_left, follow("limit_left")))
        if geo.limit_right is not None:
            self._switches.append(RegionSwitch(self.axis, geo.limit_right, math.inf, follow("limit_right")))
        if geo.reference_low is not None:
            high = geo.reference_high if geo.reference_high is not None else math.inf
            self._switches.append(RegionSwitch(self.axis, geo.reference_low, high, follow("reference")))
        for switch, name in zip(self._switches, self._switch_signals(), strict=False):
            self.signals.signal(name).value = switch.active

    def _switch_signals(self) -> list[str]:
        geo = self.cfg.axis
        names = []
        if geo.limit_left is not None:
            names.append("limit_left")
        if geo.limit_right is not None:
            names.append("limit_right")
        if geo.reference_low is not None:
            names.append("reference")
        return names

    # ======================================================================================
    # power
    # ======================================================================================
    def _power_on(self) -> None:
        """§3.5 / spec §4.1: display '-' for 2 s, then parameters from EEPROM."""
        self._cancel_timers()
        self.axis.quick_stop()
        self._reset_serial()
        self.logic_alive = True
        self.booting = self.cfg.boot_time > 0
        self.record_event("power_on")
        self.eeprom_checksum_error = bool(getattr(self.nvram, "corrupt", False))
        self.errors = 0
        self.warnings = 0
        self.errno = 0
        self.energized = False
        self.relay = False
        self.homed = False
        self.pos_ok = True  # P336
        self.motion: str | None = None
        self._stop_decel = 0.0
        self._w_updated = False
        self._homing: dict[str, Any] | None = None
        self._jog_timer: Timer | None = None
        self._standstill_watches: list[Watch] = []
        self._dispatch: Timer | None = None
        self._legs: list[tuple[float, float]] = []
        self.lost = 0.0  # increments the rotor lags behind the stator field (step loss)
        self._stall_rotor: float | None = None
        self._load_watches: list[Watch] = []
        self._setpoint: float | None = None
        self._follow_target = 0.0
        self._stopped_at = 0.0
        self.servo_calibrated = False
        self.servo_overload = False
        self._servo_resume = False
        self._posr_attempts = 0
        self.max_load_angle = 0.0
        self._jog_dir = 0
        self._jog_until: st.Condition | None = None
        self._short_latched = False
        self._stop_cycled = True
        self._stop_opened = False
        program = getattr(self, "program", None)
        if program is not None:
            program.reload()  # programming mode does not survive a power loss (P0 = 0)
        self.interpreter.reset()
        self.poly.cancel()
        self.trace_mode = False
        self._load_parameters()
        saved_pos = self.nvram.get("position")
        p51 = float(saved_pos) if saved_pos is not None else 0.0
        self.offset = self.axis.position() - p51
        for n in range(1, 17):
            self.signals.set(f"O{n}", False)
        if self.ram[1011] & 32 and not self.eeprom_checksum_error:
            self.energized = True
            self.relay = True
        self._check_supply()
        self._check_temperature()
        self._check_short()
        self._check_limits_at_power_on()
        self._update_outputs()
        if self.booting:
            self._timers.append(self.clock.call_later(self.cfg.boot_time, self._boot_done))

    def _boot_done(self) -> None:
        self.booting = False
        self.record_event("ready")
        self._autostart()

    def _autostart(self) -> None:
        """DIP switch 2 bit 8 (§3.1.2): start a valid program after power-on, unless the
        service switch is on."""
        if self.cfg.autostart and not self.cfg.service_switch and self.program.valid:
            try:
                self.run_program(None)
            except SersError as exc:
                self.record_error(exc.errno)

    @property
    def program_state(self) -> int:
        """P0: 1 while a program runs."""
        return 1 if self.interpreter.running else 0

    def _power_off(self) -> None:
        self._cancel_timers()
        self.axis.quick_stop()
        self.logic_alive = False
        self.energized = False
        self.relay = False
        self.motion = None
        self.pos_ok = True
        for n in range(1, 17):
            self.signals.set(f"O{n}", False)
        self.signals.set("READY", False)

    def power_cycle(self, *, wipe: bool = False) -> None:
        self._power_off()
        if wipe:
            self.nvram.wipe()
        self._power_on()

    def fault(self, kind: str, active: bool) -> None:
        """Scenario faults: ``blocked_axis`` (the load stalls the rotor: load-angle error or,
        in SERVO mode, following), ``emergency_stop`` (STOP input opened), ``power`` (supply off)."""
        if kind == "blocked_axis":
            self.signals.set("stall", active)
        elif kind == "emergency_stop":
            self.signals.set("stop", active)
        elif kind == "power":
            if active:
                self._power_off()
            else:
                self._power_on()
        else:
            super().fault(kind, active)

    def close(self) -> None:
        self._cancel_timers()
        self.axis.quick_stop()
        for switch in self._switches:
            switch.cancel()

    def _cancel_timers(self) -> None:
        for timer in self._timers:
            timer.cancel()
        self._timers.clear()
        for watch in self._watches + getattr(self, "_standstill_watches", []):
            watch.cancel()
        self._watches.clear()
        self._standstill_watches = []
        if getattr(self, "_jog_timer", None) is not None:
            self._jog_timer.cancel()
            self._jog_timer = None

    def _reset_serial(self) -> None:
        """Hook for the serial side (framer, selection) at power-on."""

    def spontaneous(self, text: str) -> None:
        """Hook: send an unsolicited message (``@2POS=1``)."""

    # ======================================================================================
    # parameters
    # ======================================================================================
    @property
    def scaling(self) -> Scaling:
        r = self.ram
        return Scaling(int(r[76]), int(r[44]), int(r[160]), float(r[121]), float(r[122]), float(r[123]))

    def _factory_image(self) -> dict[int, Any]:
        """Factory defaults plus the configured EEPROM values, in internal units."""
        image: dict[int, Any] = {}
        for number, pdef in PARAMETERS.items():
            if pdef.default is not None:
                image[number] = pdef.default
        image[1010] = CURRENT_MAX_MA[self.cfg.current_class] // 2
        user: dict[int, Any] = {}
        for key, value in self.cfg.params.items():
            pdef = _lookup(str(key))
            user[pdef.number] = value
        for number in WEIGHTING_PARAMS:
            if number in user:
                image[number] = user[number]
        scaling = Scaling(int(image[76]), int(image[44]), int(image[160]), image[121], image[122], image[123])
        for number, pdef in PARAMETERS.items():
            value = user.get(number, image.get(number))
            if value is None:
                continue
            if pdef.kind in WEIGHTED:
                value = scaling.to_internal(pdef.kind, float(value))
            image[number] = value
        return image

    def _load_parameters(self) -> None:
        self.ram = self._factory_image()
        stored = self.nvram.get("params")
        if stored and not self.eeprom_checksum_error:
            for key, value in stored.items():
                self.ram[int(key)] = value
        # not stored: power-on values (spec §4.1 step 4)
        self.ram.update({1110: 1, 1035: 1, 1: 0, 1047: 0, 1164: 0, 1165: 0, 1118: 0})
        for n in (100, 101, 102, 1101, 1102, 1103):
            self.ram[n] = 0
        extra = self.nvram.get("registers") or {}
        for n in (47, 1080, 1081, 1082, 1083, 1084, 1085):
            self.ram[n] = extra.get(str(n), 0)

    def psave(self) -> None:
        """P1004=2: RAM parameters → EEPROM (W and R0..R5 only with P1117=1)."""
        data = {str(n): self.ram[n] for n, pdef in PARAMETERS.items() if pdef.saved and n in self.ram}
        self.nvram.put("params", data)
        self.eeprom_checksum_error = False
        if self.ram.get(1117):
            self.save_registers()

    def save_registers(self) -> None:
        """P1004=5: R0..R5 and W."""
        self.nvram.put("registers", {str(n): self.ram[n] for n in (47, 1080, 1081, 1082, 1083, 1084, 1085)})

    def factory_defaults(self) -> None:
        """P1004=3: EEPROM and RAM parameters back to factory defaults."""
        self.nvram.delete("params")
        self.nvram.delete("registers")
        keep = {n: self.ram[n] for n in (47, 1080, 1081, 1082, 1083, 1084, 1085)}
        self.ram.update(self._factory_image())
        self.ram.update(keep)
        self.eeprom_checksum_error = False

    def possave(self) -> None:
        """P1004=4: actual position P51 → EEPROM, restored at the next power-on."""
        self.nvram.put("position", self.p51_inc())

    # -- reading ---------------------------------------------------------------------------
    def p51_inc(self) -> float:
        return self.axis.position() - self.offset

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
        value = self.ram.get(number, 0)
        if pdef.kind in WEIGHTED:
            scaling = self.scaling
            return quantize(scaling.from_internal(pdef.kind, float(value)), scaling.decimals(pdef.kind))
        return value

    def _special_read(self, n: int) -> float | None:  # noqa: C901 - one line per parameter
        if n == 0:
            return 2 if self.program_editing else self.program_state
        if n == 11:
            return self.errors
        if n == 12:
            return self.warnings
        if n == 51:
            scaling = self.scaling
            return quantize(scaling.inc_to_pos(round(self.p51_inc())), scaling.pos_decimals)
        if n == 134:
            return 7 if self.energized else 0
        if n == 336:
            return int(self.pos_ok)
        if n == 403:
            return 0 if self.homed else 3
        if n == 1013:
            return self.status_word()
        if n == 1015:
            return int(self.axis.phase() in ("accel", "decel"))
        if n == 1016:
            return int(self.axis.phase() == "const")
        if n == 1042:
            return int(self._outside_soft_limits())
        if n == 1046:
            return self.adc()
        if n == 1050:
            return self.cfg.address
        if n == 1122:
            program = getattr(self, "program", None)
            return program.free_words() if program is not None else 1024
        if n == 1133:
            return self.firmware
        if n == 1137:
            return self.errno
        if n == 1300:
            return self.inputs_byte(1)
        if n == 1301:
            return self.inputs_byte(9) if "IO" in self.cfg.options else 0
        if 1201 <= n <= 1216:
            return int(self.signals.get(f"O{n - 1200}"))
        if n == 1123:
            return int(self.poly.slot_free)
        if n in (1124, 1146):
            window = float(self.ram.get(1055 if n == 1124 else 1145, 1)) * 0.002
            measuring = int(self.ram.get(1053, 0)) in (9, 10) if n == 1124 else int(self.ram.get(1143, 0)) == 5
            return round(float(self.signals.get("pulse_frequency")) * window) if measuring else 0
        if n == 1057:
            return round(max(self.max_load_angle, abs(self.axis.position() - self.encoder_position())))
        return None

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
        if not self._reference_active():
            word |= 8
        if not s.get("service_ext"):
            word |= 128
        return word

    def adc(self) -> float:
        """P1046 (spec G-ADC): fraction of the range above the P1148 offset, 10-bit quantised."""
        volts = max(0.0, min(5.0, float(self.signals.get("adc_volts"))))
        hysteresis = int(self.ram.get(1135, 7))
        bits = max(1, 10 - int(math.log2(hysteresis + 1)))
        raw = round(volts / 5 * 1023)
        raw = (raw >> (10 - bits)) << (10 - bits)
        volts = raw / 1023 * 5
        offset = int(self.ram.get(1148, 0)) * 5 / 255
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
            self.ram[1] = "*"
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
        if pdef.kind in WEIGHTED:
            internal = self.scaling.to_internal(pdef.kind, float(value))
            self.ram[number] = internal
        else:
            self.ram[number] = _as_number(value, pdef)
        if 1201 <= number <= 1216:
            self.signals.set(f"O{number - 1200}", bool(value))
        self._after_write(number)

    def _check_range(self, pdef: ParamDef, value: float) -> None:
        if pdef.choices is not None and value not in pdef.choices:
            raise SersError(3)
        if pdef.kind == "velocity":
            rpm = self.scaling.vel_to_incps(float(value)) * 60 / INC_PER_REV
            if rpm <= 0 and pdef.number == 91:
                raise SersError(pdef.too_small_errno)
            if rpm > 10000:
                raise SersError(pdef.too_large_errno)
            if rpm < 0:
                raise SersError(pdef.too_small_errno)
            return
        if pdef.kind == "acceleration":
            rads = self.scaling.acc_to_incps2(float(value)) * 2 * math.pi / INC_PER_REV
            if rads > 100000:
                raise SersError(pdef.too_large_errno)
            if rads < (2 if pdef.number in (138, 1096) else 0):
                raise SersError(pdef.too_small_errno)
            return
        if pdef.kind == "position":
            lo, hi = self.scaling.pos_range()
            if value > hi:
                raise SersError(pdef.too_large_errno)
            if value < lo:
                raise SersError(pdef.too_small_errno)
            return
        if pdef.maximum is not None and value > pdef.maximum:
            raise SersError(pdef.too_large_errno)
        if pdef.minimum is not None and value < pdef.minimum:
            raise SersError(pdef.too_small_errno)

    def _special_writes(self) -> dict[int, Callable[[float], None]]:
        return {
            0: self._write_p0,
            11: self._write_p11,
            12: self._write_p12,
            47: self._write_w,
            51: self._write_p51,
            134: lambda v: self.switch_on() if v == 7 else self.switch_off() if v == 0 else _raise(3),
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
            self._update_outputs()

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

    def continue_positioning(self) -> None:
        """P1033=1: a program stopped during ``E`` continues the interrupted move."""
        if self._setpoint is None:
            return
        here = self.axis.position()
        direction = (self._setpoint > here) - (self._setpoint < here)
        self._motion_checks(direction)
        if direction == 0:
            self.interpreter.on_motion_end()
            return
        self._speed = float(self.ram[91])
        self._accel = float(self.ram[138])
        self._target_physical = self._setpoint
        self._begin_motion("position", self._accel)
        self._legs = [(self._setpoint, self._speed)]
        self._next_leg()
        self._arm_position_watches()

    def on_program_state(self) -> None:
        """The program started or stopped: outputs (P1126) follow."""
        self._update_outputs()

    def on_program_end(self) -> None:
        """After a program: the event dispatcher (P1098) and a level start (P1023=1) may
        start the next one."""
        if not self.logic_alive or self.interpreter.running:
            return
        events = int(self.ram.get(1098, 0))
        for n in sorted(self.interpreter.pending_events):
            self.interpreter.pending_events.discard(n)
            if events & (1 << (n - 1)) and self.signals.get(f"I{n}"):
                self._start_subroutine(n)
                return
        if self._functions_enabled(128) and int(self.ram.get(1023, 0)) == 1 and self.signals.get("I8"):
            self._clock_start = self.clock.call_later(self.interpreter.cycle, self._start_input)

    def report_program_error(self, errno: int, detail: str) -> None:
        """A program error is recorded in P12/P1137; nothing is sent (G-FAULTMSG)."""

    def _write_poly(self, number: int, value: float) -> None:
        """WP/WRP/WAP/WPT/WRPT/WAPT (P1111–P1116): a polynomial segment, closed by E."""
        self._check_range(PARAMETERS[number], value)
        self.poly.define(number, self.scaling.pos_to_inc(float(value)))

    def motion_checks_for(self, target: float) -> None:
        here = self.axis.position()
        self._motion_checks((target > here) - (target < here))

    def begin_polynomial(self) -> None:
        self._speed = float(self.ram[91])
        self._accel = float(self.ram[138])
        self._begin_motion("poly", self._accel)
        self._arm_position_watches()

    def polynomial_finished(self) -> None:
        if self.motion is not None:
            self._motion_finished()
            if self.ram.get(1121):
                self.spontaneous(f"@{self.cfg.address}POS=1")

    def _write_opcode(self, value: float) -> None:
        """P1099 (§4.8.6.16): execute a program opcode, e.g. 62213 (0xF305) = ``RUN 5``,
        63235 (0xF703) = ``E``.  Only the opcodes the manual documents are known."""
        code = int(value)
        if code >> 8 == 0xF3:
            self.run_program(code & 0xFF or None)
        elif code == 0xF703:
            self.start_positioning()
        elif code >> 8 == 0xF7:
            raise SersError(77)
        else:
            raise SersError(75)

    def _write_p11(self, value: float) -> None:
        if value != 0:
            raise SersError(3)
        if self.errors & OVERTEMP and self.signals.get("heatsink_temperature") >= 85:
            raise SersError(3)
        if self.errors & UNDERVOLTAGE and self.signals.get("supply_voltage") < self.thresholds[2]:
            raise SersError(3)
        if self.errors & SHORT and (self.signals.get("short_circuit") or not self._stop_cycled):
            raise SersError(3)
        if self.errors & STEP_LOSS:
            self._resync_to_encoder()
        self.errors = 0
        self.ram[1118] = 0
        self.energized = False
        self.relay = False
        self._update_outputs()

    def _write_p12(self, value: float) -> None:
        if value != 0:
            raise SersError(3)
        if self.warnings & STEP_LOSS:
            self._resync_to_encoder()
        self.warnings = 0
        self._check_supply()
        self._check_temperature()
        self._update_outputs()

    def _write_p51(self, value: float) -> None:
        self._check_range(PARAMETERS[51], value)
        self.offset = self.axis.position() - self.scaling.pos_to_inc(float(value))

    def _write_p1004(self, value: float) -> None:
        actions = {2: self.psave, 3: self.factory_defaults, 4: self.possave, 5: self.save_registers}
        action = actions.get(int(value)) if value == int(value) else None
        if action is None:
            raise SersError(82)
        action()

    def _write_p1014(self, value: float) -> None:
        if value not in (0, 1, 2, 3):
            raise SersError(80)
        if self.motion is not None:
            raise SersError(93)
        self.ram[1014] = int(value)

    def _write_p1031(self, value: float) -> None:
        commands = {1: "LS", 2: "RS", 4: "LF", 8: "RF"}
        if value == 16:
            self.home()
        elif value in commands:
            self.jog(commands[int(value)])
        else:
            raise SersError(3)

    def _write_p1043(self, value: float) -> None:
        if value == 0:
            return
        if value == 1:
            self.pos0()
        elif value in (2, 3):
            self.posr(force=value == 3)
        else:
            raise SersError(3)

    def _write_soft_limit(self, number: int, value: float) -> None:
        self._check_range(PARAMETERS[number], value)
        internal = self.scaling.pos_to_inc(float(value))
        lower = internal if number == 1040 else self.ram[1040]
        upper = internal if number == 1041 else self.ram[1041]
        if lower > upper:
            raise SersError(95)
        self.ram[number] = internal

    def _write_w_mode(self, value: float, mode: int) -> None:
        if self.motion is not None and self.ram[1014] != mode:
            raise SersError(93)
        self._write_w(value)
        self.ram[1014] = mode

    def _write_w(self, value: float) -> None:
        """W (P47): free while standing; while moving only in the constant phase (§4.6.6)."""
        self._check_range(PARAMETERS[47], value)
        new = self.scaling.pos_to_inc(float(value))
        if self.motion != "position":
            self.ram[47] = new
            return
        if self.axis.phase() != "const":
            raise SersError(81)
        mode = self.ram[1014]
        current_target = self._target_physical
        target = current_target + new if mode in (0, 1, 3) else new + self.offset
        position = self.axis.position()
        direction = 1 if self.axis.velocity() > 0 else -1
        remaining = (target - position) * direction
        if remaining < self.axis.stopping_distance(self._accel, self.ramp_profile()):
            self.ram[47] = new
            raise SersError(87)
        self.ram[47] = new
        self._target_physical = target
        self._w_updated = True
        self._legs = []
        self.axis.move_to(target, self._speed, self._accel, on_done=self._positioning_done, profile=self.ramp_profile())
        self._arm_position_watches()

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
        return self.param_value(self.address_number(a))

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
            result = _compare(value, cond.op, right)
        if counter and counters:  # G-COUNTER: compare the old value, then decrement (saturating at 0)
            number = ALIASES[str(left.ref)]
            old = int(self.ram.get(number, 0))
            self.ram[number] = old - 1 if (old > 0 or (number == 100 and self.ram[1014] == 3)) else 0
        return result != cond.negate

    def arithmetic(self, op: str, operand: st.Operand | None) -> None:
        """X := X (op) operand, left to right (§4.6.10, spec G-ARITH): 3 decimals, ±2147483.647."""
        x = float(self.ram.get(1047, 0))
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
                    self.warn(256)
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
            self.warn(256)
            raise SersError(98)
        if value < -2147483.647:
            self.warn(256)
            raise SersError(99)
        self.ram[1047] = quantize(value, 3)

    # ======================================================================================
    # statements
    # ======================================================================================
    def execute(self, stmt: st.Statement) -> None:  # noqa: C901 - dispatch on statement type
        if isinstance(stmt, st.Assign):
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
            return
        if isinstance(stmt, st.Arith):
            self.arithmetic(stmt.op, stmt.operand)
            return
        if isinstance(stmt, st.Unary):
            self.arithmetic(stmt.op, None)
            return
        if isinstance(stmt, st.Jog):
            self.jog(stmt.name, stmt.until)
            return
        if isinstance(stmt, st.Command):
            self._command(stmt.name)
            return
        if isinstance(stmt, st.Text):
            raise SersError(16)
        if isinstance(stmt, st.Run):
            self.run_program(stmt.label)
            return
        if isinstance(stmt, st.Change):
            raise SersError(22)
        if isinstance(stmt, st.Trace):
            self.trace_mode = True
            self.interpreter.trace_step()
            return
        if isinstance(stmt, st.Goto):
            raise SersError(54)
        if isinstance(stmt, st.Wait | st.Label | st.Comment):
            return
        raise SersError(21)

    def master_target(self) -> int | str | None:
        """In a master (address 0) after ``Z=n`` (P1): the slave statements go to."""
        if self.cfg.address != 0:
            return None
        target = self.ram.get(1, 0)
        if target == "*":
            return "*"
        return int(target) if target else None

    def program_statement(self, stmt: st.Statement) -> str | None:
        """Execute a statement of a running program; returns what the program must wait for
        (``position``: until the drive stands, §4.6.6) or None to go on at once."""
        if isinstance(stmt, st.Command) and stmt.name == "E" and self.poly.definition is not None:
            last = self.poly.definition[2]
            started = self.poly.execute() == "started"
            master_goes_on = self.cfg.address == 0 and int(self.ram.get(1110, 1)) == 0
            if last:
                return None if (master_goes_on or self.motion is None) else "position"
            return None if started else "segment"
        if isinstance(stmt, st.Command) and stmt.name in ("E", "H", "POS0", "POSR"):
            self.execute(stmt)
            if self.motion is None:
                return None
            if stmt.name == "E" and self.cfg.address == 0 and int(self.ram.get(1110, 1)) == 0:
                return None  # master with P1110=0 goes on while it moves (§4.8.5.5)
            return "position"
        if isinstance(stmt, st.Jog):
            self.jog(stmt.name, stmt.until, serial=False)
            # with ':' the statement lasts until standstill; without, it just starts (G-JOGPROG)
            return "position" if stmt.until is not None and self.motion is not None else None
        self.execute(stmt)
        return None

    def _command(self, name: str) -> None:  # noqa: C901
        program = getattr(self, "program", None)
        if name == "E":
            self.start_positioning()
        elif name == "H":
            self.home()
        elif name == "S":
            self.interpreter.stop()
            self.stop_motion()
        elif name == "ON":
            self.switch_on()
        elif name == "OFF":
            self.switch_off()
        elif name == "PSAVE":
            self.psave()
        elif name == "POSSAVE":
            self.possave()
        elif name == "POS0":
            self.pos0()
        elif name == "POSR":
            self.posr(force=False)
        elif name == "NEW":
            self.new_program()
        elif name == "PGM":
            if self.program_state == 1:
                raise SersError(44)
            program.edit()  # type: ignore[union-attr]
        elif name == "QUIT":
            if not self.program_editing:
                raise SersError(22)
            program.quit()  # type: ignore[union-attr]
        elif name == "DEL":
            raise SersError(22 if not self.program_editing else 21)
        elif name == "TRON":
            self.trace_mode = True
        elif name == "TROFF":
            self.trace_mode = False
            if self.interpreter.running and self.interpreter.waiting is None:
                self.interpreter._schedule(self.interpreter.cycle)
        elif name in ("PE", "RETURN"):
            if self.program_state != 1:
                raise SersError(54)
        else:
            raise SersError(21)

    # ======================================================================================
    # motor power and errors
    # ======================================================================================
    def switch_on(self) -> None:
        """ON = P134=7 (§4.8.2.2): phases energised, ready relay closed."""
        if self.errors or self.eeprom_checksum_error:
            raise SersError(79)
        self.energized = True
        self.relay = True
        if self.ram.get(1152) == 1 and not int(self.ram.get(147, 0)) & 256 and not self.servo_calibrated:
            # SERVO: the load-angle zero is taken 100 ms after ON (§4.8.6.7, P147 bit 8 = 0)
            self._timers.append(self.clock.call_later(0.1, self._servo_calibrate))
        self._update_outputs()

    # -- SERVO mode (option E50/C, P1152=1; §4.8.6.7, spec §5.10) ---------------------------
    def _servo_calibrate(self) -> None:
        if self.energized:
            self.servo_calibrated = True

    def _servo_check(self) -> None:
        """Positioning or jogging before the load angle is calibrated: warning 2048."""
        if self.ram.get(1152) == 1 and not self.servo_calibrated:
            self.warn(2048)

    def _servo_overload(self, overloaded: bool) -> None:
        """Under overload the SERVO drive loses no steps: the stator field holds at the rotor
        and the move resumes when the load goes away, at P1163 if P1162=1 (catch-up), else at
        V (arriving later).  P1160 signals the overload on an output."""
        self.servo_overload = overloaded
        sel = int(self.ram.get(1160, 0))
        if sel:
            port, value = abs(sel) if abs(sel) <= 4 else abs(sel) - 4, sel > 0
            if overloaded or abs(sel) > 4:
                self.signals.set(f"O{port}", value if overloaded else not value)
        if overloaded:
            if self.motion == "position":
                self.axis.quick_stop()
                self._servo_resume = True
            return
        if getattr(self, "_servo_resume", False) and self.motion == "position":
            self._servo_resume = False
            speed = self._speed
            if self.ram.get(1162) == 1:
                speed = max(speed, float(self.ram.get(1163, speed)))
            self.axis.move_to(self._target_physical, speed, self._accel, on_done=self._positioning_done)

    def switch_off(self) -> None:
        """OFF = P134=0: torque off at once (spec G-OFFMOVE), relay open."""
        if self.motion is not None:
            self._end_motion(quick=True)
        self.energized = False
        self.relay = False
        self._update_outputs()

    def drive_error(self, bit: int, immediate: bool = False) -> None:
        """Set a P11 bit: brake with P1030, open the relay, 50 ms later switch the phases off
        (§2.1.3, §2.1.4); short circuit and U < U_L switch off at once."""
        first = not self.errors & bit
        if first:
            self.record_event("error")
        self.errors |= bit
        self.poly.cancel()
        if first:
            self.interpreter.on_drive_error()
        self._homing = None
        if immediate:
            if self.motion is not None:
                self._end_motion(quick=True)
            self.energized = False
            self.relay = False
            self._update_outputs()
            return
        if not first and not self.energized:
            return

        def relay_open() -> None:
            self.relay = False
            self._update_outputs()
            self._timers.append(self.clock.call_later(0.05, self._phases_off))

        if self.motion is not None and self.axis.moving:
            self._stop_decel = self.ram[1030]
            self.motion = "error-stop"
            self._cancel_jog_timer()
            self.axis.stop(self.ram[1030], on_done=lambda: (self._motion_finished(), relay_open()))
        else:
            relay_open()
        self._update_outputs()

    def _phases_off(self) -> None:
        if self.errors and not (self.errors & STEP_LOSS and self.ram.get(1029) == 3):
            self.energized = False
            self._update_outputs()

    def warn(self, bit: int) -> None:
        self.warnings |= bit
        self._update_outputs()

    def record_error(self, errno: int) -> None:
        """Every error message sets P12 value 16 and P1137 (§4.8.3.1)."""
        self.errno = errno
        self.warn(16)

    # ======================================================================================
    # motion
    # ======================================================================================
    @property
    def moving(self) -> bool:
        return self.motion is not None

    def _motion_checks(self, direction: int) -> None:
        """Refusals in the spec's order (§3.5.3): limit (78), STOP (68), I7 (67), power (79)."""
        if direction > 0 and self.signals.get("limit_right"):
            raise SersError(78)
        if direction < 0 and self.signals.get("limit_left"):
            raise SersError(78)
        if self.signals.get("stop"):
            raise SersError(68)
        if self._i7_stop_active():
            raise SersError(67)
        if not self.energized or self.errors:
            raise SersError(79)

    def start_positioning(self) -> None:
        """E (§4.6.6) with P1014 mode 0 relative, 1 relative-clear, 2 absolute, 3 overflow."""
        if self.poly.definition is not None:
            self.poly.execute()  # E closes a polynomial segment (§4.6.7)
            return
        if self.motion == "position" and self._w_updated:
            self._w_updated = False
            return  # G-EWHILEMOVE: the running move already took the new W
        if self.motion is not None:
            raise SersError(70)
        mode = int(self.ram[1014])
        w = float(self.ram[47])
        p51 = self.p51_inc()
        if mode == 1:
            start, target = 0.0, float(round(w))
        elif mode == 2:
            start, target = p51, float(round(w))
        else:
            start, target = p51, p51 + round(w)  # W in whole increments (§5.1)
        target = self._leave_zero_phase(target)
        direction = (target > start) - (target < start)
        self._motion_checks(direction)
        lo, hi = self.scaling.pos_range()
        target_user = self.scaling.inc_to_pos(target)
        if target_user > hi or target_user < lo:
            self.warn(64)
            raise SersError(85 if target_user > hi else 86)
        if mode == 1:
            self.offset = self.axis.position()
        elif target == p51:
            return  # already there: nothing moves, POS stays 1
        self._speed = float(self.ram[91])
        self._accel = float(self.ram[138])
        self._target_physical = target + self.offset
        self._servo_check()
        self._begin_motion("position", self._accel)
        self._setpoint = self._target_physical
        self._legs = self._backlash_legs(p51 + self.offset, self._target_physical)
        self._next_leg()
        self._arm_position_watches()

    def _backlash_legs(self, start: float, target: float) -> list[tuple[float, float]]:
        """Backlash compensation P1037 (§4.8.4.7, spec §5.8 G-BACKLASH): the final approach
        is always made opposite to the homing direction (P147 bit 0), at speed P1003."""
        slack = abs(float(self.ram.get(1037, 0)))
        if not slack or target == start:
            return [(target, self._speed)]
        approach = 1 if int(self.ram.get(147, 0)) & 1 else -1
        creep = float(self.ram[1003])
        direction = 1 if target > start else -1
        if direction == approach:
            if abs(target - start) <= slack:
                return [(target, creep)]
            return [(target - direction * slack, self._speed), (target, creep)]
        return [(start + direction * slack, creep), (target + direction * slack, self._speed), (target, creep)]

    def _next_leg(self) -> None:
        target, speed = self._legs.pop(0)
        done = self._next_leg if self._legs else self._positioning_done
        self.axis.move_to(target, speed, self._accel, on_done=done, profile=self.ramp_profile())

    def ramp_profile(self) -> RampProfile | None:
        """P1032 ramp shape with the sections P1005–P1008 (§4.8.4.4, spec §5.2)."""
        r = self.ram
        shape = "sine" if int(r.get(1032, 0)) == 1 else "linear"
        fractions = [float(r.get(n, 100)) / 100 for n in (1007, 1005, 1008, 1006)]
        if shape == "linear" and all(f == 1.0 for f in fractions):
            return None
        speed1, accel1, speed2, accel2 = fractions
        return RampProfile(speed1=speed1, accel1=accel1, speed2=speed2, accel2=accel2, shape=shape)

    def _leave_zero_phase(self, target: float) -> float:
        """P1001 (§4.8.4.2): keep 0.1°/0.2°/0.3° away from multiples of 1.8° (64 increments)."""
        level = int(self.ram.get(1001, 0))
        if not level:
            return target
        step = INC_PER_REV / 200
        keep = level * 0.1 * INC_PER_REV / 360
        nearest = round(target / step) * step
        if abs(target - nearest) < keep - 1e-9:
            return float(round(nearest + (keep if target >= nearest else -keep)))
        return target

    def _positioning_done(self) -> None:
        mode = int(self.ram[1014])
        if mode == 3:
            modulo = float(self.ram.get(103, 0))
            if modulo > 0:
                while self.p51_inc() >= modulo - 1e-6:
                    self.offset += modulo
                    self.ram[100] = int(self.ram.get(100, 0)) + 1
                while self.p51_inc() <= -modulo + 1e-6:
                    self.offset -= modulo
                    self.ram[100] = int(self.ram.get(100, 0)) - 1
        self._motion_finished()
        if self.ram.get(1121):
            self.spontaneous(f"@{self.cfg.address}POS=1")

    def _begin_motion(self, kind: str, decel: float) -> None:
        self.record_event("move_start")
        self.motion = kind
        self.pos_ok = False
        self._stop_decel = decel
        self._w_updated = False
        self._update_outputs()

    def _motion_finished(self) -> None:
        was_moving = self.motion is not None
        self.poly.cancel()
        if was_moving:
            self.record_event("move_end")
        self._stopped_at = self.clock.now()
        self.motion = None
        self.pos_ok = True
        self._homing = None
        self._jog_dir = 0
        self._jog_until = None
        self._cancel_jog_timer()
        for watch in self._watches + self._standstill_watches:
            watch.cancel()
        self._watches.clear()
        self._standstill_watches = []
        self._update_outputs()
        if was_moving:
            self.interpreter.on_motion_end()

    def _end_motion(self, quick: bool) -> None:
        if quick:
            self.axis.quick_stop()
            self._motion_finished()
        else:
            self.stop_motion()

    def stop_motion(self) -> None:
        """S (§4.2): decelerate with the active motion's deceleration (spec §5.4)."""
        if self.motion is None or self.motion == "error-stop":
            return
        self._homing = None
        self.poly.cancel()
        self._cancel_jog_timer()
        profile = self.ramp_profile() if self.motion == "position" else None
        self.motion = "stopping"
        self.axis.stop(self._stop_decel, on_done=self._motion_finished, profile=profile)

    # -- jog -------------------------------------------------------------------------------
    def jog(self, name: str, until: st.Condition | None = None, serial: bool = True) -> None:
        """RS/RF/LS/LF (§4.5.1): right = positive; slow P1019, fast P1020, × P108 %."""
        direction = 1 if name[0] == "R" else -1
        self._motion_checks(direction)
        if self.motion not in (None, "jog", "position", "stopping"):
            raise SersError(70)
        speed = float(self.ram[1019 if name[1] == "S" else 1020]) * float(self.ram.get(108, 100)) / 100
        accel = float(self.ram[1018])
        if not (self.motion == "jog" and self._jog_dir == direction and self._jog_speed == speed):
            self._servo_check()
            self._begin_motion("jog", accel)
            self._jog_dir = direction
            self._jog_speed = speed
            self.axis.jog(direction, speed, accel)
            self._arm_position_watches()
        self._jog_until = until
        self._cancel_jog_timer()
        if serial and until is None and self.ram.get(1035, 1) == 1:
            self._jog_timer = self.clock.call_later(0.5, self._jog_timeout)
        if until is not None and self.evaluate(until):
            self._until_reached()

    def _jog_timeout(self) -> None:
        self._jog_timer = None
        if self.motion == "jog":
            self.stop_motion()

    def _cancel_jog_timer(self) -> None:
        if self._jog_timer is not None:
            self._jog_timer.cancel()
            self._jog_timer = None

    def _until_reached(self) -> None:
        """':' event (§4.6.9): brake with P1018, or travel the overrun distance P1039 first."""
        self._jog_until = None
        overrun = float(self.ram.get(1039, 0))
        if overrun:
            target = self.axis.position() + self._jog_dir * abs(overrun)
            self.motion = "stopping"
            self.axis.move_to(target, abs(self.axis.velocity()), float(self.ram[1018]), on_done=self._motion_finished)
        else:
            self.stop_motion()

    def _check_until(self) -> None:
        self.interpreter.poke()
        self._check_jog_until()

    def _check_jog_until(self) -> None:
        if self._jog_until is not None and self.motion == "jog" and self.evaluate(self._jog_until):
            self._until_reached()

    # -- homing ----------------------------------------------------------------------------
    def home(self, serial: bool = True) -> None:
        """H (§4.8.4.5, spec §5.5): seek the reference edge at P41, creep back at P1003.

        P147 bit 0 direction, bit 1 limit switch as reference, bit 2 then the next electrical
        zero, bit 5 centre of the switch, bit 6 encoder zero pulse instead of the switch, bit 7
        switch, then zero pulse, then electrical zero.
        """
        if self.motion is not None:
            raise SersError(70)
        p147 = int(self.ram.get(147, 0))
        direction = -1 if p147 & 1 else 1
        if p147 & 2:
            signal = "limit_left" if direction < 0 else "limit_right"
            if self.signals.get("stop"):
                raise SersError(68)
            if not self.energized or self.errors & ~LIMIT:
                raise SersError(79)
        else:
            signal = "index" if p147 & 64 and not p147 & 128 else "reference"
            self._motion_checks(0)
        accel = float(self.ram[42])
        self._homing = {"signal": signal, "direction": direction, "phase": "seek", "p147": p147}
        self._begin_motion("home", accel)
        if signal == "index":
            self._watches.append(self.axis.watch_index(self._on_index))
        if signal != "index" and self._homing_signal_active():
            self._creep()
        else:
            speed = float(self.ram[41]) * float(self.ram.get(108, 100)) / 100
            self.axis.jog(direction, speed, accel)
            self._arm_position_watches(keep=True)

    def _homing_signal_active(self) -> bool:
        assert self._homing is not None
        if self._homing["signal"] == "reference":
            return self._reference_active()
        return bool(self.signals.get(self._homing["signal"]))

    def _creep(self) -> None:
        assert self._homing is not None
        self._homing["phase"] = "creep"
        self.axis.jog(-self._homing["direction"], float(self.ram[1003]), float(self.ram[42]))

    def _on_index(self, _direction: int) -> None:
        """Encoder zero pulse (once per motor revolution) during homing with P147 bit 6/7."""
        homing = self._homing
        if homing is None:
            return
        if homing["signal"] == "index":
            self._homing_edge(homing["phase"] == "seek")
        elif homing["phase"] == "to_index":
            homing["phase"] = "edge"
            self.axis.quick_stop()
            self._electrical_reset()

    def _homing_edge(self, active: bool) -> None:
        homing = self._homing
        if homing is None:
            return
        phase, p147 = homing["phase"], homing["p147"]
        if phase == "seek" and active:
            homing["phase"] = "braking"
            self.axis.stop(float(self.ram[42]), on_done=self._creep)
        elif phase == "creep" and not active:
            # G-HOME: at creep speed the drive stops exactly at the falling edge
            if p147 & 32 and homing["signal"] == "reference":
                homing["phase"] = "measure"
                self.axis.quick_stop()
                homing["first_edge"] = self.axis.position()
                self.axis.jog(homing["direction"], float(self.ram[1003]), float(self.ram[42]))
            elif p147 & 128:
                homing["phase"] = "to_index"  # keep creeping to the next zero pulse
                self._watches.append(self.axis.watch_index(self._on_index))
            else:
                homing["phase"] = "edge"
                self.axis.quick_stop()
                self._electrical_reset()
        elif phase == "measure" and not active:
            homing["phase"] = "centre"
            self.axis.quick_stop()
            centre = (homing["first_edge"] + self.axis.position()) / 2
            self.axis.move_to(centre, float(self.ram[1003]), float(self.ram[42]), on_done=self._homing_done)

    def _electrical_reset(self) -> None:
        """P147 bit 2/7: move on to the next electrical zero (every 256 increments)."""
        homing = self._homing
        assert homing is not None
        if not homing["p147"] & (4 | 128):
            self._homing_done()
            return
        here = self.axis.position()
        if -homing["direction"] > 0:
            target = math.ceil(here / ELECTRICAL_PERIOD - 1e-9) * ELECTRICAL_PERIOD
        else:
            target = math.floor(here / ELECTRICAL_PERIOD + 1e-9) * ELECTRICAL_PERIOD
        homing["phase"] = "reset"
        self.axis.move_to(target, float(self.ram[1003]), float(self.ram[42]), on_done=self._homing_done)

    def _homing_done(self) -> None:
        self.offset = self.axis.position()
        self.homed = True
        self._motion_finished()
        if self.ram.get(1121):
            self.spontaneous(f"@{self.cfg.address}POS=1")

    def _reference_active(self) -> bool:
        selector = int(self.ram.get(1130, 0)) if self.ram else 0
        if selector:
            return bool(self.signals.get(f"I{selector}"))
        return bool(self.signals.get("reference"))

    def _on_reference(self, name: str, old: Any, new: Any) -> None:
        if self._homing is not None and self._homing["signal"] == "reference" and not self.ram.get(1130):
            self._homing_edge(bool(new))
        self._check_until()

    # -- POS0 / POSR -------------------------------------------------------------------------
    def pos0(self) -> None:
        """POS0 (§4.8.4.2, spec §5.13): go to the nearest phase zero, then P51 := 0.
        During a polynomial profile it ends polynomial mode instead (§4.6.7)."""
        if self.motion == "poly":
            self.stop_motion()
            return
        if self.motion is not None:
            raise SersError(70)
        p51 = self.p51_inc()
        target = round(p51 / ELECTRICAL_PERIOD) * ELECTRICAL_PERIOD
        direction = (target > p51) - (target < p51)
        self._motion_checks(direction)
        self._begin_motion("pos0", float(self.ram[42]))

        def done() -> None:
            self.offset = self.axis.position()
            self._motion_finished()

        self.axis.move_to(target + self.offset, float(self.ram[41]), float(self.ram[42]), on_done=done)

    def posr(self, force: bool) -> None:
        """POSR (§4.8.4.2, spec §5.9): after a step loss, follow the motor's real position
        (encoder) and travel at P41 to the setpoint of the interrupted positioning.  Only with
        P11/P12 value 32, unless P1043=3."""
        if self.motion == "poly":
            self.stop_motion()  # POSR also ends polynomial mode (§4.6.7)
            return
        stepped = self.errors & STEP_LOSS or self.warnings & STEP_LOSS
        if not force and not stepped:
            raise SersError(3)
        if self.motion is not None:
            raise SersError(70)
        if self.errors & STEP_LOSS:
            self.errors &= ~STEP_LOSS
        self.warnings &= ~STEP_LOSS
        self._resync_to_encoder()
        target = self._setpoint if self._setpoint is not None else float(self.ram[47]) + self.offset
        direction = (target > self.axis.position()) - (target < self.axis.position())
        self._motion_checks(direction)
        self._begin_motion("posr", float(self.ram[42]))
        self.axis.move_to(target, float(self.ram[41]), float(self.ram[42]), on_done=self._posr_done)
        self._arm_position_watches()

    def _posr_done(self) -> None:
        if int(self.ram.get(1140, 0)) & 2:
            self._posr_attempts = 0
        self._motion_finished()

    # -- pulse input, hand-wheel, electronic gear (§3.4, §4.8.6.6, spec §5.9) ---------------
    def pulses(self, count: int) -> None:
        """``count`` pulses (signed; 4× evaluated encoder counts) arrive at I3/I4 or ENC.

        With P1053 = 1/2/3 (I3/I4) or 5/6/7 (ENC), or P1143 = 1/2/3, the motor follows
        by count × P1054 × 64 increments, limited by A and V (hand-wheel, electric shaft)."""
        mode, alt = int(self.ram.get(1053, 0)), int(self.ram.get(1143, 0))
        if mode in (1, 2, 3, 5, 6, 7):
            weight, counter = float(self.ram.get(1054, 1)), 1119
        elif alt in (1, 2, 3):
            weight, counter = float(self.ram.get(1144, 1)), 1120
        else:
            return
        if mode in (5, 6, 7) and "E50" not in self.cfg.options:
            return
        self.ram[counter] = int(self.ram.get(counter, 0)) + count
        if not self.energized or self.errors or self.motion not in (None, "follow"):
            return
        step = count * weight * INC_PER_REV / 200
        base = self._follow_target if self.motion == "follow" else self.axis.position()
        target = base + step
        direction = (step > 0) - (step < 0)
        try:
            self._motion_checks(direction)
        except SersError:
            return  # pulses toward a blocked direction are ignored (P1094=0)
        self._follow_target = target
        if self.motion is None:
            self._begin_motion("follow", float(self.ram[138]))
        self.axis.move_to(target, float(self.ram[91]), float(self.ram[138]), on_done=self._motion_finished)

    # -- load angle / step-loss monitoring (§4.8.6.6, spec §5.9) ----------------------------
    def encoder_position(self) -> float:
        """Where the rotor really is (increments): the stator field minus the steps lost."""
        if self._stall_rotor is not None:
            return self._stall_rotor
        return self.axis.position() - self.lost

    def _monitoring(self) -> bool:
        mode = int(self.ram.get(1053, 0))
        encoder = mode == 4 or (mode == 8 and "E50" in self.cfg.options)
        return encoder and int(self.ram.get(1029, 0)) != 0

    def _on_stall(self, name: str, old: Any, new: Any) -> None:
        if self.ram.get(1152) == 1:
            self._servo_overload(bool(new))
            return
        if new:
            self._stall_rotor = self.axis.position() - self.lost
            self._arm_load_watch()
        elif self._stall_rotor is not None:
            self.lost = self.axis.position() - self._stall_rotor
            self._stall_rotor = None
            for watch in self._load_watches:
                watch.cancel()
            self._load_watches = []

    def _arm_load_watch(self) -> None:
        for watch in self._load_watches:
            watch.cancel()
        self._load_watches = []
        if self._stall_rotor is None or not self._monitoring():
            return
        window = float(self.ram.get(1002, 255))
        rotor = self._stall_rotor
        for where in (rotor + window, rotor - window):
            self._load_watches.append(self.axis.watch(where, lambda _d: self._step_loss()))

    def _step_loss(self) -> None:
        """The load angle exceeded P1002: P1029 1 = drive error, 2 = warning, 3 = error, motor on."""
        self.max_load_angle = max(self.max_load_angle, abs(self.axis.position() - self.encoder_position()))
        reaction = int(self.ram.get(1029, 0))
        if reaction == 2:
            self.warn(STEP_LOSS)
            self.stop_motion()
        elif reaction in (1, 3):
            self.drive_error(STEP_LOSS)
        retries = int(self.ram.get(1138, 0))
        if retries and self._posr_attempts < retries:
            self._posr_attempts += 1
            delay = float(self.ram.get(1139, 1.0)) * 0.1
            self.pos_ok = False
            self._timers.append(self.clock.call_later(delay, self._auto_posr))

    def _auto_posr(self) -> None:
        """P1138/P1139: automatic POSR after a step loss."""
        if self.motion is not None:
            self._timers.append(self.clock.call_later(0.01, self._auto_posr))
            return
        self.errors &= ~STEP_LOSS
        if not self.errors:
            self.energized = self.relay = True
        try:
            self.posr(force=True)
        except SersError as exc:
            self.record_error(exc.errno)

    def _resync_to_encoder(self) -> None:
        """Clearing a step loss: P51 takes the encoder's position (§4.8.6.6)."""
        if self.axis.moving:
            return
        rotor = self.encoder_position()
        if self._stall_rotor is None:
            self.lost = 0.0
        if rotor != self.axis.position():
            self.axis.set_position(rotor)
            if self._stall_rotor is not None:
                self._arm_load_watch()

    # -- software limits and compare positions (§4.8.6.12, §4.8.1.2) ------------------------
    def _soft_limits(self) -> tuple[float, float] | None:
        lower, upper = float(self.ram.get(1040, 0)), float(self.ram.get(1041, 0))
        if lower < upper:
            return lower, upper
        return None

    def _outside_soft_limits(self) -> bool:
        limits = self._soft_limits()
        if limits is None:
            return False
        p51 = self.p51_inc()
        return p51 < limits[0] or p51 > limits[1]

    def _arm_position_watches(self, keep: bool = False) -> None:
        """Software limits, compare positions and standstill monitoring for a new motion."""
        if not keep:
            for watch in self._watches:
                watch.cancel()
            self._watches.clear()
        limits = self._soft_limits()
        homing = self.motion == "home" and not int(self.ram.get(147, 0)) & 8
        if limits is not None and not homing:
            lower, upper = (x + self.offset for x in limits)
            velocity_sign = _sign(self.axis.final_position() - self.axis.position())
            here = self.axis.position()
            if (here > upper and velocity_sign > 0) or (here < lower and velocity_sign < 0):
                self._timers.append(self.clock.call_later(0, self._soft_limit_hit))
            self._watches.append(self.axis.watch(upper + 1e-9, lambda d: d > 0 and self._soft_limit_hit()))
            self._watches.append(self.axis.watch(lower - 1e-9, lambda d: d < 0 and self._soft_limit_hit()))
        self._arm_standstill_monitor()
        for pos_param, action_param in ((1024, 1025), (1026, 1027)):
            action = int(self.ram.get(action_param, 0))
            if action:
                where = float(self.ram.get(pos_param, 0)) + self.offset
                self._watches.append(self.axis.watch(where, lambda _d, a=action: self._compare_action(a)))

    def _arm_standstill_monitor(self) -> None:
        """P1044/P1045 (§4.8.6.8, spec §5.7): while moving, an edge on input P1045 must come
        at least every P1044; the distance counts from the motion start and from each edge."""
        for watch in self._standstill_watches:
            watch.cancel()
        self._standstill_watches = []
        distance = abs(float(self.ram.get(1044, 0)))
        if not distance or self.motion is None:
            return
        here = self.axis.position()
        for where in (here + distance, here - distance):
            self._standstill_watches.append(self.axis.watch(where, lambda _d: self._standstill_error()))

    def _standstill_error(self) -> None:
        if self.motion is not None and self.motion != "error-stop":
            self.drive_error(STANDSTILL)

    def _soft_limit_hit(self) -> None:
        self.warn(1)
        if self.motion not in (None, "stopping", "error-stop"):
            self.stop_motion()

    def _compare_action(self, action: int) -> None:
        """P1025/P1027: ±1..4 set/clear O1..O4, ±5..7 set/clear M1..M3."""
        value = action > 0
        n = abs(action)
        if n <= 4:
            self.signals.set(f"O{n}", value)
        elif n <= 7:
            self.ram[1100 + n - 4] = int(value)

    # ======================================================================================
    # inputs and faults
    # ======================================================================================
    def _check_limits_at_power_on(self) -> None:
        if self.signals.get("limit_left") or self.signals.get("limit_right"):
            self.errors |= LIMIT

    def _on_limit(self, name: str, old: Any, new: Any) -> None:
        if not self.logic_alive:
            return
        if new:
            homing = self._homing
            if homing is not None and homing["signal"] == name:
                self._homing_edge(True)
                return
            self.drive_error(LIMIT)
        elif self._homing is not None and self._homing["signal"] == name:
            self._homing_edge(False)
        self._check_until()

    def _on_stop_input(self, name: str, old: Any, new: Any) -> None:
        if not new and self._stop_opened:
            self._stop_cycled = True  # opened and closed again: a short may now be cleared
        if new:
            self._stop_opened = True
            self.interpreter.stop()
            if self.motion is not None:
                self.stop_motion()
        self._check_until()

    def _functions_enabled(self, bit: int) -> bool:
        """Manual functions on I1..I7 (§3.1.4, §4.8.1.1 P1021)."""
        service = self.cfg.service_switch or (self.signals.get("service_ext") and self.ram.get(1092))
        if bit == 128:
            return bool(int(self.ram.get(1021, 0)) & 128)
        return bool(service) or bool(int(self.ram.get(1021, 0)) & bit)

    def _i7_stop_active(self) -> bool:
        return bool(self.ram) and self._functions_enabled(64) and bool(self.signals.get("I7"))

    def _on_digital_input(self, name: str, old: Any, new: Any) -> None:
        if not self.logic_alive or self.booting:
            return
        n = int(name[1:])
        bit = 1 << (n - 1)
        monitored = int(self.ram.get(1045, 1)) == n and self.ram.get(1044)
        active_edge = bool(new) != (self.cfg.input_level == "low_active")
        if monitored and active_edge and self.motion is not None:
            self._arm_standstill_monitor()
        if self.ram.get(1130) == n and self._homing is not None and self._homing["signal"] == "reference":
            self._homing_edge(bool(new))
        if self._functions_enabled(bit):
            try:
                self._input_function(n, bool(new))
            except SersError as exc:
                self.record_error(exc.errno)
        elif n == 8 and new and self._functions_enabled(128):
            self._start_input()
        self._event_input(n, bool(new))
        self._check_until()

    def _input_function(self, n: int, active: bool) -> None:
        jogs = {1: "LS", 2: "RS", 3: "LF", 4: "RF"}
        if n in jogs:
            if active:
                if not self.errors:
                    self.energized = self.relay = True
                self.jog(jogs[n], serial=False)
            elif self.motion == "jog":
                self.stop_motion()
        elif n == 5 and active:
            if not self.errors:
                self.energized = self.relay = True
            self.home(serial=False)
        elif n == 6 and active:  # G-INFUNC: rising edge toggles; ON clears P11 and P12
            if self.energized:
                self.switch_off()
            else:
                self.errors = 0
                self.warnings = 0
                self.switch_on()
        elif n == 7 and active:
            self.interpreter.stop()
            if self.motion is not None:
                self.stop_motion()
        elif n == 8 and active:
            self._start_input()
        self._update_outputs()

    # -- operating modes on the inputs (§3.6, §4.5.2) -----------------------------------------------
    def _start_input(self) -> None:
        """Start input I8 (P1021 bit 128): stand-alone start from line 1, or in parallel mode
        (P1022 ≠ 0) the subroutine L(address + 1) of the BCD address on the inputs."""
        if self.interpreter.running or not self._functions_enabled(128):
            return
        mask = int(self.ram.get(1022, 0)) & 0x7F & ~int(self.ram.get(1021, 0))
        try:
            if mask:
                self._run_label((self.inputs_byte(1) & mask) + 1)
            else:
                self.run_program(None)
        except SersError as exc:
            self.record_error(exc.errno)

    def _run_label(self, label: int) -> None:
        self._check_start()
        self.interpreter.start(label, subroutine=True)

    def _check_start(self) -> None:
        """Refusals of a program start, in the order of §4.4.1 (errnos 65–69)."""
        if self.cfg.service_switch or (self.signals.get("service_ext") and self.ram.get(1092)):
            raise SersError(65)
        if self.errors:
            raise SersError(66)
        if self._i7_stop_active():
            raise SersError(67)
        if self.signals.get("stop"):
            raise SersError(68)
        if not self.program.valid:
            raise SersError(69)

    def _start_subroutine(self, n: int) -> None:
        try:
            self._run_label(n)
        except SersError as exc:
            self.record_error(exc.errno)

    def _event_input(self, n: int, active: bool) -> None:
        """Event-driven mode P1098 (§4.5.2): a rising edge on In calls Ln if no program runs;
        an edge during a program is served when it ends if the input is still active."""
        if not int(self.ram.get(1098, 0)) & (1 << (n - 1)):
            return
        if not active:
            self.interpreter.pending_events.discard(n)
            return
        self.interpreter.pending_events.add(n)
        if not self.interpreter.running and self._dispatch is None:
            # edges of one instant are served together, I1 first (§4.5.2): dispatch a cycle later
            self._dispatch = self.clock.call_later(self.interpreter.cycle, self._dispatch_events)
            self._timers.append(self._dispatch)

    def _dispatch_events(self) -> None:
        self._dispatch = None
        self.on_program_end()

    def _check_supply(self) -> None:
        """§2.1.4: U_W pre-warning (auto-clear), U_B error after braking, U_L torque off."""
        volts = float(self.signals.get("supply_voltage"))
        _u_max, u_w, u_b, u_l = self.thresholds
        if "U" not in self.cfg.options and volts < u_l / 2:
            if self.logic_alive:
                self._power_off()
            return
        if not self.logic_alive:
            self._power_on()
            return
        if volts < u_l:
            self.drive_error(UNDERVOLTAGE, immediate=True)
        elif volts < u_b:
            if not self.errors & UNDERVOLTAGE and self.ram.get(1058):
                self.possave()
            self.drive_error(UNDERVOLTAGE)
        if volts < u_w:
            self.warn(4)
        elif self.warnings & 4:
            self.warnings &= ~4
            self._update_outputs()

    def _check_temperature(self) -> None:
        """§3.5: warning at 75 °C (auto-clear), error at 85 °C."""
        celsius = float(self.signals.get("heatsink_temperature"))
        if not self.logic_alive:
            return
        if celsius >= 85:
            self.drive_error(OVERTEMP)
        if celsius >= 75:
            self.warn(2)
        elif self.warnings & 2:
            self.warnings &= ~2
            self._update_outputs()

    def _check_short(self) -> None:
        if self.logic_alive and self.signals.get("short_circuit"):
            self._stop_cycled = False
            self._stop_opened = False
            self.drive_error(SHORT, immediate=True)

    # ======================================================================================
    # outputs and display
    # ======================================================================================
    def _update_outputs(self) -> None:
        if not self.logic_alive:
            return
        self.signals.set("READY", bool(self.relay and not self.errors))
        for param, state in (
            (1125, self.pos_ok),
            (1126, self.program_state == 1),
            (1131, self.errors != 0),
            (1132, self.warnings != 0),
        ):
            sel = int(self.ram.get(param, 0))
            if sel and abs(sel) <= 4:
                self.signals.set(f"O{abs(sel)}", state if sel > 0 else not state)
        brake = int(self.ram.get(1036, 0))
        if brake:
            off = not self.energized
            self.signals.set(f"O{abs(brake)}", off if brake > 0 else not off)

    def phase_current(self) -> float:
        """Commanded phase current in mA (§4.8.6.1, spec §5.11): P1010; with P1011 bit 0
        50 % at standstill from 20 ms after the last motion; +20 % boost per bits 1/2."""
        if not self.energized:
            return 0.0
        current = float(self.ram.get(1010, 0))
        bits = int(self.ram.get(1011, 0))
        standing = self.motion is None and self.clock.now() - self._stopped_at >= 0.02
        if standing and bits & 1:
            current *= 0.5
        accel = abs(self.axis.acceleration())
        if (bits & 2 and accel > float(self.ram.get(1012, 0))) or (bits & 4 and standing):
            current *= 1.2
        return current

    def display(self) -> dict[str, Any]:
        """7-segment display (§3.5, spec §4.7 priority)."""
        if not self.logic_alive:
            return {"char": " ", "blinking": False}
        if self.booting:
            return {"char": "-", "blinking": False}
        if self.errors & SHORT:
            return {"char": "E", "blinking": False}
        if self.eeprom_checksum_error:
            return {"char": "7", "blinking": False}
        for bit, char in ERROR_DISPLAY:
            if self.errors & bit:
                return {"char": char, "blinking": False}
        for bit, char in WARNING_DISPLAY:
            if self.warnings & bit:
                return {"char": char, "blinking": True}
        if self.energized:
            return {"char": "5", "blinking": bool(self.signals.get("stop"))}
        return {"char": "4", "blinking": False}

    # ======================================================================================
    # serial helpers used by the device
    # ======================================================================================
    @property
    def handshake_mode(self) -> int:
        return int(self.ram.get(1017, 1))

    @property
    def english(self) -> bool:
        return int(self.ram.get(265, 0)) == 1

    @property
    def list_options(self) -> int:
        return int(self.ram.get(1028, 1))

    def ack_text(self) -> str:
        """``ok<d>`` (§4.1): 4 error, 0/2 moving, 1/3 standing, +2 with a warning; ``pgm``."""
        if self.program_editing:
            return "pgm"
        if self.errors:
            return "ok4"
        digit = 1 if self.pos_ok else 0
        if self.warnings:
            digit += 2
        return f"ok{digit}"

    def format_value(self, number: int, value: float) -> str:
        pdef = PARAMETERS[number]
        if pdef.kind in WEIGHTED:
            scaling = self.scaling
            return format_query(value, scaling.decimals(pdef.kind), scaling.unit(pdef.kind))
        if pdef.kind == "fixed":
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
            if pdef is not None and pdef.kind in WEIGHTED:
                scaling = self.scaling
                value = format_fixed(stmt.value.value, scaling.decimals(pdef.kind))
                unit = scaling.unit(pdef.kind) if self.list_options & 2 else ""
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
            pdef = PARAMETERS.get(number)
            if pdef is not None and pdef.kind in WEIGHTED:
                return format_query(float(value), self.scaling.decimals(pdef.kind))
            if pdef is not None and pdef.kind == "fixed":
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
                return pdef.name_en if self.english else pdef.name
            raise SersError(13)
        value = self.operand_value(target)
        if target.kind in ("P", "alias", "O"):
            number = self.address_number(target)
            if number == 1 and self.ram.get(1) == "*":
                return f"{target.text}=*"
            return f"{target.text}={self.format_value(number, value)}"
        return f"{target.text}={int(value)}"

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

    # ======================================================================================
    # control API
    # ======================================================================================
    def read(self, name: str) -> Any:  # noqa: C901
        section, _, rest = name.partition(".")
        if name == "display":
            return self.display()
        if name == "display.char":
            return self.display()["char"]
        if name == "display.blinking":
            return self.display()["blinking"]
        if section == "axis":
            values = {
                "position": self.axis.position(),
                "velocity": self.axis.velocity(),
                "acceleration": self.axis.acceleration(),
                "moving": self.axis.moving,
                "phase": self.axis.phase(),
            }
            if rest in values:
                return values[rest]
        if section in ("input", "output", "quantity") and rest in self.signals:
            return self.signals.get(rest)
        if section == "param":
            try:
                return self.param_value(_lookup(rest).number)
            except (KeyError, SersError) as exc:
                raise UnknownName(name) from exc
        simple = {
            "P11": self.errors,
            "P12": self.warnings,
            "errno": self.errno,
            "energized": self.energized,
            "ready": bool(self.relay and not self.errors),
            "motion": self.motion,
            "homed": self.homed,
            "homing": self._homing["phase"] if self._homing else None,
            "encoder.position": self.encoder_position(),
            "phase_current": self.phase_current(),
            "load_angle": self.axis.position() - self.encoder_position(),
            "booting": self.booting,
            "powered": self.logic_alive,
            "position": self.scaling.inc_to_pos(round(self.p51_inc())),
        }
        if name in simple:
            return simple[name]
        raise UnknownName(name)

    def set(self, name: str, value: Any) -> None:
        section, _, rest = name.partition(".")
        if section in ("input", "quantity") and rest in self.signals:
            kind = self.signals.signal(rest).kind
            if (section == "input") != (kind == "input"):
                raise UnknownName(name)
            self.signals.set(rest, bool(value) if kind == "input" else value)
            return
        if section == "param":
            try:
                number = _lookup(rest).number
            except KeyError as exc:
                raise UnknownName(name) from exc
            try:
                self.write_param(number, value)
            except SersError as exc:
                raise ValueError(str(exc)) from exc
            return
        if name == "encoder.pulses":
            self.pulses(int(value))
            return
        if name == "dip.service_switch":
            self.cfg = self.cfg.model_copy(update={"service_switch": bool(value)})
            return
        if name == "dip.input_level":
            self.cfg = self.cfg.model_copy(update={"input_level": value})
            return
        raise UnknownName(name)

    def state(self) -> dict[str, Any]:
        return {
            "kind": self.kind,
            "address": self.cfg.address,
            "powered": self.logic_alive,
            "display": self.display(),
            "P11": self.errors,
            "P12": self.warnings,
            "errno": self.errno,
            "energized": self.energized,
            "ready": bool(self.relay and not self.errors),
            "motion": self.motion,
            "position": self.scaling.inc_to_pos(round(self.p51_inc())),
            "axis": {"position": self.axis.position(), "velocity": self.axis.velocity()},
            "inputs": self.signals.snapshot("input"),
            "outputs": self.signals.snapshot("output"),
            "quantities": self.signals.snapshot("quantity"),
        }


def _lookup(token: str) -> ParamDef:
    text = token.strip().upper()
    if text.startswith("P") and text[1:].isascii() and text[1:].isdigit():
        number = int(text[1:])
    elif text.isascii() and text.isdigit():
        number = int(text)
    else:
        number = ALIASES[text]
    return PARAMETERS[number]


def _as_number(value: float, pdef: ParamDef) -> float | int:
    if pdef.kind == "int" and float(value).is_integer():
        return int(value)
    if pdef.kind == "fixed":
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


def _compare(left: float, op: str, right: float) -> bool:
    return {
        "<": left < right,
        "<=": left <= right,
        "=": left == right,
        ">": left > right,
        ">=": left >= right,
        "<>": left != right,
    }[op]


def _sign(x: float) -> int:
    return (x > 0) - (x < 0)


def _raise(errno: int) -> None:
    raise SersError(errno)

