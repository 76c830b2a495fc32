"""``devsim record``: sit between a host and a device and write down both directions.

The host gets a new port of its own – a pty (:class:`~devsim.transports.pty.PtyTransport`,
optionally with a stable link) or a raw TCP port (:class:`~devsim.transports.tcp.TcpTransport`)
– and the recorder forwards everything to the device's port, opened with pyserial's
``serial_for_url`` (a device path such as a devsim pty or ``/dev/ttyUSB0``, ``socket://HOST:PORT``,
``rfc2217://HOST:PORT``), and the device's bytes back.  Each chunk goes to the session file
(:mod:`devsim.observe.replay.session`) with its time and, where the kind's codec knows the protocol,
decoded.  When the host changes its line settings on the pty (baud rate, stop bits), the
recorder applies them to the device's port and writes a ``settings`` line.

The device's port is read in a thread of its own (pyserial blocks); every chunk is handed to
the event loop, which stamps and writes it, so the file holds the chunks in the order they
passed the recorder.
"""

from __future__ import annotations

import asyncio
import threading
import time
from collections.abc import Callable
from typing import Any

import msgspec
import serial

from devsim.core.console import say, stop_on_signals, warn
from devsim.core.device import SerialSettings
from devsim.observe.replay.session import SessionWriter

__all__ = ["RecordPlan", "record_session"]


class RecordPlan(msgspec.Struct):
    device_url: str
    out: str
    kind: str | None
    port_name: str
    settings: SerialSettings
    tcp: tuple[str, int] | None = None  # host side on TCP instead of a pty
    link: str | None = None


class _Recorder:
    """The host transport's endpoint: host bytes to the device, device bytes to the host, all
    of them to the session file."""

    def __init__(self, device: serial.SerialBase, writer: SessionWriter, settings: SerialSettings,
                 done: asyncio.Event) -> None:
        self.device = device
        self.done = done
        self.writer = writer
        self.serial_settings = settings  # the pty is preset with them
        self._to_host: Callable[[bytes], None] | None = None
        self._t0 = time.monotonic()
        self.failed: str | None = None

    def now(self) -> float:
        return time.monotonic() - self._t0

    # -- Endpoint ---------------------------------------------------------------------------
    def attach(self, write: Callable[[bytes], None] | None) -> None:
        self._to_host = write

    def feed(self, data: bytes) -> None:
        self.writer.chunk(self.now(), "host", data)
        try:
            self.device.write(data)
        except (serial.SerialException, OSError) as exc:
            self.failed = f"record: cannot write to the device: {exc}"
            self.done.set()

    def host_settings(self, settings: SerialSettings) -> None:
        self.writer.settings(self.now(), settings)
        try:
            self.device.apply_settings({"baudrate": settings.baudrate, "bytesize": settings.bytesize,
                                        "parity": settings.parity, "stopbits": settings.stopbits})
        except (serial.SerialException, OSError, ValueError) as exc:
            warn(f"record: the host's line settings {settings.describe()} cannot be set on the device's port: {exc}")

    def host_disconnected(self) -> None:
        pass

    # -- device side ------------------------------------------------------------------------
    def from_device(self, data: bytes) -> None:
        self.writer.chunk(self.now(), "device", data)
        if self._to_host is not None:
            self._to_host(data)


def _pump(device: serial.SerialBase, loop: asyncio.AbstractEventLoop, recorder: _Recorder,
          stop: threading.Event, done: asyncio.Event) -> None:
    """Read the device's port until ``stop``; hand each chunk to the loop."""
    try:
        while not stop.is_set():
            data = device.read(max(1, device.in_waiting))
            if data:
                loop.call_soon_threadsafe(recorder.from_device, data)
    except (serial.SerialException, OSError, TypeError) as exc:  # TypeError: pyserial on a closed port
        if not stop.is_set():
            recorder.failed = f"record: the device's port failed: {exc}"
            loop.call_soon_threadsafe(done.set)


def _open_device(plan: RecordPlan) -> serial.SerialBase:
    settings = plan.settings
    return serial.serial_for_url(plan.device_url, baudrate=settings.baudrate, bytesize=settings.bytesize,
                                 parity=settings.parity, stopbits=settings.stopbits, timeout=0.05)


class HostPortError(Exception):
    """The host's pty or TCP port could not be opened."""


async def record_session(plan: RecordPlan) -> int:
    """Record until SIGINT/SIGTERM/SIGHUP (or the device's port fails); returns 0, or 1 if the device's
    port could not be opened or failed (said on stderr).  Raises :class:`HostPortError` if the
    host's port cannot be opened, :class:`OSError` if the session file cannot be written."""
    try:
        device = _open_device(plan)
    except (serial.SerialException, OSError, ValueError) as exc:
        warn(f"Error: cannot open the device port {plan.device_url}: {exc}")
        return 1
    loop = asyncio.get_running_loop()
    done = asyncio.Event()
    unsignal = stop_on_signals(loop, done.set)
    writer = SessionWriter(plan.out, kind=plan.kind, port=plan.port_name, device=plan.device_url,
                           settings=plan.settings)
    recorder = _Recorder(device, writer, plan.settings, done)
    transport: Any
    if plan.tcp is not None:
        from devsim.transports.tcp import TcpTransport

        transport = TcpTransport(host=plan.tcp[0], port=plan.tcp[1])
    else:
        from devsim.transports.pty import PtyTransport

        transport = PtyTransport(link=plan.link)
    stop = threading.Event()
    pump: threading.Thread | None = None
    try:
        try:
            await transport.start(recorder)
        except OSError as exc:
            raise HostPortError(f"cannot open the host's port: {exc}") from None
        pump = threading.Thread(target=_pump, args=(device, loop, recorder, stop, done), name="devsim-record",
                                daemon=True)
        pump.start()
        if plan.tcp is not None:
            say(f"record: tcp {transport.url}")
        else:
            say(f"record: pty {transport.address}")
            if plan.link:
                say(f"record: link {plan.link}")
        say(f"record: device {plan.device_url}")
        say(f"record: out {plan.out}")
        await done.wait()
    finally:
        stop.set()
        await transport.close()
        if pump is not None:
            await asyncio.to_thread(pump.join, 2)
        device.close()
        writer.close()
        unsignal()
    if recorder.failed:
        warn(recorder.failed)
        return 1
    warn(f"record: {writer.chunks} chunks in {plan.out}")
    return 0
