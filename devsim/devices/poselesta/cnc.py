"""The POSELESTA II/III control as a model: modes, program memory, machine parameters, the
transfers of V6 and V7 and the V8 keyboard (manual "Schnittstellenbeschreibung POSELESTA II/III"
§2.4.1, §2.4.5, §2.6; spec poselesta.md §3.2, §3.5–§3.10, §4.1, §4.2, §4.8, §4.9).

The serial faces only hand bytes over (:meth:`PoselestaCnc.port_input`) and send what the model
announces on ``<port>_out``.  Transfers are started by the operator's panel actions, here the
points ``panel.mode``, ``panel.program`` and ``v6.transfer`` / ``v7.transfer``.
"""

from __future__ import annotations

import math
from typing import Any

from devsim.core.axis import Axis
from devsim.core.kit import declare_signals
from devsim.core.model import Model
from devsim.core.points import BadValue
from devsim.devices.poselesta.codes import KEY_CODES, WERTBEREICHES_UEBERLAUF, baud_for_code
from devsim.devices.poselesta.config import PoselestaConfig
from devsim.devices.poselesta.diagnostics import OutputTest
from devsim.devices.poselesta.execution import Executor
from devsim.devices.poselesta.keyboard import Keyboard
from devsim.devices.poselesta.limits import LimitSwitches
from devsim.devices.poselesta.manual import ManualMotion
from devsim.devices.poselesta.mst import MstBus, PlcHelper
from devsim.devices.poselesta.parameters import MachineParameters
from devsim.devices.poselesta.peers import Cassette
from devsim.devices.poselesta.signals import AXES, OUTPUTS, SIGNALS
from devsim.devices.poselesta.tape import Block, Formats, TapeReader, block_words, parse_blocks, render
from devsim.devices.poselesta.transfers import (
    CASSETTE_LEADER,
    FUNCTIONS,
    PRINTER_CR_PAUSE,
    Output,
    ReadIn,
)
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
#: The mode a port's transfers need: Σ for V6, EXT for V7 (§2.6).
PORT_MODE = {"v6": "EXTERNAL_MEDIUM", "v7": "EXTERNAL_OPERATION"}
DIAGNOSTICS, CATALOGUE = 79, 99
KEYBOARD_TEST_EXIT = 0x2D  # the key that ends the keyboard test P79 N3 (spec §3.10)
RESERVED_PROGRAMS = (DIAGNOSTICS, CATALOGUE)  # the diagnostics and the parameter catalogue (spec §4.9)


