"""A SERS on a real pty, on virtual time, with pyserial as the host."""

from __future__ import annotations

import re
import time
from collections.abc import Iterator
from typing import Any

import pytest
import serial

from devsim.runtime import Runtime
from devsim.transports.pty import PtyTransport

ACK = re.compile(rb"\n(ok\d|pgm)\n\r|\n\*[^\n]*\n\r")


class Host:
    """Host software's view: a pyserial port plus helpers that read until the device's answer."""

    def __init__(self, port: str, baudrate: int = 9600) -> None:
        self.port = serial.Serial(port, baudrate=baudrate, timeout=2.0)

    def send(self, data: bytes | str) -> None:
        self.port.write(data.encode("latin-1") if isinstance(data, str) else data)
        self.port.flush()

    def read_exact(self, n: int) -> bytes:
        data = self.port.read(n)
        assert len(data) == n, f"expected {n} bytes, got {data!r}"
        return data

    def read_until_ack(self) -> bytes:
        """Everything up to and including the line's acknowledgement or error message."""
        buf = bytearray()
        while not ACK.search(buf):
            chunk = self.port.read(1)
            assert chunk, f"timed out waiting for an acknowledgement; got {bytes(buf)!r}"
            buf += chunk
            buf += self.port.read(self.port.in_waiting)
        return bytes(buf)

    def ask(self, line: str) -> bytes:
        self.send(line)
        return self.read_until_ack()

    def expect(self, expected: bytes) -> None:
        assert self.read_exact(len(expected)) == expected

    def close(self) -> None:
        self.port.close()


class Plant:
    """A runtime with SERS drives on one pty; ``host`` talks to them."""

    def __init__(self, runtime: Runtime, names: list[str], transport: PtyTransport) -> None:
        self.runtime = runtime
        self.names = names
        self.transport = transport
        self.host = Host(transport.address)

    @property
    def name(self) -> str:
        return self.names[0]

    def read(self, name: str, device: str | None = None) -> Any:
        return self.runtime.read(device or self.name, name)

    def set(self, name: str, value: Any, device: str | None = None) -> None:
        self.runtime.set(device or self.name, name, value)

    def advance(self, seconds: float) -> None:
        self.runtime.advance(seconds)

    def wait_received(self, count: int, timeout: float = 5.0) -> None:
        """Wait (in real time, polling) until the line has delivered ``count`` host bytes."""
        deadline = time.monotonic() + timeout
        line = self.runtime.lines[self.name]
        while self.runtime.call(lambda: line.status()["bytes_in"]) < count:
            assert time.monotonic() < deadline, "the device never received the bytes"
            time.sleep(0.001)

    def settle(self, device: str | None = None, timeout: float = 60.0) -> float:
        """Run virtual time until the drive stands still; returns the simulated time taken."""
        dev = self.runtime.device(device or self.name)
        start = self.runtime.now()
        assert self.runtime.run_until(lambda: dev.read("motion.kind") is None, timeout)
        return self.runtime.now() - start


def start_plant(configs: list[dict[str, Any]], state_dir: Any = None, boot: bool = True) -> Plant:
    runtime = Runtime(virtual=True, state_dir=state_dir).start()
    names = []
    devices = []
    for i, config in enumerate(configs):
        name = "sers" if len(configs) == 1 else f"sers{config.get('address', i + 1)}"
        device = runtime.add_device("sers", name, config)
        devices.append(device)
        names.append(name)
    transport = PtyTransport()
    runtime.serve_sync(devices if len(devices) > 1 else devices[0], transport)
    if boot:
        runtime.advance(2.0)  # display '-' for 2 s after power-on (§3.5)
    return Plant(runtime, names, transport)


@pytest.fixture
def plant_factory(tmp_path: Any) -> Iterator[Any]:
    plants: list[Plant] = []

    def make(*configs: dict[str, Any], state_dir: Any = None, boot: bool = True) -> Plant:
        plant = start_plant(list(configs) or [{}], state_dir=state_dir, boot=boot)
        plants.append(plant)
        return plant

    yield make
    for plant in plants:
        plant.host.close()
        plant.runtime.stop()


@pytest.fixture
def sers(plant_factory: Any) -> Plant:
    """One SERS at address 1, default configuration, booted."""
    plant: Plant = plant_factory({})
    return plant
