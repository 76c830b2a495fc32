"""A test kind with a network port: a serial echo port and an Ether-S-Bus-shaped UDP port.

Port ``serial`` (a pty unless told otherwise) echoes bytes.  Port ``ether`` declares the default
transport ``udp:PORT`` – PORT is 5050, the Ether-S-Bus port, unless the environment variable
``DEVSIM_TEST_ETHER_PORT`` names another one when this module is imported (tests give a free
port, since 5050 may be in use on the machine running them).  It answers a "read register(s)"
request (command 06h, attribute 0) with the registers' values – register 213 holds 1000, as in
the reference telegrams of the PCD4.H3 spec, any other five times its number; any other
datagram (garbage, a wrong CRC, another command) is counted and not answered.  The frame layout
(a 9-byte Ether-S-Bus header: length, version, protocol, sequence, attribute; then station,
command, count-1, address, and CRC-16 CCITT over everything before it) is only what Wireshark's
S-Bus dissector needs to decode it.  Register with
``DEVSIM_EXTRA_KINDS="etherbus=tests.support.etherbus:EtherBusDevice"``.
"""

from __future__ import annotations

import os
import struct
from typing import Any, ClassVar

from devsim.core.device import Device, Face
from devsim.core.kit import PortDef
from devsim.core.model import Model
from devsim.core.points import Point, PointTable

ETHER_PORT = int(os.environ.get("DEVSIM_TEST_ETHER_PORT", "5050"))
READ_REGISTER = 0x06


def crc16(data: bytes) -> int:
    """CRC-16 CCITT (polynomial 1021h, initial value 0), as S-Bus uses it."""
    crc = 0
    for byte in data:
        crc ^= byte << 8
        for _ in range(8):
            crc = ((crc << 1) ^ 0x1021) if crc & 0x8000 else crc << 1
            crc &= 0xFFFF
    return crc


def frame(sequence: int, attribute: int, body: bytes) -> bytes:
    """An Ether-S-Bus frame: header, ``body``, CRC."""
    length = 9 + len(body) + 2
    head = struct.pack(">IBBHB", length, 1, 0, sequence, attribute) + body
    return head + struct.pack(">H", crc16(head))


def read_request(sequence: int, station: int, register: int, count: int = 1) -> bytes:
    """A "read register(s)" request."""
    return frame(sequence, 0, struct.pack(">BBBH", station, READ_REGISTER, count - 1, register))


def register_value(register: int) -> int:
    return 1000 if register == 213 else register * 5


class EtherBusModel(Model):
    def __init__(self, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        self.answered = 0
        self.ignored = 0


class EchoFace(Face):
    """Port serial: echoes."""

    def feed(self, data: bytes) -> None:
        self.send(data)


class EtherFace(Face):
    """Port ether: one request per datagram, one answer per request."""

    model: EtherBusModel

    def feed(self, data: bytes) -> None:
        answer = self._answer(data)
        if answer is None:
            self.model.ignored += 1
            return
        self.model.answered += 1
        self.send(answer)

    @staticmethod
    def _answer(data: bytes) -> bytes | None:
        if len(data) < 16 or struct.unpack(">I", data[:4])[0] != len(data):
            return None
        if crc16(data[:-2]) != struct.unpack(">H", data[-2:])[0]:
            return None
        _length, _version, _protocol, sequence, attribute = struct.unpack(">IBBHB", data[:9])
        _station, command, count, register = struct.unpack(">BBBH", data[9:14])
        if attribute != 0 or command != READ_REGISTER:
            return None
        values = b"".join(struct.pack(">I", register_value(register + i)) for i in range(count + 1))
        return frame(sequence, 1, values)


class EtherBusDevice(Device):
    kind: ClassVar[str] = "etherbus"
    description: ClassVar[str] = "A serial echo port and an Ether-S-Bus-shaped UDP port (test device)"
    ports = (
        PortDef("serial", "echoes"),
        PortDef("ether", "answers read-register requests", default=f"udp:{ETHER_PORT}"),
    )
    model_class = EtherBusModel
    face_classes: ClassVar[dict[str, Any]] = {"serial": EchoFace, "ether": EtherFace}
    points = PointTable.of(
        [
            Point("answered", "int", "requests answered on port ether", get=lambda m: m.answered, in_state=True),
            Point("ignored", "int", "datagrams not answered on port ether", get=lambda m: m.ignored, in_state=True),
        ]
    )
