"""The IP247 module: three axis pages and the data channel, its records and battery RAM (manual
§2.7, §4.1–§4.4, §6.3.8, §7.2, §7.3.3; spec ip247.md §3.1, §3.2, §3.4, §4.1–§4.14).

Both host interfaces reach it with the same services (spec §3.6, §3.7): :meth:`Ip247Module.operate`
(an operator job), :meth:`~Ip247Module.write_record`, :meth:`~Ip247Module.read_record`,
:meth:`~Ip247Module.delete_record` and :meth:`~Ip247Module.observe`.  Each returns the interface
acknowledgement (00H, 80H …) and leaves module errors on the pages (spec §4.3).  Machine data,
programs, SYS-ID and offsets live in battery RAM (the state dir); a battery fault loses them at the
next power-up (spec §4.14).
"""

from __future__ import annotations

from typing import Any

from devsim.core.clock import Clock
from devsim.core.kit import declare_signals
from devsim.core.model import Model
from devsim.core.nvram import NonVolatileMemory
from devsim.core.record import replace
from devsim.devices.ip247 import machine_data, values
from devsim.devices.ip247 import program as lang
from devsim.devices.ip247.automatic import ProgramRun
from devsim.devices.ip247.axis_unit import AxisUnit
from devsim.devices.ip247.jobs import START, STOP, TAKE_OVER, Job, refusal
from devsim.devices.ip247.pg_profile import ACK_ACCEPTED, ACK_FULL, ACK_NEGATIVE, ACK_QUEUED, Observation
from devsim.devices.ip247.signals import SIGNALS
from devsim.devices.ip247.store import CAPACITY, ProgramStore, Stored, StoreError
from devsim.devices.ip247.tables import MODES, NONEXISTENT, page_error

__all__ = ["Ip247Module", "OPERATOR_MODES", "READ_MODES"]

OPERATOR_MODES = frozenset(range(1, 18))
WRITE_MODES, DELETE_MODES, READ_MODES = frozenset((20, 22, 24)), frozenset((21, 23)), frozenset(range(64, 71))
AXES = (1, 2, 3)
RS_PULSE = 0.1  # seconds (spec §5.16)
BOOT_TIME, BLINK = 1.0, 0.25  # seconds until the PG port is online; LED blink period (spec §5.16)


