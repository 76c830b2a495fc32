"""The IP247's control names, signals and faults, declared once (spec ip247.md §2.1, §4.1, §4.13,
§4.14; manual per row).

``axis.<n>.*`` show what FB164 and COM247 show of an axis; ``program.<n>`` is a traverse program
as text (setting it stores it as BA22 from the PG would); ``ag.operate`` is the in-process PLC
side: an FB164 job with the values as the PLC sends them (BCD when the machine data say so).
"""

from __future__ import annotations

import re
from collections.abc import Callable
from string import hexdigits
from typing import Any

from devsim.core.kit import Command, Fault, FaultTable, Table, signal_points
from devsim.core.points import BadValue, Family, Point, PointTable, parse_as
from devsim.devices.ip247 import program as lang
from devsim.devices.ip247.machine_data import record_db
from devsim.devices.ip247.pg_profile import Operate, command_code
from devsim.devices.ip247.records import DELETE_RECORDS, READ_RECORDS, WRITE_RECORDS
from devsim.devices.ip247.services import serve
from devsim.devices.ip247.signals import SIGNALS
from devsim.devices.ip247.tables import mode_token

__all__ = ["FAULTS", "POINTS", "SIGNALS"]

def _axis_points(n: int) -> list[Point]:
    def unit(m: Any) -> Any:
        return m.units[n - 1]

    return [
        Point(f"axis.{n}.position", "int", f"axis {n} actual value (tool tip), base units", "§2.7", "base",
              get=lambda m: unit(m).actual(), in_state=True),
        Point(f"axis.{n}.residual", "int", f"axis {n} residual distance, base units", "§2.7.7", "base",
              get=lambda m: unit(m).residual()),
        Point(f"axis.{n}.machine_position", "float", f"axis {n} motor-side position (pulses × resolution)",
              "§5.1", "base", get=lambda m: unit(m).axis.position()),
        Point(f"axis.{n}.mechanical_position", "float", f"axis {n} where the motor really is (less lost steps)",
              "§5.15", "base", get=lambda m: unit(m).mechanical_position()),
        Point(f"axis.{n}.velocity", "float", f"axis {n} motor-side velocity (pulse frequency × resolution)",
              "§5.2", "base/s", get=lambda m: unit(m).axis.velocity()),
        Point(f"axis.{n}.mode", "int", f"axis {n} operating mode (BTR)", "§4.1", get=lambda m: unit(m).mode,
              in_state=True),
        Point(f"axis.{n}.running", "bool", f"axis {n} state: läuft (True) / fertig", "§4.1",
              get=lambda m: unit(m).running, in_state=True),
        Point(f"axis.{n}.error", "int", f"axis {n} pending module error", "§7.2", get=lambda m: unit(m).error,
              in_state=True),
        Point(f"axis.{n}.attributes", "int", f"axis {n} attributes byte RMLD", "§2.7",
              get=lambda m: unit(m).attributes()),
        Point(f"axis.{n}.reference_set", "bool", f"axis {n} reference point set", "§4.2.3",
              get=lambda m: unit(m).reference_set),
        Point(f"axis.{n}.tbit", "bool", f"axis {n}: FB164's TBIT, set while a job the PLC side issued runs; "
              "a program continued from the PG is the PG's", "§6.2.6", get=lambda m: m.tbit[n]),
        Point(f"axis.{n}.waiting_start", "bool", f"axis {n} holds a job until START-N/STOP falls (error 6)",
              "§2.8.4", get=lambda m: unit(m).waiting_start is not None),
        Point(f"axis.{n}.m_function", "int", f"axis {n} M function shown (MFKT)", "§2.6.9",
              get=lambda m: unit(m).m_function),
        Point(f"axis.{n}.md_error", "int", f"axis {n} machine-data error (0: none; -1: no MD)", "§7.2.1",
              get=lambda m: unit(m).md.error if unit(m).md else -1),
        Point(f"axis.{n}.machine_data", "json", f"axis {n} machine-data record (70 words; setting it stores it as "
              "BA20 from the PG would, overwriting, in the DB its word n+2 names)", "§6.3.8.1",
              get=lambda m: unit(m).md_words, put=lambda m, v: _put_md(m, n, v)),
    ]


