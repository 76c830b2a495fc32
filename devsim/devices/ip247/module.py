"""The IP247 module: three axis pages and the data channel, its records and battery RAM (manual
§2.7, §4.1–§4.4, §6.3.8, §7.2, §7.3.3; spec ip247.md §3.1, §3.2, §3.4, §4.1–§4.14).

The module is composed of parts: the axis pages (:class:`.axis_unit.AxisUnit`, ``units``), the
modes that move them (:class:`.modes.AxisModes`), the programs (:class:`.programs.ProgramJobs`)
and the data channel with the records (:class:`.records.DataChannel`, ``channel``).  Both host
interfaces reach it with the same services (spec §3.6, §3.7): :meth:`Ip247Module.operate` (an
operator job), the data channel's ``write_record``, ``read_record`` and ``delete_record``, and
:meth:`~Ip247Module.observe`.  Each returns the interface acknowledgement (00H, 80H …) and
leaves module errors on the pages (spec §4.3).  Machine data, programs, SYS-ID and offsets live
in battery RAM (the state dir); a battery fault loses them at the next power-up (spec §4.14).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from devsim.core.clock import Clock
from devsim.core.kit import Command, Table, declare_signals
from devsim.core.model import Model
from devsim.core.nvram import NonVolatileMemory, numbered
from devsim.devices.ip247 import machine_data
from devsim.devices.ip247.axis_unit import AxisUnit
from devsim.devices.ip247.basp import Basp
from devsim.devices.ip247.jobs import START, STOP, TAKE_OVER, Job, refusal
from devsim.devices.ip247.modes import AxisModes
from devsim.devices.ip247.pg_profile import ACK_ACCEPTED, ACK_FULL, ACK_NEGATIVE, ACK_QUEUED, Observation
from devsim.devices.ip247.programs import ProgramJobs
from devsim.devices.ip247.records import DataChannel
from devsim.devices.ip247.signals import SIGNALS
from devsim.devices.ip247.store import ProgramStore
from devsim.devices.ip247.tables import MODES, NONEXISTENT, OBSERVE_MODES, mode_token, page_error

__all__ = ["Ip247Module", "OBSERVED", "OPERATOR_JOBS", "OPERATOR_MODES"]

OPERATOR_MODES = frozenset(range(1, 18))
AXES = (1, 2, 3)
BOOT_TIME, BLINK = 1.0, 0.25  # seconds until the PG port is online; LED blink period (spec §5.16)
#: [SIM-CHOICE] The largest stored offset: 2^53, where the motion's float arithmetic stops being exact
#: (10^400 failed a program start with OverflowError).  No tighter bound: an aborted program folds its
#: G54 … G57 shift into BA12/13's unchecked, so shifts add up past the 32-bit double words.
OFFSET_BOUND = 2**53


class Ip247Module(Model):
    """One IP247 (6ES5 247-4UA31/41) with its three axes (manual §2.7, §4.1)."""

    def __init__(self, *, clock: Clock, config: dict[str, Any] | None = None,
                 nvram: NonVolatileMemory | None = None, name: str = "") -> None:
        super().__init__(clock=clock, config=config, nvram=nvram, name=name)
        cfg = self.config
        declare_signals(self.signals, SIGNALS)
        geometry = cfg.get("axes") or {}
        self.basp = Basp(cfg)
        self.wiring_faults: set[str] = set()  # spec §5.15: see points.FAULTS
        self.units = [AxisUnit(n, dict(geometry.get(n) or geometry.get(str(n)) or {}), clock=clock,
                               signals=self.signals, events=self, basp=self.basp, wiring_faults=self.wiring_faults)
                      for n in AXES]
        self.programs = ProgramJobs(self.units, self.save)
        self.modes = AxisModes(self.programs)
        self.channel = DataChannel(self.units, self.programs, self, cfg)
        self._boot_timers: list[Any] = []
        self.tbit = {1: False, 2: False, 3: False}  # FB164's TBIT as the PLC side would see it (spec §3.7)
        self.ag_last: dict[str, Any] | None = None  # the answer to the last in-process PLC job (points)
        self.job_lists: dict[str, list[tuple[int, int, int, int, int, int]]] = {"pg": [], "ag": []}
        self._draining = False
        unit_input = self._unit_input  # one bound method for every input of the units (not a closure each)
        for unit in self.units:
            for prefix in UNIT_INPUTS:
                self.signals.subscribe(f"{prefix}{unit.number}", unit_input)
        self.signals.subscribe("BASP", self._basp_input)
        self._load()
        self.power_up()

    # -- battery RAM (spec §4.14) -------------------------------------------------------------------
    def _load(self) -> None:
        """Battery RAM as the module left it; a section holding what the module never stores (a
        hand-edited or damaged state file) is a ValueError naming it, and the start stops with
        UnfitMemory naming the file, as for the other kinds' memories."""
        if self.config.get("battery_ok", True) is False:
            self.nvram.wipe()
        stored = "sys_id" in self.nvram  # (absent: the config's; null is no SYS-ID the module writes)
        ident = self.nvram.get("sys_id")
        default = self.config.get("sys_id") or {}
        if stored and (type(ident) is not list or len(ident) != 3
                       or not all(type(v) is int and 0 <= v <= 0xFF for v in ident)):
            raise ValueError(f"the SYS-ID {ident!r} is no three bytes as BA24 stores them")
        self.channel.sys_id = tuple(ident) if stored else (
            int(default.get("module", 0)), int(default.get("slot", 0)), int(default.get("page", 0)))
        # the numbered sections by the keys save() writes (str(n) of an axis 1 … 3): '01', '+1' or '٣'
        # was no key looked up, and that axis started without its MD or offsets, not a word said
        mds = numbered(self.nvram.get("md", {}), "machine data of axis", AXES)
        for unit in self.units:
            words = mds.get(unit.number)
            if words is not None:  # (save() writes no empty record: [] is machine_data.stored's to refuse)
                unit.load_md(machine_data.stored(words, axis=unit.number, sys_module=self.channel.sys_id[0]),
                             list(words), first=False)
        # every save() wrote the offsets of all three axes (git log -p since the kind was added), so
        # an axis missing from a stored section is a hand-edited or damaged file: refused, where it
        # loaded as 0 before; no section at all is battery RAM no save() has written yet (a wiped
        # one, or an older devsim killed between the first save's writes of md and offsets)
        offsets = numbered(self.nvram.get("offsets", {}), "offsets of axis", AXES)
        stored_offsets = "offsets" in self.nvram
        for unit in self.units:
            record = offsets.get(unit.number) if stored_offsets else [0, 0, 0]
            if record is None:
                raise ValueError(f"the offsets of axis {unit.number} are missing: the module stores all three axes'")
            if type(record) is not list or len(record) != 3:
                raise ValueError(f"the offsets of axis {unit.number} {record!r:.40} are no three as the module stores")
            zo, to, tp = record
            if not all(type(v) is int and abs(v) < OFFSET_BOUND for v in (zo, to, tp)):
                raise ValueError(f"the offsets of axis {unit.number} {[zo, to, tp]!r} are no whole numbers"
                                 f" within ±2^53")
            unit.coords.zo_mode, unit.coords.to_ba15, unit.coords.to_prog = zo, to, tp
        self.programs.store = ProgramStore.from_json(self.nvram.get("programs", ProgramStore().to_json()))

    def save(self) -> None:
        """Battery RAM in one write: four writes (one per section) left, killed between them, a
        file of machine data without the offsets, programs or SYS-ID they were saved with."""
        self.nvram.put_sections({
            "md": {str(u.number): u.md_words for u in self.units if u.md_words},
            "offsets": {str(u.number): [u.coords.zo_mode, u.coords.to_ba15, u.coords.to_prog] for u in self.units},
            "programs": self.programs.store.to_json(),
            "sys_id": list(self.channel.sys_id),
        })

    def power_up(self) -> None:
        """Jobs and programs dropped, reference lost, error 8 everywhere; for ``boot_time`` (1 s)
        the module answers nothing while its LEDs blink alternately, then green stays on
        (spec §2.1, §5.16)."""
        self.announce("power_on")
        for unit in self.units:
            unit.power_up()
        self.channel.error = 8
        for timer in self._boot_timers:
            timer.cancel()
        boot = float(self.config.get("boot_time", BOOT_TIME))
        self.booting = boot > 0
        if not self.booting:
            self._running()
            return
        self._blink_at(self.clock.now(), 0, boot)

    def _blink_at(self, start: float, k: int, boot: float) -> None:
        """The ``k``-th blink of a boot that started at ``start``, then the next (or the end of the
        boot): one timer at a time, where one per blink of the whole boot made a ``boot_time`` of
        10^9 s take all memory at the start (fuzzed), at the same instants and in the same order."""

        def blink() -> None:
            self._blink(k % 2 == 0)
            if k < boot // BLINK:  # (the last blink: as many as fit in the boot)
                self._blink_at(start, k + 1, boot)
            else:
                self._boot_timers[:] = [self.clock.call_at(start + boot, self._running)]

        self._boot_timers[:] = [self.clock.call_at(start + k * BLINK, blink)]

    def _blink(self, green: bool) -> None:
        self.signals.set("led_green", green)
        self.signals.set("led_red", not green)

    def _running(self) -> None:
        self._boot_timers.clear()
        self.signals.set("led_green", True)
        self._leds()
        if self.booting:
            self.booted()

    def power_cycle(self, *, wipe: bool = False) -> None:
        wipe = wipe or self.config.get("battery_ok", True) is False  # battery RAM lost (spec §4.14)
        super().power_cycle(wipe=wipe)
        if wipe:
            for unit in self.units:
                unit.md = unit.md_words = None
            self.programs.store, self.channel.sys_id = ProgramStore(), (0, 0, 0)
        self._load()
        self.power_up()

    # -- pages and errors ---------------------------------------------------------------------------
    def unit(self, page: int) -> AxisUnit | None:
        return self.units[page - 1] if 1 <= page <= 3 else None

    def error_of(self, page: int) -> int:
        unit = self.unit(page)
        return unit.error if unit is not None else self.channel.error

    def set_error(self, unit: AxisUnit | None, error: int) -> None:
        if unit is None:
            self.channel.error = error
        else:
            unit.error = error
        if error:  # by its number: the logs take its text from the error table (0: no error)
            self.report_error(str(error))
        self.record_event(f"error {error}")
        self._leds()

    def changed(self, unit: AxisUnit) -> None:
        self.announce("changed", unit.number)
        if not unit.running:
            self.tbit[unit.number] = False
        if not unit.braking and not self._draining and any(q and q[0][0] == unit.number for q in
                                                             self.job_lists.values()):
            self._drain(unit.number)

    def _drain(self, page: int) -> None:
        """The axis stands again: the jobs that came while it braked are interpreted in arrival
        order (spec §3.1)."""
        self._draining = True
        try:
            for source, queue in self.job_lists.items():
                while queue and queue[0][0] == page and not self.units[page - 1].braking:
                    self.operate(*queue.pop(0), source=source)
        finally:
            self._draining = False

    def _leds(self) -> None:
        self.signals.set("led_red", any(self.error_of(p) >= 10 for p in (1, 2, 3, 4)))

    def _unit_input(self, name: str, _old: Any, value: Any) -> None:
        """An input of an axis unit changed (``ANF1``, ``BB3`` …): what :data:`UNIT_INPUTS` says
        for its name without the unit's number, with the unit the number names."""
        number = int(name[-1])
        unit = next(u for u in self.units if u.number == number)
        UNIT_INPUTS[name[:-1]](self, unit, value)

    def _basp_input(self, _name: str, _old: Any, value: Any) -> None:
        self._basp(bool(value))

    def _basp(self, active: bool) -> None:
        """BASP with X21 2-3: every running axis brakes, error 55 on all axes, PE low (spec
        §5.13); with X21 1-2 it is ignored."""
        if not self.basp.honoured:
            return
        self.basp.active = active
        for unit in self.units:
            if active:
                if unit.running or unit.waiting_start is not None:
                    unit.waiting_start = None
                    unit.fail(55)
                else:
                    self.set_error(unit, 55)
            unit.set_pe()

    def _ready(self, unit: AxisUnit, ready: bool) -> None:
        """BB from the power unit: 0→1 restarts its pattern counter; falling during motion the
        pulses stop at once, error 53 (spec §5.14, §5.6.3)."""
        if ready:
            unit.pattern_base = unit.axis.position()
            return
        if unit.running:
            if unit.automatic is not None:
                unit.automatic.abort()
            unit.axis.quick_stop()
            unit.brake()
            self.set_error(unit, 53)

    def _external(self, unit: AxisUnit, level: bool) -> None:
        """START-N/STOP input: 0→1 stops (error 27 while moving), 1→0 releases a waiting job
        (spec §5.10)."""
        if level:
            if unit.waiting_start is not None:
                return
            if unit.running and unit.automatic is not None:
                unit.automatic.command(unit.mode, 2)  # interrupted, continuable with Übernahme
                self.set_error(unit, 27)
            elif unit.running:
                unit.fail(27)
            elif unit.automatic is not None and unit.automatic.halted:
                unit.automatic.halted, unit.automatic.interrupted = False, True
                self.set_error(unit, 65)
        else:
            unit.release()

    # -- operator jobs (spec §3.1, §4.2) ------------------------------------------------------------
    def operate(self, page: int, ba: int, cmd: int, b: int = 0, w: int = 0, dd: int = 0, *,
                source: str = "pg") -> int:
        """An operator job from the PG or the PLC (``source`` "ag"); returns the acknowledgement:
        00H, 80H, 01H (queued while the axis brakes) or 81H (that interface's job list is full:
        error 1 from the PG, 5 from the PLC)."""
        if ba in NONEXISTENT - {3} or (ba in MODES and ba not in OPERATOR_MODES):
            return ACK_NEGATIVE  # BA18/19/72 and the record modes: not an operator job here
        if ba in OBSERVE_MODES:  # BA74 "Beobachtung ausschalten" (FB164's own): nothing changes (§4.4)
            return ACK_ACCEPTED
        unit = self.unit(page)
        if unit is not None and unit.braking and ba in OPERATOR_MODES:
            queue = self.job_lists[source]
            if len(queue) >= int(self.config.get("job_list", 8)):
                self.set_error(unit, 1 if source == "pg" else 5)
                return ACK_FULL
            queue.append((page, ba, cmd, b, w, dd))
            return ACK_QUEUED
        if page_error(ba, page) == 46:
            self.set_error(unit, 46)
            return ACK_NEGATIVE
        job = OPERATOR_JOBS.get(mode_token(ba))
        if job is None:  # an undefined mode (3, 25 … 63, 75 …): error 2, and what runs is aborted
            error: int | None = 2
            if unit is not None and (unit.running or unit.waiting_start is not None):
                error = self.modes.operate(unit, ba, cmd, b, w, dd)  # (manual §7.2.2)
            if error is not None:
                self.set_error(unit, error)
            return ACK_ACCEPTED
        return job(self, unit, Job(page, ba, cmd), b, w, dd, source)

    def _clear_errors(self, unit: AxisUnit | None, job: Job, b: int, w: int, dd: int, source: str) -> int:
        """BA17 "Start" in the axis state "fertig" (§4.3.10): the errors of every axis and the data
        channel.  Another command, or an axis that runs or waits, is a job as any (error 2, §4.1)."""
        if unit is not None and (job.cmd != START or unit.running or unit.waiting_start is not None):
            return self._axis_job(unit, job, b, w, dd, source)
        if job.cmd != START:
            self.set_error(unit, 2)
            return ACK_ACCEPTED
        for u in self.units:
            u.error = 0
        self.channel.error = 0
        self._leds()
        if unit is not None:
            unit.mode, unit.last_cmd = 17, job.cmd
        return ACK_ACCEPTED

    def _axis_job(self, unit: AxisUnit | None, job: Job, b: int, w: int, dd: int, source: str) -> int:
        """BA1 … BA17 on an axis page: the checks (:func:`.jobs.refusal`), then the mode."""
        assert unit is not None
        unit.error = 0  # a new operator job acknowledges the page's pending error (spec §3.1)
        if unit.automatic is not None and job.ba not in (8, 9) and not unit.running:
            unit.automatic.abort()  # starting another mode aborts the program context
        error = refusal(unit.view(), job)
        if error is not None and not (unit.running and error == 2):
            if error == 2 and unit.waiting_start is None:
                self.modes.select(unit, job.ba, job.cmd)  # a senseless command: the mode all the same
            self.set_error(unit, error)
            return ACK_ACCEPTED
        error = self.modes.operate(unit, job.ba, job.cmd, b, w, dd)
        if error is not None:
            self.set_error(unit, error)
        if source == "ag" and job.cmd != STOP:
            self.tbit[job.page] = unit.running  # FB164's busy bit: set while the job it issued runs
        elif job.cmd == TAKE_OVER and job.ba in (8, 9):
            self.tbit[job.page] = False  # a program the PG continues belongs to the PG (spec §3.3.1)
        self._leds()
        self.save()
        return ACK_ACCEPTED

    # -- observe (spec §3.6.4) ----------------------------------------------------------------------
    def header(self, page: int) -> tuple[int, int, int, int]:
        """(err, btr, rmld, mfkt) of a page."""
        unit = self.unit(page)
        if unit is None:
            return self.channel.error, 0, 0, 0
        return unit.error, unit.mode, unit.attributes(), unit.m_function

    def observe(self, page: int) -> Observation:
        unit = self.unit(page)
        errors = (*(u.error for u in self.units), self.channel.error)
        if unit is None:
            return Observation(0, 0, errors, 0, 0)  # type: ignore[arg-type]
        run = unit.automatic
        flags = (int(unit.waiting_start is not None) | int(bool(run and run.interrupted)) << 1
                 | int(unit.teach_in is not None) << 2 | int(bool(run and run.halted)) << 3)
        valid = unit.md is not None
        position = OBSERVED[mode_token(71)](unit) if valid else 0
        residual = OBSERVED[mode_token(73)](unit) if valid else 0
        return Observation(position, residual, errors, unit.last_cmd, flags)  # type: ignore[arg-type]

    def close(self) -> None:
        for unit in self.units:
            unit.axis.quick_stop()


