"""The scripted PLC of a GMS96 card (manual §1.4, §2.4; spec §4.10, §4.11).

The real card runs a downloaded Step5-like program whose machine-code format is undocumented,
so the simulator does not execute Step5 (spec §4.10.2).  Instead this module is a small PLC
that runs *scripted rules* on the card's process image, cyclically on the device clock:

* each cycle: inputs EB0..EB3 → PAE snapshot, the rules (and an optional Python hook) read
  the PAE, the outputs and the markers MB0..MB255 (with the firmware's status bits overlaid),
  write markers at once and collect output writes, which go to the outputs (PAA) at the end
  of the cycle (manual §1.4);
* the cycle time is ``plc.cycle_ms`` or, when unset, the variant's measured
  ``plc_ms_per_1000`` (manual §6) × ``plc.instructions`` / 1000 (≈ 20 ms for 230
  instructions on a KSA card, the spec's default);
* state: a program is "loaded" when a download ended (`p1;100`, `a` frames stored opaquely,
  `p1;101`) or the configuration has rules (``plc.loaded`` overrides); it starts by itself at
  power-on if loaded (manual §2.4), `p1;1` starts and `p1;2` stops it; memory status
  ``T3;4`` I.1 = PLC not running, I.0 = program storage error (download longer than
  ``plc.flash_bytes``).  In interpolation mode (DIL 6) the PLC never runs (spec §4.11.6).
* while nobody looks (a scenario waits for its next step, :attr:`Plc.unobserved`), the cycles
  that would read what the last one read and change nothing are counted, not run
  (:func:`cycle_after`; with a limit rule that looks at the direction, up to where that may
  change, :func:`direction_changes_at`); with a hook every cycle runs.

Built-in rules (spec §4.10.3, all optional):

* ``auto_ack_m_functions_ms: N`` – M6.0..M10.7, M15.7, M18.7 are reset N ms after the PLC
  first saw them set (a PLC timer: the reset happens in the first cycle at or after that);
* ``limit_switches`` – an input → STOP (M0.0 follows the switch) or abort (M0.1 pulse) plus a
  message code in MB4; ``direction`` restricts the action to motion towards the switch;
* ``message_on_fault`` – an MB4 code on the rising edge of following error (position
  controller off with neither emergency stop nor monitoring), monitoring (M0.6) and emergency
  stop (M0.4 = 0); the message query ``q`` (M3.1) re-posts the codes of faults still present
  and the PLC resets M3.1 (manual §2.3.1 q);
* ``start_program_on_input`` – MB2 := program and M0.2 := 1 on an input edge;
* ``copy_bits`` – a bit follows another bit (optionally inverted), e.g. ``E0.4 → A0.5``;
* ``hook: "package.module:function"`` – called with the :class:`Plc` every cycle; it can use
  :meth:`Plc.bit`, :meth:`Plc.set_bit`, :meth:`Plc.marker_byte`, :meth:`Plc.set_marker_byte`
  and :meth:`Plc.message`.

Bit names are ``E<byte>.<bit>``, ``A<byte>.<bit>``, ``M<byte>.<bit>`` (:func:`.image.parse_bit`).
"""

from __future__ import annotations

import importlib
import math
from collections.abc import Callable
from typing import Any, Protocol

from devsim.core.clock import Clock, Timer, VirtualClock
from devsim.core.kit import Command, Table
from devsim.core.settings import Settings
from devsim.devices.gms96.counter import CounterInput
from devsim.devices.gms96.flash import Flash
from devsim.devices.gms96.image import ProcessImage, parse_bit
from devsim.devices.gms96.io import OUTPUT_BITS, Outputs
from devsim.devices.gms96.motion import Indexer
from devsim.devices.gms96.stage import PowerStage


class PlcCard(Protocol):
    """What the PLC asks of its card (manual §2.4.1): the markers as the firmware shows them (MB0/MB1/MB3 carry
    its status bits), a marker write with its side effects (M0.1 aborts, M0.2 starts ...), and
    that it tells the rest of the card."""

    def marker_byte(self, byte: int) -> int: ...
    def marker_bit(self, byte: int, bit: int) -> bool: ...
    def write_marker_byte(self, byte: int, value: int) -> None: ...
    def write_marker_bit(self, byte: int, bit: int, value: bool) -> None: ...
    def changed(self) -> None: ...
    def record_event(self, name: str) -> None: ...


