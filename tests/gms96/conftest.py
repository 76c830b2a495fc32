"""GMS96 cards on a real pty, on virtual time, with pyserial (and the Gms96Client) as the host."""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator
from typing import Any

import pytest
import serial

from devsim.devices.gms96 import codec
from devsim.devices.gms96.client import Gms96Client
from devsim.runtime import Runtime
from devsim.transports.pty import PtyTransport
from tests.support.process import wait_until


def h(text: str) -> bytes:
    return bytes.fromhex(text)


class Host:
    """Raw host: write frames, read the card's reply as the codec frames it."""

    def __init__(self, port: str, baudrate: int = 9600, received: Callable[[], int] | None = None) -> None:
        self.port = serial.Serial(port, baudrate=baudrate, parity="E", timeout=0.02)
        self.decoder = codec.FrameDecoder(short_extension=codec.short_extension_host, accept_single=True)
        self.received = received  # the bytes the card's line has read so far (a Plant's host)

    def send(self, data: bytes | str) -> None:
        self.port.write(h(data) if isinstance(data, str) else data)
        self.port.flush()

    def reply(self, timeout: float = 1.0) -> bytes:
        """The next complete reply frame's bytes, or b"" after ``timeout`` seconds of silence."""
        deadline = time.monotonic() + timeout
        buf = bytearray()
        while time.monotonic() < deadline:
            chunk = self.port.read(64)
            if not chunk:
                continue
            buf += chunk
            frames = [f for f in self.decoder.feed(chunk, time.monotonic()) if not isinstance(f, codec.FrameError)]
            if frames:
                return bytes(buf)
        self.decoder.reset()
        return bytes(buf)

    def ask(self, data: str, timeout: float = 1.0) -> str:
        self.send(data)
        return self.reply(timeout).hex(" ").upper()

    def silent(self, data: str, wait: float = 0.15) -> bool:
        """Send ``data``; True if nothing comes back within ``wait`` seconds after the card has
        read it (a Plant's host): on a loaded machine a silence also holds before the card read
        the bytes, and a step of virtual time taken then came before them (R4's idle, a boot)."""
        before = self.received() if self.received is not None else 0
        self.send(data)
        if self.received is not None:
            read = self.received
            wait_until(lambda: read() >= before + len(h(data)), "read of the bytes by the card", step=0.001)
        return self.reply(wait) == b""

    def close(self) -> None:
        self.port.close()


class Plant:
    def __init__(self, runtime: Runtime, names: list[str], transport: PtyTransport) -> None:
        self.runtime = runtime
        self.names = names
        self.transport = transport
        self.host = Host(transport.address, received=self.bytes_in)
        self._ports: list[serial.Serial] = []

    @property
    def name(self) -> str:
        return self.names[0]

    def device(self, name: str | None = None) -> Any:
        """The card's model (axis, indexer, executor ...): the device kit's ``.model``."""
        return self.runtime.device(name or self.name).model

    def face(self, name: str | None = None) -> Any:
        """The card's FT1.2 face (the link)."""
        return self.runtime.device(name or self.name).face()

    def read(self, name: str, device: str | None = None) -> Any:
        return self.runtime.read(device or self.name, name)

    def set(self, name: str, value: Any, device: str | None = None) -> None:
        self.runtime.set(device or self.name, name, value)

    def advance(self, seconds: float) -> None:
        self.runtime.advance(seconds)

    def now(self) -> float:
        return self.runtime.now()

    def client(self, address: int = 3, e_version: bool = False) -> Gms96Client:
        # a second handle on the pty (re-configuring an 8E1 pty handle fails with EINVAL)
        port = serial.Serial(self.transport.address, baudrate=9600, timeout=0.02)
        self._ports.append(port)
        # (an answer comes at once; the bound only ends a wait for one that never comes, so it
        # is wide enough for a loaded machine: 0.5 s once timed out in a full CI run)
        return Gms96Client(port, address, e_version=e_version, timeout=2.0)

    def wait_received(self, count: int, timeout: float = 5.0) -> None:
        wait_until(lambda: self.bytes_in() >= count, "receipt of the bytes by the device", timeout, step=0.001)

    def bytes_in(self) -> int:
        line = self.runtime.lines[self.name]
        return int(self.runtime.call(lambda: line.status()["bytes_in"]))

    def run_until(self, predicate: Any, timeout: float = 60.0, device: str | None = None) -> float:
        dev = self.device(device)
        start = self.now()
        assert self.runtime.run_until(lambda: predicate(dev), timeout), "condition not reached in time"
        return self.now() - start

    def idle(self, timeout: float = 60.0) -> float:
        return self.run_until(lambda d: not d.busy() and not d.axis.moving, timeout)


def start_plant(configs: list[dict[str, Any]], state_dir: Any = None, boot: bool = True) -> Plant:
    runtime = Runtime(virtual=True, state_dir=state_dir).start()
    names, devices = [], []
    for config in configs:
        address = config.get("dil", {}).get("address", 3)
        name = "gms96" if len(configs) == 1 else f"gms96_{address}"
        devices.append(runtime.add_device("gms96", name, config))
        names.append(name)
    transport = PtyTransport()
    runtime.serve_sync(devices if len(devices) > 1 else devices[0], transport)
    if boot:
        runtime.advance(0.6)  # boot time (spec §4.1.2, 500 ms)
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
        for port in plant._ports:
            port.close()
        plant.runtime.stop()


@pytest.fixture
def card(plant_factory: Any) -> Plant:
    """One card at address 3, S-version, 9600 Bd, booted (cam -20000..-15000, index every 4096)."""
    plant: Plant = plant_factory({})
    return plant


@pytest.fixture
def referenced(card: Plant) -> Plant:
    """The card after a successful Q0 (IDXOFF = 0, counter 0 at the index mark)."""
    assert card.host.ask("68 06 06 68 53 03 51 00 00 00 A7 16") == "E5"
    card.idle()
    assert card.read("idxoff") is False
    return card