class PoselestaCnc(Model):
    """One POSELESTA control: what its serial ports and its panel reach."""

    def __init__(self, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        self.cfg = PoselestaConfig.parse(self.config)
        self.formats = Formats(dict(self.cfg.decimals))
        # programs typed in inch (V22/2 H) carry two more decimals on X, Y, Z (spec §5.1)
        self.inch_formats = Formats({a: d + (0 if a == "D" else 2) for a, d in self.cfg.decimals.items()})
        declare_signals(self.signals, SIGNALS)
        self.transfers: dict[str, ReadIn | Output | None] = {"v6": None, "v7": None}
        self.last_state = {"v6": "idle", "v7": "idle"}
        self.discarded = {"v6": 0, "v7": 0}
        self.message = ""
        self.mode = "MANUAL"
        self.program = 0
        self.keyboard = Keyboard(
            self.clock, external=lambda: bool(self.signals.get("keyboard_external")),
            accept=self._key, event=lambda what, code: self.transfer_event("v8", what, code),
        )
        self.last_key: int | None = None
        self.relay_supply_lost = False
        self.rm_missing: set[str] = set()  # axes whose reference mark signal is lost (fault)
        self.keyboard_test: str | None = None  # P79 N3 running: what the screen shows ("" before a key)
        self.plotter = False  # X/Y plotter operation (POS III, V22/8 at power-on)
        self._buzzer_timer: Any = None
        self._boot_timer: Any = None
        self.params = MachineParameters(self.nvram, self.cfg.params)
        self.axes = {a: Axis(self.clock, name=a) for a in AXES}
        self.executor = Executor(self)
        self.mst = MstBus(self.clock, self.signals, lambda: max(1.0, self.params.strobe_ms) / 1000.0, self.executor.put)
        plc = self.cfg.plc
        self.plc = PlcHelper(self.clock, self.signals, plc.mst_ack, plc.rise_ms / 1000.0, plc.fall_ms / 1000.0,
                             None if plc.tool_change_ms is None else plc.tool_change_ms / 1000.0,
                             None if plc.m10_release_ms is None else plc.m10_release_ms / 1000.0)
        self.manual = ManualMotion(self)
        self.limits = LimitSwitches(self)
        self.field = WorkingField(self)
        self.output_test = OutputTest(self)
        self.cassette = Cassette(self) if self.cfg.v6_peer == "cassette" else None
        self._load()
        self._power_on()

    # -- memory -------------------------------------------------------------------------------
    def _load(self) -> None:
        stored = self.nvram.get("programs") or {}
        self.programs: dict[int, dict[int, Block]] = {
            int(p): {int(b["N"]): Block.from_json(b) for b in blocks} for p, blocks in stored.items()
        }
        self.protected: set[int] = {int(p) for p in self.nvram.get("protected") or []}
        self.inch_programs: set[int] = {int(p) for p in self.nvram.get("inch_programs") or []}
        self.tools: dict[int, dict[str, float]] = {int(t): dict(v) for t, v in (self.nvram.get("tools") or {}).items()}
        self.params.load()

    def _save_programs(self) -> None:
        self.nvram.put(
            "programs", {str(p): [b.to_json() for _, b in sorted(bs.items())] for p, bs in self.programs.items()}
        )

    # -- power ----------------------------------------------------------------------------------
    def _power_on(self) -> None:
        """§2.4.5, spec §4.2: all outputs L, the axes where the encoders count from (0)."""
        self.mode = "MANUAL"
        self.message = ""
        self.keyboard_test = None
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
        self._load()
        self._power_on()

    def close(self) -> None:
        for port in ("v6", "v7"):
            self._stop(port, "cancelled")
        self.keyboard.reset()
        if self._boot_timer is not None:
            self._boot_timer.cancel()
        self.executor.emergency_stop()
        self.manual.reset()
        self.field.cancel()
        self.output_test.cancel()
        self.plc.cancel()

    # -- the panel ------------------------------------------------------------------------------
    def select_mode(self, mode: str) -> None:
        """A mode change (spec §4.1): refused while a transfer runs or a block executes; a stopped
        program is abandoned (back to its first block); the mode code goes out (BA, §2.4.8)."""
        busy = [p for p, t in self.transfers.items() if t is not None]
        if busy and mode != self.mode:
            raise BadValue(f"a transfer runs on {busy[0]}: cancel it first (v{busy[0][1]}.transfer idle)")
        if self.executor.running and mode != self.mode:
            raise BadValue(f"block N{self.executor.block_number} executes ({self.executor.state}): "
                           "stop the program first")
        if self.booting:
            raise BadValue("the control is not ready yet")
        if self.output_test.running or self.output_test.stopped:
            raise BadValue("the output test P79 N6 runs or ran: stop it (C) and switch the control off and on")
        if mode != self.mode:
            self.manual.reset()
            self.field.cancel()  # a homing search ends with the mode
            self.executor.reset()
            self.mode = mode
            self.message = ""
            self.mst.mode(MODES[mode])
            self.record_event("mode")

    def emergency_released(self) -> None:
        """Not-Stop released (§2.3.2): the control switches to MANUAL and outputs its code."""
        if self.booting:
            return
        self.mode = "MANUAL"
        self.mst.mode(MODES["MANUAL"])
        self.record_event("mode")

    # -- the axes (spec §5.1–§5.3): positions in increments of each axis's resolution ---------------
    def to_mm(self, axis: str, increments: float) -> float:
        return increments / 10 ** self.formats.decimals[axis.upper()]

    def from_mm(self, axis: str, mm: float) -> float:
        return mm * 10 ** self.formats.decimals[axis.upper()]

    def planned_position(self, axis: str) -> float:
        """Where the axis will stand: the end of its plan, or where it is while a key or the
        homing search drives it without an end."""
        end = self.axes[axis].final_position()
        return end if math.isfinite(end) else self.axes[axis].position()

    def check_encoder(self, axis: str, speed: float) -> None:
        """Spec §5.7: the encoder signal is f = v / (4 · resolution); above the adapter's limit
        the event ``encoder_overspeed`` (speed in increments per second)."""
        if abs(speed) / 4 > self.cfg.encoder_khz * 1000:
            self.record_event("encoder_overspeed")
            self.announce("event", "axis", "encoder_overspeed", axis)

    def rapid(self, axis: str) -> float:
        """P44–P47, in increments per second."""
        return self.from_mm(axis, self.params.rapid(axis) / 60.0)

    def max_feed(self, axis: str) -> float:
        """P48–P51, in increments per second."""
        return self.from_mm(axis, self.params.max_feed(axis) / 60.0)

    def accel(self, axis: str) -> float:
        return self.from_mm(axis, self.cfg.accel)

    def _pot(self, name: str, full_scale: float) -> float:
        """A potentiometer input (0 … 10 V) in whole percent of ``full_scale`` %, as a factor."""
        return round(max(0.0, min(10.0, float(self.signals.get(name)))) * full_scale / 10) / 100

    def override(self) -> float:
        """V23/4: 0 … 10 V = 0 … 150 % (6.667 V = 100 %)."""
        return self._pot("override_pot_v", 150)

    def feed_pot(self) -> float:
        """V23/1: 0 … 10 V = 0 … 100 %."""
        return self._pot("feed_pot_v", 100)

    def kv(self, axis: str) -> float:
        """The position loop gain [1/s]: P30–P33 steps × ``kv_per_step`` (spec §5.2)."""
        return self.params.gain(axis) * self.cfg.kv_per_step

    def display(self, axis: str) -> str:
        """The actual value as the screen shows it (spec §5.1): mm with the axis's decimals, or
        with V22/2 H inch with two more (100.001 mm → 3.93705); D is not converted."""
        decimals = self.formats.decimals[axis.upper()]
        value = self.to_mm(axis, self.axes[axis].position())
        if self.signals.get("inch") and axis != "d":
            return f"{value / 25.4:.{decimals + 2}f}"
        return f"{value:.{decimals}f}"

    def following_error(self, axis: str) -> float:
        """e = v / Kv in steady state (spec §5.2), in increments; 0 with Not-Stop, open loop or a
        plotter (actual = command, spec §5.9)."""
        if not self.signals.get("emergency_stop") or self.manual.in_open_loop(axis) or self.plotter:
            return 0.0
        return self.axes[axis].velocity() / self.kv(axis)

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
        at_10v = self.cfg.drive_speed_factor * self.rapid(axis)
        volts = 10.0 * self.axes[axis].velocity() / at_10v if at_10v > 0 else 0.0
        return max(-10.0, min(10.0, volts))

    def select_program(self, number: int) -> None:
        self.program = number

    def clear_message(self) -> None:
        self.message = ""

    # -- program lock (POS III, §2.3.21; spec §4.5 G-LOCK) ------------------------------------------
    def protect(self, number: int, on: bool) -> None:
        """Protect a program (in any position of V22/9) or release it (only while V22/9 is H)."""
        if self.cfg.variant != "III":
            raise BadValue("program protection is a POS III function")
        if not on and not self.signals.get("program_lock_open"):
            self.record_event("program_locked")
            raise BadValue(f"P{number:02d} can only be released with the program lock open (V22/9 H)")
        (self.protected.add if on else self.protected.discard)(number)
        self.nvram.put("protected", sorted(self.protected))

    def program_formats(self, number: int) -> Formats:
        """The word formats a program was typed in: mm, or inch with two more decimals."""
        return self.inch_formats if number in self.inch_programs else self.formats

    def _typed(self, number: int, inch: bool) -> None:
        """A program is (re)entered: in inch while V22/2 is H (stored as typed, spec §5.1)."""
        if inch != (number in self.inch_programs):
            (self.inch_programs.add if inch else self.inch_programs.discard)(number)
            self.nvram.put("inch_programs", sorted(self.inch_programs))

    def _refuse_protected(self, number: int) -> None:
        if number in self.protected:
            self.record_event("program_protected")
            raise BadValue(f"P{number:02d} is protected: release it first (program lock open)")

    def transfer_name(self, port: str) -> str:
        running = self.transfers[port]
        if running is None:
            return "idle"
        return next(name for (p, name), f in FUNCTIONS.items() if p == port and f is running.function)

    def transfer_state(self, port: str) -> str:
        running = self.transfers[port]
        return running.state if running is not None else self.last_state[port]

    def set_transfer(self, port: str, name: str) -> None:
        if name == "idle":
            self._stop(port, "cancelled")
            return
        self.start_transfer(port, name)

    def start_transfer(self, port: str, name: str) -> None:
        """Start T1 … T7 from the panel (spec §3.2.2 ``panel.start_transfer``)."""
        function = FUNCTIONS[(port, name)]
        if self.booting:
            raise BadValue("the control is not ready yet")
        if self.mode != PORT_MODE[port]:
            self.transfer_event(port, "wrong_mode", self.mode)
            raise BadValue(f"{function.name} needs mode {PORT_MODE[port]}, the control is in {self.mode}")
        if self.transfers[port] is not None:
            raise BadValue(f"a transfer runs on {port} already (busy)")
        program = self.program
        if program == DIAGNOSTICS:
            raise BadValue("P79 is the diagnostic program, not a program to transfer")
        catalogue = program == CATALOGUE
        if function.direction == "input":
            self._refuse_protected(program)  # before anything is deleted
        if catalogue and function.direction == "input" and not self.signals.get("key_switch"):
            self.record_event("key_switch_locked")
            raise BadValue("the key switch is locked: the parameter catalogue cannot be read in")
        if self.baud(port) is None:
            self.message = WERTBEREICHES_UEBERLAUF
            raise BadValue(f"P{self.params.baud_code_key(port)}: baud rate code not available on POS {self.cfg.variant}")
        self.message = ""
        self.record_event(f"{function.name}_start")
        if function.direction == "input":
            line = None
            if catalogue:
                if self.cfg.variant == "III":  # the line stays as it was at the start (spec §3.9)
                    line = (self.baud(port), self.iso(port))
                    if self.params.baud_code(port) > 3:
                        self.message = WERTBEREICHES_UEBERLAUF
                        raise BadValue("the catalogue is read at up to 1200 baud (P68/P70 ≤ 3)")
                self.params.begin_catalogue()  # the whole catalogue is 0 first, P68–P71 too: POS II
                # so reads it at 110 baud ISO (§2.6.2.3)
            else:
                self.programs.pop(program, None)  # "zuerst das vorgewählte Programm gelöscht" (§2.6)
                self._save_programs()
                self._typed(program, bool(self.signals.get("inch")))
            reader = TapeReader(
                iso=self.iso(port) if line is None else line[1], formats=self.program_formats(program), parity_error=self.cfg.parity_error,
                ascii_bit7=self.cfg.ascii_bit7, strict_block_numbers=self.cfg.strict_block_numbers,
                catalogue=catalogue,
            )
            leader = CASSETTE_LEADER if function.name == "T3" else 0.0
            if port == "v6":
                self._v6_lines(True, record=function.name != "T3")  # the cassette plays: RTS L
            read_in = ReadIn(self, function, program, reader, leader)
            read_in.line = line
            self.transfers[port] = read_in
        else:
            blocks = self.params.catalogue_blocks() if catalogue else list(self.programs.get(program, {}).values())
            pieces = self._output_pieces(function.name, port, blocks, self.program_formats(program))
            if port == "v6":
                self._v6_lines(True)
            self.transfers[port] = Output(self, function, program, pieces, len(blocks))
        if self.cassette is not None and port == "v6":
            self.cassette.started(function.name)  # (after the transfer: its leader ends first)

    def _output_pieces(self, name: str, port: str, blocks: list[Block], formats: Formats) -> list[tuple[float, bytes]]:
        iso = self.iso(port)
        if name == "T1":
            return self._printer_pieces(blocks, formats)
        eob = "\r\n" if self.cfg.eob == "CRLF" else "\r"
        data = render(blocks, iso=iso, formatted=port == "v6", formats=formats, eob=eob,
                      leader_nul=self.cfg.leader_nul, trailer_nul=self.cfg.trailer_nul)
        return [(CASSETTE_LEADER if name == "T2" else 0.0, data)]

    def _printer_pieces(self, blocks: list[Block], formats: Formats) -> list[tuple[float, bytes]]:
        """§2.6.2.1: one word per line, CR without LF, 820 ms after every CR; 7 bits with bit 7
        = 0 whatever P69 says (the printer's parity is a ninth bit a byte cannot carry)."""
        lines = ["%", "", ""]  # "%" CR CR CR
        for block in sorted(blocks, key=lambda b: b.number):
            lines += block_words(block, formats, formatted=True)
        lines.append("M 30")
        pieces: list[tuple[float, bytes]] = []
        wait = 0.0
        for line in lines:
            pieces.append((wait, (line + "\r").encode("ascii")))
            wait = PRINTER_CR_PAUSE
        return pieces

    def _stop(self, port: str, state: str) -> None:
        """The panel ends a running transfer (cancel, power off)."""
        if self.transfers[port] is not None:
            self.transfer_ended(port, state)
            self.transfer_event(port, state)

    # -- what the transfers call ----------------------------------------------------------------
    def transfer_event(self, port: str, what: str, detail: Any = None) -> None:
        self.record_event(f"{port}.{what}")
        self.announce("event", port, what, detail)

    def transfer_ended(self, port: str, state: str, message: str | None = None) -> None:
        """A transfer is over (``done``, ``failed``, ``cancelled``): the port is idle again,
        V6's RTS/DTR drop, and a failure shows its screen message."""
        running = self.transfers[port]
        if running is not None:
            running.cancel()
            if self.cassette is not None and port == "v6":
                self.cassette.ended(running.function.name, state)
            if running.program == CATALOGUE and running.function.direction == "input" and state == "done":
                self.params.commit_catalogue()  # the parameters act after M30 (spec §3.9)
        self.transfers[port] = None
        self.last_state[port] = state
        if port == "v6":
            self._v6_lines(False)
        if state == "failed":
            self.message = WERTBEREICHES_UEBERLAUF

    def store_block(self, program: int, block: Block) -> str | None:
        """A block read in; returns why it cannot be stored (the read-in fails), or None."""
        if program == CATALOGUE:
            return self.params.store_catalogue(block)
        blocks = self.programs.setdefault(program, {})
        total = sum(len(b) for b in self.programs.values())
        if block.number not in blocks and total >= self.cfg.max_blocks_total:
            return "memory full"
        blocks[block.number] = block
        self._save_programs()
        return None

    def send(self, port: str, data: bytes) -> None:
        self.announce(f"{port}_out", data)

    def char_time(self, port: str) -> float:
        """Seconds per character on the port: the frame of §2.3 at the port's baud rate."""
        running = self.transfers[port]
        if port == "v6" and running is not None and running.function.name == "T1":
            return (12 if self.params.iso("v6") else 11) / 1200
        return (11 if self.iso(port) else 10) / (self.baud(port) or 110)

    # -- line settings --------------------------------------------------------------------------
    def iso(self, port: str) -> bool:
        running = self.transfers.get(port)
        if isinstance(running, ReadIn) and running.line is not None:
            return running.line[1]
        return port == "v8" or self.params.iso(port)

    def baud(self, port: str) -> int | None:
        """The port's baud rate: P68 (V6), P70 (V7); the printer 1200, the POS II cassette 300,
        V8 1200 (§2.2 of the spec)."""
        if port == "v8":
            return 1200
        running = self.transfers.get(port)
        if isinstance(running, ReadIn) and running.line is not None:
            return running.line[0]  # the line of this read-in, captured at its start
        name = running.function.name if running is not None else ""
        if name == "T1":
            return 1200
        if name in ("T2", "T3") and self.cfg.variant == "II":
            return 300
        if name in ("T2", "T3"):
            return {1: 300, 3: 1200, 5: 4800}.get(self.params.baud_code("v6"), 300)
        return baud_for_code(self.params.baud_code(port), self.cfg.variant)

    # -- V6 modem lines ---------------------------------------------------------------------------
    def _v6_lines(self, on: bool, record: bool = True) -> None:
        """RTS and DTR: H while a V6 transfer runs (printer, punch); the cassette: DTR = run,
        RTS = record (spec §3.8, G-V6LINES)."""
        self.signals.set("v6_dtr", on)
        self.signals.set("v6_rts", on and record)

    # -- bytes from the host ----------------------------------------------------------------------
    def port_input(self, port: str, data: bytes) -> None:
        if self.booting:
            return
        if port == "v8":
            self.keyboard.feed(data)
            return
        running = self.transfers[port]
        if running is None:
            self.discarded[port] += len(data)  # no input function active (spec §2.6)
            return
        running.feed(data)

    def press_key(self, key: str) -> None:
        """A front-panel key (spec §3.2.2 ``panel.key``): by its name in ``v8_keymap`` or its
        two-digit hex code; the same path as a key from V8, whichever keyboard V21/9 selects."""
        names = {name.upper(): code for code, name in self.cfg.v8_keymap.items()}
        code = names.get(key.strip().upper())
        if code is None:
            try:
                code = int(key, 16)
            except ValueError:
                raise BadValue(f"no key {key!r}: a name of v8_keymap ({', '.join(sorted(names))}) or a hex code")\
                    from None
        if code not in KEY_CODES:
            raise BadValue(f"{code:02X} is not a key code of the keyboard (spec §3.10)")
        if self.booting:
            raise BadValue("the control is not ready yet")
        self._key(code)

    def edit_block(self, text: str) -> None:
        """Program entry of one block (spec §3.2.2 ``panel.edit_block``): ``"20: N5 X10"`` stores
        (or replaces) block N5 of P20, by the rules of a read-in."""
        number_text, sep, block_text = text.partition(":")
        if not sep or not number_text.strip().lstrip("Pp").isdigit():
            raise BadValue("expected 'program: block', e.g. '20: N5 X10'")
        number = int(number_text.strip().lstrip("Pp"))
        if number in RESERVED_PROGRAMS or not 0 <= number <= 98:
            raise BadValue(f"P{number:02d} is not an NC program")
        self._refuse_protected(number)
        if number not in self.programs:
            self._typed(number, bool(self.signals.get("inch")))
        try:
            blocks = parse_blocks(block_text, self.program_formats(number))
        except ValueError as exc:
            raise BadValue(str(exc)) from None
        if len(blocks) != 1:
            raise BadValue("exactly one block with its number N is entered at a time")
        problem = self.store_block(number, blocks[0])
        if problem is not None:
            raise BadValue(f"{WERTBEREICHES_UEBERLAUF}: {problem}")

    def _key(self, code: int) -> None:
        self.last_key = code
        self.transfer_event("v8", "key_name", self.cfg.v8_keymap.get(code, f"{code:02X}"))
        if self.keyboard_test is not None:  # P79 N3: the code + 1 on the screen; 2D ends the test
            self.keyboard_test = None if code == KEYBOARD_TEST_EXIT else f"{code + 1:02X}"
        self.transfer_event("v8", "key", code)
        if self.params.buzzer_off == 0:
            self.signals.set("buzzer", True)
            if self._buzzer_timer is not None:
                self._buzzer_timer.cancel()
            self._buzzer_timer = self.clock.call_later(0.1, lambda: self.signals.set("buzzer", False))

    # -- programs and parameters as points ----------------------------------------------------------
    def program_text(self, number: int) -> str:
        blocks = sorted(self.programs.get(number, {}).values(), key=lambda b: b.number)
        formats = self.program_formats(number)
        return "\n".join(" ".join(block_words(b, formats, formatted=True)) for b in blocks)

    def set_program_text(self, number: int, text: str) -> None:
        """Program entry (spec §3.2.2 ``panel.edit_block``): blocks typed as text replace the
        program; the same rules as a read-in."""
        if number in RESERVED_PROGRAMS:
            raise BadValue(f"P{number:02d} is not an NC program")
        self._refuse_protected(number)
        inch = bool(self.signals.get("inch"))
        try:
            blocks = parse_blocks(text, self.inch_formats if inch else self.formats)
        except ValueError as exc:
            raise BadValue(str(exc)) from None
        others = sum(len(b) for p, b in self.programs.items() if p != number)
        if others + len(blocks) > self.cfg.max_blocks_total:
            raise BadValue(f"{WERTBEREICHES_UEBERLAUF}: program memory full")
        if blocks:
            self.programs[number] = {b.number: b for b in blocks}
        else:
            self.programs.pop(number, None)
        self._save_programs()
        self._typed(number, inch)

    def set_tool(self, number: int, value: Any) -> None:
        """The tool catalogue (spec §4.9): radius and length of T01 … T99, in the catalogue's unit
        (P1); kept in memory, not transferable serially."""
        if not isinstance(value, dict) or set(value) - {"radius", "length"}:
            raise BadValue('expected {"radius": r, "length": l}')
        entry = {}
        for key in ("radius", "length"):
            number_value = value.get(key, 0.0)
            if isinstance(number_value, bool) or not isinstance(number_value, int | float) or \
                    not math.isfinite(number_value):
                raise BadValue(f"T{number:02d}.{key}: a finite number")
            entry[key] = float(number_value)
        self.tools[number] = entry
        self.nvram.put("tools", {str(t): v for t, v in sorted(self.tools.items())})

    def set_param(self, number: int, value: float) -> None:
        try:
            self.params.write(number, value)
        except ValueError as exc:
            raise BadValue(str(exc)) from None
        if 9 <= number <= 16:
            self.field.rearm()