__all__ = ["FB254_FUNCTIONS", "M_FUNCTION_BITS", "Plc", "commanded_direction", "cycle_after", "direction_changes_at"]

#: The handshake bits the CNC sets and the PLC resets (spec §3.8.9): M6.0..M10.7, M15.7, M18.7.
M_FUNCTION_BITS: tuple[tuple[int, int], ...] = tuple((b, k) for b in range(6, 11) for k in range(8)) + (
    (15, 7),
    (18, 7),
)
_EPS = 1e-9

Hook = Callable[["Plc"], Any]


def load_hook(spec: str) -> Hook:
    """``"package.module:function"`` → the function."""
    module, _, attr = spec.partition(":")
    if not module or not attr:
        raise ValueError(f"PLC hook must be 'package.module:function', not {spec!r}")
    try:
        fn = getattr(importlib.import_module(module), attr)
    except Exception as exc:  # one line, not the import's traceback
        raise ValueError(f"PLC hook {spec!r} cannot be loaded: {type(exc).__name__}: {exc}") from None
    if not callable(fn):
        raise ValueError(f"PLC hook {spec!r} is not callable")
    return fn  # type: ignore[no-any-return]


def _at(when: float | None) -> float:
    return math.inf if when is None else when


def cycle_after(now: float, cycle: float, horizon: float) -> tuple[float, int]:
    """Sampled loops only while they matter (issue 31): after a cycle at ``now`` that changed
    nothing, each cycle would read what it read and do what it did – nothing – until the
    ``horizon``: the next timer of anything on the clock, the next boundary of the axis plan
    (the motion's status bits, :meth:`Indexer.plan_changes_at`), the moment the scenario's
    runner may look or act.  The cycle to run is the first at or after it (one at that very
    instant was scheduled after the timer there, as the cycles one by one schedule it);
    returns its time, on the grid the cycles one by one make (each time the last plus
    ``cycle``), and how many cycle times come before it."""
    when, skipped = now + cycle, 0
    while when < horizon:
        skipped += 1
        when = when + cycle
    return when, skipped


def commanded_direction(ix: Indexer, t: float | None = None) -> int:
    """Where the axis is commanded now (or at ``t`` of its plan; a limit rule's ``direction``,
    spec §4.10.3): towards the target, else the jog's way, else the set-point velocity's (+1,
    −1, 0)."""
    if ix.target is not None:
        d = ix.target - ix.axis.position(t)
        return (d > 0) - (d < 0)
    if ix.jog_dir:
        return ix.jog_dir
    v = ix.axis.velocity(t)
    return (v > 0) - (v < 0)


def direction_changes_at(indexer: Indexer, now: float, until: float) -> float:
    """Where, before ``until``, the :func:`commanded_direction` may change
    within the axis plan's segment of ``now`` (its end is a boundary of the plan that the skip
    waits for anyway): the set-point passing the target, the velocity turning.  A moment at or
    before the change (bisection), or ``until``."""
    if indexer.target is None and indexer.jog_dir:
        return until
    segment = next((seg for seg in indexer.axis.segments() if seg.t0 <= now < seg.t1), None)
    if segment is None:
        return until  # at rest: nothing moves the set-point
    target = indexer.target

    def direction(t: float) -> int:
        return commanded_direction(indexer, t)

    end = min(segment.t1, until)
    if end == math.inf:  # an endless cruise
        v = segment.velocity(now)
        if target is None or v == 0.0:
            return until
        crossing = now + (target - segment.position(now)) / v
        return max(now, crossing - 1e-9) if crossing >= now else until
    first, pieces = direction(now), [now, end]
    speed, last = segment.velocity(now), segment.velocity(end)
    if (speed > 0) != (last > 0) or (speed < 0) != (last < 0):  # it turns: the pieces either side are monotonic
        pieces.insert(1, _first_change(lambda t: (segment.velocity(t) > 0) - (segment.velocity(t) < 0), now, end))
    for low, high in zip(pieces, pieces[1:], strict=False):
        if direction(high) != first:
            return _first_change(direction, low, high) if direction(low) == first else low
    return until


