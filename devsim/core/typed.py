"""Typed data: the one way the project declares configuration, plant and scenario files (msgspec).

A declaration is a :class:`Typed` subclass, a :class:`msgspec.Struct` whose fields carry their
type, default and documentation::

    class Geometry(Typed):
        \"\"\"Where the switches sit (§2.1.2).\"\"\"

        limit_left: Annotated[float | None, doc("opens at and below this position")] = None
        index_period: Annotated[int, Meta(gt=0)] = 4096

msgspec converts and checks the types, ranges (``Meta(ge=…, le=…)``), required and unknown
keys in compiled code; :meth:`Typed.parse` adds what msgspec leaves to the caller:

* :class:`Check` (a per-field check for rules the manual states, run on the converted value),
  :class:`Keys` (a mapping's keys converted or refused one by one, e.g. ``N10`` → ``10``) and
  :meth:`Typed.screen` (a look at the raw mapping before anything else);
* NaN and infinity refused everywhere;
* every problem as ``(location, message)`` in :class:`Invalid`, worded as users know them
  ("Input should be …", "Field required", "unknown field"), found by
  :mod:`devsim.core.typed_errors` only when conversion failed.

A custom field type (a duration, a URL) is a class with a ``from_data(value)`` classmethod that
returns an instance or raises ``ValueError``; its message may name its field as ``{field}``.
A ``__post_init__`` (a rule across fields) raises ``ValueError``, or :class:`FieldError` to be
reported at one field.

Only the fast path runs when a simulator starts: ``msgspec.convert`` plus the few checks.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from typing import Annotated, Any, TypeVar, Union, get_args, get_origin

import msgspec
from msgspec import UNSET, Meta

__all__ = [
    "NOT_FINITE", "UNSET", "Check", "FieldError", "Invalid", "Keys", "Meta", "Typed", "convert", "doc", "fixer", "non_finite", "plain",
    "struct_type",
]

Location = tuple[int | str, ...]
Problem = tuple[Location, str]
T = TypeVar("T", bound="Typed")

#: The message for NaN and infinity, which no file may contain.
NOT_FINITE = "not a finite number (NaN and infinity are refused)"


class Invalid(ValueError):
    """Data that does not fit its declaration: one ``(location, message)`` per problem."""

    def __init__(self, problems: list[Problem]) -> None:
        self.problems = problems
        loc, msg = problems[0]
        super().__init__(f"{'.'.join(map(str, loc))}: {msg}" if loc else msg)


class FieldError(ValueError):
    """Raised by a ``__post_init__`` about one of its fields: reported at that field."""

    def __init__(self, name: str, message: str) -> None:
        super().__init__(f"@{name}: {message}")


def doc(text: str) -> Meta:
    """A field's description (``devsim doc`` prints it), for ``Annotated[type, doc("…")]``."""
    return Meta(description=text)


class Check:
    """``Annotated[T, Check(function)]``: ``function(value)`` returns the value (possibly
    changed) or raises ``ValueError`` with the message; it runs once the type is right."""

    def __init__(self, function: Callable[[Any], Any]) -> None:
        self.function = function


class Keys:
    """``Annotated[dict[Any, V], Keys(function, "text")]``: each key goes through
    ``function`` (which returns the key to keep or raises ``ValueError``); ``text`` names the
    keys in the documentation (``{text: V}``)."""

    def __init__(self, function: Callable[[Any], Any], text: str = "key") -> None:
        self.function = function
        self.text = text


def _dec_hook(kind: type, value: Any) -> Any:
    make = getattr(kind, "from_data", None)
    if make is None:
        raise NotImplementedError
    return make(value)


def convert(data: Any, kind: Any) -> Any:
    """``data`` (plain YAML or Python data) as ``kind``, the way :meth:`Typed.parse` converts
    (numbers and booleans from strings, custom field types); raises
    :class:`msgspec.ValidationError`."""
    return msgspec.convert(data, kind, strict=False, dec_hook=_dec_hook)


def non_finite(data: Any, loc: Location = ()) -> Location | None:
    """Where the first NaN or infinity sits in ``data`` (numbers, mappings, lists, structs)."""
    if isinstance(data, float):
        return None if math.isfinite(data) else loc
    if isinstance(data, Mapping):
        items: Any = data.items()
    elif isinstance(data, list | tuple):
        items = enumerate(data)
    elif isinstance(data, msgspec.Struct):
        items = ((key, getattr(data, name)) for name, key in
                 zip(data.__struct_fields__, data.__struct_encode_fields__, strict=True))
    else:
        return None
    for key, value in items:
        found = non_finite(value, (*loc, key))
        if found is not None:
            return found
    return None


class Typed(msgspec.Struct, forbid_unknown_fields=True):
    """Declared data: unknown keys are refused.  (A subclass that declares a required field
    after optional ones says ``kw_only=True``.)"""

    @classmethod
    def screen(cls, data: Mapping[Any, Any]) -> None:
        """A look at the raw mapping before it is converted (raise ``ValueError`` to refuse it as
        a whole, e.g. "this looks like a SERS configuration")."""

    @classmethod
    def parse(cls: type[T], data: Any = None) -> T:
        """``data`` converted and checked, defaults filled in (``None`` is an empty mapping);
        raises :class:`Invalid` naming every problem."""
        if data is None:
            data = {}
        if isinstance(data, Mapping):
            try:
                cls.screen(data)
            except ValueError as exc:
                raise Invalid([((), str(exc))]) from None
        try:
            value = convert(data, cls)
        except msgspec.ValidationError:
            from devsim.core.typed_errors import problems_of

            raise Invalid(problems_of(cls, data)) from None
        fix = fixer(cls)
        if fix is not None:
            problems: list[Problem] = []
            fix(value, (), problems)
            if problems:
                raise Invalid(problems)
        where = non_finite(value)
        if where is not None:
            raise Invalid([(where, NOT_FINITE)])
        return value

    def dump(self) -> dict[str, Any]:
        """Plain data (mappings, lists, tuples, numbers, strings) keyed as in a file, so that
        ``parse(x.dump()) == x``; fields left unset are left out."""
        return plain(self)  # type: ignore[no-any-return]

    def replace(self: T, **changes: Any) -> T:
        """A copy with some fields changed (the caller has checked the new values)."""
        return msgspec.structs.replace(self, **changes)


