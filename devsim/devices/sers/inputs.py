"""Inputs, faults, outputs and display of the SERS model: limit switches, STOP, digital inputs
and their functions, supply and temperature faults, outputs, the 7-segment display (manual
§2.1, §3.3, §3.5, §4.8.1; spec §2.7, §4.7, §4.11, §5.6, §5.14)."""

from __future__ import annotations

from typing import Any

from devsim.devices.sers.constants import LIMIT
from devsim.devices.sers.errors import SersError

__all__ = ["InputsAndFaults"]


class InputsAndFaults:
    """Part of :class:`~devsim.devices.sers.drive.SersDrive`: inputs, faults, outputs, display."""

    # ======================================================================================
    # inputs and faults
    # ======================================================================================
    def _on_limit(self, name: str, old: Any, new: Any) -> None:
        if not self.logic_alive:
            return
        if new:
            if self.motion.homing.edge(name, True):
                return
            self.power_stage.drive_error(LIMIT)
        else:
            self.motion.homing.edge(name, False)
        self.motion.check_until()

    def _on_stop_input(self, name: str, old: Any, new: Any) -> None:
        self.power_stage.stop_input(bool(new))
        if new:
            self.interpreter.stop()
            if self.motion.kind is not None:
                self.motion.stop_motion()
        self.motion.check_until()

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
        if monitored and active_edge and self.motion.kind is not None:
            self.motion.watches.arm_standstill()
        if self.params.reference_input == n:
            self.motion.homing.edge("reference", bool(new))
        if self._functions_enabled(bit):
            try:
                self._input_function(n, bool(new))
            except SersError as exc:
                self.power_stage.record_error(exc.errno)
        elif n == 8 and new and self._functions_enabled(128):
            self._start_input()
        self._event_input(n, bool(new))
        self.motion.check_until()

    def _input_function(self, n: int, active: bool) -> None:
        jogs = {1: "LS", 2: "RS", 3: "LF", 4: "RF"}
        if n in jogs:
            if active:
                self.power_stage.energize()
                self.motion.jog.start(jogs[n], serial=False)
            elif self.motion.kind == "jog":
                self.motion.stop_motion()
        elif n == 5 and active:
            self.power_stage.energize()
            self.motion.home()
        elif n == 6 and active:  # G-INFUNC: rising edge toggles; ON clears P11 and P12
            self.power_stage.toggle()
        elif n == 7 and active:
            self.interpreter.stop()
            if self.motion.kind is not None:
                self.motion.stop_motion()
        elif n == 8 and active:
            self._start_input()
        self.outputs.update()

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
            self.power_stage.record_error(exc.errno)

    def _run_label(self, label: int) -> None:
        self._check_start()
        self.interpreter.start(label, subroutine=True)

    def _check_start(self) -> None:
        """Refusals of a program start, in the order of §4.4.1 (errnos 65–69)."""
        if self.cfg.service_switch or (self.signals.get("service_ext") and self.params.external_service_switch):
            raise SersError(65)
        if self.power_stage.errors:
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
            self.power_stage.record_error(exc.errno)

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
