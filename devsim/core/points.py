"""Declared points: every control name of a device, once, with its type, unit and access.

A kind declares its points in a table (:class:`PointTable`); ``read``, ``set``, ``state``, the
list of names (``devsim ctl names``), the generated reference (``devsim doc``), the facade maps and
the contract tests all come from it.  A value is checked against the point's declared type and
range *before* it takes effect (:meth:`Point.parse`); nothing non-finite ever enters a device.

The shared vocabulary every drive has (written down in ``docs/points.md``)::

    axis.position   float  inc    actual position, motor increments at the shaft
    axis.velocity   float  inc/s  actual velocity
    motion          bool          the axis is moving under the drive's control
    energized       bool          the power stage drives the motor
    ready           bool          ready for operation (no fault, enabled)
    fault           bool          a fault (error state) is active
    input.*         bool          digital inputs as the machine sets them
    output.*        bool          digital outputs as the device drives them
    quantity.*      float         simulated analog quantities (supply voltage, temperature ...)

A kind adds its own names beside them (``param.*``, ``display``, ``marker.*`` ...).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Iterator, Mapping
from typing import Any, Literal

import msgspec

from devsim.core.changes import CHANGES

__all__ = [
    "BadValue",
    "Family",
    "Point",
    "PointTable",
    "PointType",
    "ReadOnlyName",
    "SHARED_VOCABULARY",
    "UnknownName",
    "ascii_digits",
    "ascii_upper",
    "finite",
    "parse_as",
    "number_text",
    "parse_bool",
    "range_text",
    "strip_blanks",
]

PointType = Literal["bool", "int", "float", "str", "json"]
Access = Literal["r", "rw", "w"]

Getter = Callable[[Any], Any]
Setter = Callable[[Any, Any], None]


class UnknownName(KeyError):
    """The control API asked for a name the device does not have."""

    def __str__(self) -> str:  # KeyError would quote the message
        return str(self.args[0]) if self.args else "unknown name"


class ReadOnlyName(ValueError):
    """The name exists but cannot be set."""


class BadValue(ValueError):
    """A value that does not fit the point's declared type or range; nothing was changed."""


#: The blanks a control value may have around it.  (``str.strip``, ``float`` and ``int`` also skip
#: NBSP, U+3000, VT, FF and FS … US: '\u3000on' was true, '\x1c5' the number 5.)  [SIM-CHOICE] JSON's
#: four blanks: no manual speaks of the control API.
_BLANKS = " \t\n\r"
_TRUE = frozenset({"true", "1", "on", "yes"})
_FALSE = frozenset({"false", "0", "off", "no"})

_ASCII_UPPER = str.maketrans("abcdefghijklmnopqrstuvwxyz", "ABCDEFGHIJKLMNOPQRSTUVWXYZ")


def ascii_digits(text: str) -> bool:
    """``text`` is one or more of the digits 0 … 9, the only ones a device's wire or syntax has:
    ``str.isdigit`` also takes ² ³ ¹ (latin-1 B2h, B3h, B9h), which ``int`` then refuses with its
    own message, and the digits of every other script, which ``int`` reads ('٢' is 2)."""
    return text.isascii() and text.isdigit()


def strip_blanks(text: str) -> str:
    """``text`` without the blanks a control value may have around it (:data:`_BLANKS`: space, TAB,
    LF, CR); ``str.strip`` also takes VT, FF, FS … US, NEL, NBSP, U+2028 and U+3000."""
    return text.strip(_BLANKS)


def ascii_upper(text: str) -> str:
    """``text`` with a-z in upper case, one character for one, as the controllers' firmware does:
    ``str.upper`` also makes ß SS, ſ (U+017F) S, ı (U+0131) I and µ (latin-1 B5h) the Greek Μ.
    (ASCII text takes ``str.upper``, the same there and ten times as fast as the table.)"""
    return text.upper() if text.isascii() else text.translate(_ASCII_UPPER)


