"""Inputs, faults, outputs and display of the SERS model: limit switches, STOP, digital inputs
and their functions, supply and temperature faults, outputs, the 7-segment display (manual
§2.1, §3.3, §3.5, §4.8.1; spec §2.7, §4.7, §4.11, §5.6, §5.14)."""

from __future__ import annotations

from typing import Any

from devsim.devices.sers.constants import ERROR_DISPLAY, LIMIT, OVERTEMP, SHORT, UNDERVOLTAGE, WARNING_DISPLAY
from devsim.devices.sers.errors import SersError

__all__ = ["InputsAndFaults"]


class InputsAndFaults:
    """Part of :class:`~devsim.devices.sers.drive.SersDrive`: inputs, faults, outputs, display."""

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
        service = self.cfg.service_switch or (self.signals.get("service_ext") and self.params.external_service_switch)
        if bit == 128:
            return bool(int(self.params.input_enable) & 128)
        return bool(service) or bool(int(self.params.input_enable) & bit)

    def _i7_stop_active(self) -> bool:
        return self._functions_enabled(64) and bool(self.signals.get("I7"))

    def _on_digital_input(self, name: str, old: Any, new: Any) -> None:
        if not self.logic_alive or self.booting:
            return
        n = int(name[1:])
        bit = 1 << (n - 1)
        monitored = int(self.params.standstill_input) == n and self.params.standstill_distance
        active_edge = bool(new) != (self.cfg.input_level == "low_active")
        if monitored and active_edge and self.motion is not None:
            self._arm_standstill_monitor()
        if self.params.reference_input == n and self._homing is not None and self._homing["signal"] == "reference":
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
        mask = int(self.params.input_label_enable) & 0x7F & ~int(self.params.input_enable)
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
        if self.cfg.service_switch or (self.signals.get("service_ext") and self.params.external_service_switch):
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
        if not int(self.params.program_jump_enable) & (1 << (n - 1)):
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
            if not self.errors & UNDERVOLTAGE and self.params.save_position_on_undervoltage:
                self.memory.possave()
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
        params = self.params
        for selected, state in (
            (params.output_in_position, self.pos_ok),
            (params.output_program_running, self.program_state == 1),
            (params.output_error, self.errors != 0),
            (params.output_warning, self.warnings != 0),
        ):
            sel = int(selected)
            if sel and abs(sel) <= 4:
                self.signals.set(f"O{abs(sel)}", state if sel > 0 else not state)
        brake = int(self.params.brake_output)
        if brake:
            off = not self.energized
            self.signals.set(f"O{abs(brake)}", off if brake > 0 else not off)

    def phase_current(self) -> float:
        """Commanded phase current in mA (§4.8.6.1, spec §5.11): P1010; with P1011 bit 0
        50 % at standstill from 20 ms after the last motion; +20 % boost per bits 1/2."""
        if not self.energized:
            return 0.0
        current = float(self.params.phase_current)
        bits = int(self.params.current_parameters)
        standing = self.motion is None and self.clock.now() - self._stopped_at >= 0.02
        if standing and bits & 1:
            current *= 0.5
        accel = abs(self.axis.acceleration())
        if (bits & 2 and accel > float(self.params.boost_acceleration)) or (bits & 4 and standing):
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
        if self.memory.eeprom_checksum_error:
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

