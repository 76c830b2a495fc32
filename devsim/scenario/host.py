"""The scripted host of a scenario: the far end of a port, as host software would hold it.

A :class:`HostPort` opens the real pty (raw, at the device's line settings), the TCP socket, the
RFC 2217 connection or a UDP socket (one datagram per ``send``) of a plant port, keeps everything
it receives, and sends bytes.  It runs in the runtime's event loop, next to the devices, so that
the scenario runner can wait for bytes without threads (RFC 2217 uses pyserial's client and one
reader thread).
"""

from __future__ import annotations

import asyncio
import contextlib
import os
import termios
import threading
import tty
from typing import Any

from devsim.core.device import SerialSettings

__all__ = ["HostPort", "open_host_port"]

_BAUDS = {
    rate: getattr(termios, f"B{rate}")
    for rate in (300, 600, 1200, 2400, 4800, 9600, 19200, 38400, 57600, 115200, 230400)
    if hasattr(termios, f"B{rate}")
}


class HostPort:
    """Received bytes (``received``, with a read position for expectations) and ``send``."""

    def __init__(self, name: str) -> None:
        self.name = name
        self.received = bytearray()
        self.position = 0  # start of what expectations have not consumed yet
        self.sent = 0
        self._arrived = asyncio.Event()

    # -- receiving ---------------------------------------------------------------------------
    def _on_data(self, data: bytes) -> None:
        if data:
            self.received += data
            self._arrived.set()

    @property
    def unread(self) -> bytes:
        return bytes(self.received[self.position :])

    def consume(self, upto: int) -> None:
        """Mark everything before absolute offset ``upto`` as read."""
        self.position = max(self.position, upto)

    async def wait_data(self, timeout: float) -> None:
        """Wait (real time) for the next bytes to arrive, at most ``timeout`` seconds."""
        self._arrived.clear()
        with contextlib.suppress(TimeoutError):
            await asyncio.wait_for(self._arrived.wait(), timeout)

    # -- the port ------------------------------------------------------------------------------
    async def open(self) -> None:
        raise NotImplementedError

    async def send(self, data: bytes) -> None:
        raise NotImplementedError

    async def close(self) -> None:
        raise NotImplementedError


class PtyHost(HostPort):
    """The slave side of a pty, raw, at the device's baud rate."""

    def __init__(self, name: str, path: str, settings: SerialSettings) -> None:
        super().__init__(name)
        self.path = path
        self.settings = settings
        self._fd: int | None = None

    async def open(self) -> None:
        fd = os.open(self.path, os.O_RDWR | os.O_NOCTTY | os.O_NONBLOCK)
        attrs = termios.tcgetattr(fd)
        tty.setraw(fd)
        attrs = termios.tcgetattr(fd)
        speed = _BAUDS.get(self.settings.baudrate)
        if speed is not None:
            attrs[4] = attrs[5] = speed
        termios.tcsetattr(fd, termios.TCSANOW, attrs)
        self._fd = fd
        asyncio.get_running_loop().add_reader(fd, self._readable)

    def _readable(self) -> None:
        if self._fd is None:
            return
        try:
            data = os.read(self._fd, 65536)
        except (BlockingIOError, InterruptedError):
            return
        except OSError:
            return
        self._on_data(data)

    async def send(self, data: bytes) -> None:
        assert self._fd is not None
        view = memoryview(data)
        while view:
            try:
                written = os.write(self._fd, view)
            except BlockingIOError:
                await asyncio.sleep(0.001)
                continue
            view = view[written:]
        self.sent += len(data)

    async def close(self) -> None:
        if self._fd is not None:
            asyncio.get_running_loop().remove_reader(self._fd)
            os.close(self._fd)
            self._fd = None


class TcpHost(HostPort):
    """A raw TCP client (like host software talking to a serial device server)."""

    def __init__(self, name: str, host: str, port: int) -> None:
        super().__init__(name)
        self.host, self.port = host, port
        self._writer: asyncio.StreamWriter | None = None
        self._task: asyncio.Task[None] | None = None

    async def open(self) -> None:
        reader, self._writer = await asyncio.open_connection(self.host, self.port)

        async def pump() -> None:
            while data := await reader.read(65536):
                self._on_data(data)

        self._task = asyncio.get_running_loop().create_task(pump())

    async def send(self, data: bytes) -> None:
        assert self._writer is not None
        self._writer.write(data)
        await self._writer.drain()
        self.sent += len(data)

    async def close(self) -> None:
        if self._task is not None:
            self._task.cancel()
            with contextlib.suppress(asyncio.CancelledError, Exception):
                await self._task
        if self._writer is not None:
            self._writer.close()
            with contextlib.suppress(Exception):
                await self._writer.wait_closed()


class UdpHost(HostPort):
    """A UDP client: each ``send`` is one datagram; the datagrams that come back are appended to
    what was received (an expectation sees them back to back)."""

    def __init__(self, name: str, host: str, port: int) -> None:
        super().__init__(name)
        self.host, self.port = host.strip("[]"), port
        self._transport: asyncio.DatagramTransport | None = None

    async def open(self) -> None:
        host = self

        class Protocol(asyncio.DatagramProtocol):
            def datagram_received(self, data: bytes, addr: Any) -> None:
                host._on_data(data)

        loop = asyncio.get_running_loop()
        self._transport, _ = await loop.create_datagram_endpoint(Protocol, remote_addr=(self.host, self.port))

    async def send(self, data: bytes) -> None:
        assert self._transport is not None
        self._transport.sendto(data)
        self.sent += len(data)

    async def close(self) -> None:
        if self._transport is not None:
            self._transport.close()
            self._transport = None


class Rfc2217Host(HostPort):
    """pyserial's RFC 2217 client, read by one thread that hands bytes to the loop."""

    def __init__(self, name: str, url: str, settings: SerialSettings) -> None:
        super().__init__(name)
        self.url, self.settings = url, settings
        self._port: Any = None
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None

    async def open(self) -> None:
        import serial

        loop = asyncio.get_running_loop()
        self._port = await loop.run_in_executor(
            None, lambda: serial.serial_for_url(self.url, baudrate=self.settings.baudrate, timeout=0.05)
        )

        def reader() -> None:
            while not self._stop.is_set():
                try:
                    data = self._port.read(4096)
                except Exception:  # noqa: BLE001 - the port went away
                    return
                if data:
                    loop.call_soon_threadsafe(self._on_data, data)

        self._thread = threading.Thread(target=reader, name=f"rfc2217-host-{self.name}", daemon=True)
        self._thread.start()

    async def send(self, data: bytes) -> None:
        await asyncio.get_running_loop().run_in_executor(None, self._port.write, data)
        self.sent += len(data)

    async def close(self) -> None:
        self._stop.set()
        if self._thread is not None:
            await asyncio.get_running_loop().run_in_executor(None, self._thread.join, 2)
        if self._port is not None:
            self._port.close()


def open_host_port(name: str, kind: str, transport: Any, settings: SerialSettings) -> HostPort:
    """A host port (not yet opened) for a plant port served by ``transport``."""
    if kind == "pty":
        return PtyHost(name, str(transport.address), settings)
    host, _, port = str(transport.address).rpartition(":")
    if kind == "tcp":
        return TcpHost(name, host, int(port))
    if kind == "udp":
        return UdpHost(name, host, int(port))
    return Rfc2217Host(name, f"rfc2217://{host}:{port}", settings)
