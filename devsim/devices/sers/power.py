"""The SERS's power stage and its errors: motor power ON/OFF, the drive errors P11, the warnings
P12 and the last error message P1137 (manual §2.1.3, §2.1.4, §4.8.2.2, §4.8.3.1; spec §4.3,
§4.6).

A drive error brakes a moving motor with P1030, opens the ready relay and 50 ms later switches
the phases off; a short circuit and an undervoltage below U_L switch off at once.  ``P11=0``
clears the errors once their causes are gone (spec G-P11CLEAR).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Protocol

from devsim.core.clock import Clock, Timer
from devsim.core.signals import SignalBank
from devsim.devices.sers.constants import EMCY_CODES, FAULT_MESSAGES, OVERTEMP, SHORT, STEP_LOSS, UNDERVOLTAGE
from devsim.devices.sers.errors import SersError
from devsim.devices.sers.memory import ParameterMemory
from devsim.devices.sers.params import SersParameters

__all__ = ["Brakes", "PowerStage"]


class Brakes(Protocol):
    """What a drive error and OFF (§2.1.3, §4.8.2.2) need of the motion (:class:`~.motion.Motion`)."""

    def abort_profiles(self) -> None:
        """Forget a polynomial profile and a homing run under way."""

    def quick_end(self) -> None:
        """Stop at once and end the motion (torque off), if one is under way."""

    def error_stop(self, then: Callable[[], None]) -> bool:
        """Brake a moving axis with P1030, then call ``then``; False if nothing moves."""


class PowerStage:
    """Motor power, drive errors and warnings of one SERS (§2.1.3, §4.8.2.2, §4.8.3.1)."""

    #: (Slots: a host's repeated poll reads this part: one block of memory instead of an object and its values)
    __slots__ = ("clock", "params", "signals", "memory", "_brakes", "_changed", "_program_error", "_resync",
                 "_record_event", "_announce", "undervoltage", "errors", "warnings", "errno", "energized",
                 "relay", "servo_calibrated", "_stop_cycled", "_stop_opened", "_timers", "_fault_message")

    def __init__(
        self,
        clock: Clock,
        params: SersParameters,
        signals: SignalBank,
        memory: ParameterMemory,
        brakes: Callable[[], Brakes],
        *,
        undervoltage: float,
        changed: Callable[[], None],
        program_error: Callable[[], None],
        resync: Callable[[], None],
        record_event: Callable[[str], None],
        announce: Callable[..., None],
        fault_message: Callable[[str], None] | None = None,
    ) -> None:
        self.clock = clock
        self.params = params
        self.signals = signals
        self.memory = memory
        self._brakes = brakes  # (the motion, made after the power stage)
        self._changed = changed  # the outputs and the display follow
        self._program_error = program_error  # a running program stops or jumps to L65
        self._resync = resync  # clearing a step loss: P51 takes the encoder's position
        self._record_event = record_event
        self._announce = announce
        self.undervoltage = undervoltage  # U_B of the supply class (§2.1.4): P11=0 needs more
        self.errors = 0  # P11
        self.warnings = 0  # P12
        self.errno = 0  # P1137
        self.energized = False  # the motor phases carry current
        self.relay = False  # the ready relay is closed
        #: SERVO mode: the load-angle zero has been taken after ON (§4.8.6.7).
        self.servo_calibrated = False
        self._stop_cycled = True  # the STOP input opened and closed again since a short circuit
        self._stop_opened = False
        self._timers: list[Timer] = []
        #: G-FAULTMSG ⚙ ``spontaneous_fault_messages``: sends ``*<text>`` between lines when a
        #: drive error or warning of :data:`FAULT_MESSAGES` is set (None: nothing is sent)
        self._fault_message = fault_message

    def has_errors(self) -> bool:
        return self.errors != 0

    def has_warnings(self) -> bool:
        return self.warnings != 0

    def power_on(self) -> None:
        """Everything off and cleared (§4.1); with P1011 bit 5 the motor is energised at once."""
        self.cancel()
        self.errors = 0
        self.warnings = 0
        self.errno = 0
        self.energized = False
        self.relay = False
        self.servo_calibrated = False
        self._stop_cycled = True
        self._stop_opened = False

    def energize_at_power_on(self) -> None:
        if self.params.current_parameters & 32 and not self.memory.eeprom_checksum_error:
            self.energized = True
            self.relay = True

    def power_off(self) -> None:
        self.cancel()
        self.energized = False
        self.relay = False

    def cancel(self) -> None:
        for timer in self._timers:
            timer.cancel()
        self._timers.clear()

    # -- ON / OFF ---------------------------------------------------------------------------
    def switch_on(self) -> None:
        """ON = P134=7 (§4.8.2.2): phases energised, ready relay closed."""
        if self.errors or self.memory.eeprom_checksum_error:
            raise SersError(79)
        self.energized = True
        self.relay = True
        params = self.params
        if params.servo_mode == 1 and not int(params.homing_parameters) & 256 and not self.servo_calibrated:
            # SERVO: the load-angle zero is taken 100 ms after ON (§4.8.6.7, P147 bit 8 = 0)
            self._timers.append(self.clock.call_later(0.1, self._servo_calibrate))
        self._changed()

    def energize(self) -> None:
        """The manual functions (jog, homing on the inputs) and an automatic POSR switch the
        motor on, unless a drive error is active (§4.8.1.1, §4.8.6.6)."""
        if not self.errors:
            self.energized = self.relay = True

    def toggle(self) -> None:
        """Input I6 (G-INFUNC): a rising edge switches OFF, or clears P11 and P12 and switches ON."""
        if self.energized:
            self.switch_off()
        else:
            self.errors = 0
            self.warnings = 0
            self.switch_on()

    def follow(self, on: bool) -> None:
        """Input I6 with ``i6_mode: level`` (G-INFUNC): ON while active (P11 and P12 cleared as it
        switches ON), OFF once released."""
        if on != self.energized:
            self.toggle()

    def switch_off(self) -> None:
        """OFF = P134=0: torque off at once (spec G-OFFMOVE), relay open."""
        self._brakes().quick_end()
        self.energized = False
        self.relay = False
        self._changed()

    def write_p134(self, value: float) -> None:
        """P134 (§4.8.2.2): 7 = ON, 0 = OFF."""
        if value == 7:
            self.switch_on()
        elif value == 0:
            self.switch_off()
        else:
            raise SersError(3)

    def _servo_calibrate(self) -> None:
        if self.energized:
            self.servo_calibrated = True

    def servo_check(self) -> None:
        """Positioning or jogging before the SERVO load angle is calibrated: warning 2048."""
        if self.params.servo_mode == 1 and not self.servo_calibrated:
            self.warn(2048)

    # -- errors and warnings -------------------------------------------------------------------
    def drive_error(self, bit: int, immediate: bool = False) -> None:
        """Set a P11 bit: brake with P1030, open the relay, 50 ms later switch the phases off
        (§2.1.3, §2.1.4); short circuit and U < U_L switch off at once."""
        first = not self.errors & bit
        if first:  # the code of the kind's error table (devsim.core.model.Model.report_error)
            self._announce("device_error", f"P11 {bit}", False)
            self._record_event("error")
        self.errors |= bit
        if first:
            self._announce("fault", 1, EMCY_CODES.get(bit, 0x1000))  # (a CANopen facade sends EMCY)
            if self._fault_message is not None and bit in FAULT_MESSAGES[0]:
                self._fault_message("\n*" + FAULT_MESSAGES[0][bit])
        self._brakes().abort_profiles()
        if first:
            self._program_error()
        if immediate:
            self._brakes().quick_end()
            self.energized = False
            self.relay = False
            self._changed()
            return
        if not first and not self.energized:
            return

        def relay_open() -> None:
            self.relay = False
            self._changed()
            self._timers.append(self.clock.call_later(0.05, self._phases_off))

        if not self._brakes().error_stop(relay_open):
            relay_open()
        self._changed()

    def _phases_off(self) -> None:
        if self.errors and not (self.errors & STEP_LOSS and self.params.step_monitoring == 3):
            self.energized = False
            self._changed()

    def short_circuit(self) -> None:
        """A short circuit in the motor or the power stage: off at once; P11=0 clears it only
        after the STOP input has opened and closed again (spec G-P11CLEAR)."""
        self._stop_cycled = False
        self._stop_opened = False
        self.drive_error(SHORT, immediate=True)

    def stop_input(self, opened: bool) -> None:
        """The STOP input opened (True) or closed."""
        if not opened and self._stop_opened:
            self._stop_cycled = True
        if opened:
            self._stop_opened = True

    def warn(self, bit: int) -> None:
        if self._fault_message is not None and not self.warnings & bit and bit in FAULT_MESSAGES[1]:
            self._fault_message("\n*" + FAULT_MESSAGES[1][bit])  # (G-FAULTMSG ⚙)
        self.warnings |= bit
        self._changed()

    def clear_warning(self, bit: int) -> None:
        """A warning whose cause went away by itself (supply, temperature)."""
        if self.warnings & bit:
            self.warnings &= ~bit
            self._changed()

    def clear_error(self, bit: int) -> None:
        """A drive error that goes by itself (an automatic POSR after a step loss)."""
        self.errors &= ~bit

    def clear_step_loss(self) -> None:
        """POSR: the step loss, as an error or a warning, is over (§4.8.4.2)."""
        self.errors &= ~STEP_LOSS
        self.warnings &= ~STEP_LOSS

    def record_error(self, errno: int, refused: bool = False) -> None:
        """Every error message sets P12 value 16 and P1137 (§4.8.3.1); ``refused``: the answer
        to a host's command (for the logs, topic ``device_error``)."""
        self._announce("device_error", str(errno), refused)
        self.errno = errno
        self.warn(16)  # (every error message answers a host's line)

    def record_errors(self, errnos: list[int]) -> None:
        """Error messages answering a host's lines one after the other, with nothing else in
        between (lines of noise, :mod:`.noise`): what a call of :meth:`record_error` for each
        leaves (every one heard by the logs; P12 and the outputs follow at the first, the
        rest is the same each time but P1137, the last one's)."""
        self.record_error(errnos[0], refused=True)
        announce = self._announce
        for errno in errnos[1:]:
            announce("device_error", str(errno), True)
        self.errno = errnos[-1]

    def write_p11(self, value: float) -> None:
        """``P11=0`` (spec G-P11CLEAR): only once the causes are gone."""
        if value != 0:
            raise SersError(3)
        signals = self.signals
        if self.errors & OVERTEMP and signals.get("heatsink_temperature") >= 85:
            raise SersError(3)
        if self.errors & UNDERVOLTAGE and signals.get("supply_voltage") < self.undervoltage:
            raise SersError(3)
        if self.errors & SHORT and (signals.get("short_circuit") or not self._stop_cycled):
            raise SersError(3)
        if self.errors & STEP_LOSS:
            self._resync()
        self.errors = 0
        self.params.l65_flag = 0
        self.energized = False
        self.relay = False
        self._changed()

    def write_p12(self, value: float, recheck: Callable[[], None]) -> None:
        """``P12=0``: the warnings whose causes remain come back at once (``recheck``)."""
        if value != 0:
            raise SersError(3)
        if self.warnings & STEP_LOSS:
            self._resync()
        self.warnings = 0
        recheck()
        self._changed()

