"""The GMS96 servo amplifier card as a model (manual "GMS96 Softwarebeschreibung", v4.04).

The card's state, knowing no protocol: power-on / reset (spec §4.1.2), DIL switch (§2.2),
status bytes (§4.3), markers (§4.4), faults (§4.5.3: emergency stop, following error,
monitoring, I²t, output overload), persistence (§4.8), N parameters and the queued settings.
The FT1.2 link and the command dispatch are the face (:mod:`.face`, :mod:`.link`); the executor
of queued commands is :mod:`.executor`, the indexer and position loop :mod:`.motion`, reference
runs :mod:`.reference`, the process image :mod:`.image`.
"""

from __future__ import annotations

import math
from typing import Any

from devsim.core.axis import Axis
from devsim.core.clock import Clock, Timer
from devsim.core.kit import declare_signals
from devsim.core.model import Model
from devsim.core.nvram import NonVolatileMemory
from devsim.core.settings import Values
from devsim.devices.gms96 import codec, tables
from devsim.devices.gms96.commands import QueuedCommands
from devsim.devices.gms96.config import Gms96Config
from devsim.devices.gms96.counter import CounterInput
from devsim.devices.gms96.executor import Cmd, Executor
from devsim.devices.gms96.image import ProcessImage
from devsim.devices.gms96.motion import ActualSwitch, Indexer
from devsim.devices.gms96.params import NParameters
from devsim.devices.gms96.plc import Plc
from devsim.devices.gms96.points import INPUT_BYTES, SIGNALS
from devsim.devices.gms96.program import ProgramControl
from devsim.devices.gms96.settings import Settings
from devsim.devices.gms96.spindle import Spindle

__all__ = ["Gms96Card"]

ACK = bytes([codec.ACK])
OUTPUT_BITS = 11  # A0.0..A1.2
I_BASE, K_ACC, A_REF = 0.05, 0.3, 50000.0  # motor current model (spec §5.7)


