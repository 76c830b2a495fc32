"""YAML configuration files with line-numbered validation errors.

A configuration file (``devsim run --config``, later plant and scenario files) is YAML, loaded
with a :class:`yaml.SafeLoader` subclass that remembers the line of every mapping key and list
item, then validated against its declaration (:class:`devsim.core.typed.Typed`: a kind's
configuration, :mod:`devsim.core.settings`, or the scenario and plant schema).  Every problem is
reported as one line that an editor can jump to::

    config.yaml:3: baud: baud must be one of 1200, 2400, ...
    config.yaml:7: axis.limit_left: Input should be a valid number
    config.yaml:4: mapping values are not allowed here
    plant.yaml:12: devices.3.config.address: Input should be less than or equal to 127

List items are numbered as the file reads them, from 1 (``devices.3`` is the third device).

Use :func:`load_config` for the common case, or :func:`load_yaml` + :func:`validate` when the
data needs reshaping in between.
"""

from __future__ import annotations

import os
from collections.abc import Hashable
from pathlib import Path
from typing import Any, NoReturn, TypeVar

import yaml

from devsim.core.typed import Invalid, Typed, place

__all__ = [
    "ConfigError", "LineDict", "LineList", "LineLoader", "load_config", "load_yaml", "located", "place", "plain",
    "report", "validate",
]

T = TypeVar("T", bound=Typed)


class ConfigError(ValueError):
    """A configuration file is unreadable, not YAML, or does not validate.

    ``str(error)`` is one line, ``file:line: dotted.field: message``; ``messages`` holds one such
    line per problem found (the first is the message).
    """

    def __init__(self, message: str, messages: list[str] | None = None) -> None:
        super().__init__(message)
        self.messages = messages or [message]

    @classmethod
    def of(cls, messages: list[str]) -> ConfigError:
        """The error for one or more ``file:line: …`` lines (the first, "(and N more)")."""
        first = messages[0] + (f" (and {len(messages) - 1} more)" if len(messages) > 1 else "")
        return cls(first, messages)


class LineDict(dict[Any, Any]):
    """A YAML mapping that knows its own line and each key's line (1-based)."""

    line: int = 1
    key_lines: dict[Hashable, int]


class LineList(list[Any]):
    """A YAML sequence that knows its own line and each item's line (1-based)."""

    line: int = 1
    item_lines: list[int]


class LineLoader(yaml.SafeLoader):
    """A safe loader whose mappings and sequences record line numbers; duplicate keys fail."""

    def construct_mapping(self, node: yaml.MappingNode, deep: bool = False) -> LineDict:  # type: ignore[override]
        seen: dict[tuple[str, str], int] = {}
        for key_node, _ in node.value:
            if isinstance(key_node, yaml.ScalarNode) and key_node.tag != "tag:yaml.org,2002:merge":
                ident = (key_node.tag, key_node.value)
                if ident in seen:
                    raise yaml.constructor.ConstructorError(
                        None, None, f"duplicate key {key_node.value!r} (first on line {seen[ident]})",
                        key_node.start_mark,
                    )
                seen[ident] = key_node.start_mark.line + 1
        self.flatten_mapping(node)
        result = LineDict()
        result.line = node.start_mark.line + 1
        result.key_lines = {}
        for key_node, value_node in node.value:
            key = self.construct_object(key_node, deep=deep)
            if not isinstance(key, Hashable):
                raise yaml.constructor.ConstructorError(
                    "while constructing a mapping", node.start_mark, "found an unhashable key", key_node.start_mark
                )
            result[key] = self.construct_object(value_node, deep=deep)
            result.key_lines[key] = key_node.start_mark.line + 1
        return result

    def construct_line_sequence(self, node: yaml.SequenceNode) -> LineList:
        result = LineList(self.construct_object(child, deep=True) for child in node.value)
        result.line = node.start_mark.line + 1
        result.item_lines = [child.start_mark.line + 1 for child in node.value]
        return result

    def construct_line_mapping(self, node: yaml.MappingNode) -> LineDict:
        return self.construct_mapping(node, deep=True)


LineLoader.add_constructor("tag:yaml.org,2002:map", LineLoader.construct_line_mapping)
LineLoader.add_constructor("tag:yaml.org,2002:seq", LineLoader.construct_line_sequence)


def _display(path: str | os.PathLike[str]) -> str:
    return os.fspath(path)


