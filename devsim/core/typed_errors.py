"""Every problem of data that did not convert, located and worded for a user (slow path only).

msgspec stops at the first problem and names it in its own words (``Expected `int` <= 127 -
at `$.address```; a mapping's entry only as ``$.params[...]``).  When
:meth:`devsim.core.typed.Typed.parse` fails, :func:`problems_of` converts the data again piece by
piece (each field, list item and mapping entry against its own type), so that every problem is
found with its full location, including the key of a mapping entry, and worded as users already
read them: "Input should be a valid number, unable to parse string as a number", "Field
required", "unknown field", "Input should be 'S' or 'E'", "Input should be less than or equal
to 127".  Messages of checks, custom field types and ``__post_init__`` pass through unchanged.
"""

from __future__ import annotations

import ast
import math
import re
from collections.abc import Mapping
from typing import Annotated, Any, Literal, Union, get_args, get_origin

import msgspec

from devsim.core.typed_convert import NOT_FINITE, Keys, Location, Problem, convert, fixer, struct_type

__all__ = ["problems_of", "wording"]

_AT = re.compile(r"^(?P<msg>.*?)(?: - at `(?P<path>[^`]*)`)?$", re.S)
_PATH_PART = re.compile(r"\.([^.\[]+)|\[(\d+|\.\.\.)\]")
_EXPECTED = re.compile(r"^Expected `(?P<want>[^`]*)`(?P<rest>.*?)(?:, got `(?P<got>[^`]*)`)?$")
_BOUND = re.compile(r"^ (?P<op><=|>=|<|>) (?P<num>\S+)$")
_LENGTH = re.compile(r"^ of length (?P<op>>=|<=) (?P<num>\d+)$")
_BOUND_TEXT = {">=": "greater than or equal to", ">": "greater than", "<=": "less than or equal to", "<": "less than"}


def problems_of(kind: Any, data: Any) -> list[Problem]:
    """Every problem of ``data`` as ``kind``: ``(location, message)``, in the data's order."""
    problems: list[Problem] = []
    _collect(kind, data, (), problems)
    return problems or [((), "invalid")]


def _fields(kind: type[msgspec.Struct]) -> dict[str, msgspec.structs.FieldInfo]:
    return {f.encode_name: f for f in msgspec.structs.fields(kind)}


def _collect(kind: Any, data: Any, loc: Location, problems: list[Problem]) -> None:
    if isinstance(data, float) and not math.isfinite(data) and _numeric(kind):
        problems.append((loc, NOT_FINITE))
        return
    try:
        value = convert(data, kind)
    except msgspec.ValidationError as exc:
        error = str(exc)
    else:  # this part is right as a type: its checks and keys still apply
        fix = fixer(kind)
        if fix is not None:
            fix(value, loc, problems)
        return
    base = struct_type(kind)
    origin = get_origin(base)
    before = len(problems)
    if data is not None and isinstance(base, type) and issubclass(base, msgspec.Struct) and isinstance(data, Mapping):
        fields = _fields(base)
        problems += [((*loc, key), "unknown field") for key in data if not isinstance(key, str) or key not in fields]
        for key, field in fields.items():  # in the declared order
            if key in data:
                _collect(field.type, data[key], (*loc, key), problems)
            elif field.required:
                problems.append(((*loc, key), "Field required"))
    elif origin is list and isinstance(data, list | tuple):
        for index, item in enumerate(data):
            _collect(get_args(base)[0], item, (*loc, index), problems)
    elif origin is dict and isinstance(data, Mapping):
        key_kind, value_kind = get_args(base)
        keys = _keys(kind)
        for key, value in data.items():
            try:
                convert(key, key_kind)
                if keys is not None:
                    keys.function(key)
            except msgspec.ValidationError as exc:
                problems.append(((*loc, key), wording(str(exc), key_kind, key)[1]))
                continue
            except ValueError as exc:
                problems.append(((*loc, key), str(exc)))
                continue
            _collect(value_kind, value, (*loc, key), problems)
    if len(problems) == before:  # the parts are right: the problem is the whole (a length, a rule)
        path, text = wording(error, kind, data, loc)
        problems.append(((*loc, *path), text))


def _keys(kind: Any) -> Keys | None:
    """The :class:`Keys` of an annotated mapping type."""
    while get_origin(kind) is Annotated:
        kind, *meta = get_args(kind)
        found = next((m for m in meta if isinstance(m, Keys)), None)
        if found is not None:
            return found
    return None


def _numeric(kind: Any) -> bool:
    """``kind`` takes plain numbers (so NaN given for it is refused as such)."""
    base = struct_type(kind)
    arms = get_args(base) if get_origin(base) is Union or type(base).__name__ == "UnionType" else (base,)
    arms = tuple(struct_type(a) for a in arms if a is not type(None))
    return bool(arms) and all(a in (int, float) for a in arms)