class Gms96Card(Settings, Model):
    """One GMS96 card: axis, I/O, N parameters, programs, PLC, faults and memory."""

    def __init__(
        self,
        *,
        clock: Clock,
        config: dict[str, Any] | None = None,
        nvram: NonVolatileMemory | None = None,
        name: str = "",
    ) -> None:
        super().__init__(clock=clock, config=config, nvram=nvram, name=name)
        self.cfg = Gms96Config.parse(self.config)
        self.silent_until = 0.0  # the card ignores the line until then (boot, flash erase)
        #: Frames the link dropped, by reason (checksum, length, not_idle ...).
        self.link_errors: dict[str, int] = {}
        self.hw = tables.variant(self.cfg.variant)
        self.stepper = self.hw.stepper
        self.pending_dil: Values = self.cfg.dil
        self.dil: Values = self.cfg.dil
        geo = self.cfg.axis
        self.axis = Axis(clock, counts_per_rev=geo.index_period, index_offset=geo.index_offset, name=self.name)
        self.image = ProcessImage()
        self.indexer = Indexer(self, self.axis)
        self.params = NParameters(factory=self.cfg.params, stepper=self.stepper, out_of_range=self.cfg.out_of_range)
        self.executor = Executor(self, lambda cmd: self.commands.run(cmd))
        self.program = ProgramControl(self.executor, self)
        self.commands = QueuedCommands(self.executor, self.program, self)
        self.plc_image: str | None = None
        self.plc_frames: list[int] = []
        self.plc = Plc(self)
        self.counter = CounterInput(self)
        self.spindle = Spindle(self.indexer, self.params, lambda: float(self.signals.get("ref_pulse_hz")), self.changed)
        self._define_signals()
        self._switches: list[ActualSwitch] = []
        self._build_switches()
        self.powered = False
        self.origin = 0.0
        self._changing = False
        self._timers: list[Timer] = []
        self._h7_timer: Timer | None = None
        self._inpos_timer: Timer | None = None
        self._inpos_fired = -math.inf
        self._power_on(first=True)

    # ======================================================================================
    # signals and geometry
    # ======================================================================================
    def _define_signals(self) -> None:
        s = self.signals
        declare_signals(s, SIGNALS)
        s.signal("override_pot").value = float(self.cfg.override_pot_pct)
        for byte in range(INPUT_BYTES):
            for bit in range(8):
                s.subscribe(f"E{byte}.{bit}", self._on_input)
        s.subscribe("emergency_stop", lambda *_: self._on_estop())
        s.subscribe("override_pot", lambda *_: self.indexer.replan())
        s.subscribe("load_pct", lambda *_: self._i2t_update())
        s.subscribe("blocked", lambda *_: self._update_block())
        s.subscribe("monitoring", lambda *_: self._on_monitoring())
        s.subscribe("output_overload", lambda *_: self._on_overload())
        s.subscribe("ref_pulse_hz", lambda *_: self.spindle.pulse_rate_changed())

    def _build_switches(self) -> None:
        """Cam and limit switches act on the ACTUAL position (set-point - v/Kv, spec §5.6,
        §5.11): they switch v/Kv later than the set-point passes them."""
        geo = self.cfg.axis
        if geo.cam is not None:
            lo, hi = geo.cam
            nc = geo.cam_polarity == "NC"

            def cam(active: bool) -> None:
                self.signals.set(geo.cam_input, active != nc)

            sw = ActualSwitch(self.indexer, lo, hi, cam)
            self._switches.append(sw)
            self.signals.signal(geo.cam_input).value = sw.active != nc
        for ls in geo.limit_switches:
            name = ls.input

            def follow(active: bool, name: str = name) -> None:
                self.signals.set(name, active)

            sw = ActualSwitch(self.indexer, -math.inf if ls.low is None else ls.low, math.inf if ls.high is None else ls.high, follow)
            self._switches.append(sw)
            self.signals.signal(name).value = sw.active

    # ======================================================================================
    # power, reset, persistence (spec §4.1.2, §4.8)
    # ======================================================================================
    def _power_on(self, first: bool = False) -> None:
        for t in self._timers:
            t.cancel()
        self._timers = []
        self.powered = True
        self.dil = self.pending_dil
        self.address = self.dil.address
        self.e_version = self.dil.protocol == "E"
        self.announce("power_on")  # the link starts afresh (decoder, FCB)
        self.silent_until = 0.0
        if self.cfg.boot_time > 0:
            self.silence(self.cfg.boot_time)
        self.booting = self.cfg.boot_time > 0
        if self.booting:
            self._timers.append(self.clock.call_later(self.cfg.boot_time, self._boot_done))
        self.executor.flush()
        self.executor.rejected_moves = 0
        self.indexer.target = None
        self.indexer.jog_dir = 0
        if self.axis.moving:
            self.axis.quick_stop()
        if first or self.cfg.axis.position_after_reset == "zero":
            self.origin = self.axis.position()
        self.image = ProcessImage()
        self._load_eeprom()
        self.counter.power_on()
        st = self.nvram.get("static", {}) or {}
        self.image.restore_static(st.get("data"))
        self.image.markers[18] = int(st.get("mb18", 0)) & 0xFF
        flash = self.nvram.get("flash", {}) or {}
        self.programs: dict[int, list[list[Any]]] = {int(k): v for k, v in (flash.get("programs") or {}).items()}
        self.plc_image = flash.get("plc")
        self.plc_frames = list(flash.get("plc_frames") or ([len(self.plc_image) // 2] if self.plc_image else []))
        offs = self.nvram.get("offsets", {}) or {}
        self.zero_table: dict[int, int] = {int(k): int(v) for k, v in (offs.get("table") or {}).items()}
        self.machine_zero = int(offs.get("machine_zero", 0))
        self.brake_output = self.params.brake_output == 1
        self.f = self.M
        self.f_frac = 0
        self.g_relative = False
        self.feed_mode = 94
        self.active_zero: int | None = None
        self.tool_active = True
        self.before_g53: tuple[int | None, bool] = (None, True)
        self.g92 = 0
        self.g96: int | None = None  # G96 cutting speed (executor._x_G)
        self.o2_value: int | None = None
        self.ext_override: int | None = None
        self.spindle_rpm = 0
        self.spindle.on = False
        self.estop = bool(self.signals.get("emergency_stop"))
        self.idxoff = True
        self.controller = not self.estop and not self.monitoring_cause() and not self.nv_error
        self.download: tuple[str, int, list[list[Any]]] | None = None
        self.waiting_in_position = False
        self.h22_active = False
        self.i2t_q = 0.0
        self.i2t_t = self.clock.now()
        self.i2t_limiting = False
        self.i2t_latched = False
        self._i2t_timer: Timer | None = None
        self._overload_latched = bool(self.signals.get("output_overload"))
        self.indexer.blocked_at = None
        self._update_block()
        self.record_event("power_on")
        self.plc.power_on()
        self.changed()

    def _boot_done(self) -> None:
        self.record_event("ready")
        self.booted()

    def silence(self, seconds: float) -> None:
        """The card does not listen for ``seconds`` (boot, flash erase, manual §2.3.1 p)."""
        self.silent_until = max(self.silent_until, self.clock.now() + seconds)

    @property
    def silent(self) -> bool:
        return self.clock.now() < self.silent_until or not self.powered

    def _load_eeprom(self) -> None:
        self.nv_error = bool(getattr(self.nvram, "corrupt", False))
        ee = self.nvram.get("eeprom")
        self.params.power_on(ee)
        self.M = tables.DEFAULTS["M"]
        self.B = tables.DEFAULTS["B"]
        self.S = tables.DEFAULTS["S"]
        self.override_on = bool(tables.DEFAULTS["override_active"])
        if ee:
            self.M, self.B, self.S = int(ee["M"]), int(ee["B"]), int(ee["S"])
            self.override_on = bool(ee.get("o", 1))
        self.eeprom_M = self.M

    def save_eeprom(self) -> None:
        """``s85;170``: M, S, B, all N and the override activity (manual §2.3.1 s)."""
        self.nvram.put(
            "eeprom",
            {"M": self.M, "B": self.B, "S": self.S, "o": int(self.override_on),
             **self.params.eeprom()},
        )
        self.eeprom_M = self.M
        self.record_event("eeprom_saved")

    def save_static(self) -> None:
        self.nvram.put("static", {"data": self.image.static_data(), "mb18": self.image.markers[18] & 0x7F})

    def save_flash(self) -> None:
        self.nvram.put(
            "flash",
            {"programs": {str(k): v for k, v in self.programs.items()}, "plc": self.plc_image,
             "plc_frames": list(self.plc_frames)},
        )

    def save_offsets(self) -> None:
        self.nvram.put("offsets", {"table": {str(k): v for k, v in self.zero_table.items()}, "machine_zero": self.machine_zero})

    def power_cycle(self, *, wipe: bool = False) -> None:
        self._power_off()
        if wipe:
            self.nvram.wipe()
        self._power_on()

    def _power_off(self) -> None:
        self.save_static()
        self.powered = False
        self.plc.power_off()
        self.executor.flush()
        self.indexer.power_off(brake=True)

    def reset(self) -> None:
        """A reset (emergency-stop release): like power-on, DIL re-read (manual §2.2)."""
        self._power_on()

    def power(self, on: bool) -> None:
        """The supply switched off or on (the ``power`` fault)."""
        if on:
            self._power_on()
        else:
            self._power_off()

    def close(self) -> None:
        for t in self._timers:
            t.cancel()
        self.plc.power_off()
        self.executor.flush()

    # ======================================================================================
    # small helpers used by the executor, indexer and reference runs
    # ======================================================================================
    def v_factor(self) -> int:
        return tables.v_factor(self.M)

    def nv_M(self) -> int:  # noqa: N802 - the manual's name
        return self.eeprom_M

    def monitoring_cause(self) -> str:
        return str(self.signals.get("monitoring") or "")

    def stop_marker(self) -> bool:
        return self.image.marker(0, 0)

    def enable_blocked(self) -> bool:
        return self.params.enable_input == 1 and not self.signals.get("E0.0")

    def can_move(self) -> bool:
        if self.counter.active:
            return False  # the counter input is the set-point source (spec §5.10)
        return not (self.estop or self.monitoring_cause() or self.nv_error or not self.controller or self.idxoff)

    def activate_controller(self) -> None:
        """Q3 / start of every Q: set-point := actual, position controller on (spec §5.6)."""
        if self.estop or self.monitoring_cause() or self.nv_error:
            return
        if not self.controller:
            actual = self.indexer.actual()
            if not self.axis.moving:
                self.axis.set_position(actual)
            self.controller = True
        self.indexer.arm_following_error()
        self.changed()

    def physical_to_machine(self, x: float) -> float:
        return x - self.origin

    def machine_to_physical(self, m: float) -> float:
        return m + self.origin

    def offsets(self) -> float:
        z = self.zero_table.get(self.active_zero, 0) if self.active_zero is not None else 0
        return z + (self.cfg.tool_offset if self.tool_active else 0)

    def work_to_physical(self, w: float) -> float:
        return w + self.offsets() + self.origin

    def setpoint_work(self) -> int:
        return int(round(self.axis.position() - self.origin - self.offsets()))

    def set_counter_here(self, value: float) -> None:
        """Position counter := ``value`` (machine coordinates) at the current set-point."""
        self.origin = self.axis.position() - value

    def following_error_fault(self, reason: str) -> None:
        """|e| > N20 (spec §4.5.3): IDXOFF, controller off, motion aborted, queue flushed."""
        if not self.controller:
            return
        self.record_event("following_error")
        self.announce("fault", 1, 0x8611)  # CiA 402's following error (a CANopen facade sends EMCY)
        self.idxoff = True
        self.controller = False
        self.spindle.on = False
        self.executor.flush()
        self.indexer.power_off(brake=True)
        self.changed()

    # -- outputs ----------------------------------------------------------------------------
    def output_bit(self, n: int) -> bool:
        if self._overload_latched:
            return False
        if n == 0 and self.brake_output:
            return self.controller and not self.estop and not self.monitoring_cause()
        if n == 1 and self.params.in_position_window > 0:
            return self.in_position()
        return bool(self.image.outputs[n // 8] >> (n % 8) & 1)

    def write_output(self, n: int, value: bool) -> None:
        byte, bit = divmod(n, 8)
        if value:
            self.image.outputs[byte] |= 1 << bit
        else:
            self.image.outputs[byte] &= ~(1 << bit) & 0xFF
        self.changed()

    def in_position(self) -> bool:
        """Spec §5.5: set-point finished and |e| <= |N27| for >= N28 ms (while the axis stands the
        modelled following error is constant, so the N28 time runs from the set-point's stop);
        N27 = 0 (or a stepper card): set-point finished."""
        since = self.axis.stopped_since()
        if since is None:
            return False
        window = abs(self.params.in_position_window)
        if window == 0 or self.stepper:
            return True
        if abs(self.indexer.following_error()) > window:
            return False
        return self.clock.now() >= since + self.params.in_position_time_ms / 1000.0

    def arm_in_position(self) -> None:
        """Re-evaluate the outputs and waits (A0.1, H2) when the set-point stops and N28 later."""
        if self._inpos_timer is not None:
            self._inpos_timer.cancel()
            self._inpos_timer = None
        segs = self.axis.segments() if self.axis.moving else []
        end = segs[-1].t1 if segs else self.axis.stopped_since()
        if end is None or end == math.inf:
            return
        now = self.clock.now()
        for due in (end, end + self.params.in_position_time_ms / 1000.0):
            if due >= now and due > self._inpos_fired:
                self._inpos_timer = self.clock.call_at(due, lambda due=due: self._in_position_tick(due))
                return

    def _in_position_tick(self, due: float) -> None:
        self._inpos_timer = None
        self._inpos_fired = due
        self.arm_in_position()
        self.changed()

    def output_byte(self, byte: int) -> int:
        if byte == 2:
            return 0 if self._overload_latched else self.image.outputs[2]
        if byte > 2:
            return 0
        return sum(1 << b for b in range(8) if byte * 8 + b < 16 and self.output_bit(byte * 8 + b))

    def input_byte(self, byte: int) -> int:
        if not 0 <= byte < INPUT_BYTES:
            return 0
        value = sum(1 << b for b in range(8) if self.signals.get(f"E{byte}.{b}"))
        if byte == 2 and self._overload_latched:
            value |= 0x04
        return value

    # -- markers ----------------------------------------------------------------------------
    def marker_byte(self, byte: int) -> int:
        """MB0/MB1/MB3 carry status bits the firmware keeps (spec §4.4)."""
        m = self.image.markers
        if byte == 0:
            v = m[0] & 0x07
            v |= 0x08 if self.motion() else 0
            v |= 0x10 if not self.estop else 0
            v |= 0x20 if self.controller else 0
            v |= 0x40 if self.monitoring_cause() else 0
            v |= 0x80 if self.idxoff else 0
            return v
        if byte == 1:
            v = m[1] & 0xE9
            v |= 0x02 if self.i2t_latched else 0
            v |= 0x04 if not self.busy() else 0
            v |= 0x10 if self.axis.phase() == "const" else 0
            return v
        if byte == 3:
            v = m[3] & 0xCF
            v |= 0x10 if self.params.motion_disabled == 1 else 0
            v |= 0x20 if self.executor.wait_name == "H2" else 0
            return v
        return m[byte] if 0 <= byte < 256 else 0

    def write_marker_byte(self, byte: int, value: int) -> None:
        """``p11`` / PLC: MB(byte) := value; the control bits of MB0/MB1 act (spec §4.4)."""
        if not 0 <= byte < 256:
            return
        value &= 0xFF
        m = self.image.markers
        if byte == 0:
            old = m[0]
            m[0] = value & 0x07
            if (value & 0x02) and not (old & 0x02):
                self.executor.abort()
                m[0] &= ~0x02
            if (value & 0x04) and not (old & 0x04):
                self.executor.submit(Cmd("p", 3, 1, m[2], 3))
            if (value ^ old) & 0x01:
                self.indexer.replan()
        elif byte == 1:
            m[1] = (m[1] & 0x01) | (value & 0xE8)
        elif byte == 18:
            m[18] = value
            self.save_static()
        else:
            m[byte] = value
        self.changed()

    def write_marker_bit(self, byte: int, bit: int, value: bool) -> None:
        cur = self.image.markers[byte]
        self.write_marker_byte(byte, (cur | (1 << bit)) if value else (cur & ~(1 << bit)))

    # -- status (spec §4.3) -------------------------------------------------------------------
    def busy(self) -> bool:
        return self.executor.busy

    def motion(self) -> bool:
        return (
            self.axis.moving
            or self.executor.reference is not None
            or self.spindle.on
            or self.image.marker(1, 5)
        )

    def status(self) -> int:
        s = tables.STATUS_BITS
        v = 0
        v |= s["ESTOP"] if self.estop else 0
        v |= s["MOTION"] if self.motion() else 0
        v |= s["MONITORING"] if self.monitoring_cause() else 0
        v |= s["IDXOFF"] if self.idxoff else 0
        v |= s["BUSY"] if self.busy() else 0
        v |= s["I2T_ACTIVE"] if self.i2t_limiting else 0
        v |= s["I2T_LATCHED"] if self.i2t_latched else 0
        v |= s["MESSAGE"] if self.image.markers[4] else 0
        return v

    def memory_status(self) -> int:
        s = tables.MEMORY_STATUS_BITS
        v = 0 if self.plc.running else s["PLC_NOT_RUNNING"]
        if self.plc.storage_error and not self.dil.interpolation:
            v |= s["PLC_STORAGE_ERROR"]
        if self.nv_error:
            v |= s["NV_ERROR"] | s["EEPROM_DEFECTIVE"]
        if getattr(self, "cnc_storage_error", False):
            v |= s["CNC_STORAGE_ERROR"]
        return v

    # ======================================================================================
    # events from inputs and quantities
    # ======================================================================================
    def changed(self) -> None:
        """Outputs follow the state; waiting commands re-check their condition."""
        if self._changing:
            return
        self._changing = True
        try:
            for n in range(16):
                self.signals.set(f"A{n // 8}.{n % 8}", self.output_bit(n) if n < OUTPUT_BITS else False)
            self.executor.poke()
        finally:
            self._changing = False

    def _on_input(self, name: str, old: Any, new: Any) -> None:
        self.program.input_edge(name, bool(new))
        if name == "E0.0" and self.params.enable_input == 1:
            self.indexer.replan()
        self.changed()

    def _on_estop(self) -> None:
        active = bool(self.signals.get("emergency_stop"))
        if active and not self.estop:
            self.estop = True
            self.idxoff = True
            self.controller = False
            self.spindle.on = False
            self.executor.flush()
            self.image.set_marker(0, 2, False)
            self.indexer.power_off(brake=self.brake_output)
            self.record_event("emergency_stop")
            self.changed()
        elif not active and self.estop:
            self.record_event("emergency_stop_released")
            self.reset()

    def _on_monitoring(self) -> None:
        if self.monitoring_cause():
            self.idxoff = True
            self.controller = False
            self.spindle.on = False
            self.executor.flush()
            self.indexer.power_off(brake=self.brake_output)
            self.record_event("monitoring")
        self.changed()

    def _on_overload(self) -> None:
        if self.signals.get("output_overload"):
            self._overload_latched = True  # recovery: 24 V off >= 10 s (a power cycle here)
        self.changed()

    def _blocked(self) -> bool:
        return bool(self.signals.get("blocked")) or (self.i2t_limiting and self._i2t_demand() > self._i2t_level())

    def _update_block(self) -> None:
        self.indexer.block(self._blocked())
        self.arm_torque_abort(now_only=True)

    def arm_torque_abort(self, now_only: bool = False) -> None:
        """H7 (spec §5.5): the armed move is aborted when the motor current reaches P2 % of Imax
        (acceleration and load current, or i_lim when the axis is held by a blockage or an end
        stop).  The instant is solved from the plan; ``now_only``: abort at once if it is due now,
        schedule nothing (an external change, synchronous)."""
        when = self._h7_due()
        if when is not None and when <= self.clock.now():
            if self._h7_timer is not None:
                self._h7_timer.cancel()
                self._h7_timer = None
            if now_only:
                self._torque_abort()
                return
        if now_only:
            return
        if self._h7_timer is not None:
            self._h7_timer.cancel()
            self._h7_timer = None
        if when is not None:
            self._h7_timer = self.clock.call_at(max(when, self.clock.now()), self._h7_fire)

    def _h7_fire(self) -> None:
        self._h7_timer = None
        if self.executor.h7_active() is not None and self.axis.moving:
            self._torque_abort()

    def _h7_due(self) -> float | None:
        """The first instant >= now at which the current reaches the armed H7 level, or None."""
        level = self.executor.h7_active()
        if level is None or not self.controller or not self.axis.moving:
            return None
        now = self.clock.now()
        cap = self.params.peak_current_pct / 100.0
        if self.i2t_limiting:
            cap = min(cap, self._i2t_level())
        if level > cap + 1e-12:
            return None  # the stage never delivers that much
        if self.indexer.blocked_at is not None or self.indexer.at_end_stop():
            return now
        static = I_BASE + float(self.signals.get("load_pct")) / 100.0
        if static >= level - 1e-12:
            return now
        best = self.indexer.end_stop_contact()
        a_min = (level - static) * A_REF / K_ACC  # the acceleration whose current reaches the level
        for seg in self.axis.segments():
            if seg.t1 <= now or (best is not None and seg.t0 >= best):
                continue
            t0 = max(seg.t0, now)
            if seg.shape == "linear":
                hit = t0 if abs(seg.a) >= a_min else None
            else:
                peak = 0.5 * math.pi * abs(seg.a)
                if peak < a_min:
                    continue
                tau = seg.span / math.pi * math.asin(min(1.0, a_min / peak))
                lo, hi = seg.t0 + tau, seg.t0 + seg.span - tau
                hit = max(lo, t0) if t0 <= hi else None
            if hit is not None:
                best = hit if best is None else min(best, hit)
                break
        return best

    def _torque_abort(self) -> None:
        """H7: the move ends where the axis stands, no following error (spec §5.5).  A blockage
        that still holds the axis stays (the next move sees it)."""
        self.executor.h7_level = None
        actual = self.indexer.actual()
        self.indexer.target = None
        self.indexer.set_junction(None)
        self.axis.quick_stop()
        self.axis.set_position(actual)
        self.record_event("torque_abort")
        self.indexer.block(self._blocked())
        if self.executor.current is not None and self.executor.current.letter in "A+vw":
            self.executor.complete()
        else:
            self.executor.h7_in_move = False

    # -- I²t (spec §5.7) ------------------------------------------------------------------------
    def _i2t_level(self) -> float:
        return self.params.i2t_level / 255.0

    def _i2t_demand(self) -> float:
        i_lim = self.params.peak_current_pct / 100.0
        return min(i_lim, I_BASE + float(self.signals.get("load_pct")) / 100.0)

    def current(self) -> float:
        """Motor current as a fraction of Imax (``T1;5`` = round(252·i))."""
        if not self.controller:
            return 0.0
        i_lim = self.params.peak_current_pct / 100.0
        if (self.indexer.blocked_at is not None or self.indexer.at_end_stop()) and self.axis.moving:
            i = i_lim  # held by a blockage or pressing against an end stop
        else:
            i = I_BASE + K_ACC * abs(self.axis.acceleration()) / A_REF + float(self.signals.get("load_pct")) / 100.0
        i = min(i, i_lim)
        if self.i2t_limiting:
            i = min(i, self._i2t_level())
        return i

    def _i2t_rate(self) -> float:
        level = self._i2t_level()
        if level <= 0:
            return 0.0
        i = self._i2t_demand()
        if self.i2t_limiting:
            i = min(i, level)
        return (i * i - level * level) / (level * level)

    def _i2t_update(self) -> None:
        now = self.clock.now()
        self.i2t_q = max(0.0, self.i2t_q + self._last_rate() * (now - self.i2t_t))
        self.i2t_t = now
        if self._i2t_timer is not None:
            self._i2t_timer.cancel()
            self._i2t_timer = None
        threshold = 3.0 * self.cfg.axis.i2t_t_allow_s
        rate = self._i2t_rate()
        # (a crossing closer than the clock can resolve at this time is reached now: a timer for
        # it would fire at the same instant, integrate nothing and be set again, for ever)
        if not self.i2t_limiting and self._i2t_level() > 0 and (
                self.i2t_q >= threshold - 1e-9 or (rate > 0 and now + (threshold - self.i2t_q) / rate <= now)):
            self.i2t_limiting = True
            self.i2t_latched = True
            self.record_event("i2t_limit")
        elif self.i2t_limiting and rate <= 0 and (self.i2t_q <= 1e-9 or (rate < 0 and now + self.i2t_q / -rate <= now)):
            self.i2t_limiting = False
        self._rate = self._i2t_rate()
        if not self.i2t_limiting and self._rate > 0:
            self._i2t_timer = self.clock.call_later((threshold - self.i2t_q) / self._rate, self._i2t_update)
        elif self.i2t_limiting and self._rate < 0:
            self._i2t_timer = self.clock.call_later(self.i2t_q / -self._rate, self._i2t_update)
        self._update_block()
        self.changed()

    def _last_rate(self) -> float:
        return getattr(self, "_rate", 0.0)



def _wrap24(value: int) -> int:
    """Positions travel as 24-bit two's complement (wrap-around, spec §5.1)."""
    value &= 0xFFFFFF
    return value - 0x1000000 if value & 0x800000 else value
