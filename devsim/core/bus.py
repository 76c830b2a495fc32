"""RS-485 multidrop: several devices on one line.

The bus gives every device every byte (as on a real two-wire bus, each receiver sees all
traffic) and merges their outputs onto the one line.  Which device answers is the devices' own
business: each decides from its address whether a telegram is meant for it.  Because all
devices run in one event loop and answer synchronously from :meth:`feed`, their outputs never
interleave mid-telegram.
"""

from __future__ import annotations

from collections.abc import Sequence

from devsim.core.device import ByteSink, Device, SerialSettings

__all__ = ["Bus"]


class Bus:
    """Looks like one device to a line; fans input out and output in."""

    def __init__(self, devices: Sequence[Device]) -> None:
        if not devices:
            raise ValueError("a bus needs at least one device")
        self.devices = list(devices)
        self._write: ByteSink | None = None
        for device in self.devices:
            device.shared_line = len(self.devices) > 1
            device.attach(self._emit)

    def _emit(self, data: bytes) -> None:
        if self._write is not None and data:
            self._write(data)

    def attach(self, write: ByteSink | None) -> None:
        self._write = write

    def feed(self, data: bytes) -> None:
        for device in self.devices:
            device.feed(data)

    def host_disconnected(self) -> None:
        for device in self.devices:
            device.host_disconnected()

    @property
    def serial_settings(self) -> SerialSettings:
        return self.devices[0].serial_settings
