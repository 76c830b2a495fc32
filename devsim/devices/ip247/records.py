"""The IP247's data channel (page 4) and the record modes of all pages: machine data, programs
and SYS-ID written (BA20, BA22, BA24), deleted (BA21, BA23) and read (BA64 … BA70) (manual
§4.3.11–§4.3.22, §6.3.8; spec ip247.md §3.4, §4.9, §4.10, §4.12).

Each record mode is a row of :data:`WRITE_RECORDS`, :data:`DELETE_RECORDS` or
:data:`READ_RECORDS`, looked up by its token (``BA67``); a mode a page does not permit gets 80H
and error 46 (spec §3.2).  Errors go to the page (:class:`Pages`); the records live in battery
RAM, which :meth:`Pages.save` writes.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import Any, Protocol

import msgspec

from devsim.core.kit import Command, Table
from devsim.devices.ip247 import machine_data, values
from devsim.devices.ip247 import program as lang
from devsim.devices.ip247.axis_unit import AxisUnit
from devsim.devices.ip247.pg_profile import ACK_ACCEPTED, ACK_NEGATIVE
from devsim.devices.ip247.programs import ProgramJobs
from devsim.devices.ip247.store import Stored, StoreError
from devsim.devices.ip247.tables import MODES, OBSERVE_MODES, mode_token, page_error

__all__ = ["DELETE_RECORDS", "DataChannel", "Pages", "READ_RECORDS", "WRITE_RECORDS"]

Words = list[int]
WriteHandler = Callable[["DataChannel", "AxisUnit | None", int, Words, bool, bool], tuple[int, Words]]
DeleteHandler = Callable[["DataChannel", "AxisUnit | None", int], None]
ReadHandler = Callable[["DataChannel", "AxisUnit | None", int, bool], tuple[int, Words]]


class Pages(Protocol):
    """What the data channel needs of the module: errors on the pages, battery RAM."""

    def set_error(self, unit: AxisUnit | None, error: int) -> None: ...
    def save(self) -> None: ...


class DataChannel:
    """Page 4 and the records (spec §3.4): its pending error, the SYS-ID, and the record
    modes on every page."""

    def __init__(self, units: Sequence[AxisUnit], programs: ProgramJobs, pages: Pages,
                 config: Mapping[str, Any]) -> None:
        self.units, self.programs, self.pages, self.config = units, programs, pages, config
        self.error = 8  # the data channel's pending module error (page 4)
        self.sys_id = (0, 0, 0)

    def unit(self, page: int) -> AxisUnit | None:
        return self.units[page - 1] if 1 <= page <= 3 else None

    def md_numbers_differ(self) -> bool:
        numbers = [u.md.db for u in self.units if u.md is not None]
        return len(numbers) == len(set(numbers))

    def _refused(self, ba: int, page: int) -> bool:
        """Error 46 on the page for a record mode it does not permit (then 80H)."""
        if page_error(ba, page, md_numbers_differ=self.md_numbers_differ()) == 46:
            self.pages.set_error(self.unit(page), 46)
            return True
        return False

    # -- the services ------------------------------------------------------------------------------
    def write_record(self, page: int, ba: int, db: int, words: Words, *, overwrite: bool = False,
                     from_plc: bool = False) -> tuple[int, Words]:
        """BA20, BA22, BA24: (ack, result words)."""
        handler = WRITE_RECORDS.get(mode_token(ba))
        if handler is None:
            return ACK_NEGATIVE, []
        if self._refused(ba, page):
            return ACK_NEGATIVE, []
        return handler(self, self.unit(page), db, words, overwrite and not from_plc, from_plc)

    def delete_record(self, page: int, ba: int, db: int) -> int:
        """BA21, BA23: the acknowledgement."""
        handler = DELETE_RECORDS.get(mode_token(ba))
        if handler is None:
            return ACK_NEGATIVE
        if self._refused(ba, page):
            return ACK_NEGATIVE
        handler(self, self.unit(page), db)
        return ACK_ACCEPTED

    def read_record(self, page: int, ba: int, db: int = 0, bcd: bool = False) -> tuple[int, Words]:
        """BA64 … BA70: (ack, the record's words); an empty record when there is none."""
        handler = READ_RECORDS.get(mode_token(ba))
        if handler is None:
            return ACK_NEGATIVE, []
        if self._refused(ba, page):
            return ACK_NEGATIVE, []
        unit = self.unit(page)
        if ba not in OBSERVE_MODES:  # BA66 observes (manual §4.4): the pending error stays (§4.1)
            self.pages.set_error(unit, 0)  # a transfer is an operator job: it acknowledges the page's error
        return handler(self, unit, db, bcd)

    def data_blocks(self) -> list[tuple[int, int, Words]]:
        """The records as S5 blocks for generic tools (:mod:`.s5_services`): programs as DB n,
        machine data as DX (their DB number)."""
        blocks = [(0x01, p.number, lang.record_words(p.number, p.text, p.error, p.faulty))
                  for p in self.programs.store.programs]
        blocks += [(0x0C, u.md.db, list(u.md_words)) for u in self.units if u.md is not None and u.md_words]
        return blocks

    # -- writing (spec §4.9, §4.10, §4.12) ---------------------------------------------------------
    def write_md(self, unit: AxisUnit | None, db: int, words: Words, overwrite: bool,
                 from_plc: bool) -> tuple[int, Words]:
        """BA20: the axis's machine data; the result word carries the MD error (spec §4.9).  A
        set names its axis (DR n+3) and is taken only over that axis's page: 80H and error 46
        elsewhere (manual §4.3.12, §6.3.10)."""
        assert unit is not None
        unit.error = 0
        if unit.running:
            self.pages.set_error(unit, 4)
            return ACK_ACCEPTED, [0]
        if unit.md is not None and not overwrite:
            self.pages.set_error(unit, 17)
            return ACK_ACCEPTED, [0]
        try:
            md = machine_data.decode(list(words))
        except ValueError:
            self.pages.set_error(unit, 15)
            return ACK_ACCEPTED, [0]
        if md.axis != unit.number:
            self.pages.set_error(unit, 46)  # only over the page of its axis (manual §4.3.12)
            return ACK_NEGATIVE, []
        md = msgspec.structs.replace(md, db=db)
        unit.wire_switches(md.limit_polarity if md.limit_polarity in (0, 1) else None)
        error = machine_data.check(md, sys_module=self.sys_id[0], limit_levels=unit.limit_levels())
        md = msgspec.structs.replace(md, error=error)
        stored = machine_data.encode(md)
        stored[machine_data.RESERVED] = list(words[machine_data.RESERVED])
        unit.load_md(md, stored, first=True)
        unit.pulse_rs()  # the power unit's pattern counter restarts with the IP's (spec §5.16)
        if error:
            self.pages.set_error(unit, 15)
        self.pages.save()
        return ACK_ACCEPTED, [error << 8]

    def write_program(self, unit: AxisUnit | None, db: int, words: Words, overwrite: bool,
                      from_plc: bool) -> tuple[int, Words]:
        """BA22: a traverse program; the result words are its syntax error and faulty block
        (spec §4.5, §4.10)."""
        self.error = 0
        if self.programs.teach_in_active():
            self.pages.set_error(None, 22)
            return ACK_ACCEPTED, [0, 0]
        try:
            _length, _db, _error, text = lang.record_text(list(words))
        except (ValueError, IndexError):
            self.pages.set_error(None, 2)
            return ACK_ACCEPTED, [0, 0]
        try:
            lang.parse(text)
            error, faulty = 0, 0
        except lang.SyntaxFault as fault:
            error, faulty = fault.errno, fault.block
        store = self.programs.store
        try:
            if overwrite and store.get(db) is not None:
                store.replace(Stored(db, text, error, faulty), executing=self.programs.executing())
            else:
                store.add(Stored(db, text, error, faulty), from_plc=from_plc)
        except StoreError as exc:
            self.pages.set_error(None, exc.error)
            return ACK_ACCEPTED, [0, 0]
        if error:
            self.pages.set_error(None, 48)  # stored, but marked faulty (spec §4.5)
        self.pages.save()
        return ACK_ACCEPTED, [error, faulty]

    def write_sys_id(self, unit: AxisUnit | None, db: int, words: Words, overwrite: bool,
                     from_plc: bool) -> tuple[int, Words]:
        """BA24: module, slot, page; the module number is frozen by correct MD (spec §4.12)."""
        self.error = 0
        if len(words) != 3:
            self.pages.set_error(None, 2)
            return ACK_ACCEPTED, []
        module = words[0] & 0xFF
        if module != self.sys_id[0] and any(u.md_valid for u in self.units):
            self.pages.set_error(None, 12)
            return ACK_ACCEPTED, []
        self.sys_id = (module, words[1] & 0xFF, words[2] & 0xFF)
        self.pages.save()
        return ACK_ACCEPTED, []

    # -- deleting ---------------------------------------------------------------------------------
    def delete_md(self, unit: AxisUnit | None, db: int) -> None:
        """BA21: the axis's machine data, DB ``db`` (the reference point stays)."""
        assert unit is not None
        unit.error = 0
        if unit.running:
            self.pages.set_error(unit, 4)
        elif unit.md is None or unit.md.db != db:
            self.pages.set_error(unit, 13)  # no such machine-data block (spec §4.3 [DECISION])
        else:
            unit.load_md(None, None, first=False)
            self.pages.save()

    def delete_program(self, unit: AxisUnit | None, db: int) -> None:
        """BA23: program ``db`` (error 61 when it only leaves the directory, spec §4.10); refused
        with 22 while an axis is in teach-in (manual §7.2.2)."""
        self.error = 0
        if self.programs.teach_in_active():
            self.pages.set_error(None, 22)
            return
        try:
            error = self.programs.store.delete(db, executing=self.programs.executing())
            if error:
                self.pages.set_error(None, error)
        except StoreError as exc:
            self.pages.set_error(None, exc.error)
        self.pages.save()

    # -- reading (spec §3.4.3–§3.4.7) ---------------------------------------------------------------
    def read_md_directory(self, unit: AxisUnit | None, db: int, bcd: bool) -> tuple[int, Words]:
        return ACK_ACCEPTED, values.md_directory([(u.md.db, 70) if u.md else None for u in self.units])

    def read_program_directory(self, unit: AxisUnit | None, db: int, bcd: bool) -> tuple[int, Words]:
        return ACK_ACCEPTED, values.program_directory(self.programs.store.directory())

    def read_actual_values(self, unit: AxisUnit | None, db: int, bcd: bool) -> tuple[int, Words]:
        assert unit is not None
        record, _binary = values.actual_values(unit.actual(), unit.residual(), bcd)
        return ACK_ACCEPTED, record

    def read_md(self, unit: AxisUnit | None, db: int, bcd: bool) -> tuple[int, Words]:
        """BA67: over its axis's page; over any page when the DB numbers differ (manual §4.3.15)."""
        source = unit
        if unit is None or ((unit.md is None or unit.md.db != db) and self.md_numbers_differ()):
            source = next((u for u in self.units if u.md and u.md.db == db), None)
        if source is None or source.md_words is None or (source.md is not None and source.md.db != db):
            self.pages.set_error(unit, 13)
            return ACK_ACCEPTED, []
        return ACK_ACCEPTED, list(source.md_words)

    def read_md_overview(self, unit: AxisUnit | None, db: int, bcd: bool) -> tuple[int, Words]:
        return ACK_ACCEPTED, values.md_overview(
            [(u.md.db, u.md.module, u.md.axis, 70, u.md.error) if u.md else None for u in self.units])

    def read_program(self, unit: AxisUnit | None, db: int, bcd: bool) -> tuple[int, Words]:
        stored = self.programs.store.get(db)
        if stored is None:
            self.pages.set_error(unit, 19)
            return ACK_ACCEPTED, []
        return ACK_ACCEPTED, lang.record_words(db, stored.text, stored.error, stored.faulty)

    def read_sys_id(self, unit: AxisUnit | None, db: int, bcd: bool) -> tuple[int, Words]:
        return ACK_ACCEPTED, values.sys_id_record(*self.sys_id, firmware=str(self.config.get("firmware", "A02.1")))


def _row(number: int, handler: Any) -> Command[Any]:
    return Command(mode_token(number), handler, "§4.1.1", MODES[number].describe())


#: The record modes (spec §3.2, §3.4), by token.
WRITE_RECORDS: Table[WriteHandler] = Table([
    _row(20, DataChannel.write_md), _row(22, DataChannel.write_program), _row(24, DataChannel.write_sys_id),
])
DELETE_RECORDS: Table[DeleteHandler] = Table([_row(21, DataChannel.delete_md), _row(23, DataChannel.delete_program)])
READ_RECORDS: Table[ReadHandler] = Table([
    _row(64, DataChannel.read_md_directory), _row(65, DataChannel.read_program_directory),
    _row(66, DataChannel.read_actual_values), _row(67, DataChannel.read_md), _row(68, DataChannel.read_md_overview),
    _row(69, DataChannel.read_program), _row(70, DataChannel.read_sys_id),
])
