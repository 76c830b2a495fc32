"""What ``devsim ctl`` prints: for people, tables and plain words (``ok``, ``axis.position = 1200
inc``); with ``--json``, the result as JSON for scripts (one value, or an object or list indented
by two; stable: scripts and tests parse it).  Text is printed as characters in both (``§``, not
``\\u00a7``).

:data:`FORMATTERS` is the table: op of :data:`devsim.runtime.ops.CONTROL` → a callable that turns
the op's result into text; :func:`render` picks the row (or JSON).  A formatter gets a
:class:`View`: the request, the terminal's width and, for the units of a read or a state, the
device's declared names (asked once, only when a formatter needs them)."""

from __future__ import annotations

import json
import os
import shutil
import sys
from collections.abc import Callable, Iterable, Sequence
from typing import Any

import click

from devsim.runtime import requests as rq
from devsim.runtime.ops import op_of

__all__ = [
    "FORMATTERS",
    "JsonCommand",
    "JsonGroup",
    "View",
    "as_json",
    "by_pattern_text",
    "names_text",
    "render",
    "table",
    "value_text",
    "wants_json",
]

_JSON_KEY = "devsim.ctl.json"

#: Narrowest and widest table we lay out (columns of a terminal).
MIN_WIDTH, MAX_WIDTH = 40, 200
PIPE_WIDTH = 10_000  # (no terminal: rows whole)


# -- --json, on the group and on every command ------------------------------------------------
def _remember_json(ctx: click.Context, _param: click.Parameter, value: bool) -> bool:
    if value:
        ctx.meta[_JSON_KEY] = True  # meta is shared by the group's context and its command's
    return value


def json_option() -> click.Option:
    """``--json``: print the result as JSON (for scripts) instead of text."""
    return click.Option(["--json", "json_output"], is_flag=True, expose_value=False, callback=_remember_json,
                        help="Print the result as JSON (for scripts) instead of text.")


def wants_json(ctx: click.Context) -> bool:
    """Whether ``--json`` was given to ``devsim ctl`` or to its command."""
    return bool(ctx.meta.get(_JSON_KEY))


class JsonCommand(click.Command):
    """A ``devsim ctl`` command: it takes ``--json`` unless it declares its own."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        if not any("--json" in getattr(param, "opts", ()) for param in self.params):
            self.params.append(json_option())


class JsonGroup(click.Group):
    """``devsim ctl``: ``--json`` on the group (``devsim ctl --json read ...``) and on each command."""

    command_class = JsonCommand

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.params.append(json_option())


# -- values and tables ------------------------------------------------------------------------
def as_json(result: Any) -> str:
    """The JSON of ``--json``: objects and lists indented by two, characters as they are."""
    if isinstance(result, dict | list):
        return json.dumps(result, indent=2, ensure_ascii=False)
    return json.dumps(result, ensure_ascii=False)


def value_text(value: Any) -> str:
    """A value as a person reads it: text as it is, ``true``/``false``, numbers, JSON for the rest."""
    if isinstance(value, str):
        return value
    if isinstance(value, float) and value.is_integer() and abs(value) < 1e15:
        return str(int(value))
    return json.dumps(value, ensure_ascii=False)


def terminal_width() -> int:
    """The terminal's width (``COLUMNS`` where set); a pipe or a file has none: nothing is cut
    there (a script that greps a row must find all of it)."""
    if "COLUMNS" not in os.environ and (sys.stdout is None or not sys.stdout.isatty()):
        return PIPE_WIDTH
    return max(MIN_WIDTH, min(MAX_WIDTH, shutil.get_terminal_size().columns))


def _cut(text: str, width: int) -> str:
    return text if len(text) <= width else text[: max(0, width - 1)] + "…"


def table(rows: Sequence[Sequence[Any]], headers: Sequence[str] | None = None, *, width: int | None = None,
          indent: str = "") -> list[str]:
    """Rows in columns two spaces apart; the last column is cut (``…``) to fit ``width``."""
    texts = [[value_text(cell) if not isinstance(cell, str) else cell for cell in row] for row in rows]
    if headers is not None:
        texts.insert(0, list(headers))
    if not texts:
        return []
    count = max(len(row) for row in texts)
    sizes = [max((len(row[i]) for row in texts if i < len(row)), default=0) for i in range(count - 1)]
    lines = []
    for row in texts:
        cells = [cell.replace("\n", "⏎") for cell in row]
        head = "".join(f"{cell:<{sizes[i]}}  " for i, cell in enumerate(cells[:-1]))
        line = indent + head + cells[-1]
        if width is not None:
            line = _cut(line, width)
        lines.append(line.rstrip())
    return lines


def _flatten(value: Any, prefix: str = "") -> Iterable[tuple[str, Any]]:
    """A nested state as dotted names: ``{"axis": {"position": 1}}`` → ``("axis.position", 1)``."""
    if isinstance(value, dict) and value:
        for key, item in value.items():
            yield from _flatten(item, f"{prefix}.{key}" if prefix else str(key))
    else:
        yield prefix, value


# -- the view a formatter gets ----------------------------------------------------------------
class View:
    """What a formatter knows besides the result: the request, the terminal width, and the
    declared names of the request's device (``names(device)``, asked at most once)."""

    def __init__(self, request: rq.ControlRequest, names: Callable[[str], list[dict[str, Any]]] | None = None,
                 width: int | None = None) -> None:
        self.request = request
        self.width = width if width is not None else terminal_width()
        self._names = names
        self._units: dict[str, str] | None = None

    def unit(self, name: str) -> str:
        """The declared unit of ``name`` on the request's device ("" if none or unknown)."""
        if self._units is None:
            self._units = {}
            device = getattr(self.request, "device", None)
            if self._names is not None and device:
                try:
                    self._units = {row["name"]: row.get("unit") or "" for row in self._names(device)}
                except Exception:  # noqa: BLE001 - the value is shown without its unit
                    self._units = {}
        return self._units.get(name, "")


