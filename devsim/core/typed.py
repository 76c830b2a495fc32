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

from collections.abc import Mapping
from typing import Any, TypeVar

import msgspec
from msgspec import UNSET, Meta

from devsim.core.typed_convert import (
    NOT_FINITE,
    Check,
    Keys,
    Problem,
    convert,
    fixer,
    non_finite,
)

__all__ = ["Check", "FieldError", "Invalid", "Keys", "Meta", "Typed", "doc", "place", "plain"]

T = TypeVar("T", bound="Typed")


class Invalid(ValueError):
    """Data that does not fit its declaration: one ``(location, message)`` per problem (the
    message names the first's place in ``data`` with :func:`place`)."""

    def __init__(self, problems: list[Problem], data: Any = None) -> None:
        self.problems = problems
        loc, msg = problems[0]
        super().__init__(f"{place(data, loc)}: {msg}" if loc else msg)


def place(data: Any, loc: tuple[int | str, ...]) -> str:
    """A location in plain data as a user reads it: keys by name, list items counted from 1 (as
    a file's errors count them, :func:`devsim.core.config.located`)."""
    parts: list[str] = []
    node = data
    for step in loc:
        if isinstance(node, list | tuple) and isinstance(step, int) and 0 <= step < len(node):
            parts.append(str(step + 1))
            node = node[step]
        else:
            parts.append(str(step))
            node = node.get(step) if isinstance(node, Mapping) else None
    return ".".join(parts)


class FieldError(ValueError):
    """Raised by a ``__post_init__`` about one of its fields: reported at that field."""

    def __init__(self, name: str, message: str) -> None:
        super().__init__(f"@{name}: {message}")


def doc(text: str) -> Meta:
    """A field's description (``devsim doc`` prints it), for ``Annotated[type, doc("…")]``."""
    return Meta(description=text)


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
                raise Invalid([((), str(exc))], data) from None
        try:
            value = convert(data, cls)
        except msgspec.ValidationError:
            from devsim.core.typed_errors import problems_of

            raise Invalid(problems_of(cls, data), data) from None
        fix = fixer(cls)
        if fix is not None:
            problems: list[Problem] = []
            fix(value, (), problems)
            if problems:
                raise Invalid(problems, data)
        where = non_finite(value)
        if where is not None:
            raise Invalid([(where, NOT_FINITE)], data)
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