class Ip247Module(Model):
    """One IP247 (6ES5 247-4UA31/41) with its three axes."""

    def __init__(self, *, clock: Clock, config: dict[str, Any] | None = None,
                 nvram: NonVolatileMemory | None = None, name: str = "") -> None:
        super().__init__(clock=clock, config=config, nvram=nvram, name=name)
        cfg = self.config
        declare_signals(self.signals, SIGNALS)
        geometry = cfg.get("axes") or {}
        self.units = [AxisUnit(self, n, dict(geometry.get(n) or geometry.get(str(n)) or {})) for n in AXES]
        self.channel_error = 8
        self.sys_id = (0, 0, 0)
        self.store = ProgramStore()
        self.basp = False
        self._boot_timers: list[Any] = []
        self.wiring_faults: set[str] = set()  # spec §5.15: see points.FAULTS
        self.tbit = {1: False, 2: False, 3: False}  # FB164's TBIT as the PLC side would see it (spec §3.7)
        self.ag_last: dict[str, Any] | None = None  # the answer to the last in-process PLC job (points)
        self.job_lists: dict[str, list[tuple[int, int, int, int, int, int]]] = {"pg": [], "ag": []}
        self._draining = False
        for unit in self.units:
            n = unit.number
            self.signals.subscribe(f"ANF{n}", lambda _n, _o, v, u=unit: u.limit_input("anf"))
            self.signals.subscribe(f"END{n}", lambda _n, _o, v, u=unit: u.limit_input("end"))
            self.signals.subscribe(f"BERO{n}", lambda _n, _o, v, u=unit: u.cam_input(bool(v)))
            self.signals.subscribe(f"START{n}", lambda _n, _o, v, u=unit: self._external(u, bool(v)))
            self.signals.subscribe(f"BB{n}", lambda _n, _o, v, u=unit: self._ready(u, bool(v)))
        self.signals.subscribe("BASP", lambda _n, _o, v: self._basp(bool(v)))
        self._load()
        self.power_up()

    # -- battery RAM (spec §4.14) -------------------------------------------------------------------
    def _load(self) -> None:
        if self.config.get("battery_ok", True) is False:
            self.nvram.wipe()
        mds = self.nvram.get("md") or {}
        for unit in self.units:
            words = mds.get(str(unit.number))
            if words:
                unit.load_md(machine_data.decode(list(words)), list(words), first=False)
        offsets = self.nvram.get("offsets") or {}
        for unit in self.units:
            zo, to, tp = offsets.get(str(unit.number), (0, 0, 0))
            unit.coords.zo_mode, unit.coords.to_ba15, unit.coords.to_prog = zo, to, tp
        self.store = ProgramStore.from_json(self.nvram.get("programs"))
        ident = self.nvram.get("sys_id")
        default = self.config.get("sys_id") or {}
        self.sys_id = tuple(ident) if ident else (int(default.get("module", 0)), int(default.get("slot", 0)),
                                                   int(default.get("page", 0)))

    def save(self) -> None:
        self.nvram.put("md", {str(u.number): u.md_words for u in self.units if u.md_words})
        self.nvram.put("offsets", {str(u.number): [u.coords.zo_mode, u.coords.to_ba15, u.coords.to_prog]
                                   for u in self.units})
        self.nvram.put("programs", self.store.to_json())
        self.nvram.put("sys_id", list(self.sys_id))

    def power_up(self) -> None:
        """Jobs and programs dropped, reference lost, error 8 everywhere; for ``boot_time`` (1 s)
        the module answers nothing while its LEDs blink alternately, then green stays on
        (spec §2.1, §5.16)."""
        for unit in self.units:
            unit.power_up()
        self.channel_error = 8
        for timer in self._boot_timers:
            timer.cancel()
        boot = float(self.config.get("boot_time", BOOT_TIME))
        self.booting = boot > 0
        if not self.booting:
            self._running()
            return
        blinks = int(boot / BLINK)
        for k in range(blinks + 1):
            self._boot_timers.append(self.clock.call_later(k * BLINK, lambda k=k: self._blink(k % 2 == 0)))
        self._boot_timers.append(self.clock.call_later(boot, self._running))

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
            self.store, self.sys_id = ProgramStore(), (0, 0, 0)
        self._load()
        self.power_up()

    # -- pages and errors ---------------------------------------------------------------------------
    def unit(self, page: int) -> AxisUnit | None:
        return self.units[page - 1] if 1 <= page <= 3 else None

    def error_of(self, page: int) -> int:
        unit = self.unit(page)
        return unit.error if unit is not None else self.channel_error

    def set_error(self, unit: AxisUnit | None, error: int) -> None:
        if unit is None:
            self.channel_error = error
        else:
            unit.error = error
        self.record_event(f"error {error}")
        self._leds()

    def fail(self, unit: AxisUnit, error: int) -> None:
        """Stop the axis and its program (a limit switch, an external stop): error ``error``."""
        if unit.automatic is not None:
            unit.automatic.abort()
        unit.brake()
        self.set_error(unit, error)

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

    @property
    def basp_forces_pe(self) -> bool:
        return self.basp and self.config.get("x21", "2-3") == "2-3"

    def _basp(self, active: bool) -> None:
        """BASP with X21 2-3: every running axis brakes, error 55 on all axes, PE low (spec
        §5.13); with X21 1-2 it is ignored."""
        if self.config.get("x21", "2-3") != "2-3":
            return
        self.basp = active
        for unit in self.units:
            if active:
                if unit.running or unit.waiting_start is not None:
                    unit.waiting_start = None
                    self.fail(unit, 55)
                else:
                    self.set_error(unit, 55)
            unit.set_pe()

    def pulse_rs(self, unit: AxisUnit) -> None:
        """A 100 ms high pulse on RS; the pattern counter restarts at 0 (spec §2.8.1, §5.6.3)."""
        name = f"RS{unit.number}"
        self.signals.set(name, True)
        self.clock.call_later(RS_PULSE, lambda: self.signals.set(name, False))
        unit.pattern_base = unit.axis.position()

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
                self.fail(unit, 27)
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
        unit = self.unit(page)
        if unit is not None and unit.braking and ba in OPERATOR_MODES:
            queue = self.job_lists[source]
            if len(queue) >= int(self.config.get("job_list", 8)):
                self.set_error(unit, 1 if source == "pg" else 5)
                return ACK_FULL
            queue.append((page, ba, cmd, b, w, dd))
            return ACK_QUEUED
        if ba not in MODES:  # an undefined mode (3, 25 … 63, 75 …): error 2
            self.set_error(unit, 2)
            return ACK_ACCEPTED
        if page_error(ba, page) == 46:
            self.set_error(unit, 46)
            return ACK_NEGATIVE
        if ba == 17:
            for u in self.units:
                u.error = 0
            self.channel_error = 0
            self._leds()
            if unit is not None:
                unit.mode, unit.last_cmd = 17, cmd
            return ACK_ACCEPTED
        assert unit is not None
        unit.error = 0  # a new operator job acknowledges the page's pending error (spec §3.1)
        if unit.automatic is not None and ba not in (8, 9) and not unit.running:
            unit.automatic.abort()  # starting another mode aborts the program context
        error = refusal(unit.view(), Job(page, ba, cmd))
        if error is not None and not (unit.running and error == 2):
            self.set_error(unit, error)
            return ACK_ACCEPTED
        error = unit.operate(ba, cmd, b, w, dd)
        if error is not None:
            self.set_error(unit, error)
        if source == "ag" and cmd != STOP:
            self.tbit[page] = unit.running  # FB164's busy bit: set while the job it issued runs
        elif cmd == TAKE_OVER and ba in (8, 9):
            self.tbit[page] = False  # a program the PG continues belongs to the PG (spec §3.3.1)
        self._leds()
        self.save()
        return ACK_ACCEPTED

    def program_job(self, unit: AxisUnit, cmd: int, number: int) -> int | None:
        """BA8/BA9 while the axis is "fertig" (spec §4.2, §5.11)."""
        run = unit.automatic
        if cmd == STOP:
            if run is None:
                return None
            error, _ = run.stop_at_rest()
            return error
        if cmd == TAKE_OVER:
            return run.take_over() if run is not None else 2
        if cmd != START:
            return 2
        if run is not None:
            run.abort()
        stored = self.store.get(number)
        if stored is None:
            return 19
        if stored.error:
            return 48
        programs = {}
        for p in self.store.programs:
            if not p.error:
                programs[p.number] = lang.parse(p.text)
        unit.automatic = ProgramRun(unit, number, unit.mode == 9, programs)
        unit.automatic.start()
        return None

    def teach_job(self, unit: AxisUnit, cmd: int, number: int) -> int | None:
        """BA10 (teach-in on for a new program) and BA11 (close it with M02), spec §5.12."""
        if unit.mode == 10:
            if any(u.teach_in is not None for u in self.units):
                return 22  # one axis at a time
            if self.store.get(number) is not None:
                return 49
            if self.store.used + len(self._teach_text(number, [])) > CAPACITY:
                return 24
            unit.teach_in, unit.taught = number, []
            return None
        if unit.teach_in is None:
            return 2
        self._close_teach_in(unit)
        return None

    @staticmethod
    def _teach_text(number: int, blocks: list[str]) -> str:
        """The generated program (spec §5.12 [DECISION]): ``%  7``, ``N1 X1258.250 F2500``, ``N3 M02``."""
        return "".join(f"{line}\n" for line in (f"%{number:3d}", *blocks, f"N{len(blocks) + 1} M02"))

    def _close_teach_in(self, unit: AxisUnit) -> None:
        number, unit.teach_in = unit.teach_in, None
        assert number is not None
        self.store.add(Stored(number, self._teach_text(number, unit.taught)), from_plc=False)
        self.save()

    def teach_store(self, unit: AxisUnit) -> int | None:
        """Übernahme in teach-in at standstill: the actual value becomes a block with the MD
        step velocity, message 3 "Satz abgespeichert" (spec §5.12)."""
        if unit.teach_in is None or unit.md is None:
            return 2
        block = f"N{len(unit.taught) + 1} X{unit.actual() / 1000:.3f} F{unit.md.step_velocity}"
        if self.store.used + len(self._teach_text(unit.teach_in, [*unit.taught, block])) > CAPACITY:
            unit.taught[-1:] = []  # memory full: the last stored block makes way for the end block
            self._close_teach_in(unit)
            return 24
        unit.taught.append(block)
        return 3

    # -- records (spec §3.4, §4.9, §4.10) -----------------------------------------------------------
    def md_numbers_differ(self) -> bool:
        numbers = [u.md.db for u in self.units if u.md is not None]
        return len(numbers) == len(set(numbers))

    def _record_page(self, ba: int, page: int) -> int | None:
        """80H (and error 46 on the page) for a record mode the page does not permit, or None
        when it may run there."""
        if page_error(ba, page, md_numbers_differ=self.md_numbers_differ()) == 46:
            self.set_error(self.unit(page), 46)
            return ACK_NEGATIVE
        return None

    def write_record(self, page: int, ba: int, db: int, words: list[int], *, overwrite: bool = False,
                     from_plc: bool = False) -> tuple[int, list[int]]:
        """BA20, BA22, BA24: (ack, result words)."""
        if ba not in WRITE_MODES:
            return ACK_NEGATIVE, []
        refused = self._record_page(ba, page)
        if refused is not None:
            return refused, []
        unit = self.unit(page)
        if ba == 20:
            assert unit is not None
            return ACK_ACCEPTED, self._write_md(unit, db, words, overwrite and not from_plc)
        if ba == 22:
            return ACK_ACCEPTED, self._write_program(db, words, overwrite and not from_plc, from_plc)
        self.channel_error = 0
        if len(words) != 3:
            self.set_error(None, 2)
            return ACK_ACCEPTED, []
        module = words[0] & 0xFF
        if module != self.sys_id[0] and any(u.md_valid for u in self.units):
            self.set_error(None, 12)  # the module number is frozen by correct MD (spec §4.12)
            return ACK_ACCEPTED, []
        self.sys_id = (module, words[1] & 0xFF, words[2] & 0xFF)
        self.save()
        return ACK_ACCEPTED, []

    def _write_md(self, unit: AxisUnit, db: int, words: list[int], overwrite: bool) -> list[int]:
        unit.error = 0
        if unit.running:
            self.set_error(unit, 4)
            return [0]
        if unit.md is not None and not overwrite:
            self.set_error(unit, 17)
            return [0]
        try:
            md = machine_data.decode(list(words))
        except ValueError:
            self.set_error(unit, 15)
            return [0]
        md = replace(md, db=db)
        unit.wire_switches(md.limit_polarity if md.limit_polarity in (0, 1) else None)
        levels = (bool(self.signals.get(f"ANF{unit.number}")), bool(self.signals.get(f"END{unit.number}")))
        error = machine_data.check(md, sys_module=self.sys_id[0], limit_levels=levels)
        md = replace(md, error=error)
        stored = machine_data.encode(md)
        stored[48:] = list(words[48:70])
        unit.load_md(md, stored, first=True)
        self.pulse_rs(unit)  # the power unit's pattern counter restarts with the IP's (spec §5.16)
        if error:
            self.set_error(unit, 15)
        self.save()
        return [error << 8]

    def _write_program(self, db: int, words: list[int], overwrite: bool, from_plc: bool) -> list[int]:
        self.channel_error = 0
        if any(u.teach_in is not None for u in self.units):
            self.set_error(None, 22)
            return [0, 0]
        try:
            _length, _db, _error, text = lang.record_text(list(words))
        except (ValueError, IndexError):
            self.set_error(None, 2)
            return [0, 0]
        try:
            lang.parse(text)
            error, faulty = 0, 0
        except lang.SyntaxFault as fault:
            error, faulty = fault.errno, fault.block
        executing = {u.automatic.number for u in self.units if u.automatic is not None}
        try:
            if overwrite and self.store.get(db) is not None:
                self.store.delete(db, executing=executing)
            self.store.add(Stored(db, text, error, faulty), from_plc=from_plc)
        except StoreError as exc:
            self.set_error(None, exc.error)
            return [0, 0]
        if error:
            self.set_error(None, 48)  # stored, but marked faulty (spec §4.5)
        self.save()
        return [error, faulty]

    def delete_record(self, page: int, ba: int, db: int) -> int:
        if ba not in DELETE_MODES:
            return ACK_NEGATIVE
        refused = self._record_page(ba, page)
        if refused is not None:
            return refused
        unit = self.unit(page)
        if ba == 21:
            assert unit is not None
            unit.error = 0
            if unit.running:
                self.set_error(unit, 4)
            elif unit.md is None or unit.md.db != db:
                self.set_error(unit, 13)  # no such machine-data block (spec §4.3 [DECISION])
            else:
                unit.load_md(None, None, first=False)
                self.save()
            return ACK_ACCEPTED
        self.channel_error = 0
        executing = {u.automatic.number for u in self.units if u.automatic is not None}
        try:
            error = self.store.delete(db, executing=executing)
            if error:
                self.set_error(None, error)
        except StoreError as exc:
            self.set_error(None, exc.error)
        self.save()
        return ACK_ACCEPTED

    def read_record(self, page: int, ba: int, db: int = 0, bcd: bool = False) -> tuple[int, list[int]]:
        """BA64 … BA70: (ack, the record's words); an empty record when there is none."""
        if ba not in READ_MODES:
            return ACK_NEGATIVE, []
        refused = self._record_page(ba, page)
        if refused is not None:
            return refused, []
        unit = self.unit(page)
        self.set_error(unit, 0)  # a transfer is an operator job: it acknowledges the page's error
        if ba == 64:
            return ACK_ACCEPTED, values.md_directory([(u.md.db, 70) if u.md else None for u in self.units])
        if ba == 65:
            return ACK_ACCEPTED, values.program_directory(self.store.directory())
        if ba == 66:
            assert unit is not None
            record, _binary = values.actual_values(unit.actual(), unit.residual(), bcd)
            return ACK_ACCEPTED, record
        if ba == 67:
            source = unit if unit is not None else next((u for u in self.units if u.md and u.md.db == db), None)
            if source is None or source.md_words is None or (source.md is not None and source.md.db != db):
                self.set_error(unit, 13)
                return ACK_ACCEPTED, []
            return ACK_ACCEPTED, list(source.md_words)
        if ba == 68:
            return ACK_ACCEPTED, values.md_overview(
                [(u.md.db, u.md.module, u.md.axis, 70, u.md.error) if u.md else None for u in self.units])
        if ba == 69:
            stored = self.store.get(db)
            if stored is None:
                self.set_error(unit, 19)
                return ACK_ACCEPTED, []
            return ACK_ACCEPTED, lang.record_words(db, stored.text, stored.error, stored.faulty)
        return ACK_ACCEPTED, values.sys_id_record(*self.sys_id, firmware=str(self.config.get("firmware", "A02.1")))

    def data_blocks(self) -> list[tuple[int, int, list[int]]]:
        """The records as S5 blocks for generic tools (:mod:`.s5_services`): programs as DB n,
        machine data as DX (their DB number)."""
        blocks = [(0x01, p.number, lang.record_words(p.number, p.text, p.error, p.faulty)) for p in self.store.programs]
        blocks += [(0x0C, u.md.db, list(u.md_words)) for u in self.units if u.md is not None and u.md_words]
        return blocks

    # -- observe (spec §3.6.4) ----------------------------------------------------------------------
    def header(self, page: int) -> tuple[int, int, int, int]:
        """(err, btr, rmld, mfkt) of a page."""
        unit = self.unit(page)
        if unit is None:
            return self.channel_error, 0, 0, 0
        return unit.error, unit.mode, unit.attributes(), unit.m_function

    def observe(self, page: int) -> Observation:
        unit = self.unit(page)
        errors = (*(u.error for u in self.units), self.channel_error)
        if unit is None:
            return Observation(0, 0, errors, 0, 0)  # type: ignore[arg-type]
        run = unit.automatic
        flags = (int(unit.waiting_start is not None) | int(bool(run and run.interrupted)) << 1
                 | int(unit.teach_in is not None) << 2 | int(bool(run and run.halted)) << 3)
        valid = unit.md is not None
        return Observation(unit.actual() if valid else 0, unit.residual() if valid else 0, errors,  # type: ignore[arg-type]
                           unit.last_cmd, flags)

    def close(self) -> None:
        for unit in self.units:
            unit.axis.quick_stop()
