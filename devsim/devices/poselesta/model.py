"""The POSELESTA II/III control as a model: modes, program memory, machine parameters, the
transfers of V6 and V7 and the V8 keyboard (manual "Schnittstellenbeschreibung POSELESTA II/III"
§2.4.1, §2.4.5, §2.6; spec poselesta.md §3.2, §3.5–§3.10, §4.1, §4.2, §4.8, §4.9).

The model builds its parts and hands each the collaborators it needs: the axes
(:mod:`~devsim.devices.poselesta.axes`), the machine parameters, the program memory, the
transfers (:mod:`~devsim.devices.poselesta.links`), the front panel, the block cycle
(:mod:`~devsim.devices.poselesta.execution`), manual motion, the limit switches, the working
field, the output test and the cassette.  The serial faces only hand bytes over
(:meth:`PoselestaCnc.port_input`) and send what the model announces on ``<port>_out``.
"""

from __future__ import annotations

import functools
import types
from collections.abc import Callable, Mapping
from functools import partial
from typing import Any

from devsim.core.clock import Timer
from devsim.core.kit import declare_signals
from devsim.core.model import Model
from devsim.core.points import BadValue
from devsim.devices.poselesta.axes import Axes
from devsim.devices.poselesta.block_motion import BlockMotion
from devsim.devices.poselesta.config import PoselestaConfig
from devsim.devices.poselesta.diagnostics import OutputTest
from devsim.devices.poselesta.execution import ExecutionOptions, Executor
from devsim.devices.poselesta.flow import ProgramFlow
from devsim.devices.poselesta.functions import BlockFunctions
from devsim.devices.poselesta.keyboard import Keyboard
from devsim.devices.poselesta.limits import LimitSwitches
from devsim.devices.poselesta.links import SerialLinks
from devsim.devices.poselesta.manual import ManualMotion
from devsim.devices.poselesta.mst import MstBus, PlcHelper
from devsim.devices.poselesta.panel import FrontPanel
from devsim.devices.poselesta.parameters import MachineParameters
from devsim.devices.poselesta.peers import Cassette
from devsim.devices.poselesta.programs import ProgramMemory
from devsim.devices.poselesta.screen import Screen
from devsim.devices.poselesta.signals import INPUTS, OUTPUTS, SIGNALS, feed_pot, override
from devsim.devices.poselesta.terminals import InputTerminals
from devsim.devices.poselesta.working_field import WorkingField

__all__ = ["MODES", "PoselestaCnc"]

#: Operating modes and their code on the data bus (§2.4.1; spec §4.1).
MODES = {
    "MANUAL": 0x08,
    "PROGRAM_ENTRY": 0x09,
    "EXTERNAL_OPERATION": 0x0A,
    "EXTERNAL_MEDIUM": 0x0B,
    "AUTO_CONTINUOUS": 0x0C,
    "AUTO_SINGLE_BLOCK": 0x0D,
    "MANUAL_SINGLE_BLOCK": 0x0E,
}


def _input_delays(cfg: PoselestaConfig) -> Mapping[str, tuple[float, float]]:
    """The delay of each opto-coupled input V19–V22 (§2.3), by the configuration; the pots V23 and
    the reference mark activation V24 (§2.3.23: at most 5 ms opening, 0.2 ms closing) have none."""
    return _delays_of((cfg.input_rise_ms / 1000.0, cfg.input_fall_ms / 1000.0))


@functools.lru_cache(maxsize=16)
def _delays_of(opto: tuple[float, float]) -> Mapping[str, tuple[float, float]]:
    """One read-only table per pair of delays, shared by the controls configured alike."""
    return types.MappingProxyType(
        {d.name: opto for d in INPUTS if d.point_type == "bool" and not d.name.startswith("rm_enable_")})


