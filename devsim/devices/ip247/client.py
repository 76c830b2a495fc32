"""Small host-side clients for the IP247 (spec ip247.md §3.5–§3.7).

:class:`PgClient` is the programmer's side of the PG port: one AS511 transaction per call, over
anything with ``write(bytes)`` and ``read(n) -> bytes`` (a pyserial port at 9600 8E1 with a
timeout).  :class:`AgClient` is a PLC replacement's side of the "IP247-SIM/AG v1" endpoint: one
length-framed message per call over a TCP socket.  Both carry the services of
:mod:`devsim.devices.ip247.pg_profile` with the same helpers (:class:`Services`): ``operate``,
``observe``, ``read_record``, ``write_record``, ``delete_record``."""

from __future__ import annotations

import socket
import struct
from typing import Protocol

from devsim.devices.ip247.as511 import ACK, DLE, EOT, ETX, NAK, STX, dle_double
from devsim.devices.ip247.attributes import AgFramer, ag_frame
from devsim.devices.ip247.pg_profile import command_code, pack_words

__all__ = ["AgClient", "As511Error", "PgClient", "Services"]

class Port(Protocol):
    def write(self, data: bytes) -> object: ...
    def read(self, size: int = 1) -> bytes: ...


class As511Error(IOError):
    """The device refused (DLE NAK), answered something else, or stayed silent."""


class Services:
    """The profile's services over :meth:`transaction` (spec §3.6.3, §3.6.4); every answer is
    the response data: the 8-byte header (ack, page, BA, command, error, BTR, RMLD, MFKT) and
    what follows it."""

    def transaction(self, function: int, parameters: bytes) -> bytes | None:
        raise NotImplementedError

    def operate(self, page: int, ba: int, cmd: int | str, b: int = 0, w: int = 0, dd: int = 0) -> bytes:
        """An operator job: ``cmd`` 1 … 5 or Start, Stopp, Vorwärts, Rückwärts, Übernahme."""
        code = command_code(cmd)
        if code is None:
            raise ValueError(f"unknown command {cmd!r}")
        return self._call(0x61, struct.pack(">BBBBHI", page, ba, code, b & 0xFF, w & 0xFFFF, dd & 0xFFFF_FFFF))

    def observe(self, page: int) -> bytes:
        """Header, position and residual (int32), the four error bytes, last command, flags."""
        return self._call(0x62, bytes((page,)))

    def read_record(self, page: int, ba: int, db: int = 0, bcd: bool = False) -> bytes:
        return self._call(0x64, bytes((page, ba, db, int(bcd))))

    def write_record(self, page: int, ba: int, db: int, words: list[int], overwrite: bool = False) -> bytes:
        return self._call(0x63, bytes((page, ba, db, int(overwrite))) + pack_words(words))

    def delete_record(self, page: int, ba: int, db: int) -> bytes:
        return self._call(0x65, bytes((page, ba, db)))

    def _call(self, function: int, parameters: bytes) -> bytes:
        answer = self.transaction(function, parameters)
        if answer is None:
            raise As511Error("no response data")
        return answer


class AgClient(Services):
    """The PLC side (spec §3.7) on TCP: pages are absolute (S2 base page + 0 … 3), values are BCD
    where the axis's machine data say so."""

    def __init__(self, host: str, port: int, timeout: float = 5.0) -> None:
        self.socket = socket.create_connection((host, port), timeout=timeout)
        self._framer = AgFramer()

    def transaction(self, function: int, parameters: bytes) -> bytes:
        self.socket.sendall(ag_frame(function, parameters))
        while True:
            data = self.socket.recv(4096)
            if not data:
                raise As511Error("the endpoint closed the connection")
            messages = self._framer.feed(data)
            if messages:
                return messages[0][1]

    def close(self) -> None:
        self.socket.close()

    def __enter__(self) -> AgClient:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


class PgClient(Services):
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
