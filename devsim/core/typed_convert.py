"""Plain data into declared types: msgspec's conversion and what follows it.

:func:`convert` is ``msgspec.convert`` in lax mode (numbers and booleans from strings) with the
project's custom field types (classes with a ``from_data(value)`` classmethod);
:func:`fixer` gives, for a declared type, what still runs on a converted value: the
:class:`Check` functions and :class:`Keys` conversions annotated inside it.  Used by
:mod:`devsim.core.typed` (the fast path) and :mod:`devsim.core.typed_errors` (the slow one).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from typing import Annotated, Any, Union, get_args, get_origin

import msgspec

__all__ = ["NOT_FINITE", "Check", "Fixer", "Keys", "Location", "Problem", "convert", "fixer", "non_finite", "struct_type"]

Location = tuple[int | str, ...]
Problem = tuple[Location, str]

#: The message for NaN and infinity, which no file may contain.
NOT_FINITE = "not a finite number (NaN and infinity are refused)"


class Check:
    """``Annotated[T, Check(function)]``: ``function(value)`` returns the value (possibly
    changed) or raises ``ValueError`` with the message; it runs once the type is right."""

    def __init__(self, function: Callable[[Any], Any]) -> None:
        self.function = function


class Keys:
    """``Annotated[dict[Any, V], Keys(function, "text")]``: each key goes through
    ``function`` (which returns the key to keep or raises ``ValueError``); ``text`` names the
    keys in the documentation (``{text: V}``).  ``entry(key, value)`` (the key converted) returns
    the entry's value or raises ``ValueError``: a rule on each entry (a parameter's range),
    reported at its own key, every entry that breaks it (a ``Check`` on the whole mapping says
    only the first, at the mapping)."""

    def __init__(self, function: Callable[[Any], Any], text: str = "key",
                 entry: Callable[[Any, Any], Any] | None = None) -> None:
        self.function = function
        self.text = text
        self.entry = entry


def _dec_hook(kind: type, value: Any) -> Any:
    make = getattr(kind, "from_data", None)
    if make is None:
        raise NotImplementedError
    return make(value)


def convert(data: Any, kind: Any) -> Any:
    """``data`` (plain YAML or Python data) as ``kind``, the way :meth:`Typed.parse` converts
    (numbers and booleans from strings, custom field types); raises
    :class:`msgspec.ValidationError`."""
    try:
        return msgspec.convert(data, kind, strict=False, dec_hook=_dec_hook)
    except UnicodeEncodeError as exc:  # (text with a lone surrogate, which msgspec cannot compare as UTF-8)
        raise msgspec.ValidationError(f"{exc.object!r} is no text (a lone surrogate)") from None


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
            value_now = entry if item is None else item(entry, (*loc, key), problems)
            if keys.entry is not None:
                try:
                    value_now = keys.entry(new_key, value_now)
                except ValueError as exc:
                    problems.append(((*loc, key), str(exc)))
                    continue
            converted[new_key] = value_now
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
