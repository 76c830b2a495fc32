"""Records: the classes of table rows, parsed statements and other plain values, cheap to declare.

``@record`` reads a class body like :func:`dataclasses.dataclass` does (annotated fields,
defaults, :func:`field` with ``default``, ``default_factory``, ``compare`` and ``repr``,
inheritance, ``__post_init__``) and gives the class ``__init__``, ``__repr__``, ``__eq__``,
``__match_args__`` and, unless ``frozen=False``, immutability and ``__hash__``.

Why not :func:`dataclasses.dataclass`: it compiles six functions for each frozen class, and a
simulator declares some sixty such classes before its port opens; that was half of the time
``devsim run`` took to start (issue 9).  A record compiles one function (``__init__``) and
shares the others.  :func:`replace`, :func:`fields` and :func:`asdict` work as the
:mod:`dataclasses` functions of those names do.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import MISSING, Field, FrozenInstanceError, field
from typing import Any, TypeVar, dataclass_transform, overload

__all__ = ["FrozenInstanceError", "RecordField", "asdict", "field", "fields", "is_record", "record", "replace"]

T = TypeVar("T")


class RecordField:
    """One field of a record: name, default or factory, and whether it compares and shows."""

    __slots__ = ("compare", "default", "factory", "name", "repr")

    def __init__(self, name: str, default: Any, factory: Any, compare: bool, repr: bool) -> None:  # noqa: A002
        self.name, self.default, self.factory, self.compare, self.repr = name, default, factory, compare, repr

    def __repr__(self) -> str:
        return f"RecordField({self.name!r})"


def _is_classvar(annotation: Any) -> bool:
    text = annotation if isinstance(annotation, str) else repr(annotation)
    return text.startswith(("ClassVar", "typing.ClassVar", "t.ClassVar"))


def _own_fields(cls: type) -> dict[str, RecordField]:
    found: dict[str, RecordField] = {}
    for base in reversed(cls.__mro__[1:]):
        for spec in getattr(base, "__record_fields__", ()):
            found[spec.name] = spec
    for name, annotation in cls.__dict__.get("__annotations__", {}).items():
        if _is_classvar(annotation):
            continue
        value = cls.__dict__.get(name, MISSING)
        if isinstance(value, Field):
            spec = RecordField(name, value.default, value.default_factory, bool(value.compare), bool(value.repr))
            if value.default is MISSING:
                delattr(cls, name)
            else:
                setattr(cls, name, value.default)
        else:
            if isinstance(value, list | dict | set):
                raise ValueError(f"mutable default {type(value)} for field {name} is not allowed: use default_factory")
            spec = RecordField(name, value, MISSING, True, True)
        found[name] = spec
    return found


def _init_source(specs: tuple[RecordField, ...], frozen: bool, post_init: bool) -> tuple[str, dict[str, Any]]:
    """One ``__init__`` for the class, compiled once."""
    params, body, env = [], [], {"_set": object.__setattr__, "_FACTORY": _FACTORY}
    seen_default = False
    for index, spec in enumerate(specs):
        if spec.default is not MISSING:
            env[f"_d{index}"] = spec.default
            params.append(f"{spec.name}=_d{index}")
            value = spec.name
            seen_default = True
        elif spec.factory is not MISSING:
            env[f"_f{index}"] = spec.factory
            params.append(f"{spec.name}=_FACTORY")
            value = f"_f{index}() if {spec.name} is _FACTORY else {spec.name}"
            seen_default = True
        else:
            if seen_default:
                raise TypeError(f"non-default argument {spec.name!r} follows default argument")
            params.append(spec.name)
            value = spec.name
        body.append(f"  _set(self, {spec.name!r}, {value})" if frozen else f"  self.{spec.name} = {value}")
    if post_init:
        body.append("  self.__post_init__()")
    source = f"def __init__(self, {', '.join(params)}):\n" + ("\n".join(body) or "  pass") + "\n"
    return source, env


class _Factory:
    def __repr__(self) -> str:
        return "<factory>"


_FACTORY: Any = _Factory()


def _repr(self: Any) -> str:
    shown = ", ".join(f"{s.name}={getattr(self, s.name)!r}" for s in self.__record_fields__ if s.repr)
    return f"{type(self).__qualname__}({shown})"


def _key(self: Any) -> tuple[Any, ...]:
    return tuple(getattr(self, name) for name in self.__record_compare__)


def _eq(self: Any, other: Any) -> Any:
    if other.__class__ is not self.__class__:
        return NotImplemented
    return _key(self) == _key(other)


def _hash(self: Any) -> int:
    return hash(_key(self))


def _frozen_setattr(self: Any, name: str, value: Any) -> None:
    raise FrozenInstanceError(f"cannot assign to field {name!r}")


def _frozen_delattr(self: Any, name: str) -> None:
    raise FrozenInstanceError(f"cannot delete field {name!r}")


def _make(cls: type[T], frozen: bool) -> type[T]:
    specs = tuple(_own_fields(cls).values())
    source, env = _init_source(specs, frozen, hasattr(cls, "__post_init__"))
    exec(source, env)  # noqa: S102 - the source is built above from the class's own field names
    init = env["__init__"]
    init.__qualname__ = f"{cls.__qualname__}.__init__"
    init.__module__ = cls.__module__
    cls.__init__ = init
    cls.__record_fields__ = specs
    cls.__record_compare__ = tuple(s.name for s in specs if s.compare)
    cls.__match_args__ = tuple(s.name for s in specs)
    if "__repr__" not in cls.__dict__:
        cls.__repr__ = _repr
    if "__eq__" not in cls.__dict__:
        cls.__eq__ = _eq
    if frozen:
        cls.__setattr__ = _frozen_setattr
        cls.__delattr__ = _frozen_delattr
        if "__hash__" not in cls.__dict__ or cls.__dict__["__hash__"] is None:
            cls.__hash__ = _hash
    elif "__hash__" not in cls.__dict__:
        cls.__hash__ = None
    return cls


@overload
def record(cls: type[T], /) -> type[T]: ...
@overload
def record(*, frozen: bool = True) -> Callable[[type[T]], type[T]]: ...


@dataclass_transform(frozen_default=True, field_specifiers=(field,))
def record(cls: type[T] | None = None, /, *, frozen: bool = True) -> type[T] | Callable[[type[T]], type[T]]:
    """Make ``cls`` a record (immutable unless ``frozen=False``)."""
    if cls is None:
        return lambda inner: _make(inner, frozen)
    return _make(cls, frozen)


def is_record(value: Any) -> bool:
    return hasattr(type(value), "__record_fields__") and not isinstance(value, type)


def fields(value: Any) -> tuple[RecordField, ...]:
    """The fields of a record or record class, in ``__init__`` order."""
    return (value if isinstance(value, type) else type(value)).__record_fields__  # type: ignore[no-any-return]


def replace(value: T, /, **changes: Any) -> T:
    """A copy of the record ``value`` with some fields changed."""
    current = {spec.name: getattr(value, spec.name) for spec in fields(value)}
    current.update(changes)
    return type(value)(**current)


def asdict(value: Any) -> Any:
    """A record as plain data: nested records, lists, tuples and mappings converted too."""
    if is_record(value):
        return {spec.name: asdict(getattr(value, spec.name)) for spec in fields(value)}
    if isinstance(value, list | tuple):
        return type(value)(asdict(v) for v in value) if not hasattr(value, "_fields") else value
    if isinstance(value, dict):
        return {k: asdict(v) for k, v in value.items()}
    return value