def parse_bool(value: Any) -> bool:
    """true/false/1/0/on/off/yes/no (any case) or a real bool; anything else is a :class:`BadValue`."""
    if isinstance(value, bool):
        return value
    if isinstance(value, int) and value in (0, 1):
        return bool(value)
    if isinstance(value, float) and value in (0.0, 1.0):
        return bool(value)
    if isinstance(value, str):
        text = value.strip(_BLANKS).lower()
        if text in _TRUE:
            return True
        if text in _FALSE:
            return False
    raise BadValue(f"expects a boolean (true/false/1/0/on/off/yes/no), not {_show(value)}")


def _plain(text: str) -> bool:
    """Text a number may be read from: ASCII (Python's ``float`` and ``int`` also read the digits of
    other scripts, which no device's wire takes) with no blanks around it but :data:`_BLANKS`."""
    return text.isascii() and text.strip(_BLANKS) == text.strip()


def finite(value: Any) -> float:
    """A finite float from a number or a numeric string (:func:`_plain`); NaN, ±inf and overflow
    are refused."""
    if isinstance(value, bool) or (isinstance(value, str) and not _plain(value)):
        raise BadValue(f"expects a number, not {_show(value)}")
    try:
        number = float(value)
    except (TypeError, ValueError, OverflowError):
        raise BadValue(f"expects a number, not {_show(value)}") from None
    if not math.isfinite(number):
        raise BadValue(f"expects a finite number, not {_show(value)}")
    return number


def _parse_int(value: Any) -> int:
    if isinstance(value, int) and not isinstance(value, bool):
        return value
    if isinstance(value, str) and _plain(value):
        text = value.strip()
        try:
            return int(text, 0)
        except ValueError:
            pass
    number = finite(value)
    if not number.is_integer():
        raise BadValue(f"expects a whole number, not {_show(value)}")
    return int(number)


def parse_as(kind: PointType, value: Any) -> Any:
    """``value`` as a ``kind`` (``bool``, ``int``, ``float``, ``str``, ``json``), or
    :class:`BadValue`: the one conversion of a control value, for a point
    (:meth:`Point.parse`) and a parameter row (:meth:`devsim.core.parameters.Param.check`)."""
    if kind == "bool":
        return parse_bool(value)
    if kind == "int":
        return _parse_int(value)
    if kind == "float":
        return finite(value)
    if kind == "str":
        if not isinstance(value, str):
            raise BadValue(f"expects text, not {_show(value)}")
        return value
    if isinstance(value, str):  # text from a command line: JSON if it parses
        import json  # (not at import: a plain start reads no command line)

        try:
            value = json.loads(value)
        except (ValueError, RecursionError):
            pass
    return _check_json(value)


