"""The PCD4.H3 test helpers: a PCD with H3 modules on a real pty, reached over S-Bus in serial
data mode as a host would (spec pcd4h3.md §9.2), in virtual time."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import serial

from devsim.devices.pcd4h3.model import Pcd4
from devsim.devices.pcd4h3.sbus import FS, crc16, stuff, unstuff

__all__ = ["EXAMPLE", "Station", "flag", "hexbytes", "load", "reg", "run"]

#: The manual's example installation (§4.1, §9.1 a): FMAH3 48, BAR = BAF = 200, one axis;
#: answers at once (the 2 ms response delay would need the virtual clock advanced).
EXAMPLE: dict[str, Any] = {"h3def": {"fmah3": 48, "bar": 200, "baf": 200, "mna": 1}, "response_delay_ms": 0}


def hexbytes(text: str) -> bytes:
    return bytes.fromhex(text.replace(" ", ""))


class Station:
    """A host on the S-Bus pty of a ``devsim_device`` PCD."""

    def __init__(self, sim: Any, port: str = "sbus") -> None:
        self.sim = sim
        self.serial = serial.serial_for_url(sim.port_url(port), baudrate=9600, timeout=2)

    def close(self) -> None:
        self.serial.close()

    def send_raw(self, telegram: bytes) -> None:
        """A request as the spec writes it (raw, before stuffing)."""
        self.serial.write(stuff(telegram))

    def receive(self, data_bytes: int | None) -> bytes:
        """One telegram back, unstuffed: a response with ``data_bytes`` of data, or (None) an
        ACK/NAK."""
        wire = bytearray()
        want = 2 + (2 if data_bytes is None else data_bytes) + 2
        while True:
            chunk = self.serial.read(1)
            if not chunk:
                raise TimeoutError(f"no complete answer; got {wire.hex(' ')}")
            wire += chunk
            raw = unstuff(bytes(wire)) if not wire.endswith(b"\xc5") else None
            if raw is not None and len(raw) >= want:
                return raw

    def request(self, telegram: bytes, data_bytes: int | None = None) -> bytes:
        self.send_raw(telegram)
        return self.receive(data_bytes)

    def call(self, command: int, parameters: bytes = b"", data_bytes: int | None = None, station: int = 1) -> bytes:
        """A request built here (CRC added); returns the reply's data (or its ACK/NAK code)."""
        body = bytes((FS, 0, station, command)) + parameters
        raw = self.request(body + crc16(body).to_bytes(2, "big"), data_bytes)
        assert crc16(raw[:-2]) == int.from_bytes(raw[-2:], "big")
        return raw[2:-2]

    def write_registers(self, address: int, *values: int) -> bytes:
        data = b"".join((v & 0xFFFF_FFFF).to_bytes(4, "big") for v in values)
        return self.call(0x0E, bytes((4 * len(values) + 1,)) + address.to_bytes(2, "big") + data)

    def read_registers(self, address: int, count: int = 1) -> list[int]:
        data = self.call(0x06, bytes((count - 1,)) + address.to_bytes(2, "big"), 4 * count)
        return [int.from_bytes(data[i : i + 4], "big", signed=True) for i in range(0, 4 * count, 4)]

    def write_flags(self, address: int, *bits: int) -> bytes:
        packed = bytearray((len(bits) + 7) // 8)
        for i, bit in enumerate(bits):
            packed[i // 8] |= (1 if bit else 0) << (i % 8)
        return self.call(0x0B, bytes((len(packed) + 2,)) + address.to_bytes(2, "big") + bytes((len(bits) - 1,)) + packed)

    def read_flags(self, address: int, count: int = 1, command: int = 0x02) -> list[int]:
        data = self.call(command, bytes((count - 1,)) + address.to_bytes(2, "big"), (count + 7) // 8)
        return [data[i // 8] >> (i % 8) & 1 for i in range(count)]


def reg(symbol: str, axis: int = 1, bar: int = 200) -> int:
    """A register's address in the example installation (§4.2)."""
    from devsim.devices.pcd4h3.layout import Layout

    return Layout(bar=bar, baf=bar, axes=2).register(axis, symbol)


def flag(symbol: str, axis: int = 1, baf: int = 200) -> int:
    from devsim.devices.pcd4h3.layout import Layout

    return Layout(bar=baf, baf=baf, axes=2).flag(axis, symbol)


def load(pcd: Station, axis: int = 1, **registers: int) -> None:
    """Write registers by symbol over S-Bus."""
    for symbol, value in registers.items():
        assert pcd.write_registers(reg(symbol, axis), value) == b"\x00\x00"


def run(pcd: Station, *functions: str, axis: int = 1, cycles: int = 1) -> None:
    """Set command flags over S-Bus, wait (virtual time) until AxHndlg has processed them, then
    let the PLC cycle ``cycles`` more times."""
    for symbol in functions:
        assert pcd.write_flags(flag(symbol, axis), 1) == b"\x00\x00"
    names = [f"axis.{axis}.{symbol}" for symbol in functions]
    assert pcd.sim.run_until(lambda d: not any(d.read(name) for name in names), 1.0), functions
    pcd.sim.advance(0.010 * cycles)


#: A step of a scripted run: what it does to the station at its moment.
Step = Callable[[Pcd4], None]


def keys(*inputs: int, value: int = 1) -> Step:
    """A step: the inputs set to ``value`` (the station caught up to now first), the PLC woken."""
    def act(pcd: Pcd4) -> None:
        pcd.catch_up()
        for n in inputs:
            pcd.inputs[n] = value
        pcd.wake()
    return act


def command(n: int, *flags: str, **registers: float) -> Step:
    """A step: registers of axis ``n`` loaded and flags set (caught up first), the PLC woken."""
    def act(pcd: Pcd4) -> None:
        pcd.catch_up()
        axis = pcd.axes[n - 1]
        for symbol, value in registers.items():
            axis.registers.load(symbol, value)
        for symbol in flags:
            axis.set_flag(symbol, 1)
        pcd.wake()
    return act


def blocked(n: int, active: bool) -> Step:
    """A step: axis ``n``'s motor blocked (or free again), its chip poked, the PLC woken."""
    def act(pcd: Pcd4) -> None:
        pcd.catch_up()
        pcd.drives[n - 1].motor.blocked = active
        pcd.drives[n - 1].poke()
        pcd.wake()
    return act
