"""RS-485 multidrop: several devices on one line.

The bus gives every device every byte (as on a real two-wire bus, each receiver sees all
traffic) and merges their outputs onto the one line.  What one device sends is also heard by
the others that listen to the line (``Device.hears_others``) – that is how a SERS master
(address 0) drives its slaves on the same line – but never by itself, and what a device that
does not talk to others (``Device.talks_to_others``: a SERS slave's echo, answer or ``@1POS=1``)
sends only by those that do (the master waiting for that answer): a slave's echo of a host's
line is no command for the other slaves (SERS manual §3.6.2: a master commands its slaves).
A device hears another's bytes through ``Port.hear`` (the face's ``hear``; by default what
the host sends), so a face can tell them from the host's.
Which device answers is the devices' own business: each decides from its address whether a
telegram is meant for it.

Bytes a device sends while another is still digesting input are queued and handed on once that
device has finished, so no device is ever fed re-entrantly; the order on the line is the order
in which they were sent.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Sequence

from devsim.core.changes import CHANGES
from devsim.core.device import ByteSink, Device, Port, SerialSettings

__all__ = ["Bus"]


class Bus:
    """Looks like one device to a line; fans input out and output in."""

    def __init__(self, devices: Sequence[Device | Port], port: str = "main") -> None:
        if not devices:
            raise ValueError("a bus needs at least one device")
        self.devices: list[Port] = [d.port(port) if isinstance(d, Device) else d for d in devices]
        self._write: ByteSink | None = None
        self._queue: deque[tuple[Port | None, bytes]] = deque()
        self._busy = False
        CHANGES.count += 1  # (a door: devsim.core.changes; the members' lines become shared)
        peers = tuple(self.devices)
        for member in self.devices:
            member.peers = peers
            member.attach(lambda data, source=member: self._emit(source, data))

    def _emit(self, source: Port, data: bytes) -> None:
        if not data:
            return
        if self._write is not None:
            self._write(data)
        if len(self.devices) > 1:
            self._queue.append((source, data))
            self._pump()

    def _pump(self) -> None:
        if self._busy:
            return  # the outer loop hands it on
        self._busy = True
        try:
            while self._queue:
                source, data = self._queue.popleft()
                talker = source is None or source.talks_to_others
                for device in self.devices:
                    if source is None:
                        device.feed(data)
                    elif device is not source and device.hears_others and (talker or device.talks_to_others):
                        device.hear(data)
        finally:
            self._busy = False

    def attach(self, write: ByteSink | None) -> None:
        self._write = write

    def feed(self, data: bytes) -> None:
        """Bytes from the host: every device hears them."""
        self._queue.append((None, data))
        self._pump()

    def host_disconnected(self) -> None:
        for device in self.devices:
            device.host_disconnected()

    @property
    def serial_settings(self) -> SerialSettings:
        return self.devices[0].serial_settings
