"""A small PG-side client for the IP247's programmer port: one AS511 transaction per call, over
anything with ``write(bytes)`` and ``read(n) -> bytes`` (a pyserial port at 9600 8E1 with a
timeout).  The device side is :mod:`devsim.devices.ip247.as511`; the services and their
parameter blocks are :mod:`devsim.devices.ip247.pg_profile` (spec ip247.md §3.5, §3.6)."""

from __future__ import annotations

from typing import Protocol

from devsim.devices.ip247.as511 import ACK, DLE, EOT, ETX, NAK, STX, dle_double

__all__ = ["As511Error", "PgClient"]


class Port(Protocol):
    def write(self, data: bytes) -> object: ...
    def read(self, size: int = 1) -> bytes: ...


class As511Error(IOError):
    """The device refused (DLE NAK), answered something else, or stayed silent."""


class PgClient:
    """The programmer's side of AS511 (the PG is the master)."""

    def __init__(self, port: Port) -> None:
        self.port = port

    def _read(self, count: int) -> bytes:
        data = b""
        while len(data) < count:
            piece = self.port.read(count - len(data))
            if not piece:
                raise As511Error(f"timeout after {data.hex(' ') or 'nothing'}")
            data += piece
        return data

    def _expect(self, expected: bytes, step: str) -> None:
        got = self._read(len(expected))
        if got != expected:
            if got == bytes((DLE,)):
                got += self._read(1)  # STX expected, a DLE came: DLE NAK?
            if got[:2] == bytes((DLE, NAK)):
                raise As511Error(f"{step}: refused (DLE NAK)")
            raise As511Error(f"{step}: expected {expected.hex(' ')}, got {got.hex(' ')}")

    def _block(self, end: int) -> bytes:
        """A DLE-doubled block up to DLE ``end``."""
        data = bytearray()
        while True:
            byte = self._read(1)[0]
            if byte != DLE:
                data.append(byte)
                continue
            following = self._read(1)[0]
            if following == DLE:
                data.append(DLE)
            elif following == end:
                return bytes(data)
            else:
                raise As511Error(f"a single DLE followed by {following:02x} in a block")

    def transaction(self, function: int, parameters: bytes, *, data_phase: bool = True) -> bytes | None:
        """Send one request (spec §3.5.2) and return the response data (None without a data
        phase)."""
        ack = bytes((DLE, ACK))
        self.port.write(bytes((STX,)))
        self._expect(ack, "request to send")
        self.port.write(bytes((function,)))
        self._expect(bytes((STX,)), f"function {function:02x}")
        self.port.write(ack)
        self._expect(bytes((0x16, DLE, ETX)), "accept")
        self.port.write(ack)
        self.port.write(dle_double(parameters) + bytes((DLE, EOT)))
        self._expect(ack, "parameters")
        self._expect(bytes((STX,)), "response")
        self.port.write(ack)
        data = None
        first = self._read(1)
        if data_phase and first != b"\x12":
            head = self._unescape_first(first)
            data = head + self._block(ETX)
            self.port.write(ack)
            self._expect(bytes((STX,)), "end")
            self.port.write(ack)
            first = self._read(1)
        if first + self._read(2) != bytes((0x12, DLE, ETX)):
            raise As511Error("end: expected 12 10 03")
        self.port.write(ack)
        return data

    def _unescape_first(self, first: bytes) -> bytes:
        if first[0] == DLE:  # a doubled DLE as the first data byte
            if self._read(1)[0] != DLE:
                raise As511Error("a single DLE at the start of the data")
        return first
