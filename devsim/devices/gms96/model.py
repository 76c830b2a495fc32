"""The GMS96 servo amplifier card as a model (manual "GMS96 Softwarebeschreibung", v4.04).

The card knows no protocol.  It is composed of parts that own their state: the N parameters
(:mod:`.params`), the speeds (:mod:`.feed`), the frames (:mod:`.coordinates`), the power stage
(:mod:`.stage`), I²t (:mod:`.i2t`), the current and H7 (:mod:`.torque`), the indexer and position
loop (:mod:`.motion`), the inputs and outputs (:mod:`.io`), the process image (:mod:`.image`),
the EEPROM (:mod:`.memory`) and FLASH (:mod:`.flash`), the counter input (:mod:`.counter`), the
command executor (:mod:`.executor`) with its commands (:mod:`.commands`, :mod:`.program`), the
reference runs (:mod:`.reference`), the spindle (:mod:`.spindle`) and the PLC (:mod:`.plc`).  The
model builds them, wires the signals, and keeps what is the card's own: power-on / reset (spec
§4.1.2), the DIL switch (§2.2), the status bytes (§4.3), the special markers (§4.4) and the faults
(§4.5.3: emergency stop, following error, monitoring, output overload).  The FT1.2 link and the
command dispatch are the face (:mod:`.face`, :mod:`.link`).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from devsim.core.axis import Axis
from devsim.core.clock import Clock, Timer
from devsim.core.kit import declare_signals
from devsim.core.model import Model
from devsim.core.nvram import NonVolatileMemory
from devsim.devices.gms96 import tables
from devsim.devices.gms96.commands import QUEUED_COMMANDS, QueuedCommands
from devsim.devices.gms96.config import DilSwitch, Gms96Config
from devsim.devices.gms96.coordinates import Coordinates
from devsim.devices.gms96.counter import CounterInput
from devsim.devices.gms96.executor import Cmd, Executor
from devsim.devices.gms96.feed import Feed
from devsim.devices.gms96.flash import Flash
from devsim.devices.gms96.i2t import I2t
from devsim.devices.gms96.image import ProcessImage
from devsim.devices.gms96.io import INPUT_BYTES, Outputs, axis_switches, inputs_shown_at
from devsim.devices.gms96.memory import Memory
from devsim.devices.gms96.motion import ActualSwitch, Indexer
from devsim.devices.gms96.params import NParameters
from devsim.devices.gms96.plc import Plc
from devsim.devices.gms96.points import SIGNALS
from devsim.devices.gms96.program import ProgramControl
from devsim.devices.gms96.reference import References
from devsim.devices.gms96.spindle import Spindle
from devsim.devices.gms96.stage import PowerStage
from devsim.devices.gms96.torque import Torque

__all__ = ["Gms96Card"]

#: The bits of :meth:`Gms96Card.status` (:data:`~devsim.devices.gms96.tables.STATUS_BITS`).
_ESTOP, _MOTION, _MONITORING, _IDXOFF, _BUSY, _I2T_ACTIVE, _I2T_LATCHED, _MESSAGE = (
    tables.STATUS_BITS[name]
    for name in ("ESTOP", "MOTION", "MONITORING", "IDXOFF", "BUSY", "I2T_ACTIVE", "I2T_LATCHED", "MESSAGE")
)
_M1_5 = 1 << 5  #: marker M1.5 in its byte (one of the motion bit's causes, :meth:`Gms96Card.motion`)


class Gms96Card(Model):
    """One GMS96 card (spec §4): its parts, power-on and reset, status bytes, markers, faults."""

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
        #: The DIL switch as set now (``dil.*`` points) and as read at the last power-on / reset.
        self.pending_dil: DilSwitch = self.cfg.dil
        self.dil: DilSwitch = self.cfg.dil
        self.powered = False
        self._changing = False
        self._timers: list[Timer] = []
        clock, geo, signals, stepper = self.clock, self.cfg.axis, self.signals, self.hw.stepper
        self.axis = Axis(clock, counts_per_rev=geo.index_period, index_offset=geo.index_offset, name=self.name)
        self.image = ProcessImage()
        self.stage = PowerStage(signals)
        self.params = NParameters(factory=self.cfg.params, stepper=stepper, out_of_range=self.cfg.out_of_range)
        self.feed = Feed()
        self.coordinates = Coordinates(self.axis, self.nvram, int(self.cfg.tool_offset))
        cfg = self.cfg
        self.flash = Flash(self.nvram, QUEUED_COMMANDS, max_programs=cfg.max_programs,
                           max_commands=cfg.max_total_commands, plc_bytes=cfg.plc.flash_bytes)
        self.memory = Memory(self.nvram, self.params, self.feed, self.image, self.record_event)
        self.indexer = Indexer(
            clock=clock, axis=self.axis, feed=self.feed, params=self.params, stage=self.stage, image=self.image,
            signals=signals, geometry=geo, stepper=stepper, card=self,
            max_speed=float(self.hw.max_step_frequency_hz) if self.hw.max_step_frequency_hz else None,
        )
        self.counter = CounterInput(
            clock=clock, axis=self.axis, indexer=self.indexer, params=self.params, stage=self.stage,
            coordinates=self.coordinates, feed=self.feed, memory=self.memory, h22_address=self.cfg.h22_data_address,
            changed=self.changed, record_event=self.record_event,
        )
        self.executor = Executor(
            clock=clock, indexer=self.indexer, counter=self.counter, feed=self.feed, coordinates=self.coordinates,
            params=self.params, card=self, run=lambda cmd: self.commands.run(cmd),
            queue_capacity=self.cfg.queue_capacity,
        )
        self.i2t = I2t(clock, self.params, geo, self.indexer, self.stage, self._i2t_settled, self.record_event)
        self.torque = Torque(
            clock, self.axis, self.indexer, self.params, self.stage, self.i2t, self.executor,
            lambda: bool(signals.get("blocked")), self.record_event,
        )
        self.outputs = Outputs(
            clock, self.axis, self.image, signals, self.params, self.stage, self.indexer, stepper, self.changed,
            shown_at=lambda: inputs_shown_at(self.hw.name, self.dil.interpolation),
            resolver=self.hw.feedback == "resolver", fitted_outputs=self.hw.output_bits,
        )
        self.plc = Plc(
            card=self, clock=clock, options=self.cfg.plc, ms_per_1000=self.hw.plc_ms_per_1000, flash=self.flash,
            image=self.image, outputs=self.outputs, counter=self.counter, indexer=self.indexer, stage=self.stage,
            interpolation=lambda: bool(self.dil.interpolation), powered=lambda: self.powered,
        )
        self.spindle = Spindle(self.indexer, self.params, lambda: float(signals.get("ref_pulse_hz")), self.changed)
        self.references = References(
            clock=clock, indexer=self.indexer, stage=self.stage, coordinates=self.coordinates, params=self.params,
            signals=signals, image=self.image, geometry=geo, record_event=self.record_event,
            report_error=self.report_error,
        )
        self.program = ProgramControl(
            executor=self.executor, flash=self.flash, image=self.image, outputs=self.outputs,
            plc=self.plc, marker_byte=self.marker_byte, motion_changes_at=self.indexer.plan_changes_at,
            write_marker_byte=self.write_marker_byte,
        )
        self.commands = QueuedCommands(
            card=self, executor=self.executor, program=self.program, references=self.references,
            indexer=self.indexer, feed=self.feed, coordinates=self.coordinates, params=self.params,
            stage=self.stage, i2t=self.i2t, counter=self.counter, spindle=self.spindle, outputs=self.outputs,
            image=self.image, memory=self.memory, eeprom_write_s=self.cfg.eeprom_write_s,
        )
        self._define_signals()
        self.switches: list[ActualSwitch] = axis_switches(self.indexer, signals, geo)
        self._power_on(first=True)

    @property
    def address(self) -> int:
        """The card's address on the line (DIL switches 1..5, read at power-on: manual §2.2)."""
        return int(self.dil.address)

    @property
    def e_version(self) -> bool:
        """DIL switch 7: the E version of the protocol (FCB, ACD, DFC; manual §2.2)."""
        return bool(self.dil.protocol == "E")

    # ======================================================================================
    # signals (spec §4.5.3, §4.11)
    # ======================================================================================
    def _define_signals(self) -> None:
        s = self.signals
        declare_signals(s, SIGNALS)
        s.signal("override_pot").value = float(self.cfg.override_pot_pct)
        on_input = self._on_input  # one bound method for the 32 inputs, not one each
        for byte in range(INPUT_BYTES):
            for bit in range(8):
                s.subscribe(f"E{byte}.{bit}", on_input)
        s.subscribe("emergency_stop", lambda *_: self._on_estop())
        s.subscribe("override_pot", lambda *_: self.speed_changed())
        s.subscribe("load_pct", lambda *_: self.i2t.update())
        s.subscribe("blocked", lambda *_: self.torque.update_block())
        s.subscribe("monitoring", lambda *_: self._on_monitoring())
        s.subscribe("output_overload", lambda *_: self._on_overload())
        s.subscribe("ref_pulse_hz", lambda *_: self.spindle.pulse_rate_changed())

    # ======================================================================================
    # power, reset, persistence (spec §4.1.2, §4.8)
    # ======================================================================================
    def _power_on(self, first: bool = False) -> None:
        for t in self._timers:
            t.cancel()
        self._timers = []
        self.powered = True
        self.dil = self.pending_dil
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
        self.coordinates.power_on(reset_origin=first or self.cfg.axis.position_after_reset == "zero")
        self.image.clear()
        stage = self.stage
        stage.nv_error = self.memory.load()
        self.counter.power_on()
        self.memory.load_static()
        self.flash.power_on()
        stage.brake_output = self.params.brake_output == 1
        self.spindle.on = False
        stage.estop = bool(self.signals.get("emergency_stop"))
        stage.idxoff = True
        stage.controller = not stage.estop and not stage.monitoring_cause() and not stage.nv_error
        self.executor.waiting_in_position = False
        self.i2t.power_on()
        stage.overload_latched = bool(self.signals.get("output_overload"))
        self.indexer.blocked_at = None
        self.torque.update_block()
        self.record_event("power_on")
        self.plc.power_on(self.cfg.boot_time if self.booting else 0.0)
        self.changed()

    def _boot_done(self) -> None:
        self.record_event("ready")
        self.booted()

    def silence(self, seconds: float) -> None:
        """The card does not listen for ``seconds`` (boot, flash erase, manual §2.3.1 p)."""
        self.silent_until = max(self.silent_until, self.clock.now() + seconds)

    @property
    def silent(self) -> bool:
        return self.silent_at(self.clock.now())

    def silent_at(self, now: float) -> bool:
        """Whether the card does not listen at ``now`` (the link's clock reading of a chunk)."""
        return now < self.silent_until or not self.powered

    def power_cycle(self, *, wipe: bool = False) -> None:
        self._power_off()
        if wipe:
            self.memory.wipe()
        self._power_on()

    def _power_off(self) -> None:
        self.memory.save_static()
        self.powered = False
        self.i2t.power_off()
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
    # what the parts ask of the card
    # ======================================================================================
    def set_n(self, index: int, value: int, p3: int = 0) -> None:
        """``N value;index;P3`` (manual §2.3.1 N) and the ``param.N*`` points: the value (the
        parts that own its effect listen: the position loop, I²t), then outputs and waits."""
        if self.params.write(index, value, p3):
            self.changed()

    def can_move(self) -> bool:
        """A move may start (spec §4.2.4); not in counter-input mode (the counter input is the
        set-point source, spec §5.10)."""
        if self.counter.active:
            return False
        return self.stage.ready()

    def activate_controller(self) -> None:
        """Q3 / start of every Q: set-point := actual, position controller on (spec §5.6)."""
        if self.stage.faulted():
            return
        if not self.stage.controller:
            actual = self.indexer.actual()
            if not self.axis.moving:
                self.axis.set_position(actual)
            self.stage.controller = True
        self.indexer.arm_following_error()
        self.changed()

    def plan_changed(self) -> None:
        """The indexer planned anew: I²t, H7 and in-position solved again, the outputs follow (A0.1)."""
        self.i2t.replan()
        self.torque.arm()
        self.outputs.arm_in_position()
        self.changed()

    def arm_torque_abort(self) -> None:
        self.torque.arm()

    def following_error_fault(self, reason: str) -> None:
        """|e| > N20 (spec §4.5.3): IDXOFF, controller off, motion aborted, queue flushed."""
        if not self.stage.controller:
            return
        self.record_event("following_error")
        self.announce("fault", 1, 0x8611)  # CiA 402's following error (a CANopen facade sends EMCY)
        self.stage.switch_off()
        self.spindle.on = False
        self.executor.flush()
        self.indexer.power_off(brake=True)
        self.changed()

    # ======================================================================================
    # markers and status (spec §4.3, §4.4)
    # ======================================================================================
    def marker_byte(self, byte: int) -> int:
        """MB(byte) as the PLC and the host read it: MB0/MB1/MB3 carry status bits the firmware
        keeps (:data:`STATUS_MARKERS`, spec §4.4) over the stored byte."""
        return _marker_byte(self, byte)

    def marker_bit(self, byte: int, bit: int) -> bool:
        """Bit ``bit`` of :meth:`marker_byte`, the firmware's status looked at only for a live bit."""
        return _marker_bit(self, byte, bit)

    def write_marker_byte(self, byte: int, value: int) -> bool:
        """``p11`` / PLC: MB(byte) := value (:func:`_write_marker_byte`); whether that changed anything."""
        return _write_marker_byte(self, byte, value)

    def write_marker_bit(self, byte: int, bit: int, value: bool) -> bool:
        """M(byte).(bit) := value, as :meth:`write_marker_byte` writes its byte; whether that changed anything."""
        cur = self.image.markers[byte]
        return self.write_marker_byte(byte, (cur | (1 << bit)) if value else (cur & ~(1 << bit)))

    def unobserved_until(self, when: float) -> None:
        """Nobody looks before ``when``: the PLC skips the cycles that would change nothing."""
        self.plc.unobserved = when

    def busy(self) -> bool:
        return self.executor.busy

    def programs_ended(self) -> None:
        """The executor dropped its programs (#0, M0.1, a fault): M0.2 "a CNC program runs" is 0
        and no program ended successfully (manual §2.4.1)."""
        self.image.set_marker(0, 2, False)

    def speed_changed(self) -> None:
        """An override or the G95 spindle speed changed: the plan follows, waits re-check (spec §5.2)."""
        self.indexer.replan()
        self.changed()

    def motion(self) -> bool:
        return (
            self.axis.moving
            or self.executor.reference is not None
            or self.spindle.on
            or self.image.marker(1, 5)
        )

    def status(self) -> int:
        """The standard status byte of ``T3;0`` (spec §4.3.1; every status poll asks for it).
        (:meth:`motion`, :meth:`busy`, ``Executor.busy`` and the monitoring cause read in place: a
        poll's path.)"""
        stage, i2t, markers, executor = self.stage, self.i2t, self.image.markers, self.executor
        motion = self.axis.moving or executor.reference is not None or self.spindle.on or markers[1] & _M1_5
        return ((_ESTOP if stage.estop else 0) | (_MOTION if motion else 0)
                | (_MONITORING if stage.signals.get("monitoring") else 0) | (_IDXOFF if stage.idxoff else 0)
                | (_BUSY if executor.current is not None or executor.queue else 0)
                | (_I2T_ACTIVE if i2t.limiting else 0)
                | (_I2T_LATCHED if i2t.latched else 0) | (_MESSAGE if markers[4] else 0))

    def memory_status(self) -> int:
        """The memory status byte of ``T3;4`` (spec §4.3.2)."""
        s = tables.MEMORY_STATUS_BITS
        v = 0 if self.plc.running else s["PLC_NOT_RUNNING"]
        if self.plc.storage_error and not self.dil.interpolation:
            v |= s["PLC_STORAGE_ERROR"]
        if self.stage.nv_error:
            v |= s["NV_ERROR"] | s["EEPROM_DEFECTIVE"]
        if self.flash.cnc_storage_error:
            v |= s["CNC_STORAGE_ERROR"]
        if self.flash.write_error:
            v |= s["FLASH_ERROR"]
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
            self.outputs.follow()
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
        stage = self.stage
        if active and not stage.estop:
            stage.estop = True
            stage.switch_off()
            self.spindle.on = False
            self.executor.flush()
            self.image.set_marker(0, 2, False)
            self.indexer.power_off(brake=stage.brake_output)
            self.record_event("emergency_stop")
            self.changed()
        elif not active and stage.estop:
            self.record_event("emergency_stop_released")
            self.reset()

    def _on_monitoring(self) -> None:
        if self.stage.monitoring_cause():
            self.stage.switch_off()
            self.spindle.on = False
            self.executor.flush()
            self.indexer.power_off(brake=self.stage.brake_output)
            self.record_event("monitoring")
        self.changed()

    def _on_overload(self) -> None:
        if self.signals.get("output_overload"):
            self.stage.overload_latched = True  # recovery: 24 V off >= 10 s (a power cycle here)
        self.changed()

    def _i2t_settled(self) -> None:
        self.torque.update_block()
        self.changed()


