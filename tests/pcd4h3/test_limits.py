"""How much one S-Bus telegram reads or writes (spec pcd4h3.md §9.4: at most 32 registers,
counters or timers, 128 flags, inputs or outputs), at the limit and one over, in both directions,
through the real ports: the S-Bus pty and Ether-S-Bus on UDP and TCP.  Over the limit the station
answers NAK 0001h and writes nothing (§9.2: "bad count")."""

from __future__ import annotations

import socket
import struct
from collections.abc import Callable
from typing import Any

import pytest

from devsim.devices.pcd4h3.sbus import crc16, ether_frame
from devsim.devices.pcd4h3.services import SERVICES
from devsim.scenario.plant import plant_running
from devsim.scenario.schema import PlantSpec
from tests.pcd4h3.helpers import EXAMPLE, Station

NAK, ACK = b"\x00\x01", b"\x00\x00"
USER = 1000  # registers and flags of the user's, outside the axis and diagnostics blocks
READS = {"00h": ("counter", 32), "02h": ("flag", 128), "03h": ("input", 128), "05h": ("output", 128),
         "06h": ("register", 32), "07h": ("timer", 32)}


def test_the_limits_are_the_tables() -> None:
    for code, (medium, most) in READS.items():
        assert SERVICES.get(code).telegram.most == most, (code, medium)
    assert SERVICES.get("0Eh").telegram.most == 32 and SERVICES.get("0Bh").telegram.most == 128


def _read(code: str, count: int) -> tuple[int, bytes, int | None]:
    medium, _ = READS[code]
    address = 0 if medium == "timer" else USER if medium in ("register", "flag") else 0
    width = 4 * count if medium in ("register", "counter", "timer") else (count + 7) // 8
    return int(code[:2], 16), bytes((count - 1,)) + address.to_bytes(2, "big"), width


def _write_registers(count: int, base: int = 7) -> bytes:
    data = b"".join(struct.pack(">i", base + i) for i in range(count))
    return bytes((4 * count + 1,)) + USER.to_bytes(2, "big") + data


def _write_flags(count: int) -> bytes:
    packed = bytes([0xFF] * ((count + 7) // 8))
    return bytes((len(packed) + 2,)) + USER.to_bytes(2, "big") + bytes((count - 1,)) + packed


# -- the serial data mode on the pty ---------------------------------------------------------------
@pytest.mark.parametrize("code", list(READS))
def test_a_read_at_the_limit_is_answered_and_one_over_refused_on_the_pty(pcd: Station, code: str) -> None:
    most = READS[code][1]
    command, parameters, width = _read(code, most)
    assert len(pcd.call(command, parameters, width)) == width
    command, parameters, _ = _read(code, most + 1)
    assert pcd.call(command, parameters) == NAK


def test_32_registers_are_written_and_33_refused_on_the_pty(pcd: Station) -> None:
    assert pcd.call(0x0E, _write_registers(32)) == ACK
    assert pcd.read_registers(USER, 32) == [7 + i for i in range(32)]
    assert pcd.call(0x0E, _write_registers(33, base=100)) == NAK
    assert pcd.read_registers(USER, 32) == [7 + i for i in range(32)]  # nothing written
    assert pcd.read_registers(USER + 32) == [0]


def test_128_flags_are_written_and_129_refused_on_the_pty(pcd: Station) -> None:
    assert pcd.call(0x0B, _write_flags(128)) == ACK
    assert pcd.read_flags(USER, 128) == [1] * 128
    pcd.call(0x0B, bytes((18,)) + USER.to_bytes(2, "big") + bytes((127,)) + bytes(16))  # all 0 again
    assert pcd.call(0x0B, _write_flags(129)) == NAK
    assert pcd.read_flags(USER, 128) == [0] * 128 and pcd.read_flags(USER + 128) == [0]


# -- Ether-S-Bus on UDP and TCP ------------------------------------------------------------------
def _ether_request(sequence: int, command: int, parameters: bytes) -> bytes:
    return ether_frame(1, sequence, 0, bytes((1, command)) + parameters)


def _payload(reply: bytes) -> bytes:
    assert crc16(reply[:-2]) == int.from_bytes(reply[-2:], "big")
    return reply[9:-2]


@pytest.fixture(params=["ether_udp", "ether_tcp"])
def ether(request: pytest.FixtureRequest) -> Any:
    spec = PlantSpec.parse({"devices": [{"name": "pcd", "kind": "pcd4h3", "config": dict(EXAMPLE)}]})
    with plant_running(spec, virtual=True) as plant:
        host, _, number = plant.port(f"pcd.{request.param}").partition("://")[2].rpartition(":")
        if request.param == "ether_udp":
            sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
            sock.connect((host, int(number)))
        else:
            sock = socket.create_connection((host, int(number)), timeout=5)
        sock.settimeout(5)
        with sock:
            yield _exchange(sock)


def _exchange(sock: socket.socket) -> Callable[[int, bytes], bytes]:
    sequence = iter(range(1, 1 << 16))

    def call(command: int, parameters: bytes) -> bytes:
        sock.sendall(_ether_request(next(sequence), command, parameters))
        reply = b""
        while len(reply) < 4 or len(reply) < int.from_bytes(reply[:4], "big"):
            chunk = sock.recv(4096)
            assert chunk, "connection closed"
            reply += chunk
        return _payload(reply)

    return call


@pytest.mark.parametrize("code", list(READS))
def test_a_read_at_the_limit_is_answered_and_one_over_refused_over_ether(ether: Any, code: str) -> None:
    most = READS[code][1]
    command, parameters, width = _read(code, most)
    assert len(ether(command, parameters)) == width
    command, parameters, _ = _read(code, most + 1)
    assert ether(command, parameters) == NAK


def test_register_and_flag_writes_at_and_over_the_limit_over_ether(ether: Any) -> None:
    assert ether(0x0E, _write_registers(32)) == ACK
    assert ether(0x0E, _write_registers(33, base=100)) == NAK
    data = ether(0x06, bytes((31,)) + USER.to_bytes(2, "big"))
    assert list(struct.unpack(">32i", data)) == [7 + i for i in range(32)]
    assert ether(0x0B, _write_flags(128)) == ACK
    assert ether(0x0B, _write_flags(129)) == NAK
    assert ether(0x02, bytes((0,)) + (USER + 128).to_bytes(2, "big")) == b"\x00"  # flag 129 not written