def _show(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 40 else text[:37] + "..."


def _check_json(value: Any, depth: int = 0) -> Any:
    if depth > 32:
        raise BadValue("value nested too deeply")
    if isinstance(value, float) and not math.isfinite(value):
        raise BadValue(f"expects finite numbers, not {_show(value)}")
    if isinstance(value, Mapping):
        for item in value.values():
            _check_json(item, depth + 1)
    elif isinstance(value, list | tuple):
        for item in value:
            _check_json(item, depth + 1)
    return value


class Point(msgspec.Struct, frozen=True):
    """One control name: ``name``, ``type``, ``unit``, ``access``, ``doc`` and manual ``section``.

    Write one with the name, type, doc and section positionally, the rest by keyword:
    ``Point("axis.position", "float", "actual position", "§5.1", "inc", get=...)``.
    ``get(model)`` reads it; ``put(model, value)`` sets it with a value already parsed and checked
    (type, ``minimum``/``maximum``, ``choices``); ``check(model, value)`` may refuse a value with
    a :class:`BadValue` before anything changes (a device's own range).  ``in_state`` points
    appear in ``state()``.
    """

    name: str
    type: PointType
    doc: str
    section: str = ""
    unit: str = ""
    get: Getter | None = None
    put: Setter | None = None
    minimum: float | None = None
    maximum: float | None = None
    choices: tuple[Any, ...] | None = None
    in_state: bool = False
    shared: bool = False  # one of the shared vocabulary's names
    #: A valid value for a write-only point (the contract tests set it; readable points are
    #: set to the value they read).
    example: Any = None

    @property
    def access(self) -> Access:
        if self.put is None:
            return "r"
        return "rw" if self.get is not None else "w"

    @property
    def readable(self) -> bool:
        return self.get is not None

    def describe(self) -> dict[str, Any]:
        """The point as the control op ``names`` lists it: name, type, unit, access, doc, section."""
        return {"name": self.name, "type": self.type, "unit": self.unit, "access": self.access, "doc": self.doc,
                "section": self.section}

    @property
    def settable(self) -> bool:
        return self.put is not None

    def parse(self, value: Any) -> Any:
        """The value converted to the declared type and checked, or :class:`BadValue`."""
        parsed = parse_as(self.type, value)
        if self.choices is not None and parsed not in self.choices:
            options = ", ".join(str(c) for c in self.choices)
            raise BadValue(f"expects one of {options}, not {_show(value)}")
        if self.minimum is not None and parsed < self.minimum:
            raise BadValue(f"{_show(value)} is below the minimum {self.minimum:g}{_unit(self.unit)}")
        if self.maximum is not None and parsed > self.maximum:
            raise BadValue(f"{_show(value)} is above the maximum {self.maximum:g}{_unit(self.unit)}")
        return parsed

    def checked(self, value: Any) -> Any:
        """:meth:`parse` as a set reports it: a :class:`BadValue` names the point."""
        try:
            return self.parse(value)
        except BadValue as exc:
            raise BadValue(f"{self.name}: {exc}") from None

    def range_text(self) -> str:
        return range_text(self.minimum, self.maximum, self.choices)


def number_text(value: float) -> str:
    """A limit as a reference prints it: every digit the manual gives (99999999, not 1e+08;
    214748.3647, not 214748)."""
    return str(int(value)) if float(value).is_integer() else f"{value:.12g}"


def range_text(minimum: float | None, maximum: float | None, choices: tuple[Any, ...] | None = None) -> str:
    """``low … high``, or the choices, of a point or a parameter row (empty: no range)."""
    if choices is not None:
        return " / ".join(str(c) for c in choices)
    if minimum is None and maximum is None:
        return ""
    low = "" if minimum is None else number_text(minimum)
    high = "" if maximum is None else number_text(maximum)
    return f"{low} … {high}"


def _unit(unit: str) -> str:
    return f" {unit}" if unit else ""


class Family(msgspec.Struct, frozen=True):
    """Many names of one shape, made when asked for: ``marker.M<byte>.<bit>`` for 2,048 marker
    bits.  ``make(name)`` returns the point for a name of the family, or None."""

    pattern: str
    type: PointType
    doc: str
    section: str
    make: Callable[[str], Point | None]
    access: Access = "rw"
    #: The family as a Modbus mirror (``devsim.facades.modbus_map.ModbusMap.mirror``): the tables
    #: that show it and how many members from ``<n>`` = 0 (a kind's own Modbus layout, e.g. the
    #: PCD's media in spec pcd4h3 §9.8).
    modbus: tuple[tuple[str, ...], int] | None = None


class PointTable(msgspec.Struct):
    """A kind's points by name, with an optional ``alias`` hook that maps a spelling
    (``param.n15``, ``param.V``) to the declared name, and families of names made on demand."""

    points: dict[str, Point] = msgspec.field(default_factory=dict)
    alias: Callable[[str], str | None] | None = None
    families: tuple[Family, ...] = ()

    @classmethod
    def of(
        cls,
        *groups: Iterable[Point],
        alias: Callable[[str], str | None] | None = None,
        families: Iterable[Family] = (),
    ) -> PointTable:
        table = cls(alias=alias, families=tuple(families))
        for group in groups:
            for point in group:
                table.add(point)
        return table

    def add(self, point: Point) -> None:
        if point.name in self.points:
            raise ValueError(f"point {point.name!r} declared twice")
        self.points[point.name] = point

    def __iter__(self) -> Iterator[Point]:
        return iter(self.points.values())

    def __len__(self) -> int:
        return len(self.points)

    def __contains__(self, name: object) -> bool:
        return isinstance(name, str) and self.find(name) is not None

    def names(self) -> list[str]:
        return list(self.points)

    def find(self, name: str) -> Point | None:
        point = self.points.get(name)
        if point is None and self.alias is not None:
            canonical = self.alias(name)
            if canonical is not None:
                name = canonical
                point = self.points.get(canonical)
        if point is None:
            for family in self.families:
                point = family.make(name)
                if point is not None:
                    break
        return point

    def lookup(self, name: str, owner: str = "the device") -> Point:
        point = self.find(name)
        if point is None:
            raise UnknownName(self.unknown_text(name, owner))
        return point

    def unknown_text(self, name: str, owner: str) -> str:
        shown = name if len(name) <= 60 else name[:57] + "..."
        import difflib  # only for a misspelt name

        close = difflib.get_close_matches(name[:60], self.points, n=3, cutoff=0.6)
        hint = f" (did you mean {', '.join(close)}?)" if close else ""
        return f"{owner} has no {shown!r}{hint}"

    # -- the derived control API ------------------------------------------------------------
    def read(self, model: Any, name: str, owner: str = "the device") -> Any:
        point = self.lookup(name, owner)
        if point.get is None:
            raise UnknownName(f"{point.name} of {owner} can only be set")
        return point.get(model)

    def parse(self, name: str, value: Any, owner: str = "the device", model: Any = None) -> tuple[Point, Any]:
        """Look the name up and check the value, changing nothing."""
        point = self.lookup(name, owner)
        if point.put is None:
            raise ReadOnlyName(f"{point.name} of {owner} is read-only")
        return point, point.checked(value)

    def set(self, model: Any, name: str, value: Any, owner: str = "the device") -> None:
        point, parsed = self.parse(name, value, owner, model)
        assert point.put is not None
        CHANGES.count += 1  # (a door: devsim.core.changes)
        point.put(model, parsed)

    def state(self, model: Any) -> dict[str, Any]:
        """The ``in_state`` points as a nested mapping (``axis.position`` → ``{"axis": {...}}``)."""
        data: dict[str, Any] = {}
        for point in self.points.values():
            if not point.in_state or point.get is None:
                continue
            node = data
            *parents, leaf = point.name.split(".")
            for part in parents:
                child = node.setdefault(part, {})
                if not isinstance(child, dict):
                    break
                node = child
            else:
                node[leaf] = point.get(model)
        return data


#: The names every drive shares: name → (type, unit, description).
SHARED_VOCABULARY: dict[str, tuple[PointType, str, str]] = {
    "axis.position": ("float", "inc", "actual position in motor increments at the shaft"),
    "axis.velocity": ("float", "inc/s", "actual velocity in motor increments per second"),
    "motion": ("bool", "", "the axis moves under the drive's control"),
    "energized": ("bool", "", "the power stage drives the motor"),
    "ready": ("bool", "", "ready for operation: powered, booted, enabled, no fault"),
    "fault": ("bool", "", "a fault (error state) is active"),
    "input.*": ("bool", "", "digital inputs, as the machine sets them"),
    "output.*": ("bool", "", "digital outputs, as the device drives them"),
    "quantity.*": ("float", "", "simulated analog quantities (supply voltage, temperature ...)"),
}