def load_yaml(path: str | os.PathLike[str], text: str | None = None) -> Any:
    """Parse a YAML file (or ``text``, reported as ``path``) keeping line numbers.

    Mappings come back as :class:`LineDict`, sequences as :class:`LineList`; an empty document
    is ``None``.  Raises :class:`ConfigError` (``file:line: problem``) for unreadable files and
    YAML syntax errors.
    """
    name = _display(path)
    if text is None:
        try:
            text = Path(path).read_text(encoding="utf-8")
        except FileNotFoundError:
            raise ConfigError(f"{name}: no such file") from None
        except (OSError, UnicodeDecodeError) as exc:
            raise ConfigError(f"{name}: cannot read: {exc}") from None
    try:
        return yaml.load(text, Loader=LineLoader)  # noqa: S506 - LineLoader is a SafeLoader
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark or exc.context_mark
        line = mark.line + 1 if mark is not None else 1
        problem = exc.problem or exc.context or "invalid YAML"
        if exc.context and exc.problem and exc.context != exc.problem:
            problem = f"{problem} ({exc.context})"
        raise ConfigError(f"{name}:{line}: {problem}") from None
    except yaml.YAMLError as exc:
        raise ConfigError(f"{name}:1: {exc}") from None
    except RecursionError:  # (PyYAML composes nested collections recursively)
        raise ConfigError(f"{name}: nested deeper than this reader goes") from None


def _locate(data: Any, loc: tuple[int | str, ...]) -> tuple[int, list[str]]:
    """The best YAML line for a problem's location, and the location's printable parts.

    Walks ``data`` along ``loc`` as far as the data goes; list items are numbered from 1, as
    the file reads.  A key missing from a mapping (a required field) is still named and reported
    at the mapping's line.
    """
    line = getattr(data, "line", 1)
    parts: list[str] = []
    node = data
    for step in loc:
        if isinstance(node, LineDict):
            if step in node:
                line = node.key_lines.get(step, line)
                parts.append(str(step))
                node = node[step]
                continue
            # a missing field
            parts.append(str(step))
            break
        if isinstance(node, LineList) and isinstance(step, int) and 0 <= step < len(node):
            line = node.item_lines[step]
            parts.append(str(step + 1))
            node = node[step]
            continue
        break
    return line, parts


def _kind(data: Any) -> str:
    if isinstance(data, list):
        return "a list"
    if isinstance(data, str):
        return "a string"
    return type(data).__name__


def validate(data: Any, model: type[T], path: str | os.PathLike[str]) -> T:
    """Validate YAML data from :func:`load_yaml` against a declaration (a configuration or the
    scenario schema, :class:`devsim.core.typed.Typed`); errors name file and line."""
    name = _display(path)
    if data is None:
        data = LineDict()
        data.key_lines = {}
    try:
        return model.parse(data)
    except Invalid as exc:
        _refuse(name, data, exc.problems)


def located(name: str, data: Any, loc: tuple[int | str, ...], text: str) -> tuple[int, str]:
    """A problem at ``loc`` in ``data`` (from :func:`load_yaml` of file ``name``) as its line and
    its ``file:line: dotted.field: message``."""
    line, parts = _locate(data, loc)
    field = ".".join(parts)
    if not parts and not isinstance(data, dict):
        text = f"expected a mapping at the top level, got {_kind(data)}"
    return line, f"{name}:{line}: {field}: {text}" if field else f"{name}:{line}: {text}"


def report(name: str, data: Any, problems: list[tuple[tuple[int | str, ...], str]]) -> list[str]:
    """One ``file:line: key: message`` per problem, in the file's order (by line)."""
    rows: list[tuple[int, str]] = []
    seen: set[tuple[int, str]] = set()
    for loc, text in problems:
        line, parts = _locate(data, loc)
        if (line, ".".join(parts)) in seen:  # e.g. one error per member of a union: keep the first
            continue
        seen.add((line, ".".join(parts)))
        rows.append(located(name, data, loc, text))
    return [message for _line, message in sorted(rows, key=lambda row: row[0])]


def _refuse(name: str, data: Any, problems: list[tuple[tuple[int | str, ...], str]]) -> NoReturn:
    """Every problem as a ``file:line: key: message`` line (the first is the error's message)."""
    raise ConfigError.of(report(name, data, problems)) from None


def load_config(path: str | os.PathLike[str], model: Any) -> Any:
    """Load a YAML file and validate it against ``model``.

    Raises :class:`ConfigError` whose message is one line, ``file:line: dotted.field: message``
    (or ``file:line: message`` for YAML syntax errors).
    """
    return validate(load_yaml(path), model, path)


def plain(data: Any) -> Any:
    """``data`` from :func:`load_yaml` as plain dicts and lists (line information dropped)."""
    if isinstance(data, dict):
        return {key: plain(value) for key, value in data.items()}
    if isinstance(data, list):
        return [plain(value) for value in data]
    return data
