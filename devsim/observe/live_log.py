"""``devsim run``/``devsim up`` on stderr: host connects and disconnects, line mismatches, device
errors and (``-v``) the traffic as they happen, one line each (``-v``/``-q`` raise or lower how much).

Two streams: **stdout** carries the output a user or a script needs to connect (``NAME: pty
/dev/pts/5``, ``control: ...``, ``NAME: ready``): it is never silenced (a stream whose reader
has gone goes to the null device: :mod:`devsim.core.console`).  **stderr** carries the log,
at a level of ``2 + verbose - quiet`` (clamped):

* 0 (``-qq``): nothing but fatal errors (``Error: ...`` and a non-zero exit status);
* 1 (``-q``): warnings and errors: device errors by their number and text from the kind's error
  table (``sers error P11 8192: drive error: limit switch``; :func:`~devsim.runtime.watch_stream.error_text`),
  the model's own faults, line settings that do not match the device's (``host settings 4800
  baud, 1 stop bit (data bits and parity not visible) (mismatch, device 9600 8N1)``), ports a
  plant could not open;
* 2 (default): also the banner (what each device expects: ``devsim: serving gms96 (main 9600 8E1,
  address 3); Ctrl-C to stop``), host connects and disconnects and the host's line settings;
* 3 (``-v``): also every event (``move_start``, ``move_end`` ...), declared faults switched, line
  faults started or ended, host commands the device refused (``sers refused 34: = oder ?
  erwartet — = or ? expected``) and every telegram both ways, decoded by the port's framing
  (:mod:`devsim.observe.traffic_log`).

A line: ``devsim: 12.300 sers connect host connected`` (device time, then
:func:`devsim.runtime.watch_stream.describe`).  A line repeated (same device, port and message
kind: a bad byte after another on the POSELESTA's V8) is written once, then counted: ``...
repeated 12345 times in the last 5 s`` every few seconds while it goes on
(:class:`~devsim.observe.repeats.RepeatLimiter`, on every port of every kind).  Built on :class:`~devsim.runtime.watch_stream.WatchStream`
without point sampling: a quiet simulator stays idle.
"""

from __future__ import annotations

import asyncio
from collections.abc import Callable, Hashable
from typing import Any

from devsim.core.console import warn

__all__ = ["DEFAULT_LEVEL", "attach_log", "banner", "expects", "level_of", "log_options", "repeat_key"]

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


def repeat_key(item: dict[str, Any]) -> Hashable:
    """What makes two log items repeats of each other: device, port and message kind (the event's
    name, the error's code, a line's moment and text: other host settings are news), not the time."""
    return (item.get("device"), item.get("port", "main"), item.get("type"), item.get("name"), item.get("code"),
            item.get("text"))


class _Repeats:
    """Counts written every :data:`~devsim.observe.repeats.WINDOW` / 5 seconds on the loop's timer,
    armed only while the limiter holds a count to write (an idle simulator, and one whose log
    lines do not repeat, has no timer for its log: a timer in the loop costs every wake-up)."""

    def __init__(self, limiter: Any, out: Callable[[str], None]) -> None:
        self.limiter, self.out = limiter, out
        self._handle: asyncio.TimerHandle | None = None
        try:
            self._loop: asyncio.AbstractEventLoop | None = asyncio.get_running_loop()
        except RuntimeError:
            self._loop = None  # (no loop: a count is written with the next line of its kind)

    def arm(self) -> None:
        """A repeat was counted: the count is due when its window ends."""
        if self._handle is None and self._loop is not None:
            self._handle = self._loop.call_later(self.limiter.window / 5, self._tick)

    def _tick(self) -> None:
        self._handle = None
        for text in self.limiter.due():
            self.out(text)
        if self.limiter.pending:
            self.arm()

    def stop(self) -> None:
        if self._handle is not None:
            self._handle.cancel()
            self._handle = None
        for text in self.limiter.flush():
            self.out(text)


def attach_log(runtime: Any, level: int, write: Callable[[str], None] | None = None,
               clock: Callable[[], float] | None = None) -> list[Any]:
    """Log what happens to every device of ``runtime`` at ``level`` (run in the loop thread);
    returns the streams (``stop()`` ends them).  ``write`` defaults to a flushed stderr line;
    ``clock`` (seconds, default the monotonic wall clock) times the windows of repeated lines."""
    if level <= 0:
        return []
    from devsim.observe.repeats import RepeatLimiter
    from devsim.runtime.watch_stream import WatchStream, describe

    out = write or warn
    limiter = RepeatLimiter() if clock is None else RepeatLimiter(clock=clock)

    def send(item: dict[str, Any]) -> None:
        if _level(item) <= level:
            key = repeat_key(item)
            if limiter.counted(key):
                repeats.arm()
                return  # a repeat in its window (noise: most errors): no text made
            lines = limiter.offer(key, f"devsim: {describe(item)}")
            for text in lines:
                out(text)
            if not lines:
                repeats.arm()  # (a repeat after all: offer counted it)

    repeats = _Repeats(limiter, out)
    streams: list[Any] = [repeats]
    for device in runtime.devices.values():
        stream = WatchStream(runtime, device, send, values=False, refused=_level({"type": "refused"}) <= level)
        stream.start()
        streams.append(stream)
    if level >= 3:
        from devsim.observe.traffic_log import watch_traffic

        watch_traffic(runtime, out)
    return streams


def expects(runtime: Any, device: Any) -> str:
    """What the host must set to talk to ``device``: each serial port's line settings (a port
    with a network default has none) and the device's ``address`` where it has one, e.g.
    ``main 9600 8E1, address 3``."""
    from devsim.runtime.process import port_key

    parts = []
    for spec in device.ports:
        line = runtime.lines.get(port_key(device.name, spec.name))
        if line is not None and spec.default is None:
            parts.append(f"{spec.name} {line.device_settings.describe()}")
    if any(point.name == "address" and point.readable for point in device.points):
        parts.append(f"address {device.read('address')}")
    return ", ".join(parts)


def banner(runtime: Any, devices: list[Any]) -> str:
    """``devsim: serving gms96 (main 9600 8E1, address 3); Ctrl-C to stop``."""
    names = ", ".join(f"{device.name} ({shown})" if (shown := expects(runtime, device)) else device.name
                      for device in devices)
    return f"devsim: serving {names}; Ctrl-C to stop"


def log_options(command: Callable[..., Any]) -> Callable[..., Any]:
    """``-v``/``--verbose`` and ``-q``/``--quiet`` (both countable) for a command."""
    import click  # (here: `devsim run` reads the level without click, devsim.cli.quick)

    command = click.option("-q", "--quiet", count=True,
                           help="Log less to stderr (-q: warnings and errors only; -qq: nothing but fatal errors)."
                           )(command)
    return click.option("-v", "--verbose", count=True,
                        help="Log more to stderr (default: what each device expects, connects, disconnects, "
                             "mismatches, errors; -v: also every event, refused command and telegram, decoded)."
                        )(command)
