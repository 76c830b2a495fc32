"""A PCD4.H3 session on its serial S-Bus port (data mode, spec pcd4h3.md §9.2, §9.4) through a
real pty of ``devsim run pcd4h3 --trace x.pcap``, decoded by tshark with devsim's Lua dissectors:
station, command, element count, address, data (stuffed bytes undone), the CRC, a NAK."""

from __future__ import annotations

import struct
from pathlib import Path

import serial

from devsim.devices.pcd4h3 import sbus
from tests.support.programs import needs_program
from tests.wireshark.captures import Session, tshark_fields

STATION = 1  # the default (config ``station``)


def request(command: int, parameters: bytes = b"") -> bytes:
    body = bytes((sbus.FS, 0, STATION, command)) + parameters
    return sbus.stuff(body + struct.pack(">H", sbus.crc16(body)))


def answer(port: serial.Serial) -> bytes:
    """The station's answer: read until its CRC (over FS .. CRC, unstuffed) comes out 0."""
    wire = b""
    while len(wire) < 4 or sbus.crc16(sbus.unstuff(wire) or b"\x01") != 0:
        chunk = port.read(1)
        assert chunk, f"no complete answer, got {wire.hex()}"
        wire += chunk
    return wire


def values(rows: list[list[str]], index: int, direction: str) -> list[str]:
    return [v for row in rows if row[0] == direction and row[index] for v in row[index].split("|")]


def test_a_serial_s_bus_session_decodes(tmp_path: Path) -> None:
    needs_program("tshark")
    requests = [
        request(0x1B),  # read status
        request(0x0E, bytes((9, 0, 0xB5)) + struct.pack(">ii", -5, 0xC5)),  # write R181, R182: B5h, C5h stuffed
        request(0x06, bytes((1, 0, 0xB5))),  # read 2 registers from 181
        request(0x47),  # no such command: NAK
    ]
    # (the Ether-S-Bus ports on ephemeral ports: another simulator may hold the default 5050)
    with Session(tmp_path, "pcd4h3", "--port", "ether_udp=udp:0", "--port", "ether_tcp=tcp:0") as sim, \
            serial.Serial(sim.ports["pcd4h3.sbus"], 9600, timeout=5) as port:
        answers = []
        for telegram in requests:
            port.write(telegram)
            answers.append(answer(port))
    assert answers[3] == sbus.serial_ack(sbus.NAK)
    rows = tshark_fields(sim.capture, ["devsim.dir", "sbusserial.station", "sbusserial.command", "sbusserial.count",
                                       "sbusserial.address", "sbusserial.register", "sbusserial.ack",
                                       "sbusserial.crc.ok", "sbusserial.att"])
    assert values(rows, 1, "0") == ["1"] * 4
    assert values(rows, 2, "0") == ["0x1b", "0x0e", "0x06", "0x47"]
    assert values(rows, 3, "0") == ["2"] and values(rows, 4, "0") == ["181", "181"]
    assert values(rows, 5, "1") == ["-5", "197"]  # the registers read back
    assert values(rows, 6, "1") == ["0", "1"]  # the write's ACK, the unknown command's NAK
    assert set(values(rows, 7, "0") + values(rows, 7, "1")) == {"1"}
    assert values(rows, 8, "1") == ["0x01", "0x02", "0x01", "0x02"]
