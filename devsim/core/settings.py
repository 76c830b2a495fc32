"""Configuration: what a user can set for one device, declared as typed data (msgspec).

A kind declares its configuration (DIP switches, variant, options, geometry) as a
:class:`Settings` struct, one field per key, the docstring saying what it is::

    class SersConfig(Settings):
        \"\"\"What a user can set for one SERS (--config FILE.yaml or a plant file).\"\"\"

        address: Annotated[int, Meta(ge=0, le=127), doc("DIP switch 2 bits 1-7; 0 = master")] = 1
        baud: Annotated[int, Check(_baud), doc("DIP switch 1 bits 1-3")] = 9600
        axis: AxisGeometry = field(default_factory=AxisGeometry)

The same declaration validates a ``--config`` file, a plant file's ``config:`` and ``--drives``
(``SersConfig.parse(data)``, an instance with attribute access, ``.dump()`` and ``.replace()``),
documents every key (:func:`rows`, printed by ``devsim doc``) and lets
:mod:`devsim.core.config` name the file and line of a problem (:class:`Invalid`).  See
:mod:`devsim.core.typed` for the vocabulary (:class:`Check`, :class:`Keys`, :func:`doc`).
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import Annotated, Any, Literal, Union, get_args, get_origin

import msgspec
from msgspec import Meta, field

from devsim.core.typed import Check, Invalid, Keys, Typed, doc

__all__ = [
    "Check", "Invalid", "Keys", "Meta", "Settings", "doc", "field", "rows", "type_text",
]


class Settings(Typed):
    """A configuration (or one nested part of it): each key a field."""


def _plain_doc(kind: type) -> str:
    return " ".join((kind.__doc__ or "").split())


def type_text(kind: Any) -> str:
    """A field type as the reference prints it: ``int``, ``'S' | 'E'``, ``[float, float] | None``,
    ``list[mapping]``, ``{N parameter: int}``."""
    keys = "key"
    if get_origin(kind) is Annotated:
        kind, *meta = get_args(kind)
        keys = next((m.text for m in meta if isinstance(m, Keys)), keys)
    origin = get_origin(kind)
    if origin is Literal:
        return " | ".join(map(repr, get_args(kind)))
    if origin is Union or type(kind).__name__ == "UnionType":
        return " | ".join("None" if a is type(None) else type_text(a) for a in get_args(kind))
    if origin is list:
        return f"list[{type_text(get_args(kind)[0])}]"
    if origin is tuple:
        return f"[{', '.join(type_text(a) for a in get_args(kind))}]"
    if origin is dict:
        return f"{{{keys}: {type_text(get_args(kind)[1])}}}"
    if isinstance(kind, type) and issubclass(kind, msgspec.Struct):
        return "mapping"
    return getattr(kind, "__name__", str(kind))


def _description(kind: Any) -> str:
    if get_origin(kind) is not Annotated:
        return ""
    return next((m.description for m in get_args(kind)[1:] if isinstance(m, Meta) and m.description), "")


def rows(config: type[msgspec.Struct], prefix: str = "") -> Iterator[tuple[str, str, str, str]]:
    """(key, type, default, description) of every key, nested keys dotted (for ``devsim doc``)."""
    for info in msgspec.structs.fields(config):
        key = f"{prefix}{info.encode_name}"
        inner = get_args(info.type)[0] if get_origin(info.type) is Annotated else info.type
        if isinstance(inner, type) and issubclass(inner, msgspec.Struct):  # a nested part: its keys follow
            yield key, "mapping", "", _description(info.type) or _plain_doc(inner)
            yield from rows(inner, f"{key}.")
            continue
        if info.default is not msgspec.NODEFAULT:
            default = repr(info.default)
        elif info.default_factory is not msgspec.NODEFAULT:
            default = repr(info.default_factory())
        else:
            default = ""
        yield key, type_text(info.type), default if len(default) <= 40 else default[:37] + "...", _description(info.type)