def _given(data: Any, path: list[int | str]) -> str:
    """", not N" after a length message, when the problem is at ``data`` itself."""
    return f" after validation, not {len(data)}" if not path and isinstance(data, list | dict | str) else ""


def _path(text: str | None) -> list[int | str]:
    parts: list[int | str] = []
    for name, index in _PATH_PART.findall(text or ""):
        parts.append(name if name else int(index) if index != "..." else "...")
    return parts


def _kind_at(kind: Any, path: list[int | str]) -> Any:
    """The declared type at ``path`` inside ``kind`` (None where it cannot be followed)."""
    for step in path:
        base = struct_type(kind)
        if isinstance(base, type) and issubclass(base, msgspec.Struct) and isinstance(step, str):
            field = _fields(base).get(step)
            if field is None:
                return None
            kind = field.type
        elif get_origin(base) in (list, tuple) and isinstance(step, int):
            args = get_args(base)
            kind = args[0] if get_origin(base) is list or len(args) == 2 and args[1] is ... else (
                args[step] if step < len(args) else None)
        elif get_origin(base) is dict:
            kind = get_args(base)[1]
        else:
            return None
    return kind


def wording(error: str, kind: Any, data: Any, loc: Location = ()) -> tuple[list[int | str], str]:
    """(location inside ``kind``, message) of a msgspec error, in the users' words; ``loc`` is
    where ``kind`` sits (its last key names the field in a custom type's message)."""
    match = _AT.match(error)
    assert match is not None
    message, path = match["msg"], _path(match["path"])
    missing = re.fullmatch(r"Object missing required field `([^`]*)`", message)
    if missing:
        return [*path, missing[1]], "Field required"
    unknown = re.fullmatch(r"Object contains unknown field `([^`]*)`", message)
    if unknown:
        return [*path, unknown[1]], "unknown field"
    located = re.match(r"@([^:]+): (.*)", message, re.S)
    if located:  # FieldError
        path, message = [*path, located[1]], located[2]
    if "..." in path:  # an entry of a mapping: the piecewise pass names its key
        path = path[:path.index("...")]
    target = struct_type(_kind_at(kind, path))
    field = next((p for p in reversed((*loc, *path)) if isinstance(p, str) and p != "..."), "value")
    if located or "{field}" in message and not message.startswith("Expected"):
        return path, message.replace("{field}", field)
    text = _expected(message, target)
    return path, text + _given(data, path) if text.endswith(("item", "items", "character", "characters")) else text


def _listed(choices: tuple[Any, ...]) -> str:
    names = [repr(c) for c in choices]
    return names[0] if len(names) == 1 else f"{', '.join(names[:-1])} or {names[-1]}"


def _expected(message: str, target: Any) -> str:
    if get_origin(target) is Literal:
        return f"Input should be {_listed(get_args(target))}"
    if message.startswith("Invalid enum value"):
        return message
    if message == "Number out of range":  # text such as "1e400" read as a number
        return NOT_FINITE
    match = _EXPECTED.match(message)
    if match is None:
        return message
    want = match["want"].removesuffix(" | null")
    rest, got = match["rest"], match["got"]
    bound = _BOUND.match(rest)
    if bound:
        number = float(bound["num"])
        return f"Input should be {_BOUND_TEXT[bound['op']]} {number:g}"
    length = _LENGTH.match(rest)
    if length:
        what = {"array": "List", "object": "Dictionary", "str": "String"}.get(want, "Value")
        unit = "character" if want == "str" else "item"
        least = "at least" if length["op"] == ">=" else "at most"
        count = int(length["num"])
        return f"{what} should have {least} {count} {unit}{'' if count == 1 else 's'}"
    if rest.startswith(" matching regex "):
        pattern = ast.literal_eval(rest.removeprefix(" matching regex "))  # msgspec shows it as a repr
        return f"String should match pattern '{pattern}'"
    if want == "array" and get_origin(target) is tuple:
        return "Input should be a list of two values" if len(get_args(target)) == 2 else "Input should be a valid list"
    if want == "int":
        if got == "str":
            return "Input should be a valid integer, unable to parse string as an integer"
        if got == "float":
            return "Input should be a valid integer, got a number with a fractional part"
        return "Input should be a valid integer"
    if want in ("float", "int | float", "float | int"):
        if got == "str":
            return "Input should be a valid number, unable to parse string as a number"
        return "Input should be a valid number"
    simple = {"bool": "a valid boolean", "str": "a valid string", "array": "a valid list", "object": "a valid dictionary"}
    if want in simple:
        return f"Input should be {simple[want]}"
    return message
