"""The SERS's inputs: the limit switches and STOP, the digital inputs I1..I16 with their manual
functions, the start input, the parallel and event-driven modes, and what the inputs read as
(P1300, P1301, P1013, J1..J5, the ADC) (manual §2.1.2, §3.3, §3.6, §4.5.2, §4.8.1, §4.8.3.2;
spec §4.11, §5.6, G-INFUNC, G-ADC).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any, Protocol

from devsim.core.clock import Clock, Timer
from devsim.core.kit import Command, Table
from devsim.core.signals import SignalBank
from devsim.devices.sers.constants import LIMIT
from devsim.devices.sers.errors import SersError
from devsim.devices.sers.motion import Motion
from devsim.devices.sers.params import SersParameters
from devsim.devices.sers.power import PowerStage
from devsim.devices.sers.program import ProgramMemory

__all__ = ["INPUT_FUNCTIONS", "Inputs", "ProgramStarts"]

#: I6 by ``i6_mode`` (spec G-INFUNC): ``toggle``, a rising edge switches ON (clearing P11 and
#: P12) or OFF; ``level``, ON (clearing them) at the rising edge and OFF at the falling one.
_I6_MODES: dict[str, Callable[[PowerStage, bool], None]] = {
    "toggle": lambda power, active: power.toggle() if active else None,
    "level": PowerStage.follow,
}

#: The manual functions of I1..I4 (P1021 bits 0–3, §4.8.1.1).
_JOGS = {1: "LS", 2: "RS", 3: "LF", 4: "RF"}
#: J1..J5 (§4.6.1): the P1013 bit that is set while the switch is open.
_J_BITS = {1: 8, 2: 2, 3: 1, 4: 4, 5: 128}


class ProgramStarts(Protocol):
    """What the inputs start and stop (§3.6, §4.5.2): the program execution
    (:class:`~.execution.Execution`)."""

    @property
    def running(self) -> bool: ...

    @property
    def cycle(self) -> float:
        """The control cycle (0.5 ms, or 2 ms with P1127=1)."""

    def stop_program(self) -> None: ...

    def run_program(self, label: int | None) -> None: ...

    def run_subroutine(self, label: int) -> None: ...

    def jog_input_activated(self) -> None:
        """A manual function of I1..I6 was carried out (P1093, §4.8.6.3)."""

    def jog_inputs_released(self) -> None:
        """No input I1..I6 with its manual function is active any more (P1093, §4.8.6.3)."""


class Inputs:
    """The inputs of one SERS and what they set off (§3.3, §4.8.1)."""

    def __init__(
        self,
        clock: Clock,
        signals: SignalBank,
        params: SersParameters,
        power: PowerStage,
        motion: Motion,
        program: ProgramMemory,
        *,
        config: Callable[[], Any],
        alive: Callable[[], bool],
        booting: Callable[[], bool],
        programs: Callable[[], ProgramStarts],
        changed: Callable[[], None],
    ) -> None:
        self.clock = clock
        self.signals = signals
        self.params = params
        self.power = power
        self.motion = motion
        self.program = program
        self._config = config
        self._alive = alive
        self._booting = booting
        self._programs = programs  # (the program execution, made after the inputs)
        self._changed = changed
        #: Inputs whose rising edge came while a program ran (served when it ends, §4.5.2).
        self.pending_events: set[int] = set()
        self._dispatch: Timer | None = None
        self._level_start: Timer | None = None

    def power_on(self) -> None:
        self.power_off()
        self.pending_events.clear()

    def power_off(self) -> None:
        """The event dispatch and a level start (P1023=1) due a cycle later do not happen."""
        for timer in (self._dispatch, self._level_start):
            if timer is not None:
                timer.cancel()
        self._dispatch = self._level_start = None

    def initialised(self) -> None:
        """The initialisation after power-on is over (§3.5): with P1095=0 a jog function (I1..I6)
        whose input is already active starts now, by its static level (§4.8.6.3); with P1095=1
        only a later rising edge starts it."""
        if int(self.params.jog_at_power_on) != 0:
            return
        for n in range(1, 7):
            if self.signals.get(f"I{n}") and self.functions_enabled(1 << (n - 1)):
                try:
                    self._input_function(n, True)
                except SersError as exc:
                    self.power.record_error(exc.errno)

    # -- what the inputs read as ------------------------------------------------------------------
    def inputs_byte(self, first: int) -> int:
        """P1300 (I1..I8, ``first`` = 1) or P1301 (I9..I16, ``first`` = 9)."""
        if self._config().input_level == "invalid" and first == 1:
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

    def j_value(self, n: int) -> int:
        """J1..J5 (§4.6.1): 1 = 24 V at the input (inverse of the P1013 'open' bits)."""
        if n not in _J_BITS:
            raise SersError(13)
        return 0 if self.status_word() & _J_BITS[n] else 1

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

    def pulses_in_window(self, n: int) -> int:
        """P1124 / P1146 (§4.8.6.6): pulses counted in the window P1055 / P1145 (× 2 ms)."""
        params = self.params
        window = float(params.frequency_window if n == 1124 else params.frequency_window2) * 0.002
        measuring = int(params.pulse_input) in (9, 10) if n == 1124 else int(params.pulse_input2) == 5
        return round(float(self.signals.get("pulse_frequency")) * window) if measuring else 0

    # -- the switches ---------------------------------------------------------------------------------
    def on_limit(self, name: str, old: Any, new: Any) -> None:
        if not self._alive():
            return
        motion = self.motion
        if new:
            if motion.homing.edge(name, True):
                return
            self.power.drive_error(LIMIT)
        else:
            motion.homing.edge(name, False)
        motion.check_until()

    def on_stop(self, name: str, old: Any, new: Any) -> None:
        self.power.stop_input(bool(new))
        if new:
            self._programs().stop_program()
            self.motion.stop_command()
        self.motion.check_until()

    def on_reference(self, name: str, old: Any, new: Any) -> None:
        if not self.params.reference_input:
            self.motion.homing.edge("reference", bool(new))
        self.motion.check_until()

    # -- the digital inputs -----------------------------------------------------------------------
    def functions_enabled(self, bit: int) -> bool:
        """Manual functions on I1..I7 (§3.1.4, §4.8.1.1 P1021)."""
        params = self.params
        service = self._config().service_switch or (self.signals.get("service_ext") and params.external_service_switch)
        if bit == 128:
            return bool(int(params.input_enable) & 128)
        return bool(service) or bool(int(params.input_enable) & bit)

    def i7_stop_active(self) -> bool:
        return self.functions_enabled(64) and bool(self.signals.get("I7"))

    def on_digital_input(self, name: str, old: Any, new: Any) -> None:
        if not self._alive() or self._booting():
            return
        n = int(name[1:])
        bit = 1 << (n - 1)
        params, motion = self.params, self.motion
        monitored = int(params.standstill_input) == n and params.standstill_distance
        # P1044 (§4.8.6.8): "Flanke 0 → 1 bei High-aktiven ... oder Flanke 1 → 0 bei Low-aktiven
        # Eingangssignalen" -- the edge to active; the input reads active when set, whatever the
        # DIP level (as P1300 and the input functions read it)
        if monitored and new and motion.kind is not None:
            motion.watches.arm_standstill()
        if params.reference_input == n:
            motion.homing.edge("reference", motion.homing.reference_active())
        if self.functions_enabled(bit):
            try:
                self._input_function(n, bool(new))
            except SersError as exc:
                self.power.record_error(exc.errno)
        elif n == 8 and new and self.functions_enabled(128):
            self.start_input()
        self._event_input(n, bool(new))
        motion.check_until()

    def _input_function(self, n: int, active: bool) -> None:
        """The manual function of input ``n`` (:data:`INPUT_FUNCTIONS`), then the outputs."""
        function = _INPUT_FUNCTION.get(n)
        if function is not None:
            function(self, active)
            if n <= 6:
                self._program_reacts(active)
        self._changed()

    def _program_reacts(self, active: bool) -> None:
        """A manual function of I1..I6 interrupts or aborts a running program (P1093, §4.8.6.3);
        the program hears when the last of these inputs is released."""
        programs = self._programs()
        if active:
            programs.jog_input_activated()
        elif not any(self.signals.get(f"I{m}") and self.functions_enabled(1 << (m - 1)) for m in range(1, 7)):
            programs.jog_inputs_released()

    def jog_input(self, n: int, active: bool) -> None:
        """I1–I4: jog while the input is active (LS, RS, LF, RF)."""
        motion = self.motion
        if active:
            self.power.energize()
            motion.jog.start(_JOGS[n], serial=False)
        elif motion.kind == "jog":
            motion.stop_motion()

    def home_input(self, active: bool) -> None:
        if active:
            self.power.energize()
            self.motion.home()

    def power_input(self, active: bool) -> None:
        """I6 „Motor ON/OFF, zusätzlich P11=0 und P12=0 bei Motor → ON“ (§4.8.1.1), as
        :data:`_I6_MODES` reads it for the configured ``i6_mode`` (spec G-INFUNC)."""
        _I6_MODES[self._config().i6_mode](self.power, active)

    def stop_input(self, active: bool) -> None:
        if active:
            self._programs().stop_program()
            self.motion.stop_command()

    def start_input_edge(self, active: bool) -> None:
        if active:
            self.start_input()

    # -- starting programs from the inputs (§3.6, §4.5.2) ---------------------------------------
    def start_input(self) -> None:
        """Start input I8 (P1021 bit 128): stand-alone start from line 1, or in parallel mode
        (P1022 ≠ 0) the subroutine L(address + 1) of the BCD address on the inputs."""
        programs = self._programs()
        if programs.running or not self.functions_enabled(128):
            return
        params = self.params
        mask = int(params.input_label_enable) & 0x7F & ~int(params.input_enable)
        try:
            if mask:
                programs.run_subroutine((self.inputs_byte(1) & mask) + 1)
            else:
                programs.run_program(None)
        except SersError as exc:
            self.power.record_error(exc.errno)

    def check_start(self) -> None:
        """Refusals of a program start, in the order of §4.4.1 (errnos 65–69)."""
        if self._config().service_switch or (self.signals.get("service_ext") and self.params.external_service_switch):
            raise SersError(65)
        if self.power.errors:
            raise SersError(66)
        if self.i7_stop_active():
            raise SersError(67)
        if self.signals.get("stop"):
            raise SersError(68)
        if not self.program.valid:
            raise SersError(69)

    def _event_input(self, n: int, active: bool) -> None:
        """Event-driven mode P1098 (§4.5.2): a rising edge on In calls Ln if no program runs;
        an edge during a program is served when it ends if the input is still active."""
        if not int(self.params.program_jump_enable) & (1 << (n - 1)):
            return
        if not active:
            self.pending_events.discard(n)
            return
        self.pending_events.add(n)
        programs = self._programs()
        if not programs.running and self._dispatch is None:
            # edges of one instant are served together, I1 first (§4.5.2): dispatch a cycle later
            self._dispatch = self.clock.call_later(programs.cycle, self._dispatch_events)

    def _dispatch_events(self) -> None:
        self._dispatch = None
        self.program_ended()

    def program_ended(self) -> None:
        """After a program: the event dispatcher (P1098) and a level start (P1023=1) may
        start the next one."""
        programs = self._programs()
        if not self._alive() or programs.running:
            return
        events = int(self.params.program_jump_enable)
        for n in sorted(self.pending_events):
            self.pending_events.discard(n)
            if events & (1 << (n - 1)) and self.signals.get(f"I{n}"):
                try:
                    programs.run_subroutine(n)
                except SersError as exc:
                    self.power.record_error(exc.errno)
                return
        if self.functions_enabled(128) and int(self.params.start_enable) == 1 and self.signals.get("I8"):
            self._level_start = self.clock.call_later(programs.cycle, self._level_start_due)

    def _level_start_due(self) -> None:
        self._level_start = None
        self.start_input()


#: The manual functions of the inputs I1..I8 when P1021 (or the service switch) enables them
#: (§4.8.1.1; the handler gets the input's new level).
INPUT_FUNCTIONS: Table[Callable[[Inputs, bool], None]] = Table(
    [
        *(Command(f"I{n}", lambda i, active, n=n: i.jog_input(n, active), "§4.8.1.1", f"jog {_JOGS[n]} while active")
          for n in _JOGS),
        Command("I5", Inputs.home_input, "§4.8.1.1", "homing (H)"),
        Command("I6", Inputs.power_input, "§4.8.1.1", "motor ON/OFF (ON clears P11 and P12)"),
        Command("I7", Inputs.stop_input, "§4.8.1.1", "stop the program and the motion"),
        Command("I8", Inputs.start_input_edge, "§4.8.1.1", "start the program"),
    ]
)
_INPUT_FUNCTION = {int(row.token[1:]): row.handler for row in INPUT_FUNCTIONS}
