"""The SERS drive behind the serial line, composed of its parts (manual "SERS Version V04,
Firmware ab 120901"; spec sers.md).

Implements (manual section → spec section) through its parts:

* the parameters (:mod:`.params`) with their access by number (:mod:`.access`), range checks,
  units and PSAVE/POSSAVE/P1004 (:mod:`.memory`) (§4.7, §4.8, §4.8.6.10 → §4.8);
* the power stage ON/OFF, drive errors P11 and warnings P12 (:mod:`.power`), the supply and
  heat-sink supervision (:mod:`.supply`), the outputs and the 7-segment display (:mod:`.outputs`)
  (§2.1.3, §2.1.4, §3.5, §4.8.3.1 → §4.3, §4.6, §4.7);
* the motion (:mod:`.motion` with :mod:`.jog`, :mod:`.homing`, :mod:`.watches`, :mod:`.encoder`,
  :mod:`.polynomial`): positioning E, jog, homing, POS0/POSR, limits and step loss (§4.5.1,
  §4.6.6, §4.8.4, §4.8.6 → §3.5, §5);
* the inputs and their functions (:mod:`.inputs`, §3.3, §4.8.1 → §4.11);
* statements, commands and the program (:mod:`.execution`, :mod:`.operands`, :mod:`.interpreter`,
  :mod:`.remote`, :mod:`.program`, :mod:`.answers`, :mod:`.interruption`) (§4.2–§4.6, §4.8.6.3
  → §3.3, §4.4).

The model builds the parts and hands each the collaborators it needs; where two parts need
each other, the one made first gets the other as a callable.  Internally positions are motor
increments, speeds inc/s and accelerations inc/s²; the weighting parameters (P76, P44, P160,
P121–P123) only matter at the serial interface.
"""

from __future__ import annotations

from typing import Any, Literal

from devsim.core.axis import Axis
from devsim.core.clock import Clock, Timer
from devsim.core.device import Port
from devsim.core.kit import declare_signals
from devsim.core.model import Model
from devsim.core.nvram import NonVolatileMemory
from devsim.devices.sers import codec
from devsim.devices.sers.access import ParameterAccess
from devsim.devices.sers.answers import Answers
from devsim.devices.sers.config import SersConfig
from devsim.devices.sers.constants import INC_PER_REV
from devsim.devices.sers.execution import Execution
from devsim.devices.sers.inputs import Inputs
from devsim.devices.sers.interpreter import Interpreter
from devsim.devices.sers.master import MasterLink
from devsim.devices.sers.memory import ParameterMemory
from devsim.devices.sers.motion import Motion
from devsim.devices.sers.operands import Operands
from devsim.devices.sers.outputs import Outputs
from devsim.devices.sers.parameters import SUPPLY_THRESHOLDS
from devsim.devices.sers.params import SersParameters
from devsim.devices.sers.power import PowerStage
from devsim.devices.sers.program import PROGRAM_BYTES, PROGRAM_BYTES_P8, ProgramMemory
from devsim.devices.sers.runahead import RunAhead
from devsim.devices.sers.signals import SIGNALS
from devsim.devices.sers.supply import SupplyMonitor
from devsim.devices.sers.units import query_formatter
from devsim.devices.sers.wiring import MotorWiring

__all__ = ["SersDrive"]



