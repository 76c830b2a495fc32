"""Test helpers for the transport tests: a recording endpoint and a tiny echo device."""

from __future__ import annotations

import asyncio
from collections.abc import Callable

from devsim.core.device import SerialSettings


class Recorder:
    """An Endpoint that records everything and, with ``echo``, sends the host's bytes back."""

    def __init__(self, echo: bool = False) -> None:
        self.echo = echo
        self.data = bytearray()
        self.chunks: list[bytes] = []
        self.settings: list[SerialSettings] = []
        self.disconnects = 0
        self.write: Callable[[bytes], None] | None = None
        self._event = asyncio.Event()

    def attach(self, write: Callable[[bytes], None] | None) -> None:
        self.write = write
        self._event.set()

    def feed(self, data: bytes) -> None:
        self.data += data
        self.chunks.append(data)
        if self.echo and self.write is not None:
            self.write(data)
        self._event.set()

    def host_settings(self, settings: SerialSettings) -> None:
        self.settings.append(settings)
        self._event.set()

    def host_disconnected(self) -> None:
        self.disconnects += 1
        self._event.set()

    async def wait_for(self, predicate: Callable[[], bool], timeout: float = 3.0) -> None:
        """Wait (event-driven, no polling sleeps) until ``predicate()`` holds."""
        loop = asyncio.get_running_loop()
        deadline = loop.time() + timeout
        while not predicate():
            remaining = deadline - loop.time()
            if remaining <= 0:
                raise AssertionError("timed out waiting for the endpoint")
            self._event.clear()
            if predicate():
                break
            try:
                await asyncio.wait_for(self._event.wait(), remaining)
            except TimeoutError:
                pass


class EchoTarget:
    """A minimal device for a Line: records what it receives and echoes it."""

    def __init__(self, settings: SerialSettings | None = None, echo: bool = True) -> None:
        self.serial_settings = settings or SerialSettings()
        self.echo = echo
        self.received = bytearray()
        self.disconnects = 0
        self._write: Callable[[bytes], None] | None = None
        self.event = asyncio.Event()

    def attach(self, write: Callable[[bytes], None] | None) -> None:
        self._write = write

    def send(self, data: bytes) -> None:
        if self._write is not None:
            self._write(data)

    def feed(self, data: bytes) -> None:
        self.received += data
        self.event.set()
        if self.echo:
            self.send(data)

    def host_disconnected(self) -> None:
        self.disconnects += 1