def plain(value: Any) -> Any:
    """``value`` with every :class:`msgspec.Struct` as a mapping keyed as in a file."""
    if isinstance(value, msgspec.Struct):
        return {key: plain(getattr(value, name))
                for name, key in zip(value.__struct_fields__, value.__struct_encode_fields__, strict=True)
                if getattr(value, name) is not UNSET}
    if isinstance(value, list):
        return [plain(v) for v in value]
    if isinstance(value, tuple):
        return tuple(plain(v) for v in value)
    if isinstance(value, dict):
        return {k: plain(v) for k, v in value.items()}
    for base in (str, float):  # a custom field type (a duration, a URL) as its plain base type
        if isinstance(value, base) and type(value) is not base:
            return base(value)
    return value


# -- checks and keys after conversion ------------------------------------------------------------
Fixer = Callable[[Any, Location, list[Problem]], Any]
_FIXERS: dict[Any, Fixer | None] = {}
_BUILDING = object()


def fixer(kind: Any) -> Fixer | None:
    """What :meth:`Typed.parse` still does to a converted value of ``kind`` (run the checks and
    key conversions inside it), or None if nothing."""
    try:
        cached = _FIXERS.get(kind, _BUILDING)
    except TypeError:  # an unhashable annotation
        return _build(kind)
    if cached is _BUILDING:
        _FIXERS[kind] = None  # a recursive type finds nothing to do while it is being built
        _FIXERS[kind] = cached = _build(kind)
    return cached  # type: ignore[return-value]


def _build(kind: Any) -> Fixer | None:
    origin = get_origin(kind)
    if origin is Annotated:
        inner_kind, *meta = get_args(kind)
        keys = next((m for m in meta if isinstance(m, Keys)), None)
        checks = [m for m in meta if isinstance(m, Check)]
        if keys is not None:  # Annotated[dict[Any, V], Keys(...)]
            return _keyed(keys, fixer(get_args(struct_type(inner_kind))[1]), checks)
        return _checked(fixer(inner_kind), checks)
    if isinstance(kind, type) and issubclass(kind, msgspec.Struct):
        return _struct(kind)
    if origin is list:
        item = fixer(get_args(kind)[0])
        return None if item is None else lambda v, loc, p: [item(x, (*loc, i), p) for i, x in enumerate(v)]
    if origin is dict:
        value = fixer(get_args(kind)[1])
        return None if value is None else lambda v, loc, p: {k: value(x, (*loc, k), p) for k, x in v.items()}
    if origin is Union or type(kind).__name__ == "UnionType":
        arms = [(a, fixer(a)) for a in get_args(kind) if a is not type(None)]
        found = [(a, f) for a, f in arms if f is not None]
        if not found:
            return None
        return lambda v, loc, p: v if v is None else _first_arm(found, v, loc, p)
    return None


def _first_arm(arms: list[tuple[Any, Fixer]], value: Any, loc: Location, problems: list[Problem]) -> Any:
    for kind, fix in arms:
        base = get_origin(struct_type(kind)) or struct_type(kind)
        if not isinstance(base, type) or isinstance(value, base):
            return fix(value, loc, problems)
    return value


def _checked(inner: Fixer | None, checks: list[Check]) -> Fixer | None:
    if not checks:
        return inner

    def fix(value: Any, loc: Location, problems: list[Problem]) -> Any:
        before = len(problems)
        if inner is not None:
            value = inner(value, loc, problems)
        for check in checks:
            if len(problems) > before:  # a check sees only a value whose type is right
                break
            try:
                value = check.function(value)
            except ValueError as exc:
                problems.append((loc, str(exc)))
        return value

    return fix


def _keyed(keys: Keys, item: Fixer | None, checks: list[Check]) -> Fixer:
    def convert_keys(value: Any, loc: Location, problems: list[Problem]) -> Any:
        converted = {}
        for key, entry in value.items():
            try:
                new_key = keys.function(key)
            except ValueError as exc:
                problems.append(((*loc, key), str(exc)))
                continue
            converted[new_key] = entry if item is None else item(entry, (*loc, key), problems)
        return converted

    fix = _checked(convert_keys, checks)
    assert fix is not None
    return fix


def _struct(kind: type[msgspec.Struct]) -> Fixer | None:
    fields = [(f.name, f.encode_name, fixer(f.type)) for f in msgspec.structs.fields(kind)]
    plan = [(name, key, fix) for name, key, fix in fields if fix is not None]
    if not plan:
        return None

    def fix(value: Any, loc: Location, problems: list[Problem]) -> Any:
        for name, key, field_fix in plan:
            old = getattr(value, name)
            new = field_fix(old, (*loc, key), problems)
            if new is not old:
                setattr(value, name, new)
        return value

    return fix


def struct_type(kind: Any) -> Any:
    """``kind`` without ``Annotated`` and without ``| None``, when that leaves one type."""
    while True:
        if get_origin(kind) is Annotated:
            kind = get_args(kind)[0]
            continue
        if get_origin(kind) is Union or type(kind).__name__ == "UnionType":
            arms = [a for a in get_args(kind) if a is not type(None)]
            if len(arms) == 1:
                kind = arms[0]
                continue
        return kind