#: The marker bits the firmware shows from its own state, by their names in
#: :data:`~devsim.devices.gms96.tables.MARKERS` (spec §4.4): read from the card, never from the
#: stored byte.
STATUS_MARKERS: dict[str, Callable[[Gms96Card], bool]] = {
    "MOTION_ACTIVE": lambda card: card.axis.moving,  # motor motion only, not M1.5 (manual §2.4.1 M0.3)
    "ESTOP_OK": lambda card: not card.stage.estop,
    "POSITION_CONTROL": lambda card: card.stage.controller,
    "MONITORING_FAULT": lambda card: bool(card.stage.monitoring_cause()),
    "IDXOFF": lambda card: card.stage.idxoff,
    "I2T": lambda card: card.i2t.latched,
    "RDY": lambda card: not card.busy(),
    "SPEED_REACHED": lambda card: card.axis.phase() == "const",
    "MOTION_SUPPRESSED": lambda card: card.params.motion_disabled == 1,
    "WAIT_IN_POSITION": lambda card: card.executor.wait_name == "H2",
}


def _status_bytes() -> dict[int, tuple[int, tuple[tuple[int, Callable[[Gms96Card], bool]], ...]]]:
    """:data:`STATUS_MARKERS` by marker byte: (the live bits' mask, (bit mask, state) per bit)."""
    by_byte: dict[int, list[tuple[int, Callable[[Gms96Card], bool]]]] = {}
    for name, state in STATUS_MARKERS.items():
        byte, bit = tables.MARKERS[name]
        by_byte.setdefault(byte, []).append((1 << bit, state))
    return {byte: (sum(mask for mask, _ in bits), tuple(bits)) for byte, bits in by_byte.items()}


