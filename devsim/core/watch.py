"""Watching a device's points for change, on the device clock: the one way a facade (CANopen
change-of-state TPDOs, MQTT, OPC UA) or a monitor learns that values moved.

A model announces protocol-level moments (``fault``, ``ready`` ...) but not every value it holds
changes through an announcement: an axis moves in closed form, a parameter is set from a serial
line.  :class:`PointWatch` therefore samples the names it watches every ``period`` seconds of
device time (virtual time in tests) and hands the ones whose values differ from the last sample
to its listener.  It runs where the device lives (the runtime's loop thread); a watch with no
period samples only when asked (:meth:`PointWatch.sample`), so an idle simulator stays idle.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from typing import Any

from devsim.core.device import Device
from devsim.core.points import UnknownName

__all__ = ["PointWatch", "readable_names"]

Changes = dict[str, Any]


def readable_names(device: Device) -> list[str]:
    """Every declared (non-family) name of ``device`` that can be read."""
    return [point.name for point in device.points if point.readable]


class PointWatch:
    """Sample ``names`` of ``device`` (default: every readable declared name) every ``period``
    seconds of device time (None: only on :meth:`sample`) and call ``on_change(changes)`` with
    ``{name: value}`` of those that changed since the previous sample.  The first sample reports
    every name.  A name whose read fails (a family member that vanished, a value the device
    cannot give in its state) is reported as None."""

    def __init__(
        self,
        device: Device,
        on_change: Callable[[Changes], None],
        *,
        names: Iterable[str] | None = None,
        period: float | None = None,
    ) -> None:
        if period is not None and not period > 0:
            raise ValueError("a watch period is a positive number of seconds")
        self.device = device
        self.names = list(names) if names is not None else readable_names(device)
        self.period = period
        self.on_change = on_change
        self.last: Changes = {}
        self._timer: Any = None
        self._running = False
        # declared points' getters, looked up once (a sample reads every name: a SERS has 247);
        # other names (a family member, an alias) go through Device.read each time
        declared = device.points.points
        self._getters = {name: point.get for name in self.names
                         if (point := declared.get(name)) is not None and point.get is not None}

    def values(self, names: Iterable[str] | None = None) -> Changes:
        """The present values of the watched names (or of ``names``)."""
        values: Changes = {}
        model = self.device.model
        getters = self._getters
        for name in self.names if names is None else names:
            get = getters.get(name)
            try:
                values[name] = get(model) if get is not None else self.device.read(name)
            except (UnknownName, ValueError, LookupError, ArithmeticError):
                values[name] = None
        return values

    def sample(self, names: Iterable[str] | None = None) -> Changes:
        """Read now (every watched name, or only ``names``: a point just set); call the listener
        with what changed (if anything) and return it."""
        values = self.values(names)
        changes = {name: value for name, value in values.items()
                   if name not in self.last or self.last[name] != value}
        if names is None:
            self.last = values
        else:
            self.last.update(values)
        if changes:
            self.on_change(changes)
        return changes

    def start(self) -> None:
        """The first sample now, then one every period (if there is one)."""
        self._running = True
        self.sample()
        self._arm()

    def _arm(self) -> None:
        if self._running and self.period is not None:
            self._timer = self.device.clock.call_later(self.period, self._tick)

    def _tick(self) -> None:
        self._timer = None
        if self._running:
            self.sample()
            self._arm()

    def stop(self) -> None:
        self._running = False
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None
