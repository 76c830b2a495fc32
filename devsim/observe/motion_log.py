"""The motion log: every axis of a run as CSV rows, at its events and on a time grid.

``devsim run/up/scenario run --motion-log FILE.csv [--motion-resolution SECONDS]`` writes one
row per axis

    time,device,axis,setpoint,position,velocity,following_error,event,kind

* at the **exact time of each event** the model records (``move_start``, ``move_end``, errors …,
  :meth:`devsim.core.model.Model.record_event`) and of each declared fault switched on or off
  (``fault:blocked_axis=on``), with the event's name in ``event``;
* every ``resolution`` seconds of **device time** (virtual time in tests), through a
  :class:`~devsim.core.watch.PointWatch`, for the axes whose values changed since the previous
  sample.  An axis at rest writes nothing; when it starts to change again, the last resting values
  are written once more at the previous sample time, so that a plot draws the rest as a flat line.
  A last row per axis is written when the log closes.

``kind`` is the device's kind (``sers``, ``gms96`` …): what ``devsim plot`` takes the units of the
columns from (the kind's declared points, ``axis.velocity`` in ``inc/s``).

Times and values are written exactly (``repr`` of the float): a time in the log is a time of the
device clock, the same clock the wire traces (``--trace``) use.

The axes are derived from the declared points, generically, by a table of name patterns
(:data:`AXIS_PATTERN`, :data:`COLUMNS`): every readable numeric ``axis.position`` or
``axis.<id>.position`` is an axis, and its set-point, velocity and following error are the
points of the same prefix that exist (a stepper has no following error, a kind without a
profile generator no set-point: the cell stays empty).  Every kind declares its axes this way
(the drive actions of :attr:`devsim.core.device.Device.drive` read the same values for one axis).

Nothing here samples unless a log is started: an idle simulator without ``--motion-log`` keeps no
timer.  Everything runs in the runtime's loop thread.
"""

from __future__ import annotations

import csv
import math
import re
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any, TextIO

from devsim.core.device import Device
from devsim.core.watch import PointWatch
from devsim.transports.trace import TraceFile

__all__ = [
    "AXIS_PATTERN",
    "COLUMNS",
    "HEADER",
    "MotionLog",
    "axis_columns",
    "motion_log_problem",
    "start_motion_log",
]

#: The CSV header of a motion log.
HEADER = ("time", "device", "axis", "setpoint", "position", "velocity", "following_error", "event", "kind")

#: A point that makes an axis: ``axis.position`` (prefix ``axis``), ``axis.x.position``, ``axis.1.position``.
AXIS_PATTERN = re.compile(r"^(axis(?:\.[A-Za-z0-9_]+)?)\.position$")

#: Column → the point names that give it, tried in order (``{axis}`` is the axis prefix).
COLUMNS: dict[str, tuple[str, ...]] = {
    "setpoint": ("{axis}.setpoint", "{axis}.set_position", "{axis}.target"),
    "position": ("{axis}.position",),
    "velocity": ("{axis}.velocity",),
    "following_error": ("{axis}.following_error",),
}

#: The resolutions a log accepts (seconds of device time).
MIN_RESOLUTION = 1e-4
MAX_RESOLUTION = 3600.0

_NUMERIC = ("int", "float")


def motion_log_problem(resolution: float) -> str | None:
    """What is wrong with a ``--motion-resolution`` (None: nothing)."""
    if not (math.isfinite(resolution) and MIN_RESOLUTION <= resolution <= MAX_RESOLUTION):
        return f"--motion-resolution: expected {MIN_RESOLUTION:g} … {MAX_RESOLUTION:g} seconds, got {resolution:g}"
    return None


def axis_columns(device: Device) -> dict[str, dict[str, str]]:
    """``{axis prefix: {column: point name}}`` of the readable numeric points of ``device``."""
    points = {p.name: p for p in device.points if p.readable and p.type in _NUMERIC}
    axes: dict[str, dict[str, str]] = {}
    for name in points:
        match = AXIS_PATTERN.match(name)
        if match is None:
            continue
        axis = match.group(1)
        columns: dict[str, str] = {}
        for column, patterns in COLUMNS.items():
            for pattern in patterns:
                candidate = pattern.format(axis=axis)
                if candidate in points:
                    columns[column] = candidate
                    break
        axes[axis] = columns
    return axes


def _cell(value: Any) -> str:
    if value is None or isinstance(value, bool) or not isinstance(value, int | float):
        return ""
    return repr(float(value)) if isinstance(value, float) else str(value)