class PoselestaCnc(Model):
    """One POSELESTA control: what its serial ports and its panel reach (manual §2.4.1, §2.4.5,
    §2.6; spec §4.1, §4.2)."""

    def __init__(self, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        cfg = self.cfg = PoselestaConfig.parse(self.config)
        signals = self.signals
        declare_signals(signals, SIGNALS)
        self.terminals = InputTerminals(self.clock, signals, _input_delays(cfg))
        self.mode = "MANUAL"
        self.program = 0
        self.relay_supply_lost = False
        self.plotter = False  # X/Y plotter operation (POS III, V22/8 at power-on)
        self._boot_timer: Timer | None = None
        mode: Callable[[], str] = lambda: self.mode  # noqa: E731
        booting: Callable[[], bool] = lambda: self.booting  # noqa: E731
        self.screen = Screen(self.record_event, self.announce)
        self.params = MachineParameters(self.nvram, cfg.params)
        self.axes = Axes(self.clock, self.params, self.screen, decimals=cfg.decimals, accel=cfg.accel,
                         kv_per_step=cfg.kv_per_step, encoder_khz=cfg.encoder_khz)
        self.memory = ProgramMemory(
            self.nvram, formats=self._formats, inch=lambda: bool(signals.get("inch")),
            lock_open=lambda: bool(signals.get("program_lock_open")), record=self.record_event,
            max_blocks=cfg.max_blocks_total, protection=cfg.variant == "III")
        self.panel = FrontPanel(self.clock, signals, self.params, self.screen, cfg.v8_keymap)
        self.keyboard = Keyboard(
            self.clock, external=lambda: bool(signals.get("keyboard_external")), accept=self.panel.key,
            event=lambda what, code: self.screen.port_event("v8", what, code),
        )
        self.links = SerialLinks(self.clock, signals, self.params, self.memory, self.screen, cfg, mode=mode,
                                 program=lambda: self.program, booting=booting, send=self._send,
                                 leader_nul=cfg.leader_nul, trailer_nul=cfg.trailer_nul)
        self.field = WorkingField(signals, self.axes, self.params, self.screen,
                                  settings=lambda a: getattr(cfg.axes, a), mode=mode, booting=booting,
                                  left=lambda: (self.executor.left_field(), self.manual.left_field()))
        self.limits = LimitSwitches(signals, self.axes, self.screen, outside_towards=self.field.outside_towards,
                                    homing_turn=self.field.turn_back,
                                    stopped=lambda: (self.manual.reset(), self.executor.abort()))
        self.functions = BlockFunctions(signals, self.screen)
        self.block_motion = BlockMotion(self.axes, self.functions, self.limits, self.params, self.screen,
                                        override=lambda: override(signals), ijk_incremental=cfg.ijk_incremental)
        self.mst = MstBus(self.clock, signals, lambda: max(1.0, self.params.strobe_ms) / 1000.0,
                          self.functions.put)
        self.executor = Executor(
            self.clock, signals, self.mst, self.block_motion, self.functions, ProgramFlow(signals, self.screen, g13_total=cfg.g13_count_is_total),
            self.params, self.screen, mode=mode,
            booting=booting, inside_field=lambda: self.field.inside,
            program=lambda: self.memory.to_run(self.program, self.mode == "MANUAL_SINGLE_BLOCK"),
            stop_manual=lambda: self.manual.reset(),
            options=ExecutionOptions(cfg.variant == "III", cfg.m06_requires_nc_start, cfg.g25_full_circle,
                                     start_stop_status=cfg.variant == "III",
                                     invert_optional_stop=cfg.invert_optional_stop))
        plc = cfg.plc
        self.plc = PlcHelper(self.clock, signals, plc.mst_ack, plc.rise_ms / 1000.0, plc.fall_ms / 1000.0,
                             None if plc.tool_change_ms is None else plc.tool_change_ms / 1000.0,
                             None if plc.m10_release_ms is None else plc.m10_release_ms / 1000.0)
        self.manual = ManualMotion(signals, self.axes, self.params, self.limits, self.screen, mode=mode,
                                   booting=booting, program_moving=lambda: self.executor.state == "MOVING",
                                   feed_pot=lambda: feed_pot(signals))
        self.output_test = OutputTest(self.clock, signals, self.record_event, may_start=lambda: (
            self.mode == "PROGRAM_ENTRY" and not self.executor.running))
        signals.subscribe("emergency_stop", self._not_stop)
        self.cassette: Cassette | None = None
        if cfg.v6_peer == "cassette":
            self.cassette = Cassette(self.clock, self.nvram, function=lambda: self.links.function("v6"),
                                     play=partial(self.port_input, "v6"))
            self.links.peer = self.cassette
            self.listen("v6_out", self.cassette.heard)
        self._port_inputs: dict[str, Callable[[bytes], None]] = {
            "v6": partial(self.links.feed, "v6"), "v7": partial(self.links.feed, "v7"), "v8": self.keyboard.feed}
        self._power_on()

    def _formats(self, inch: bool) -> Any:
        return self.axes.inch_formats if inch else self.axes.formats

    def _send(self, port: str, data: bytes) -> None:
        self.announce(f"{port}_out", data)

    # -- power ----------------------------------------------------------------------------------
    def _power_on(self) -> None:
        """§2.4.5, spec §4.2: all outputs L, the axes where the encoders count from (0)."""
        self.announce("power_on")
        self.terminals.settle()  # the inputs as they are at power-on
        self.mode = "MANUAL"
        self.screen.clear()
        self.panel.keyboard_test = None
        self.panel.page = None
        self.plotter = self.cfg.variant == "III" and bool(self.signals.get("xy_plotter"))  # sampled now only
        for output in OUTPUTS:
            self.signals.set(output.name, output.initial)
        self.booting = self.cfg.boot_time > 0
        if self.booting:
            self._boot_timer = self.clock.call_later(self.cfg.boot_time, self._boot_done)
        else:
            self._boot_done()

    def _boot_done(self) -> None:
        """§2.4.5: after about 2 s the control is in MANUAL, NC ready, mode code on the bus."""
        self._boot_timer = None
        self.signals.set("nc_ready", True)
        self.signals.set("machine_standstill", True)
        self.signals.set("inside_working_field", True)
        self.mst.mode(MODES[self.mode])
        self.booted()

    def power_cycle(self, *, wipe: bool = False) -> None:
        self.close()
        self.output_test.stopped = False
        super().power_cycle(wipe=wipe)  # (the axes stay where they stood)
        self.memory.load()
        self.params.load()
        self._power_on()

    def close(self) -> None:
        self.memory.flush()  # (blocks stored and not yet saved: before a wipe, before the end)
        self.terminals.cancel()
        self.panel.cancel()
        for port in ("v6", "v7"):
            self.links.stop(port, "cancelled")
        self.keyboard.reset()
        if self._boot_timer is not None:
            self._boot_timer.cancel()
        self.executor.emergency_stop()
        self.manual.reset()
        self.field.cancel()
        self.output_test.cancel()
        self.plc.cancel()

    # -- the panel ------------------------------------------------------------------------------
    @property
    def message(self) -> str:
        """The screen message (``panel.message``)."""
        return self.screen.message

    def select_mode(self, mode: str) -> None:
        """A mode change (spec §4.1): refused while a block executes; it cancels a transfer that
        runs (spec §3.5.1: "any --panel.cancel_transfer / mode change--> CANCELLED"); a stopped
        program is abandoned (back to its first block); the mode code goes out (BA, §2.4.8)."""
        if self.executor.running and mode != self.mode:
            raise BadValue(f"block N{self.executor.block_number} executes ({self.executor.state}): "
                           "stop the program first")
        if self.booting:
            raise BadValue("the control is not ready yet")
        if self.output_test.running or self.output_test.stopped:
            raise BadValue("the output test P79 N6 runs or ran: stop it (C) and switch the control off and on")
        self.panel.mode_key()
        if mode != self.mode:
            for port in self.links.busy():
                self.links.stop(port, "cancelled")
            self.manual.reset()
            self.field.cancel()  # a homing search ends with the mode
            self.executor.reset()
            self.mode = mode
            self.screen.clear()
            self.mst.mode(MODES[mode])
            self.record_event("mode")

    def _not_stop(self, _name: str, _old: Any, new: Any) -> None:
        """Not-Stop V19/2 (§2.3.2): L stops the axes at once and gives the program up, the release
        switches to MANUAL.  The output test P79 N6 "läuft unabhängig von der Stellung der
        Steuerungseingänge Not-Stop und NC-Stop ab" (§2.4.11): while it has the outputs (running,
        or stopped by C until the power cycle) the axes stop, the outputs and the mode stay."""
        if self.output_test.running or self.output_test.stopped:
            if not new:
                self.block_motion.quick_stop()
                self.manual.reset()
        elif not new:
            self.executor.emergency_stop()
        else:
            self.emergency_released()

    def emergency_released(self) -> None:
        """Not-Stop released (§2.3.2): the control switches to MANUAL and outputs its code."""
        if self.booting:
            return
        self.mode = "MANUAL"
        self.mst.mode(MODES["MANUAL"])
        self.record_event("mode")

    def select_program(self, number: int) -> None:
        self.program = number

    def press_key(self, key: str) -> None:
        """A front-panel key (spec §3.2.2 ``panel.key``): by its name in ``v8_keymap`` or its
        two-digit hex code; the same path as a key from V8, whichever keyboard V21/9 selects
        ([SIM-CHOICE]: manual §2.6.4 switches "von der internen auf die externe Tastatur"; the
        deviation is in :mod:`~devsim.devices.poselesta.deviations`)."""
        code = self.panel.code_of(key)
        if self.booting:
            raise BadValue("the control is not ready yet")
        self.panel.key(code)

    def set_param(self, number: int, value: float) -> None:
        """A machine parameter entered at the panel (the catalogue P99, spec §4.8).  With the key
        switch locked (V21/8 L) it is refused, as a catalogue read-in is (spec §4.5: "machine
        parameters cannot be changed, keyboard or read-in refused"; the manual's §2.3.10 is lost)."""
        if not self.signals.get("key_switch"):
            self.screen.record("key_switch_locked")
            raise BadValue("the key switch is locked: machine parameters cannot be changed")
        try:
            self.params.write(number, value)
        except ValueError as exc:
            raise BadValue(str(exc)) from None

    # -- the axes' outputs (spec §5.2, §5.9) -------------------------------------------------------
    def following_error(self, axis: str) -> float:
        """e = v / Kv in steady state (spec §5.2), in increments; 0 with Not-Stop, open loop or a
        plotter (actual = command, spec §5.9), and without a gain (P30–P33 = 0, as a catalogue
        read-in that does not carry them leaves them, §2.6.2.3: no position loop either)."""
        if not self.signals.get("emergency_stop") or self.manual.in_open_loop(axis) or self.plotter:
            return 0.0
        kv = self.axes.kv(axis)
        return self.axes[axis].velocity() / kv if kv > 0 else 0.0

    def analog_out(self, axis: str) -> float:
        """The ±10 V set-point: the speed over the drive's speed at 10 V (spec §5.2); for an
        X/Y plotter the position over the working field P9–P16, in 14 bits (spec §5.9)."""
        if self.plotter:
            low, high = self.field.limits(axis)
            if high <= low:
                return 0.0
            share = (self.axes[axis].position() - low) / (high - low)
            steps = round(max(0.0, min(1.0, share)) * (2**14 - 1))
            return -10.0 + 20.0 * steps / (2**14 - 1)
        if not self.signals.get("emergency_stop") or self.manual.in_open_loop(axis):
            return 0.0
        at_10v = self.cfg.drive_speed_factor * self.axes.rapid(axis)
        volts = 10.0 * self.axes[axis].velocity() / at_10v if at_10v > 0 else 0.0
        return max(-10.0, min(10.0, volts))

    # -- bytes from the host ----------------------------------------------------------------------
    def port_input(self, port: str, data: bytes) -> None:
        if self.booting:
            return
        self._port_inputs[port](data)

    def baud(self, port: str) -> int | None:
        return self.links.baud(port)