class SersDrive(Model):
    """One SERS: its parts, its power-on and the selection on the serial line (§3.5, §3.6.2)."""

    #: Not the drive's state (:class:`~.runahead.RunAhead` leaves them out): the event log
    #: (moved on its own), the listeners and the run-ahead itself.
    not_state = frozenset({"events", "_listeners"})

    def __init__(
        self,
        *,
        clock: Clock,
        config: dict[str, Any] | None = None,
        nvram: NonVolatileMemory | None = None,
        name: str = "",
    ) -> None:
        super().__init__(clock=clock, config=config, nvram=nvram, name=name)
        self.cfg = SersConfig.parse(self.config)
        signals = self.signals
        cfg = self._cfg
        # the collaborators as bound methods of the model (64 bytes each; a lambda costs 200)
        alive, booting, execution, outputs_changed = self._alive, self._booting, self._execution, self._outputs_changed
        self.params = params = SersParameters()
        self.memory = memory = ParameterMemory(self.nvram, params, cfg, self._p51_inc)
        self.program = program = ProgramMemory(
            self.nvram, PROGRAM_BYTES_P8 if "P8" in self.cfg.options else PROGRAM_BYTES)  # (§4.4)
        self.master = master = MasterLink(clock, self.line_out)
        thresholds = SUPPLY_THRESHOLDS[self.cfg.supply_class]
        self.axis = Axis(clock, counts_per_rev=INC_PER_REV, index_offset=self.cfg.axis.index_offset, name=self.name)
        self.power_stage = power = PowerStage(
            clock, params, signals, memory, self._motion,
            undervoltage=thresholds[2],
            changed=outputs_changed,
            program_error=self._drive_error,
            resync=self._resync,
            record_event=self.record_event,
            announce=self.announce,
            fault_message=self.spontaneous if self.cfg.spontaneous_fault_messages else None,
        )
        self.motion = motion = Motion(
            clock, self.axis, params, signals, power,
            evaluate=self._evaluate,
            i7_stop=self._i7_stop,
            ended=self._motion_ended,
            poke=self._poke,
            segment_ended=self._segment_ended,
            in_position_message=self._in_position_message,
            has_option_e50=self._has_option_e50,
            record_event=self.record_event,
            changed=outputs_changed,
        )
        self.supply = supply = SupplyMonitor(
            signals, power, memory, thresholds,
            has_option_u=self._has_option_u, alive=alive, logic_power=self.switch_supply,
        )
        self.outputs = outputs = Outputs(
            signals, params, power, memory, alive=alive, booting=booting,
            in_position=self._in_position, program_running=self._program_running,
        )
        self.inputs = inputs = Inputs(
            clock, signals, params, power, motion, program,
            config=cfg, alive=alive, booting=booting, programs=execution, changed=outputs.update,
        )
        self.access = access = ParameterAccess(
            params, memory, power, motion, inputs, program, signals,
            config=cfg, programs=execution, changed=outputs.update, recheck_warnings=supply.recheck,
            rotation_changed=self.apply_rotation_sense,
            query_format=query_formatter(self.cfg.query_fixed_decimals, self.cfg.query_units),
        )
        self.operands = operands = Operands(access, inputs, params, power, self.cfg.counter_decrement_first)
        self.answers = Answers(access, operands, params, power, motion, program,
                               self.cfg.list_decimals, self.cfg.query_name_style)
        self.interpreter = interpreter = Interpreter(
            clock, params, program, operands, power, motion, master,
            host=execution, render=self.answers.render_statement, spontaneous=self.spontaneous,
            address=self._address, runahead=RunAhead(clock, self, self.events, self.axis.remembered_since),
        )
        self.execution = Execution(
            params, memory, power, motion, inputs, program, interpreter, access, operands,
            config=cfg, changed=outputs.update,
        )
        #: The drive was addressed last (True), another one was (False), every drive was (``"*"``,
        #: a broadcast); None: not yet.
        self.addressed: bool | Literal["*"] | None = None
        #: The ports on this drive's line, its own too (RS-485; empty: a line of its own); the face
        #: tells.  (One attribute for both uses: a 30th made every drive's __dict__ lose its shared
        #: keys, 1.3 KB a drive.)
        self.peers: tuple[Port, ...] = ()
        self.logic_alive = False
        self.booting = False
        self._timers: list[Timer] = []
        self._define_signals(thresholds)
        self.wiring = MotorWiring(self.axis, signals, self.cfg.axis)
        signals.subscribe_all(self.runahead.notice)
        self.heard = self.runahead.notice  # (an announcement someone hears: no loop is run ahead over it)
        self._power_on()

    def unobserved_until(self, when: float) -> None:
        self.runahead.unobserved_until(when)

    @property
    def runahead(self) -> RunAhead:
        """What runs the passes of a looping program ahead (held by the interpreter: one more
        attribute here would cost every drive a dict of its own)."""
        return self.interpreter.runahead  # type: ignore[return-value]

    def _poke(self, *_changed: Any) -> None:
        """A signal changed: a parked WAIT may go on."""
        self.interpreter.poke()

    def _cfg(self) -> Any:
        """The configuration as it is now (a DIP switch may change it)."""
        return self.cfg

    # the collaborators handed to the parts, as methods: a part made before another gets it
    # through one of these (a bound method each, not a closure each)
    def _alive(self) -> bool:
        return self.logic_alive

    def _booting(self) -> bool:
        return self.booting

    def _execution(self) -> Execution:
        return self.execution

    def _motion(self) -> Motion:
        return self.motion

    def _outputs_changed(self) -> None:
        self.outputs.update()

    def _p51_inc(self) -> float:
        return self.motion.p51_inc()

    def _drive_error(self) -> None:
        self.interpreter.on_drive_error()

    def _resync(self) -> None:
        self.motion.encoder.resync()

    def _evaluate(self, cond: Any) -> bool:
        return self.operands.evaluate(cond)

    def _i7_stop(self) -> bool:
        return self.inputs.i7_stop_active()

    def _motion_ended(self) -> None:
        self.execution.motion_ended()

    def _segment_ended(self) -> None:
        self.interpreter.resume("segment")

    def _in_position_message(self) -> None:
        self.spontaneous(f"@{self.cfg.address}POS=1")

    def _has_option_e50(self) -> bool:
        return "E50" in self.cfg.options

    def _has_option_u(self) -> bool:
        return "U" in self.cfg.options

    def _in_position(self) -> bool:
        return self.motion.pos_ok

    def _program_running(self) -> bool:
        return self.interpreter.running

    def _address(self) -> int:
        return self.cfg.address

    def _supply_changed(self, *_changed: Any) -> None:
        self.supply.check_supply()

    def _temperature_changed(self, *_changed: Any) -> None:
        self.supply.check_temperature()

    def _short_changed(self, *_changed: Any) -> None:
        self.supply.check_short()

    def _stall_changed(self, _name: str, _old: Any, new: Any) -> None:
        self.motion.stall(bool(new))

    # ======================================================================================
    # signals and geometry
    # ======================================================================================
    def _define_signals(self, thresholds: tuple[int, int, int, int]) -> None:
        s = self.signals
        declare_signals(s, SIGNALS)
        nominal = thresholds[0] * 0.8 if self.cfg.supply_voltage is None else self.cfg.supply_voltage
        s.signal("supply_voltage").value = float(nominal)
        s.signal("heatsink_temperature").value = float(self.cfg.heatsink_temperature)
        inputs = self.inputs
        on_limit, on_digital_input = inputs.on_limit, inputs.on_digital_input  # one bound method each
        for name in ("limit_left", "limit_right"):
            s.subscribe(name, on_limit)
        s.subscribe("stop", inputs.on_stop)
        s.subscribe("reference", inputs.on_reference)
        for n in range(1, 9):
            s.subscribe(f"I{n}", on_digital_input)
        s.subscribe("supply_voltage", self._supply_changed)
        s.subscribe("heatsink_temperature", self._temperature_changed)
        s.subscribe("short_circuit", self._short_changed)
        s.subscribe("stall", self._stall_changed)
        s.subscribe_all(self._poke)  # after each signal's own listeners: one entry, not one per signal

    # ======================================================================================
    # power
    # ======================================================================================
    def _power_on(self) -> None:
        """§3.5 / spec §4.1: display '-' for 2 s, then parameters from EEPROM."""
        self._cancel_timers()
        self.axis.quick_stop()
        self.addressed = None
        self.master.cancel()
        self.announce("power_on")  # the serial face starts afresh (framer, selection)
        self.logic_alive = True
        self.booting = self.cfg.boot_time > 0
        self.record_event("power_on")
        self.power_stage.power_on()
        self.motion.power_on()
        self.inputs.power_on()
        self.program.reload()  # programming mode does not survive a power loss (P0 = 0)
        self.interpreter.reset()
        self.memory.power_on()
        self.apply_rotation_sense()
        self.motion.set_p51(self.memory.saved_position() or 0.0)
        for n in range(1, 17):
            self.signals.set(f"O{n}", False)
        self.power_stage.energize_at_power_on()
        self.supply.check_all()
        self.supply.check_limits_at_power_on()
        self.outputs.update()
        if self.booting:
            self._timers.append(self.clock.call_later(self.cfg.boot_time, self._boot_done))

    def apply_rotation_sense(self) -> None:
        """P1134 (§4.8.2.3) as the parameters hold it now (power-on, a write, factory defaults)."""
        self.wiring.set_inverted(bool(self.params.direction_inverted))

    def _boot_done(self) -> None:
        self.record_event("ready")
        self.booted()
        self.inputs.initialised()
        self.execution.autostart()

    def _power_off(self) -> None:
        self._cancel_timers()
        self.inputs.power_off()
        self.motion.power_off()
        self.logic_alive = False
        self.power_stage.power_off()
        for n in range(1, 17):
            self.signals.set(f"O{n}", False)
        self.signals.set("READY", False)

    def power_cycle(self, *, wipe: bool = False) -> None:
        self._power_off()
        if wipe:
            self.nvram.wipe()
        self._power_on()

    def switch_supply(self, on: bool) -> None:
        """The supply switched off or on (the ``power`` fault, the supply monitor)."""
        if on:
            self._power_on()
        else:
            self._power_off()

    def close(self) -> None:
        self._cancel_timers()
        self.inputs.power_off()
        self.motion.cancel_all()
        self.power_stage.cancel()
        self.axis.quick_stop()
        self.wiring.close()

    def _cancel_timers(self) -> None:
        for timer in self._timers:
            timer.cancel()
        self._timers.clear()

    # ======================================================================================
    # the serial line
    # ======================================================================================
    def spontaneous(self, text: str) -> None:
        """An unsolicited message (``@2POS=1``) for the serial face to send between lines."""
        self.announce("spontaneous", text)

    def line_out(self, data: bytes) -> None:
        """Bytes a master sends to its slaves on the serial line (G-MASTER).  Its ``#n`` is on
        the line for every drive, the master too: the lines after it without an address are
        for drive n, not for the master (§4.1), as the slaves that hear it take them."""
        _complete, address, _stop = codec.read_address(data, 0)
        self.note_address(address, False)
        self.announce("line_out", data)

    def hears_as_master(self, data: bytes) -> bool:
        """Bytes another drive on the line sent: for a master (address 0) only the answer it
        may wait for, never a line to carry out (its statements go to slaves, §3.6.2: a slave's
        echo of a broadcast is no broadcast for the master); False for a slave, which takes a
        master's statements as a host's."""
        if self.cfg.address != 0:
            return False
        if self.master.awaiting and self.logic_alive:
            self.master.feed(data)
        return True

    @property
    def line_address(self) -> int:
        """The address this drive's lines carry after ``#`` (its DIP address; 0, the master's,
        is written ``#200``, G-ADDR)."""
        return self.cfg.address or 200

    @property
    def selected(self) -> bool:
        """Whether statements without an address are for this drive (G-ADDR): it was addressed
        last, alone or with every drive (``#*``)."""
        if self.addressed is None:
            initially = self.cfg.initially_selected
            self.addressed = (len(self.peers) < 2) if initially is None else initially
        return self.addressed is not False

    def selection(self, address: int | str | None) -> tuple[bool, bool]:
        """Whether this drive executes and answers a line with ``address`` after its ``#``
        (G-ADDR), changing nothing: without one, if it is selected (after a broadcast, as a
        broadcast); ``*``, executed by all and answered as :meth:`answers_broadcast` says; its
        own address, both; another, neither."""
        if address is None:
            if self.addressed == "*":
                return True, self.answers_broadcast()
            selected = self.selected
            return selected, selected
        if address == "*":
            return True, self.answers_broadcast()
        mine = address == self.line_address
        return mine, mine

    def answers_broadcast(self) -> bool:
        """Whether this drive answers a broadcast line (G-ADDR ⚙ ``broadcast_reply``): none does,
        or the drive with the lowest address on the line."""
        if self.cfg.broadcast_reply == "none":
            return False
        return all(self.line_address <= peer.device.model.line_address for peer in self.peers
                   if isinstance(peer.device.model, SersDrive))

    def note_address(self, address: int | str | None, mine: bool) -> None:
        """A line's address selects the drive it names for the lines after it and deselects the
        others; ``*`` selects every drive (§4.1: „Nach dem Senden der Adresse sind alle folgenden
        Kommandos und Parameter-Zuweisungen dem entsprechenden Antrieb zugeordnet“, §4.2: ``*``
        „Adressiert alle Achsen“).  A line without one changes nothing.  ``mine``: the address is
        this drive's."""
        if address == "*":
            self.addressed = "*"
        elif address is not None:
            self.addressed = mine