class _DeviceLog:
    """One device's axes in the log: a point watch on the grid, listeners for events and faults."""

    def __init__(self, log: MotionLog, device: Device, resolution: float) -> None:
        self.log = log
        self.device = device
        self.resolution = resolution
        self.axes = axis_columns(device)
        names = [name for columns in self.axes.values() for name in columns.values()]
        # sampled on an exact grid (origin + k · resolution) of the device clock, not by the
        # watch's own period (whose sum of floats drifts off the grid)
        self.watch = PointWatch(device, self._changed, names=names)
        self._origin = 0.0
        self._ticks = 0
        self._tick_timer: Any = None
        self.last: dict[str, tuple[str, ...]] = {}  # axis → the cells of its last row
        self.last_time: dict[str, float] = {}  # axis → the time of its last row
        self._undo: list[Callable[[], None]] = []

    # -- reading -------------------------------------------------------------------------------
    def _cells(self, axis: str, values: dict[str, Any]) -> tuple[str, ...]:
        columns = self.axes[axis]
        cells = {column: _cell(values.get(name)) for column, name in columns.items()}
        return tuple(cells.get(column, "") for column in HEADER[3:7])

    def _row(self, when: float, axis: str, cells: tuple[str, ...], event: str = "") -> None:
        self.log.write((repr(float(when)), self.device.name, axis, *cells, event, self.device.kind))
        self.last[axis] = cells
        self.last_time[axis] = when

    # -- the grid --------------------------------------------------------------------------------
    def start(self) -> None:
        if not self.axes:  # nothing moves: no timer either
            return
        model = self.device.model
        self._undo.append(model.listen("recorded", self._event))
        self._undo.append(model.listen("fault_switched", self._fault))
        self._origin = self.device.clock.now()
        self.watch.start()
        self._arm()

    def _arm(self) -> None:
        clock = self.device.clock
        due = math.floor((clock.now() - self._origin) / self.resolution + 1e-9) + 1
        self._ticks = max(self._ticks + 1, due)  # a stalled loop skips samples, never bunches them
        self._tick_timer = clock.call_at(self._origin + self._ticks * self.resolution, self._tick)

    def _tick(self) -> None:
        self._tick_timer = None
        self.watch.sample()
        self._arm()

    def _changed(self, changes: dict[str, Any]) -> None:
        now = self.device.clock.now()
        values = self.watch.last
        for axis, columns in self.axes.items():
            if not any(name in changes for name in columns.values()):
                continue
            cells = self._cells(axis, values)
            held = now - self.resolution
            if axis in self.last and held > self.last_time[axis] + self.resolution / 2:
                self._row(held, axis, self.last[axis])  # it rested until the previous sample
            self._row(now, axis, cells)
        self.log.flush()

    # -- events ----------------------------------------------------------------------------------
    def _event(self, when: float, name: str) -> None:
        # read at once: in real time a later read would be later than the event's time
        if self.log.closed:
            return
        values = self.watch.values()
        for axis in self.axes:
            self._row(when, axis, self._cells(axis, values), name)
        self.log.flush()

    def _fault(self, kind: str, active: bool) -> None:
        self._event(self.device.clock.now(), f"fault:{kind}={'on' if active else 'off'}")

    def close(self) -> None:
        self.watch.stop()
        if self._tick_timer is not None:
            self._tick_timer.cancel()
            self._tick_timer = None
        for undo in self._undo:
            undo()
        now = self.device.clock.now()
        values = self.watch.values()
        for axis in self.axes:
            if self.last_time.get(axis, -math.inf) < now:
                self._row(now, axis, self._cells(axis, values))


class MotionLog:
    """A motion log written to ``path`` (refused through a symlink, like a trace) or to an open
    text stream; :meth:`add` a device, :meth:`close` at the end (writes the last rows)."""

    def __init__(self, target: str | Path | TextIO, resolution: float = 0.01) -> None:
        problem = motion_log_problem(resolution)
        if problem is not None:
            raise ValueError(problem)
        self.resolution = resolution
        if isinstance(target, str | Path):
            self.path: str | None = str(target)
            self._file: TextIO | TraceFile = TraceFile(target, encoding="utf-8", newline="", at_once=False,
                                                               what="motion log")
        else:
            self.path = None
            self._file = target
        self._writer = csv.writer(self._file, lineterminator="\n")
        self._writer.writerow(HEADER)
        self._devices: list[_DeviceLog] = []
        self.closed = False

    def add(self, device: Device) -> None:
        """Log ``device``'s axes from now on (call in the runtime's loop thread)."""
        entry = _DeviceLog(self, device, self.resolution)
        self._devices.append(entry)
        entry.start()

    def write(self, row: Sequence[str]) -> None:
        if not self.closed:
            self._writer.writerow(row)

    def flush(self) -> None:
        if not self.closed:
            self._file.flush()

    def close(self) -> None:
        """Stop sampling, write each axis's last row and close the file (idempotent)."""
        if self.closed:
            return
        for entry in self._devices:
            entry.close()
        self._file.flush()
        self.closed = True
        if self.path is not None:
            self._file.close()


def start_motion_log(runtime: Any, devices: Sequence[Device], path: str | Path, resolution: float = 0.01) -> MotionLog:
    """Log ``devices`` of ``runtime`` (call in its loop thread) to ``path``; the log is closed
    with the runtime."""
    log = MotionLog(path, resolution)
    for device in devices:
        log.add(device)

    async def close() -> None:
        log.close()

    runtime.add_closer(close)
    return log