_STATUS_BYTES = _status_bytes()


def _marker_byte(card: Gms96Card, byte: int) -> int:
    m = card.image.markers
    overlay = _STATUS_BYTES.get(byte)
    if overlay is None:
        return m[byte] if 0 <= byte < 256 else 0
    live, bits = overlay
    v = m[byte] & ~live
    for mask, state in bits:
        if state(card):
            v |= mask
    return v


def _marker_bit(card: Gms96Card, byte: int, bit: int) -> bool:
    mask = 1 << bit
    overlay = _STATUS_BYTES.get(byte)
    if overlay is None or not overlay[0] & mask:
        return 0 <= byte < 256 and bool(card.image.markers[byte] & mask)
    return any(state(card) for live, state in overlay[1] if live == mask)


def _write_marker_byte(card: Gms96Card, byte: int, value: int) -> bool:
    """``p11`` / PLC: MB(byte) := value on ``card``; the control bits of MB0/MB1 act (spec §4.4; M0.2 reads
    "CNC-Programmausgabe läuft" until the program ends, manual §2.4.1, even held by STOP).  A value
    beyond a byte is clamped to 0 … 255, or ignored with ``out_of_range: ignore`` (spec §3.10).
    Returns whether the write changed a marker or started, aborted or replanned anything (a 0
    written to M0.2 of a running program, or to M1's read-only bits, changes nothing)."""
    if not 0 <= byte < 256:
        return False
    if not 0 <= value <= 0xFF:
        if card.cfg.out_of_range == "ignore":
            return False
        value = min(max(value, 0), 0xFF)
    m = card.image.markers
    old = m[byte]
    acted = False
    if byte == 0:
        m[0] = (value & 0x07) | (old & 0x04)  # M0.2 w: 1 starts; 0 ends nothing (M §2.4.1)
        if (value & 0x02) and not (old & 0x02):
            card.executor.abort()
            m[0] &= ~0x02
            acted = True
        if (value & 0x04) and not (old & 0x04):
            card.executor.submit(Cmd("p", 3, 1, m[2], 3))
            acted = True
        if (value ^ old) & 0x01:
            card.indexer.replan()
    elif byte == 1:
        m[1] = (m[1] & 0x01) | (value & 0xE8)
    elif byte == 18:
        m[18] = value
        card.memory.save_static()
    else:
        card.image.write_marker_byte(byte, value)  # (MB5: the buffered SNDF codes follow)
        acted = True
    card.changed()
    return acted or m[byte] != old