def _ok(_result: Any, _view: View) -> str:
    return "ok"


def _read(result: Any, view: View) -> str:
    name = getattr(view.request, "name", "")
    unit = view.unit(name)
    return f"{name} = {value_text(result)}{' ' + unit if unit else ''}"


def _state(result: Any, view: View) -> str:
    rows = [(name, value_text(value), view.unit(name)) for name, value in _flatten(result)]
    return "\n".join(table(rows, width=view.width))


def _seconds(value: Any) -> str:
    """A clock's time to the microsecond (its sum of steps may be 6.800000000000001)."""
    if isinstance(value, float):
        return value_text(round(value, 6))
    return value_text(value)


def _advance(result: Any, view: View) -> str:
    if isinstance(result, dict):  # a fleet: each process's new time
        return "ok\n" + _per_process(result, view)
    return f"ok, time {_seconds(result)} s"


def _now(result: Any, view: View) -> str:
    if isinstance(result, dict):
        return _per_process(result, view)
    return f"{_seconds(result)} s"


def _per_process(result: dict[str, Any], view: View) -> str:
    return "\n".join(table([(process, f"{_seconds(t)} s") for process, t in result.items()],
                           ("process", "time"), width=view.width))


def _records(result: Any, view: View) -> str:
    """A list of objects (devices, fleet rows) as a table with a column per key."""
    if not isinstance(result, list) or not all(isinstance(row, dict) for row in result):
        return as_json(result)
    if not result:
        return "(none)"
    keys: list[str] = []
    for row in result:
        keys += [key for key in row if key not in keys and key != "ports"]
    rows = [[_cell(row.get(key)) for key in keys] for row in result]
    return "\n".join(table(rows, keys, width=view.width))


def _cell(value: Any) -> str:
    if value is None:
        return "-"
    if isinstance(value, list):
        return ", ".join(value_text(item) for item in value) or "-"
    return value_text(value)


def _line(result: Any, view: View) -> str:
    rows = [(name, _cell(value)) for name, value in _flatten(result)]
    return "\n".join(table(rows, width=view.width))


def _telegrams(result: Any, view: View) -> str:
    if not result:
        return "(no telegrams yet: the tap starts with the first request)"
    rows = []
    for item in result:
        decoded = "; ".join(_fields(d) for d in item.get("decoded", ()))
        rows.append((f"{float(item.get('t', 0.0)):.3f}", item.get("dir", ""), item.get("text", ""), decoded))
    return "\n".join(table(rows, ("time", "dir", "bytes", "decoded"), width=view.width))


def _fields(message: Any) -> str:
    """A decoded message as ``key=value`` words (``frame=short C=40 A=1``)."""
    if isinstance(message, dict):
        return " ".join(f"{key}={value_text(value)}" for key, value in message.items())
    return value_text(message)


def family(name: str) -> str:
    """A name's family: the part before its first dot (``axis.position`` → ``axis``)."""
    return name.split(".", 1)[0]