def _put_md(m: Any, axis: int, record: Any) -> None:
    if isinstance(record, str):
        texts = re.split(r"[ \t\r\n]+", record.strip(" \t\r\n"))  # (str.split(): also NBSP, NEL, FS … US)
        if not all(0 < len(text) <= 4 and all(c in hexdigits for c in text) for text in texts):
            # (int(text, 16) also read '0x10', '-1', '1_0' and the digits of other scripts)
            raise BadValue("machine data in one string are hex words (1 to 4 digits, blanks between)")
        record = [int(text, 16) for text in texts]
    if not isinstance(record, list) or len(record) != 70 or not all(isinstance(w, int) for w in record):
        raise BadValue("machine data are 70 words (a list of numbers, or hex words in one string)")
    unit = m.units[axis - 1]
    before = unit.md_words
    m.channel.write_record(axis, 20, record_db(record), [w & 0xFFFF for w in record], overwrite=True)
    if unit.md is None or unit.md_words is before:  # refused (a record stored with an MD error is stored)
        raise BadValue(f"machine data not stored: module error {unit.error}")


def _program(name: str) -> Point | None:
    match = re.fullmatch(r"program\.(\d{1,3})", name, re.ASCII)
    if match is None or int(match[1]) > 255:
        return None
    number = int(match[1])

    def put(m: Any, text: Any) -> None:
        try:
            words = lang.record_words(number, str(text).replace("\r\n", "\n"))
        except UnicodeEncodeError as exc:
            raise BadValue(f"program {number}: {exc.object[exc.start:exc.end]!r} is no character a record carries"
                           " (latin-1)") from None
        m.channel.write_record(4, 22, number, words, overwrite=True)
        if m.channel.error:
            raise BadValue(f"program {number} not stored: module error {m.channel.error}")

    return Point(name, "str", f"traverse program {number} as text, one block per line", "§2.6",
                 get=lambda m: (m.programs.store.get(number).text if m.programs.store.get(number) else None), put=put)


def _whole(job: dict[str, Any], key: str, default: Any = None) -> int:
    """A job's field as a whole number (the block's DB, DW, BA …), or BadValue."""
    try:
        return int(parse_as("int", job.get(key, default)))
    except BadValue as exc:
        raise BadValue(f"{key}: {exc}") from None


def _page(m: Any, job: dict[str, Any]) -> int:
    """The job's absolute page (default: S2's base page) as the module's page 1 … 4."""
    base = int(m.config.get("base_page", 0))
    return _whole(job, "page", base) - base + 1


def _ag_record(m: Any, job: Any) -> None:
    """An FB165 job from the PLC: {ba, page (absolute), db, words, bcd} (spec §3.3.3)."""
    if not isinstance(job, dict) or "ba" not in job:
        raise BadValue("an FB165 job is a mapping {ba, page, db, words, bcd}")
    ba, db = _whole(job, "ba"), _whole(job, "db", 0) & 0xFF
    page = _page(m, job)
    words = job.get("words", [])
    if not isinstance(words, list):
        raise BadValue("an FB165 job's words are a list of whole numbers")
    words = [parse_as("int", w) & 0xFFFF for w in words]
    if not 1 <= page <= 4:
        m.ag_last = {"ack": 0x80, "err": 0, "words": []}
        return
    transfer = FB165_JOBS.get(mode_token(ba)) or _fb165_read  # (a mode no record has: read's 80H)
    ack, result = transfer(m, page, ba, db, words, bool(job.get("bcd", False)))
    m.ag_last = {"ack": ack, "err": m.error_of(page), "words": result}


def _fb165_write(m: Any, page: int, ba: int, db: int, words: list[int], bcd: bool) -> tuple[int, list[int]]:
    return m.channel.write_record(page, ba, db, words, from_plc=True)


def _fb165_delete(m: Any, page: int, ba: int, db: int, words: list[int], bcd: bool) -> tuple[int, list[int]]:
    return m.channel.delete_record(page, ba, db), []


def _fb165_read(m: Any, page: int, ba: int, db: int, words: list[int], bcd: bool) -> tuple[int, list[int]]:
    return m.channel.read_record(page, ba, db, bcd)


Transfer = Callable[[Any, int, int, int, list[int], bool], tuple[int, list[int]]]

