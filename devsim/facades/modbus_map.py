"""The Modbus register map of a device kind, generated from its declared points (issue 13; the
Modbus Application Protocol's four tables).

* a settable ``bool`` point is a **coil** (FC 1, 5, 15), a read-only one a **discrete input** (FC 2);
* a settable ``int``/``float`` point is a **holding register pair** (FC 3, 6, 16), a read-only one
  an **input register pair** (FC 4): a 32-bit two's-complement integer, high word first, holding
  ``round(value × scale)`` (``int`` points scale 1, ``float`` points 1000 unless overridden),
  saturated at the int32 range;
* ``str`` and ``json`` points have no Modbus form and are left out.

Addresses are given in table order, each table from 0.  A plant file may override any entry
(``{name: {address: 100, scale: 10}}``, ``{name: {table: input}}``) or drop it (``{name: null}``).
Pure: no I/O; :mod:`devsim.facades.modbus` serves it.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from typing import Any

import msgspec

from devsim.core.points import Point, PointTable

__all__ = ["TABLES", "Entry", "ModbusMap", "from_words", "to_words"]

TABLES = ("coil", "discrete", "holding", "input")
BITS = ("coil", "discrete")
INT32 = 1 << 31
FLOAT_SCALE = 1000.0


class Entry(msgspec.Struct, frozen=True):
    """One point in the map: its table, first address, width in bits or registers, scale."""

    name: str
    table: str
    address: int
    width: int  # 1 bit, or 2 registers
    scale: float
    type: str
    unit: str = ""
    doc: str = ""

    @property
    def end(self) -> int:
        return self.address + self.width


def to_words(value: Any, scale: float) -> tuple[int, int]:
    """A number as the two registers of a scaled int32, high word first (saturated)."""
    number = round(float(value) * scale) if value is not None else 0
    number = max(-INT32, min(INT32 - 1, number)) & 0xFFFF_FFFF
    return number >> 16, number & 0xFFFF


def from_words(high: int, low: int, scale: float, kind: str) -> int | float:
    """The value two registers hold (the point's type)."""
    number = (high & 0xFFFF) << 16 | (low & 0xFFFF)
    if number & 0x8000_0000:
        number -= 1 << 32
    value = number / scale
    return round(value) if kind == "int" else value


class ModbusMap:
    """The entries of a device's map and where each address lands."""

    def __init__(self, entries: Iterable[Entry]) -> None:
        self.entries = sorted(entries, key=lambda e: (TABLES.index(e.table), e.address))
        self.by_name: dict[str, Entry] = {}
        for e in self.entries:
            self.by_name.setdefault(e.name, e)
        self._at: dict[tuple[str, int], tuple[Entry, int]] = {}
        for entry in self.entries:
            for offset in range(entry.width):
                key = (entry.table, entry.address + offset)
                if key in self._at:
                    raise ValueError(f"{entry.name} overlaps {self._at[key][0].name} at {entry.table} {key[1]}")
                self._at[key] = (entry, offset)

    @classmethod
    def generate(cls, points: PointTable | Iterable[Point], overrides: Mapping[str, Any] | None = None) -> ModbusMap:
        """The map of a kind's points, with a plant file's ``overrides`` applied."""
        overrides = dict(overrides or {})
        for name in overrides:
            if name not in {p.name for p in points}:
                raise ValueError(f"modbus map: the device has no point {name!r}")
        following = dict.fromkeys(TABLES, 0)
        entries: list[Entry] = []
        for point in points:
            entry = _default(point)
            if entry is None and point.name not in overrides:
                continue
            if point.name in overrides:
                change = overrides[point.name]
                if change is None:
                    continue
                entry = _override(point, entry, change)
            if entry.address < 0:
                entry = msgspec.structs.replace(entry, address=following[entry.table])
            following[entry.table] = max(following[entry.table], entry.end)
            entries.append(entry)
        return cls(entries)

    @classmethod
    def layout(cls, points: PointTable, layout: str = "points", overrides: Mapping[str, Any] | None = None) -> ModbusMap:
        """The map of ``layout``: generated from the points with a plant file's ``overrides``
        (``points``), or the kind's own mirror (``mirror``, which takes no overrides); ValueError
        for a map the kind cannot have (``devsim check`` asks it too)."""
        if layout == "mirror":
            if overrides:
                raise ValueError("the mirror layout takes no map overrides")
            return cls.mirror(points)
        if layout != "points":
            raise ValueError(f"a Modbus layout is points or mirror, not {layout!r}")
        return cls.generate(points, overrides)

    @classmethod
    def mirror(cls, points: PointTable) -> ModbusMap:
        """A kind's own layout from its families that declare one (``Family.modbus``): member
        ``<n>`` at address n (bits) or 2n (32-bit registers, raw, high word first)."""
        entries = []
        for family in points.families:
            if family.modbus is None:
                continue
            tables, count = family.modbus
            for table in tables:
                width = 1 if table in BITS else 2
                for n in range(count):
                    name = family.pattern.replace("<n>", str(n))
                    entries.append(Entry(name, table, n * width, width, 1.0, family.type, "", family.doc))
        if not entries:
            raise ValueError("the kind declares no Modbus mirror")
        return cls(entries)

    def find(self, table: str, address: int) -> tuple[Entry, int] | None:
        """The entry holding ``address`` of ``table`` and the offset into it."""
        return self._at.get((table, address))

    def size(self, table: str) -> int:
        """One past the highest address used in ``table``."""
        return max((e.end for e in self.entries if e.table == table), default=0)

    def rows(self) -> list[tuple[str, ...]]:
        """(table, address(es), name, type, scale, unit, doc) per entry, for the docs."""
        out = []
        for e in self.entries:
            where = str(e.address) if e.width == 1 else f"{e.address}–{e.end - 1}"
            scale = "" if e.table in BITS else (f"×{e.scale:g}" if e.scale != 1 else "×1")
            out.append((e.table, where, e.name, e.type, scale, e.unit, e.doc))
        return out


def _default(point: Point) -> Entry | None:
    if point.type == "bool":
        table = "coil" if point.settable else "discrete"
        return Entry(point.name, table, -1, 1, 1.0, "bool", point.unit, point.doc)
    if point.type in ("int", "float"):
        table = "holding" if point.settable else "input"
        scale = 1.0 if point.type == "int" else FLOAT_SCALE
        return Entry(point.name, table, -1, 2, scale, point.type, point.unit, point.doc)
    return None


def _override(point: Point, entry: Entry | None, change: Any) -> Entry:
    if not isinstance(change, Mapping):
        raise ValueError(f"modbus map: {point.name}: give {{address, table, scale}} or null")
    unknown = set(change) - {"address", "table", "scale"}
    if unknown:
        raise ValueError(f"modbus map: {point.name}: unknown keys {', '.join(sorted(unknown))}")
    if entry is None:
        raise ValueError(f"modbus map: {point.name} ({point.type}) has no Modbus form")
    table = change.get("table", entry.table)
    if table not in TABLES or (table in BITS) != (entry.table in BITS):
        raise ValueError(f"modbus map: {point.name}: table {table!r} does not fit a {point.type} point")
    if table in ("coil", "holding") and not point.settable:
        raise ValueError(f"modbus map: {point.name} is read-only: it cannot be a {table}")
    address = change.get("address", entry.address)
    if not isinstance(address, int) or not -1 <= address <= 65535 - entry.width + 1:
        raise ValueError(f"modbus map: {point.name}: address {address!r} is not 0 … 65535")
    scale = change.get("scale", entry.scale)
    if isinstance(scale, bool) or not isinstance(scale, int | float) or not 0 < scale < 1e12:
        raise ValueError(f"modbus map: {point.name}: scale {scale!r} must be a positive number")
    return msgspec.structs.replace(entry, table=table, address=address, scale=float(scale))
