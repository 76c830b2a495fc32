"""Configuration tables: what a user can set for one device, declared as data.

A kind declares its configuration (DIP switches, variant, options, geometry) as a
:class:`Section` of :class:`Setting` rows::

    CONFIG = Section("SERS configuration", (
        Setting("address", Int(ge=0, le=127), 1, "DIP switch 2 bits 1-7; 0 = master"),
        Setting("axis", AXIS_GEOMETRY),
        ...
    ))

The same table validates a ``--config`` file, a plant file's ``config:`` and ``--drives``
(:meth:`Section.parse`, giving :class:`Values` with attribute access), documents every key
(``devsim doc``) and lets :mod:`devsim.core.config` name the file and line of a problem.  It
needs nothing beyond the standard library, so a simulator starts without importing a schema
library.  Messages follow the wording users already see from the scenario schema ("Input
should be ...", "Field required", "unknown field").
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Mapping
from types import SimpleNamespace
from typing import Any

from devsim.core.record import record

__all__ = [
    "REQUIRED", "Bool", "DictOf", "Float", "Int", "Invalid", "ListOf", "Maybe", "OneOf", "PairOf", "Section",
    "Setting", "Text", "Values",
]

Location = tuple[int | str, ...]


class _Required:
    def __repr__(self) -> str:
        return "REQUIRED"


#: The default of a setting that must be given.
REQUIRED: Any = _Required()


class Invalid(ValueError):
    """Configuration data that does not fit its table: one ``(location, message)`` per problem."""

    def __init__(self, problems: list[tuple[Location, str]]) -> None:
        self.problems = problems
        loc, msg = problems[0]
        super().__init__(f"{'.'.join(map(str, loc))}: {msg}" if loc else msg)


class _Problem(Exception):
    """One value is wrong (raised by a type's check, caught by the enclosing container)."""


class Type:
    """A setting's type: converts a value from YAML (or raises :class:`_Problem`) and names itself."""

    text = "any"

    def check(self, value: Any, loc: Location, problems: list[tuple[Location, str]]) -> Any:
        raise NotImplementedError


def _bounds(value: float, ge: float | None, gt: float | None, le: float | None, lt: float | None) -> None:
    if ge is not None and not value >= ge:
        raise _Problem(f"Input should be greater than or equal to {ge:g}")
    if gt is not None and not value > gt:
        raise _Problem(f"Input should be greater than {gt:g}")
    if le is not None and not value <= le:
        raise _Problem(f"Input should be less than or equal to {le:g}")
    if lt is not None and not value < lt:
        raise _Problem(f"Input should be less than {lt:g}")


@record
class Int(Type):
    """An integer (a float with no fraction and a numeric string are taken too)."""

    ge: int | None = None
    gt: int | None = None
    le: int | None = None
    lt: int | None = None
    text = "int"

    def check(self, value: Any, loc: Location, problems: list[tuple[Location, str]]) -> int:
        if isinstance(value, bool):
            raise _Problem("Input should be a valid integer")
        if isinstance(value, str):
            try:
                value = int(value.strip())
            except ValueError:
                raise _Problem("Input should be a valid integer, unable to parse string as an integer") from None
        elif isinstance(value, float):
            if not math.isfinite(value):
                raise _Problem("not a finite number (NaN and infinity are refused)")
            if not value.is_integer():
                raise _Problem("Input should be a valid integer, got a number with a fractional part")
            value = int(value)
        elif not isinstance(value, int):
            raise _Problem("Input should be a valid integer")
        _bounds(value, self.ge, self.gt, self.le, self.lt)
        return value


@record
class Float(Type):
    """A finite number, as a float (``integers``: an integer stays an integer, as YAML gave it)."""

    ge: float | None = None
    gt: float | None = None
    le: float | None = None
    lt: float | None = None
    integers: bool = False

    @property
    def text(self) -> str:  # type: ignore[override]
        return "float | int" if self.integers else "float"

    def check(self, value: Any, loc: Location, problems: list[tuple[Location, str]]) -> float | int:
        if isinstance(value, bool):
            raise _Problem("Input should be a valid number")
        if isinstance(value, str):
            try:
                value = float(value.strip())
            except ValueError:
                raise _Problem("Input should be a valid number, unable to parse string as a number") from None
        elif not isinstance(value, int | float):
            raise _Problem("Input should be a valid number")
        if not math.isfinite(value):
            raise _Problem("not a finite number (NaN and infinity are refused)")
        _bounds(value, self.ge, self.gt, self.le, self.lt)
        return value if self.integers and isinstance(value, int) else float(value)


_TRUE = frozenset({"true", "yes", "on", "1", "t", "y"})
_FALSE = frozenset({"false", "no", "off", "0", "f", "n"})


@record
class Bool(Type):
    """``true``/``false`` (also 0/1 and the usual words)."""

    text = "bool"

    def check(self, value: Any, loc: Location, problems: list[tuple[Location, str]]) -> bool:
        if isinstance(value, bool):
            return value
        if isinstance(value, int) and value in (0, 1):
            return bool(value)
        if isinstance(value, str) and value.strip().lower() in _TRUE | _FALSE:
            return value.strip().lower() in _TRUE
        raise _Problem("Input should be a valid boolean")


@record
class Text(Type):
    """A string."""

    text = "str"

    def check(self, value: Any, loc: Location, problems: list[tuple[Location, str]]) -> str:
        if not isinstance(value, str):
            raise _Problem("Input should be a valid string")
        return value


class OneOf(Type):
    """One of the listed values (strings or integers), compared as given."""

    def __init__(self, *choices: str | int) -> None:
        self.choices = choices
        self.text = " | ".join(map(repr, choices))

    def check(self, value: Any, loc: Location, problems: list[tuple[Location, str]]) -> Any:
        for choice in self.choices:
            if value == choice and type(value) is type(choice):
                return choice
        names = [repr(c) for c in self.choices]
        listed = names[0] if len(names) == 1 else f"{', '.join(names[:-1])} or {names[-1]}"
        raise _Problem(f"Input should be {listed}")


@record
class Maybe(Type):
    """``null`` or a value of ``inner``."""

    inner: Type

    @property
    def text(self) -> str:  # type: ignore[override]
        return f"{self.inner.text} | None"

    def check(self, value: Any, loc: Location, problems: list[tuple[Location, str]]) -> Any:
        return None if value is None else self.inner.check(value, loc, problems)


@record
class ListOf(Type):
    """A list of ``item`` values."""

    item: Type

    @property
    def text(self) -> str:  # type: ignore[override]
        return f"list[{self.item.text}]"

    def check(self, value: Any, loc: Location, problems: list[tuple[Location, str]]) -> list[Any]:
        if not isinstance(value, list | tuple):
            raise _Problem("Input should be a valid list")
        return [_checked(self.item, item, (*loc, index), problems) for index, item in enumerate(value)]


@record
class PairOf(Type):
    """Two values ``[low, high]``, kept as a tuple."""

    item: Type

    @property
    def text(self) -> str:  # type: ignore[override]
        return f"[{self.item.text}, {self.item.text}]"

    def check(self, value: Any, loc: Location, problems: list[tuple[Location, str]]) -> tuple[Any, Any]:
        if not isinstance(value, list | tuple) or len(value) != 2:
            raise _Problem("Input should be a list of two values")
        low, high = (_checked(self.item, item, (*loc, index), problems) for index, item in enumerate(value))
        return (low, high)


@record
class DictOf(Type):
    """A mapping whose keys ``key`` converts (or refuses with ``ValueError``) and whose values
    are ``value``."""

    key: Callable[[Any], Any]
    value: Type
    key_text: str = "key"

    @property
    def text(self) -> str:  # type: ignore[override]
        return f"{{{self.key_text}: {self.value.text}}}"

    def check(self, value: Any, loc: Location, problems: list[tuple[Location, str]]) -> dict[Any, Any]:
        if not isinstance(value, Mapping):
            raise _Problem("Input should be a valid dictionary")
        out: dict[Any, Any] = {}
        for key, item in value.items():
            try:
                converted = self.key(key)
            except ValueError as exc:
                problems.append(((*loc, key), str(exc)))
                continue
            out[converted] = _checked(self.value, item, (*loc, key), problems)
        return out


def _checked(kind: Type, value: Any, loc: Location, problems: list[tuple[Location, str]]) -> Any:
    try:
        return kind.check(value, loc, problems)
    except _Problem as exc:
        problems.append((loc, str(exc)))
        return None


@record
class Setting:
    """One key of a configuration: its type, default (:data:`REQUIRED` if it must be given),
    meaning, an optional ``check`` on the converted value (raise ``ValueError`` with the
    message) and an optional ``alias``, the key's name in a file when that is a Python word."""

    name: str
    type: Type
    default: Any = REQUIRED
    doc: str = ""
    check: Callable[[Any], Any] | None = None
    alias: str | None = None

    @property
    def key(self) -> str:
        return self.alias or self.name


class Values(SimpleNamespace):
    """A validated configuration: each setting an attribute; compares by value."""

    def dump(self) -> dict[str, Any]:
        """Plain data (nested mappings and lists), keyed by setting name."""
        return {name: _plain(value) for name, value in vars(self).items()}

    def replace(self, **changes: Any) -> Values:
        """A copy with some settings changed (the caller has checked the new values)."""
        return type(self)(**{**vars(self), **changes})


def _plain(value: Any) -> Any:
    if isinstance(value, Values):
        return value.dump()
    if isinstance(value, list):
        return [_plain(v) for v in value]
    if isinstance(value, dict):
        return {k: _plain(v) for k, v in value.items()}
    return value


class Section(Type):
    """A mapping of settings (a whole configuration or one nested part of it).

    ``before`` sees the raw mapping first and may refuse it as a whole (``ValueError``).
    Unknown keys are refused."""

    text = "mapping"

    def __init__(
        self, doc: str, settings: tuple[Setting, ...], before: Callable[[Mapping[Any, Any]], None] | None = None
    ) -> None:
        self.doc, self.settings, self.before = doc, settings, before
        self.by_key: dict[str, Setting] = {}
        for setting in settings:
            self.by_key[setting.name] = setting
            self.by_key[setting.key] = setting

    def __repr__(self) -> str:
        return f"Section({self.doc!r})"

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(s.name for s in self.settings)

    def check(self, value: Any, loc: Location, problems: list[tuple[Location, str]]) -> Values:
        if value is None:
            value = {}
        if not isinstance(value, Mapping):
            raise _Problem("Input should be a valid dictionary")
        if self.before is not None:
            try:
                self.before(value)
            except ValueError as exc:
                raise _Problem(str(exc)) from None
        given: dict[str, Any] = {}
        for key, item in value.items():
            setting = self.by_key.get(key) if isinstance(key, str) else None
            if setting is None:
                problems.append(((*loc, key), "unknown field"))
            else:
                given[setting.name] = (key, item)
        out: dict[str, Any] = {}
        for setting in self.settings:
            if setting.name in given:
                key, raw = given[setting.name]
            elif setting.default is REQUIRED:
                problems.append(((*loc, setting.key), "Field required"))
                continue
            else:
                key, raw = setting.key, setting.default
            before = len(problems)
            converted = _checked(setting.type, raw, (*loc, key), problems)
            if setting.check is not None and len(problems) == before:
                try:
                    converted = setting.check(converted)
                except ValueError as exc:
                    problems.append(((*loc, key), str(exc)))
            out[setting.name] = converted
        return Values(**out)

    def parse(self, data: Mapping[str, Any] | None = None) -> Values:
        """``data`` validated, defaults filled in; raises :class:`Invalid` naming every problem."""
        problems: list[tuple[Location, str]] = []
        values = _checked(self, data, (), problems)
        if problems:
            raise Invalid(problems)
        return values

    def __call__(self, **data: Any) -> Values:
        return self.parse(data)

    def rows(self, prefix: str = "") -> Iterable[tuple[str, str, str, str]]:
        """(key, type, default, description) of every key, nested keys dotted (for the docs)."""
        for setting in self.settings:
            key = f"{prefix}{setting.key}"
            inner = setting.type
            if isinstance(inner, Section):
                yield key, "mapping", "", setting.doc or inner.doc
                yield from inner.rows(f"{key}.")
                continue
            default = "" if setting.default is REQUIRED else repr(setting.default)
            yield key, inner.text, default if len(default) <= 40 else default[:37] + "...", setting.doc