OperatorJob = Callable[[Ip247Module, "AxisUnit | None", Job, int, int, int, str], int]

#: The operator jobs FB164 and the PG's OPERATE give (spec §3.1, §3.2): the axis modes (their
#: behaviour in :data:`.modes.AXIS_MODES`) and BA17 "Fehler löschen".
OPERATOR_JOBS: Table[OperatorJob] = Table([
    *(Command(mode_token(n), Ip247Module._axis_job, "§4.1.1", MODES[n].describe()) for n in sorted(MODES) if n < 17),
    Command(mode_token(17), Ip247Module._clear_errors, "§4.1.1", MODES[17].describe()),
])
#: The observe modes (spec §3.2, §3.6.4): what OBSERVE shows of an axis page.
OBSERVED: Table[Callable[[AxisUnit], int]] = Table([
    Command(mode_token(71), AxisUnit.actual, "§4.1.1", MODES[71].describe()
            + "; shown by OBSERVE (62H), not an operator job (80H)"),
    Command(mode_token(73), AxisUnit.residual, "§4.1.1", MODES[73].describe()
            + "; shown by OBSERVE (62H), not an operator job (80H)"),
])


#: What an input of an axis unit does when it changes, by its name without the unit's number:
#: the limit switches ANF/END (spec §5.7), the reference cam BERO (§5.6.2), START-N/STOP (§5.10) and
#: BB from the power unit (§5.14).
UNIT_INPUTS: dict[str, Callable[[Ip247Module, AxisUnit, Any], None]] = {
    "ANF": lambda _module, unit, _value: unit.limit_input("anf"),
    "END": lambda _module, unit, _value: unit.limit_input("end"),
    "BERO": lambda _module, unit, value: unit.cam_input(bool(value)),
    "START": lambda module, unit, value: module._external(unit, bool(value)),
    "BB": lambda module, unit, value: module._ready(unit, bool(value)),
}