def names_text(rows: Sequence[dict[str, Any]], width: int) -> str:
    """Declared names grouped by family, each with type, unit, access and its description cut
    to ``width`` (columns aligned within a group); names alone in their family (``ready``,
    ``errno``) share a first group."""
    groups: dict[str, list[dict[str, Any]]] = {}
    for row in rows:
        groups.setdefault(family(row["name"]), []).append(row)
    single = [g[0] for key, g in groups.items() if len(g) == 1 and g[0]["name"] == key]
    ordered: list[tuple[str, list[dict[str, Any]]]] = [("(single names)", single)] if single else []
    ordered += [(key, g) for key, g in groups.items() if not (len(g) == 1 and g[0]["name"] == key)]
    lines: list[str] = []
    for title, members in ordered:
        lines.append(f"{title} ({len(members)})")
        cells = [(row["name"], row.get("type") or "", row.get("unit") or "", row.get("access") or "",
                  row.get("doc") or "") for row in members]
        lines += table(cells, width=max(width, 40), indent="  ")
    lines.append(_cut(f"{len(rows)} names in {len(ordered)} groups (--json: every field)", max(width, 40)))
    return "\n".join(lines)


def by_pattern_text(patterns: Sequence[dict[str, Any]], aliases: Sequence[dict[str, Any]], width: int) -> str:
    """What ``devsim ctl names`` adds after a device's names: the kind's names made from a pattern
    (``marker.M<byte>.<bit>``, with type, access and description, as ``devsim doc KIND`` shows
    them) and its aliases (``param.V  for  param.P91  rw ...``), one line each, cut to ``width``; ""
    for a kind with neither."""
    width = max(width, MIN_WIDTH)
    lines: list[str] = []
    if patterns:
        lines.append("also by pattern:")
        lines += table([(row["name"], row.get("type") or "", row.get("unit") or "", row.get("access") or "",
                         row.get("doc") or "") for row in patterns], width=width, indent="  ")
    if aliases:
        lines.append("also by alias:")
        lines += table([(row["name"], "for", row["for"], row.get("access") or "", row.get("doc") or "")
                        for row in aliases], width=width, indent="  ")
    return "\n".join(lines)


def _names(result: Any, view: View) -> str:
    return names_text(result, view.width)


def _scenario(result: Any, view: View) -> str:
    """``scenario NAME: step 3 of 7, 2.300 of 5.000 s, running`` and a row per step so far (a
    fleet: each process's, under its name)."""
    if not isinstance(result, dict):
        return "(no scenario runs)"
    if "steps" not in result:  # a fleet: process → its record or null
        return "\n".join(f"{process}: {_scenario(record, view)}" for process, record in sorted(result.items()))
    state = "running" if result.get("running") else ("passed" if result.get("passed") else "failed")
    head = (f"scenario {result.get('name')}: step {result.get('done')} of {result.get('total')}, "
            f"{value_text(result.get('now'))} of {value_text(result.get('end'))} s, {state}")
    rows = [(str(step.get("index")), step.get("status", ""), step.get("label", ""), step.get("message", ""))
            for step in result.get("steps", []) if step.get("status") != "pending"]
    return "\n".join([head, *table(rows, width=view.width)] if rows else [head])


#: op → formatter (result, view) → text; ``watch`` prints its own lines (``describe``).
FORMATTERS: dict[str, Callable[[Any, View], str]] = {
    "read": _read,
    "set": _ok,
    "state": _state,
    "power_cycle": _ok,
    "advance": _advance,
    "now": _now,
    "info": _line,
    "devices": _records,
    "line": _line,
    "names": _names,
    "fault": _ok,
    "line_fault": _ok,
    "telegrams": _telegrams,
    "scenario": _scenario,
}


def render(answers: Sequence[tuple[rq.ControlRequest, Any]], *, json_output: bool,
           names: Callable[[str], list[dict[str, Any]]] | None = None, width: int | None = None) -> str:
    """The text of one or more answered requests: JSON (``--json``: one request's result as it
    came, several reads as ``{name: value}``) or the op's formatter; several reads are one table
    of name, value and unit."""
    if json_output:
        if len(answers) == 1:
            return as_json(answers[0][1])
        return as_json({getattr(request, "name", op_of(request)): result for request, result in answers})
    if len(answers) == 1:
        request, result = answers[0]
        return FORMATTERS[op_of(request)](result, View(request, names, width))
    view = View(answers[0][0], names, width)
    rows = [(getattr(request, "name", ""), value_text(result), view.unit(getattr(request, "name", "")))
            for request, result in answers]
    return "\n".join(table(rows, ("name", "value", "unit"), width=view.width))
