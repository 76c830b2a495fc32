"""The kit's parameters: one row type for every kind's parameters, their table and their values.

A parameter is what the manual lists as a numbered or named setting of the device: the SERS's
``P41`` (V), the GMS96's N parameters, the POSELESTA's machine parameters ``P1 … P98``, the
IP247's machine data, the PCD4.H3's register block.  Every kind declares its parameters as
:class:`Param` rows in one :class:`ParameterTable`; the model keeps their values in a
:class:`Parameters` part and reads them through named accessors (``params.velocity``, made with
:func:`accessor`), never by a bare number.  The points ``param.*`` (:func:`parameter_points`),
the generated reference (``devsim doc``), the facade maps and the range checks derive from the
rows.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Iterator, Mapping, MutableMapping
from operator import itemgetter
from types import MappingProxyType
from typing import Any, Literal

import msgspec

from devsim.core.points import (
    BadValue,
    Point,
    UnknownName,
    ascii_digits,
    ascii_upper,
    number_text,
    parse_as,
    range_text,
    strip_blanks,
)

__all__ = [
    "EMPTY",
    "Param",
    "ParamType",
    "ParameterTable",
    "ParameterValues",
    "Parameters",
    "accessor",
    "alias_hook",
    "parameter_points",
]

ParamType = Literal["int", "float", "bool", "str"]
Effect = Literal["simulated", "stored"]
Access = Literal["rw", "r", "w"]
Key = int | str

#: An empty, immutable ``extra`` mapping (the default of :attr:`Param.extra`).
EMPTY: Mapping[str, Any] = MappingProxyType({})


class _Missing:
    """The mark of a row that has no value (a row without a factory value, or one deleted)."""

    __slots__ = ()

    def __repr__(self) -> str:
        return "MISSING"


MISSING: Any = _Missing()
#: Immutable value types that a device may share with the table's factory value when equal.
_SHAREABLE = (int, float, str, bool)


class Param(msgspec.Struct, frozen=True):
    """One parameter as the manual lists it.

    ``key`` is what the host names it by: a number (``41`` for the SERS's P41, ``15`` for the
    GMS96's N15, a register offset) or a name.  ``name`` is the manual's designation (in the
    manual's language where the device shows it), ``doc`` an English description, ``section`` the
    manual section.  ``type``, ``minimum`` / ``maximum`` (inclusive) and ``choices`` are the range
    the device takes; ``unit`` is the unit or the weighting (``"inc"``, ``"mm/min"``,
    ``"position"``); ``decimals`` the places the device shows.  ``default`` is the factory / power-on
    value, ``saved`` whether the device stores it in non-volatile memory, ``effect`` whether the
    simulator gives it the effect the manual describes (``"simulated"``) or only keeps and answers
    it (``"stored"``), ``access`` whether a host may read and write it.  ``attr`` is the model's
    accessor name for it (``velocity``), ``extra`` the kind's own facts about the row (an error
    number, a command keyword) that no other kind has.
    """

    key: Key
    name: str
    section: str
    doc: str = ""
    aliases: tuple[str, ...] = ()
    type: ParamType = "int"
    minimum: float | None = None
    maximum: float | None = None
    choices: tuple[Any, ...] | None = None
    unit: str = ""
    decimals: int = 0
    default: Any = 0
    saved: bool = True
    effect: Effect = "simulated"
    access: Access = "rw"
    attr: str = ""
    extra: Mapping[str, Any] = EMPTY

    @property
    def readable(self) -> bool:
        return self.access != "w"

    @property
    def writable(self) -> bool:
        return self.access != "r"

    def check(self, value: Any) -> Any:
        """The value as this parameter's type, inside its range and choices, or :class:`BadValue`
        (nothing changes).  A kind with its own range rules checks those after this."""
        try:
            parsed = parse_as(self.type, value)
        except BadValue as exc:
            raise BadValue(f"{self.label}: {exc}") from None
        if self.type in ("int", "float"):
            if self.minimum is not None and parsed < self.minimum:
                raise BadValue(f"{self.label}: {number_text(parsed)} is below the minimum {number_text(self.minimum)}{_unit(self.unit)}")
            if self.maximum is not None and parsed > self.maximum:
                raise BadValue(f"{self.label}: {number_text(parsed)} is above the maximum {number_text(self.maximum)}{_unit(self.unit)}")
        if self.choices is not None and parsed not in self.choices:
            raise BadValue(f"{self.label}: expects one of {', '.join(map(str, self.choices))}, not {value!r}")
        return parsed

    @property
    def label(self) -> str:
        return str(self.key) if isinstance(self.key, str) else f"#{self.key}"

    def range_text(self) -> str:
        return range_text(self.minimum, self.maximum, self.choices)


def _unit(unit: str) -> str:
    return f" {unit}" if unit and unit.isascii() and unit[:1].isalpha() else ""


class ParameterTable:
    """A kind's parameters by key, found also by alias and by the kind's spelling of a key.

    ``prefix`` is how the kind writes a numbered key (``"P"`` → ``P41``, ``"N"`` → ``N15``); a
    token ``P41``, ``p41``, ``41`` or an alias (any case) finds the row."""

    def __init__(self, rows: Iterable[Param], *, prefix: str = "", name: str = "parameter") -> None:
        self.prefix = prefix
        self.name = name
        self.rows: dict[Key, Param] = {}
        self._aliases: dict[str, Key] = {}
        self._attrs: dict[str, Key] = {}
        #: Each row's position: where a device's :class:`ParameterValues` keeps its value.
        self.positions: dict[Key, int] = {}
        for row in rows:
            if row.key in self.rows:
                raise ValueError(f"{name} {self.spell(row.key)} declared twice")
            self.rows[row.key] = row
            self.positions[row.key] = len(self.positions)
            for alias in row.aliases:
                if ascii_upper(alias) in self._aliases:
                    raise ValueError(f"alias {alias!r} declared twice")
                self._aliases[ascii_upper(alias)] = row.key
            if row.attr:
                if row.attr in self._attrs:
                    raise ValueError(f"accessor {row.attr!r} declared twice")
                self._attrs[row.attr] = row.key
        #: The factory values by position (:data:`MISSING` for a row without one), shared by
        #: every device's :class:`ParameterValues` until it writes another value: never written.
        self.template: list[Any] = [MISSING if row.default is None else row.default for row in self.rows.values()]

    def __iter__(self) -> Iterator[Param]:
        return iter(self.rows.values())

    def __len__(self) -> int:
        return len(self.rows)

    def __contains__(self, key: object) -> bool:
        return key in self.rows

    def __getitem__(self, key: Key) -> Param:
        return self.rows[key]

    def get(self, key: Key) -> Param | None:
        return self.rows.get(key)

    def spell(self, key: Key) -> str:
        """A key as the kind writes it: ``P41``, ``N15``, or a name as it is."""
        return f"{self.prefix}{key}" if isinstance(key, int) else key

    def find(self, token: str | int) -> Param | None:
        """The row for ``P41`` / ``p 41`` / ``41`` / an alias / a name, or None."""
        if isinstance(token, int):
            return self.rows.get(token)
        text = strip_blanks(str(token))  # (str.strip: 'param.\u3000P41', 'param.P41\x1c' were P41)
        row = self.rows.get(text)
        if row is not None:
            return row
        upper = ascii_upper(text).replace(" ", "")  # ('poſ' is no POS, 'ın' no IN)
        if upper in self._aliases:
            return self.rows[self._aliases[upper]]
        digits = upper[len(self.prefix):] if self.prefix and upper.startswith(self.prefix.upper()) else upper
        if ascii_digits(digits):
            return self.rows.get(int(digits))
        return None

    def lookup(self, token: str | int, owner: str = "the device") -> Param:
        row = self.find(token)
        if row is None:
            raise UnknownName(f"{owner} has no {self.name} {token!r}")
        return row

    def by_attr(self, attr: str) -> Param:
        return self.rows[self._attrs[attr]]

    def defaults(self) -> dict[Key, Any]:
        """Every row's factory value (rows with ``default=None`` have none)."""
        return {row.key: row.default for row in self.rows.values() if row.default is not None}

    def saved(self) -> tuple[Key, ...]:
        return tuple(row.key for row in self.rows.values() if row.saved)

    def picker(self, *keys: Key) -> Callable[[list[Any]], Any]:
        """The values of ``keys`` (rows with a factory value) at once, for the paths that read
        several per message: ``picker(values.cells)`` of a device's :class:`ParameterValues` is
        the tuple of their values, in one call of compiled code (an ``operator.itemgetter`` of
        the rows' positions; one key: the value itself)."""
        for key in keys:
            if self.rows[key].default is None:
                raise ValueError(f"{self.spell(key)} has no factory value: a picker could find none")
        return itemgetter(*(self.positions[key] for key in keys))


class ParameterValues(MutableMapping[Key, Any]):
    """One device's parameter values, compact: a list with one cell per row of the table, at the
    row's position (:attr:`ParameterTable.positions`), instead of a dict per device.

    Until the device writes a value other than the factory one it shares the table's
    :attr:`~ParameterTable.template` (copy-on-write), and a value equal to the factory value
    (same type, same sign of zero) is kept as the factory value's own object, so a thousand
    devices do not hold a thousand copies of one number.  A key that is no row (a kind may keep
    one beside its rows) lives in a small dict made when first needed.  It behaves as the dict it
    replaces: keys in the table's order, a row without a value is absent."""

    __slots__ = ("_positions", "_template", "cells", "_extra")
    #: Not the values (a snapshot of a device leaves them out): the table's positions and its
    #: factory values, shared by every device of the kind.
    not_state = frozenset({"_positions", "_template"})

    #: The values by row position (:data:`MISSING` where a row has none): read it (a
    #: :meth:`ParameterTable.picker` does), never write into it.
    cells: list[Any]

    def __init__(self, table: ParameterTable, values: Mapping[Key, Any] | None = None) -> None:
        self._positions = table.positions
        self._template = table.template
        self.cells = self._template
        self._extra: dict[Key, Any] | None = None
        if values:
            self.update(values)

    def __getitem__(self, key: Key) -> Any:
        position = self._positions.get(key)
        if position is None:
            if self._extra is None:
                raise KeyError(key)
            return self._extra[key]
        value = self.cells[position]
        if value is MISSING:
            raise KeyError(key)
        return value

    def get(self, key: Key, default: Any = None) -> Any:
        position = self._positions.get(key)
        if position is None:
            return default if self._extra is None else self._extra.get(key, default)
        value = self.cells[position]
        return default if value is MISSING else value

    def __contains__(self, key: object) -> bool:
        position = self._positions.get(key)  # type: ignore[call-overload]
        if position is None:
            return self._extra is not None and key in self._extra
        return self.cells[position] is not MISSING

    def __setitem__(self, key: Key, value: Any) -> None:
        position = self._positions.get(key)
        if position is None:
            if self._extra is None:
                self._extra = {}
            self._extra[key] = value
            return
        cells = self.cells
        if cells[position] is value:
            return
        factory = self._template[position]
        if _shares(value, factory):
            value = factory
        if cells is self._template:
            if value is factory:
                return
            cells = self.cells = list(cells)
        cells[position] = value

    def __delitem__(self, key: Key) -> None:
        position = self._positions.get(key)
        if position is None:
            if self._extra is None:
                raise KeyError(key)
            del self._extra[key]
            return
        if self.cells[position] is MISSING:
            raise KeyError(key)
        if self.cells is self._template:
            self.cells = list(self.cells)
        self.cells[position] = MISSING

    def __iter__(self) -> Iterator[Key]:
        cells = self.cells
        for key, position in self._positions.items():
            if cells[position] is not MISSING:
                yield key
        if self._extra:
            yield from list(self._extra)

    def __len__(self) -> int:
        return len(self.cells) - self.cells.count(MISSING) + (len(self._extra) if self._extra else 0)

    def clear(self) -> None:
        self.cells = [MISSING] * len(self._template)
        self._extra = None

    def factory(self) -> None:
        """Every row back to its factory value (shared again); keys that are no row stay."""
        self.cells = self._template

    def __repr__(self) -> str:
        return f"ParameterValues({dict(self.items())!r})"


def _shares(value: Any, factory: Any) -> bool:
    """``value`` may be kept as the object ``factory``: an immutable value of the same type,
    equal, with the same sign of zero."""
    kind = type(value)
    if kind is not type(factory) or kind not in _SHAREABLE or value != factory:
        return False
    return kind is not float or value != 0 or math.copysign(1.0, value) == math.copysign(1.0, factory)


class Parameters:
    """The part that owns a kind's parameter values: one value per row, the factory values at
    the start, writes checked against the row.  A kind subclasses it to name the values its model
    reads (``velocity = accessor(41)``); what a write *does* beyond storing the value belongs to
    the part that owns that behaviour, which listens with :meth:`on_change`.

    ``store`` is where the values live when the device keeps them in a memory of its own (the
    PCD's registers: a view of the axis's register block); it is taken as it is (no factory
    values are written into it: :meth:`reset` does that).  Without it the part keeps its own
    :class:`ParameterValues`, filled with the factory values."""

    def __init__(self, table: ParameterTable, values: Mapping[Key, Any] | None = None, *,
                 store: MutableMapping[Key, Any] | None = None) -> None:
        self.table = table
        self.values: MutableMapping[Key, Any] = ParameterValues(table) if store is None else store
        if values:
            self.values.update(values)
        self._listeners: tuple[Callable[[Param, Any], None], ...] = ()

    def __getitem__(self, key: Key) -> Any:
        return self.values[key]

    def get(self, key: Key, default: Any = None) -> Any:
        return self.values.get(key, default)

    def set(self, key: Key, value: Any, *, check: bool = True) -> Any:
        """Store a value (checked against the row unless ``check`` is False); returns it."""
        row = self.table[key]
        if check:
            value = row.check(value)
        self.values[key] = value
        for listener in self._listeners:
            listener(row, value)
        return value

    def on_change(self, listener: Callable[[Param, Any], None]) -> None:
        self._listeners = (*self._listeners, listener)

    def reset(self, keys: Iterable[Key] | None = None) -> None:
        """Factory values again, for ``keys`` or for every row."""
        if keys is None and type(self.values) is ParameterValues:
            self.values.factory()
            return
        defaults = self.table.defaults()
        for key in self.table.rows if keys is None else keys:
            if key in defaults:
                self.values[key] = defaults[key]
            else:
                self.values.pop(key, None)

    def snapshot(self, keys: Iterable[Key] | None = None) -> dict[Key, Any]:
        """The values of ``keys`` (default: the saved rows), e.g. for non-volatile memory."""
        chosen = self.table.saved() if keys is None else keys
        return {key: self.values[key] for key in chosen if key in self.values}

    def restore(self, values: Mapping[Key, Any]) -> None:
        """Take values back from memory, keys of rows only (a stale image keeps no strangers)."""
        for key, value in values.items():
            if key in self.table.rows and (not isinstance(value, float) or math.isfinite(value)):
                self.values[key] = value


def accessor(key: Key, doc: str = "") -> Any:
    """A named accessor on a :class:`Parameters` subclass: ``velocity = accessor(41)`` reads
    ``values[41]``; setting it stores the value unchecked (the model's own computed value)."""

    def get(self: Parameters) -> Any:
        values = self.values
        try:  # the common case, a row of ParameterValues, without a call of __getitem__
            value = values.cells[values._positions[key]]  # type: ignore[attr-defined]
        except (AttributeError, KeyError):  # another store, a key that is no row
            return values[key]
        if value is MISSING:
            raise KeyError(key)
        return value

    def put(self: Parameters, value: Any) -> None:
        self.values[key] = value

    return property(get, put, doc=doc or f"parameter {key!r}")


def parameter_points(
    table: ParameterTable,
    read: Callable[[Any, Param], Any],
    write: Callable[[Any, Param, Any], None] | None,
    *,
    name: Callable[[Param], str] | None = None,
    in_state: bool = False,
    example: Callable[[Param], Any] | None = None,
) -> list[Point]:
    """``param.<key>`` points for every row: ``read(model, row)`` and ``write(model, row, value)``
    (the value already checked against the row's type and range).  ``name`` spells a row's point
    name (default ``param.`` + the kind's spelling of the key)."""
    spell = name or (lambda row: f"param.{table.spell(row.key)}")
    points = []
    for row in table:

        def get(model: Any, row: Param = row) -> Any:
            return read(model, row)

        def put(model: Any, value: Any, row: Param = row) -> None:
            assert write is not None
            write(model, row, value)

        points.append(
            Point(
                spell(row),
                row.type,
                row.doc or row.name,
                row.section,
                row.unit,
                get=get if row.readable else None,
                put=put if write is not None and row.writable else None,
                minimum=row.minimum,
                maximum=row.maximum,
                choices=row.choices,
                in_state=in_state,
                example=example(row) if example is not None else _example(row),
            )
        )
    return points


def _example(row: Param) -> Any:
    """A value a write-only row accepts: its default, its first choice, or a value in range
    (:attr:`~devsim.core.points.Point.example`); None for a readable row, which is set to the
    value it reads."""
    if row.readable:
        return None
    if row.choices:
        return row.choices[0]
    if row.default is not None:
        return row.default
    if row.minimum is not None:
        return row.minimum
    return 0 if row.type in ("int", "float") else ""


def alias_hook(table: ParameterTable, section: str = "param") -> Callable[[str], str | None]:
    """A :class:`~devsim.core.points.PointTable` alias hook: ``param.V`` / ``param.p41`` /
    ``param.41`` → ``param.P41``."""

    def alias(name: str) -> str | None:
        head, dot, rest = name.partition(".")
        if head != section or not dot:
            return None
        row = table.find(rest)
        return None if row is None else f"{section}.{table.spell(row.key)}"

    return alias