def _first_change(sign: Callable[[float], int], low: float, high: float) -> float:
    """A moment at or before the first change of ``sign`` between ``low`` (where it is as at
    the start) and ``high`` (where it differs), for a sign that changes once in between."""
    start = sign(low)
    while high - low > 1e-9:
        middle = 0.5 * (low + high)
        if sign(middle) == start:
            low = middle
        else:
            high = middle
    return low


class Plc:
    """The scripted PLC of one card (manual §1.4, §2.4; spec §4.10): run state, download image, cycle and rules."""

    #: The cycle's own bookkeeping in slots, the rest in the instance dictionary: that one shares
    #: its keys among the cards while it holds 29 or fewer (see :class:`devsim.core.model.Model`).
    __slots__ = ("_wrote", "_pae", "_prev_pae", "_fe_pending", "_controller_was_on", "_copies", "_directed",
                 "_reads_inputs", "__dict__", "__weakref__")

    def __init__(
        self,
        *,
        card: PlcCard,
        clock: Clock,
        options: Settings,
        ms_per_1000: int | None,
        flash: Flash,
        image: ProcessImage,
        outputs: Outputs,
        counter: CounterInput,
        indexer: Indexer,
        stage: PowerStage,
        interpolation: Callable[[], bool],
        powered: Callable[[], bool],
    ) -> None:
        self.card = card
        self.clock = clock
        self.cfg = options  # the configuration's ``plc:``
        self.ms_per_1000 = ms_per_1000  # the variant's measured cycle time (manual §6)
        self.flash = flash
        self.image = image
        self.outputs = outputs
        self.counter = counter
        self.indexer = indexer
        self.stage = stage
        self.interpolation = interpolation  # DIL 6: the PLC functionality is lost
        self.powered = powered
        self.running = False
        self.storage_error = False
        self.cycles = 0
        self.hooks: list[Hook] = [load_hook(self.cfg.hook)] if self.cfg.hook else []
        #: Why the PLC stopped by itself (a hook raised), or None.
        self.fault: str | None = None
        self._timer: Timer | None = None
        #: Nobody looks at the card before this simulated time (the scenario runner's hint, issue 31).
        self.unobserved = -math.inf
        self._wrote = False  # the cycle running changed a marker, an output or a message
        self._pae = bytes(4)
        self._paa_writes: dict[int, bool] = {}
        self._reset_rule_state()

    # -- configuration ----------------------------------------------------------------------
    @property
    def cycle_s(self) -> float:
        if self.cfg.cycle_ms is not None:
            return self.cfg.cycle_ms / 1000.0
        per_1000 = self.ms_per_1000 or 87
        return per_1000 * self.cfg.instructions / 1000.0 / 1000.0

    def scripted(self) -> bool:
        """The configuration describes a PLC program (rules or a hook)."""
        c = self.cfg
        return bool(
            c.auto_ack_m_functions_ms is not None
            or c.limit_switches
            or c.message_on_fault is not None
            or c.start_program_on_input
            or c.copy_bits
            or self.hooks
        )

    @property
    def loaded(self) -> bool:
        """A PLC program is in FLASH (downloaded, or the scenario's scripted program)."""
        if self.flash.plc_image is not None:
            return True
        return self.cfg.loaded if self.cfg.loaded is not None else self.scripted()

    @property
    def disabled(self) -> bool:
        """Behind a GMS-I (DIL 6) the PLC functionality is lost (spec §4.11.6)."""
        return self.interpolation()

    # -- run state ------------------------------------------------------------------------------
    def power_on(self, boot_time: float = 0.0) -> None:
        """Power-on / reset: a program in FLASH starts by itself (manual §2.4), after the card's
        ``boot_time``."""
        self._cancel()
        self.running = False
        self.storage_error = False
        self._reset_rule_state()
        if self.loaded and not self.disabled:
            self.running = True
            first = boot_time + self.cycle_s
            self._timer = self.clock.call_later(first, self._cycle)

    def power_off(self) -> None:
        self._cancel()
        self.running = False

    def start(self) -> None:
        """``p1;1``: start the PLC program (no program: stays stopped, T3;4 I.1 = 1)."""
        if self.running or self.disabled or not self.loaded:
            return
        self.running = True
        self.fault = None
        self._reset_rule_state()
        self.card.record_event("plc_start")
        self._schedule()

    def stop(self) -> None:
        """``p1;2``: stop the PLC (outputs and markers keep their state [R])."""
        if not self.running:
            return
        self._cancel()
        self.running = False
        self.card.record_event("plc_stop")

    def _cancel(self) -> None:
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None

    def _schedule(self) -> None:
        self._cancel()
        self._timer = self.clock.call_later(self.cycle_s, self._cycle)

    def _cycle(self) -> None:
        self._timer = None
        if not self.running or not self.powered():
            return
        try:
            self.run_cycle()
        except Exception as exc:  # a hook (trusted Python from a config file) failed
            self.running = False
            self.fault = f"{type(exc).__name__}: {exc}"
            self.card.record_event("plc_fault")
            return
        if self.running:
            self._schedule_next()

    def _schedule_next(self) -> None:
        """The next cycle; after one that changed nothing, while nobody looks, the first that
        may not (:func:`cycle_after`); only a virtual clock knows its next timer."""
        clock = self.clock
        if (self._wrote or self._ack_seen or self.hooks or self.unobserved == -math.inf
                or not isinstance(clock, VirtualClock)):
            self._schedule()
            return
        now = clock.now()
        horizon = min(self.unobserved, _at(clock.next_event()), _at(self.indexer.plan_changes_at()))
        if self._directed:  # (the inputs the limit rules read change only at events: the clock's, a step's)
            horizon = direction_changes_at(self.indexer, now, horizon)
        when, skipped = cycle_after(now, self.cycle_s, horizon)
        self.cycles += skipped
        self._cancel()
        self._timer = self.clock.call_at(when, self._cycle)

    # -- download (spec §3.8.24) ---------------------------------------------------------------
    def begin_download(self) -> None:
        """``p1;100``: the flash sector is erased: the program is gone, the PLC stops."""
        self.stop()
        self.flash.erase_plc()

    def end_download(self, frames: list[bytes]) -> None:
        """``p1;101``: store the ``a`` frames' raw data in order as the PLC program image.

        An empty download leaves no program; one longer than ``plc.flash_bytes`` sets the
        storage error (T3;4 I.0) and is discarded.  The new program is not started: the manual
        says it "can be started and stopped after a successful download" (`p1;1`) [R]."""
        size = sum(len(f) for f in frames)
        if size > self.cfg.flash_bytes:
            self.storage_error = True
            self.card.record_event("plc_storage_error")
            return
        self.storage_error = False
        self.card.record_event("plc_download" if self.flash.store_plc(frames) else "flash_error")

    # -- process image access for rules and hooks ----------------------------------------------
    def bit(self, name: str) -> bool:
        """A bit as the PLC sees it: E from this cycle's PAE, A from the outputs, M markers."""
        return self._bit(*parse_bit(name))

    def _bit(self, area: str, byte: int, bit: int) -> bool:
        if area == "E":
            return bool(self._pae[byte] >> bit & 1) if byte < len(self._pae) else False
        if area == "A":
            n = byte * 8 + bit
            if n in self._paa_writes:
                return self._paa_writes[n]
            return n < OUTPUT_BITS and self.outputs.output_bit(n)
        return self.card.marker_bit(byte, bit)

    def set_bit(self, name: str, value: bool) -> None:
        """Write an output (PAA, transferred at the end of the cycle) or a marker (at once)."""
        area, byte, bit = parse_bit(name)
        if area == "A":
            n = byte * 8 + bit
            if n < OUTPUT_BITS:
                self._paa_writes[n] = bool(value)
        elif area == "M":
            self.set_marker_bit(byte, bit, bool(value))
        else:
            raise ValueError(f"the PLC cannot write input {name}")

    def marker_byte(self, byte: int) -> int:
        return self.card.marker_byte(byte)

    def set_marker_byte(self, byte: int, value: int) -> None:
        if self.image.markers[byte] != value & 0xFF and self.card.write_marker_byte(byte, value):
            self._wrote = True

    def set_marker_bit(self, byte: int, bit: int, value: bool) -> None:
        # (a write the card takes without a change, e.g. M0.2 := 0 while a program runs, is none)
        if self.image.marker(byte, bit) != value and self.card.write_marker_bit(byte, bit, value):
            self._wrote = True

    def message(self, code: int) -> None:
        """Like SNDM: the code into MB4, buffered behind a waiting one (spec §4.5.1)."""
        self._wrote = True
        self.image.post_message(code)
        self.card.changed()

    def fb254(self, accu1: int, accu2: int = 0) -> None:
        """The FB 254 stand-in for a hook: the function in Accu1 (:data:`FB254_FUNCTIONS`; any
        other is not modelled and does nothing) with Accu2."""
        handler = FB254_FUNCTIONS.get(str(accu1))
        if handler is not None:
            handler(self, int(accu2))

    def h22_copy(self, address: int) -> None:
        """FB 254 / Accu1 = 22: copy the H22 measurement into the data area from byte ``address``
        (spec §3.8.7, layout in counter.py)."""
        self.counter.h22_copy(address)

    @property
    def now(self) -> float:
        return self.clock.now()

    # -- one cycle -------------------------------------------------------------------------------
    def run_cycle(self) -> None:
        self.cycles += 1
        self._wrote = False
        if self._reads_inputs:  # (no rule or hook looks at the PAE: not taken, issue 31)
            self._pae = bytes(self.outputs.input_byte(b) for b in range(4))
        self._paa_writes = {}
        self._auto_ack()
        self._limit_switches()
        self._fault_messages()
        self._start_rules()
        self._copy_rules()
        for hook in self.hooks:
            hook(self)
        self._prev_pae = self._pae
        self._flush_paa()

    def _flush_paa(self) -> None:
        outputs = self.image.outputs
        changed = False
        for n, value in self._paa_writes.items():
            if bool(outputs[n // 8] >> (n % 8) & 1) != value:
                byte, bit = divmod(n, 8)
                if value:
                    outputs[byte] |= 1 << bit
                else:
                    outputs[byte] &= ~(1 << bit) & 0xFF
                changed = True
        self._paa_writes = {}
        if changed:
            self._wrote = True
            self.card.changed()

    def _reset_rule_state(self) -> None:
        self._ack_seen: dict[tuple[int, int], float] = {}
        self._limit_active: list[bool] = [False] * len(self.cfg.limit_switches)
        self._stop_by_rules = False
        self._faults: dict[str, bool] = {
            "following_error": False,
            "monitoring": False,
            "emergency_stop": False,
        }
        self._prev_pae: bytes | None = None
        self._fe_pending = False
        self._controller_was_on = bool(self.stage.controller)
        c = self.cfg
        #: The copy rules with their bits parsed: ((area, byte, bit) read, invert, (area, byte, bit) written).
        self._copies = [(parse_bit(rule.source), rule.invert, parse_bit(rule.to)) for rule in c.copy_bits]
        #: Whether a limit rule acts only on motion one way (it reads the commanded direction).
        self._directed = any(rule.direction != "any" for rule in c.limit_switches)
        #: Whether a cycle takes the inputs into the PAE: a rule or a hook reads them.
        self._reads_inputs = bool(c.limit_switches or c.start_program_on_input or self.hooks
                                  or any(source[0] == "E" for source, _invert, _to in self._copies))

    # -- rules -----------------------------------------------------------------------------------
    def _auto_ack(self) -> None:
        ms = self.cfg.auto_ack_m_functions_ms
        if ms is None:
            return
        markers = self.image.markers
        if not self._ack_seen and not (any(markers[6:11]) or (markers[15] | markers[18]) & 0x80):
            return  # no M function bit set, none waiting (the loop below would do nothing)
        now = self.now
        for byte, bit in M_FUNCTION_BITS:
            key = (byte, bit)
            if not self.image.marker(byte, bit):
                self._ack_seen.pop(key, None)
                continue
            seen = self._ack_seen.setdefault(key, now)
            if now - seen >= ms / 1000.0 - _EPS:
                del self._ack_seen[key]
                self.set_marker_bit(byte, bit, False)

    def _limit_switches(self) -> None:
        rules = self.cfg.limit_switches
        if not rules:
            return
        direction = commanded_direction(self.indexer)
        want_stop = False
        for i, rule in enumerate(rules):
            active = self.bit(rule.input) != rule.active_low
            towards = rule.direction == "any" or direction == (1 if rule.direction == "+" else -1)
            edge = active and not self._limit_active[i]
            self._limit_active[i] = active
            if edge and rule.message:
                self.message(rule.message)
            if rule.action == "stop":
                want_stop = want_stop or (active and towards)
            elif active and towards and (edge or (rule.direction != "any" and direction != 0)):
                self.card.record_event("plc_limit_abort")
                self.set_marker_bit(0, 1, True)  # the firmware aborts and clears M0.1
        if any(r.action == "stop" for r in rules) and want_stop != self._stop_by_rules:
            self._stop_by_rules = want_stop
            self.set_marker_bit(0, 0, want_stop)

    def _fault_states(self) -> dict[str, bool]:
        """Fault levels from MB0: a following error is the position controller (M0.5) going
        off while neither emergency stop (M0.4 = 0) nor monitoring (M0.6) is present; it stays
        pending until the controller is on again (Q / Q3)."""
        mb0 = self.card.marker_byte(0)
        estop = not mb0 & 0x10
        monitoring = bool(mb0 & 0x40)
        controller = bool(mb0 & 0x20)
        if controller:
            self._fe_pending = False
        elif self._controller_was_on and not estop and not monitoring:
            self._fe_pending = True
        self._controller_was_on = controller
        return {"following_error": self._fe_pending, "monitoring": monitoring, "emergency_stop": estop}

    def _fault_messages(self) -> None:
        codes = self.cfg.message_on_fault
        query = self.image.marker(3, 1)
        if codes is not None:  # (without codes the fault states matter to nothing: not taken)
            states = self._fault_states()
            for name, active in states.items():
                code = getattr(codes, name)
                if code and active and (query or not self._faults[name]):
                    self.message(code)
            self._faults = states
        if query:
            self.set_marker_bit(3, 1, False)  # the PLC resets M3.1 after re-reporting (M §2.3.1 q)

    def _start_rules(self) -> None:
        prev = self._prev_pae
        if prev is None:
            return  # no edge in the first cycle after a (re)start
        for rule in self.cfg.start_program_on_input:
            _area, byte, bit = parse_bit(rule.input)
            old, new = bool(prev[byte] >> bit & 1), bool(self._pae[byte] >> bit & 1)
            if old == new or new != (rule.edge == "rising"):
                continue
            if self.image.marker(0, 2):
                continue  # a program runs: M0.2 is already 1
            self.card.record_event("plc_start_program")
            self.set_marker_byte(2, rule.program)
            self.set_marker_bit(0, 2, True)

    def _copy_rules(self) -> None:
        for source, invert, (area, byte, bit) in self._copies:
            value = self._bit(*source) != invert
            if area == "A":
                n = byte * 8 + bit
                if n < OUTPUT_BITS and bool(self.image.outputs[byte] >> bit & 1) != value:
                    self._paa_writes[n] = value
            elif area == "M":
                self.set_marker_bit(byte, bit, value)

    # -- inspection --------------------------------------------------------------------------------
    def state(self) -> dict[str, Any]:
        return {
            "loaded": self.loaded,
            "running": self.running,
            "cycles": self.cycles,
            "cycle_ms": self.cycle_s * 1000.0,
            "storage_error": self.storage_error,
            "fault": self.fault,
            "image_bytes": len(self.flash.plc_image or "") // 2,
            "frames": len(self.flash.plc_frames),
        }


#: The functions of the firmware block FB 254 a PLC program calls, by Accu1 (manual §2.3.1 H).
FB254_FUNCTIONS: Table[Callable[[Plc, int], None]] = Table(
    [Command("22", Plc.h22_copy, "§2.3.1 H", "copy the H22 measurement to the data area from byte Accu2")]
)