#: FB165's jobs (spec §3.3.3): the record modes, written, deleted or read on the data channel.
FB165_JOBS: Table[Transfer] = Table([
    *(Command(row.token, _fb165_write, row.section, row.doc) for row in WRITE_RECORDS),
    *(Command(row.token, _fb165_delete, row.section, row.doc) for row in DELETE_RECORDS),
    *(Command(row.token, _fb165_read, row.section, row.doc) for row in READ_RECORDS),
])


def _ag_operate(m: Any, job: Any) -> None:
    """An FB164 job from the PLC: {page (absolute), ba, cmd (name or 1 … 5), b, w, dd}."""
    if not isinstance(job, dict):
        raise BadValue("an FB164 job is a mapping {page, ba, cmd, b, w, dd}")
    cmd = job.get("cmd", "Start")
    code = command_code(cmd)
    ba = _whole(job, "ba", 0)
    if code not in range(256) or ba not in range(256):  # (a code is a byte of the job)
        raise BadValue(f"unknown command {cmd!r} (Start, Stopp, Vorwärts, Rückwärts, Übernahme)")
    page = _page(m, job)
    request = Operate(page, ba, int(code), _whole(job, "b", 0) & 0xFF,
                      _whole(job, "w", 0) & 0xFFFF, _whole(job, "dd", 0) & 0xFFFF_FFFF)
    answer = serve(m, request, plc=True) if 1 <= page <= 4 else bytes((0x80,)) + bytes(7)
    m.ag_last = {"ack": answer[0], "err": answer[4], "btr": answer[5], "rmld": answer[6], "mfkt": answer[7]}


POINTS = PointTable.of(
    *(_axis_points(n) for n in (1, 2, 3)),
    [
        Point("channel.error", "int", "data channel (page 4) pending module error", "§7.2",
              get=lambda m: m.channel.error, in_state=True),
        Point("sys_id", "json", "module identification: [module, slot, page]", "§4.3.22",
              get=lambda m: list(m.channel.sys_id)),
        Point("programs", "json", "program directory: [[number, record words], …]", "§6.3.8.5",
              get=lambda m: [list(e) for e in m.programs.store.directory()]),
        Point("ag.operate", "json", "an FB164 job from the PLC side: {page, ba, cmd, b, w, dd}", "§6.2",
              put=_ag_operate),
        Point("ag.record", "json", "an FB165 job from the PLC side: {ba, page, db, words, bcd} (no overwrite)",
              "§6.3", put=_ag_record),
        Point("ag.last", "json", "the answer to the last ag.operate ({ack, err, btr, rmld, mfkt}) or ag.record "
              "({ack, err, words})", "§6.2",
              get=lambda m: m.ag_last),
    ],
    signal_points(SIGNALS),
    families=[Family("program.<n>", "str", "traverse program n (0 … 255) as text", "§2.6", _program)],
)


def _battery(m: Any, active: bool) -> None:
    m.config["battery_ok"] = not active


def _power(m: Any, active: bool) -> None:
    m.config["powered"] = not active
    if not active:
        m.power_cycle()


def _wiring(name: str) -> Any:
    def apply(m: Any, active: bool) -> None:
        (m.wiring_faults.add if active else m.wiring_faults.discard)(name)

    return apply


FAULTS = FaultTable([
    *(Fault(f"rp_swapped_{n}", f"axis {n}: T and RP swapped: the motor turns the other way while the module counts "
            "on (mechanical_position); from the next move", "§7.1.5.3", _wiring(f"rp_swapped_{n}")) for n in (1, 2, 3)),
    *(Fault(f"rs_stuck_{n}", f"axis {n}: RS permanently active: the motor does not move although the actual value "
            "counts; from the next move", "§7.1.5.3", _wiring(f"rs_stuck_{n}")) for n in (1, 2, 3)),
    Fault("no_special_voltage", "the special voltage Us is missing: no output signals reach the power units, no "
          "motor moves; from the next move", "§3.1.4", _wiring("no_special_voltage")),
    Fault("battery_failed", "the buffer battery failed: machine data, programs, SYS-ID and offsets are lost at "
          "the next power-up", "§4.14", _battery),
    Fault("power", "the supply is off while active: the PG port answers nothing; on again afterwards (a "
          "power-up: reference lost, error 8)", "§3.1.1", _power),
])
