"""``devsim run``/``devsim up`` on stderr: host connects and disconnects, line mismatches and
device errors as they happen, one line each (``-v``/``-q`` raise or lower how much).

Levels (``2 + verbose - quiet``, clamped):

* 0 (``-qq``): nothing;
* 1 (``-q``): device errors (events named ``...error...``, the model's own faults) and line
  settings that do not match the device's (``host settings 4800 8N1 (mismatch, device 9600 8N1)``);
* 2 (default): also host connects and disconnects, and the host's line settings;
* 3 (``-v``): also every event (``move_start``, ``move_end`` ...), declared faults switched and
  line faults started or ended.

A line: ``devsim: 12.300 sers connect host connected`` (device time, then
:func:`devsim.runtime.watch_stream.describe`).  Built on :class:`~devsim.runtime.watch_stream.WatchStream`
without point sampling: a quiet simulator stays idle.  stdout (ports, ``control:``, ``NAME: ready``)
is not touched: scripts parse it.
"""

from __future__ import annotations

import sys
from collections.abc import Callable
from typing import Any

import click

__all__ = ["DEFAULT_LEVEL", "attach_log", "level_of", "log_options"]

DEFAULT_LEVEL = 2

_CONNECTS = ("connect", "disconnect", "host_settings")


def level_of(verbose: int, quiet: int) -> int:
    """The log level ``-v``/``-q`` (counted) ask for."""
    return max(0, min(3, DEFAULT_LEVEL + verbose - quiet))


def _level(item: dict[str, Any]) -> int:
    """The least level that shows ``item``."""
    kind = item.get("type")
    if kind in ("error", "drive_fault") or (kind == "host_settings" and item.get("mismatch")):
        return 1
    if kind in _CONNECTS:
        return 2
    return 3


def attach_log(runtime: Any, level: int, write: Callable[[str], None] | None = None) -> list[Any]:
    """Log what happens to every device of ``runtime`` at ``level`` (run in the loop thread);
    returns the streams (``stop()`` ends them).  ``write`` defaults to a flushed stderr line."""
    if level <= 0:
        return []
    from devsim.runtime.watch_stream import WatchStream, describe

    def emit(text: str) -> None:
        print(text, file=sys.stderr, flush=True)

    out = write or emit

    def send(item: dict[str, Any]) -> None:
        if _level(item) <= level:
            out(f"devsim: {describe(item)}")

    streams = []
    for device in runtime.devices.values():
        stream = WatchStream(runtime, device, send, values=False)
        stream.start()
        streams.append(stream)
    return streams


def log_options(command: Callable[..., Any]) -> Callable[..., Any]:
    """``-v``/``--verbose`` and ``-q``/``--quiet`` (both countable) for a command."""
    command = click.option("-q", "--quiet", count=True,
                           help="Log less to stderr (-q: errors and mismatches only; -qq: nothing).")(command)
    return click.option("-v", "--verbose", count=True,
                        help="Log more to stderr (default: connects, disconnects, mismatches, errors; "
                             "-v: every event and fault).")(command)
