"""The Modbus facade against the standard (issue 29): Modbus Application Protocol Specification
V1.1b3 and Modbus Messaging on TCP/IP Implementation Guide V1.0b, over a real socket and a real pty.
Expected answers come from the standard's text; the clients are raw bytes (where a client library
would not send the request or would hide the answer's bytes), pymodbus's and modbus-tk's."""

from __future__ import annotations

import socket
import struct
from collections.abc import Iterator
from typing import Any

import pytest
import serial
from modbus_tk import defines as cst
from modbus_tk.exceptions import ModbusError
from modbus_tk.modbus_rtu import RtuMaster
from modbus_tk.modbus_tcp import TcpMaster
from pymodbus.client import ModbusTcpClient
from pymodbus.framer import FramerRTU

from devsim.facades.modbus_map import ModbusMap
from devsim.scenario.plant import plant_running
from devsim.scenario.schema import PlantSpec

#: Requests and the standard's answers: §7 (the function code plus 80h), §6.1 (1 … 2000 coils),
#: §6.3 (1 … 125 registers), §6.5 (FF00h or 0000h).
REFUSALS = [
    pytest.param("55", "D5 01", id="unknown function 55h: D5 01"),
    pytest.param("03 0000 0000", "83 03", id="read 0 registers: 83 03"),
    pytest.param("03 0000 007E", "83 03", id="read 126 registers: 83 03"),
    pytest.param("04 0000 0000", "84 03", id="read 0 input registers: 84 03"),
    pytest.param("01 0000 0000", "81 03", id="read 0 coils: 81 03"),
    pytest.param("01 0000 07D1", "81 03", id="read 2001 coils: 81 03"),
    pytest.param("02 0000 07D1", "82 03", id="read 2001 discrete inputs: 82 03"),
    pytest.param("05 {coil} 1234", "85 03", id="write coil 1234h: 85 03"),
    pytest.param("05 {coil} 00FF", "85 03", id="write coil 00FFh: 85 03"),
    pytest.param("05 {coil} FFFF", "85 03", id="write coil FFFFh: 85 03"),
]


def spec(modbus: dict[str, Any]) -> PlantSpec:
    return PlantSpec.parse({"devices": [{"name": "drive", "kind": "sers", "modbus": modbus}]})


def crc(frame: bytes) -> bytes:
    return FramerRTU.compute_CRC(frame).to_bytes(2, "big")


@pytest.fixture(scope="module")
def plant() -> Iterator[Any]:
    with plant_running(spec({"tcp": {"port": 0}}), virtual=True) as running:
        yield running


@pytest.fixture(scope="module")
def sers_map(plant: Any) -> ModbusMap:
    return ModbusMap.generate(plant.devices["drive"].points)


@pytest.fixture
def where(plant: Any) -> tuple[str, int]:
    host, _, port = plant.port("drive.modbus").removeprefix("socket://").rpartition(":")
    return host, int(port)


def mbap(transaction: int, pdu: bytes, unit: int = 1, protocol: int = 0) -> bytes:
    return struct.pack(">HHHB", transaction, protocol, len(pdu) + 1, unit) + pdu


def receive(sock: socket.socket) -> bytes:
    """One MBAP response: its header, then as many bytes as its length says."""
    head = recv_exactly(sock, 7)
    return head + recv_exactly(sock, struct.unpack(">H", head[4:6])[0] - 1)


def recv_exactly(sock: socket.socket, size: int) -> bytes:
    data = b""
    while len(data) < size:
        chunk = sock.recv(size - len(data))
        assert chunk, f"connection closed after {data.hex()}"
        data += chunk
    return data


def pdu_of(text: str, sers_map: ModbusMap) -> bytes:
    coil = sers_map.by_name["input.I1"].address
    return bytes.fromhex(text.format(coil=f"{coil:04X}"))


@pytest.mark.parametrize(("request_pdu", "expected"), REFUSALS)
def test_tcp_exceptions_repeat_the_function_code(where: tuple[str, int], sers_map: ModbusMap,
                                                 request_pdu: str, expected: str) -> None:
    with socket.create_connection(where, timeout=5) as sock:
        sock.sendall(mbap(7, pdu_of(request_pdu, sers_map)))
        assert receive(sock) == mbap(7, bytes.fromhex(expected))


def test_rtu_answers_the_exceptions_too(sers_map: ModbusMap) -> None:
    """The same requests on the RTU port, raw bytes on the pty: each answered (it was silence)."""
    with plant_running(spec({"rtu": {}, "line": "115200 8N1"}), virtual=True) as running, \
            serial.Serial(running.port("drive.modbus"), 115200, timeout=2) as port:
        for case in REFUSALS:
            request_pdu, expected = case.values
            frame = b"\x01" + pdu_of(str(request_pdu), sers_map)
            port.write(frame + crc(frame))
            answer = b"\x01" + bytes.fromhex(str(expected))
            assert port.read(5) == answer + crc(answer), case.id


def test_modbus_tk_over_rtu_gets_03_for_too_many_registers() -> None:
    """(modbus-tk reads an exception response until its timeout: it expected a longer answer.)"""
    with plant_running(spec({"rtu": {}, "line": "115200 8N1"}), virtual=True) as running:
        master = RtuMaster(serial.Serial(running.port("drive.modbus"), 115200, timeout=0.5))
        master.set_timeout(0.5)
        try:
            with pytest.raises(ModbusError) as refused:
                master.execute(1, cst.READ_HOLDING_REGISTERS, 0, 126)
            assert refused.value.get_exception_code() == 3
        finally:
            master.close()


def test_bits_outside_the_map_are_02_for_reads_as_for_writes(where: tuple[str, int], sers_map: ModbusMap) -> None:
    """§6.1, §6.2: an address that does not exist is exception 02 (reads there gave zeros)."""
    coils, discretes = sers_map.size("coil"), sers_map.size("discrete")
    client = ModbusTcpClient(where[0], port=where[1], timeout=5)
    assert client.connect()
    try:
        assert not client.read_coils(0, count=coils, device_id=1).isError()
        assert not client.read_discrete_inputs(0, count=discretes, device_id=1).isError()
        for answer in (client.read_coils(coils, count=1, device_id=1),
                       client.read_coils(coils - 1, count=2, device_id=1),
                       client.read_coils(60_000, count=8, device_id=1),
                       client.read_discrete_inputs(discretes, count=1, device_id=1),
                       client.read_discrete_inputs(0, count=discretes + 1, device_id=1),
                       client.write_coil(coils, True, device_id=1)):
            assert answer.isError() and answer.exception_code == 2, answer
    finally:
        client.close()
    master = TcpMaster(where[0], where[1], timeout_in_sec=5.0)
    try:
        with pytest.raises(ModbusError) as missing:
            master.execute(1, cst.READ_DISCRETE_INPUTS, discretes, 3)
        assert missing.value.get_exception_code() == 2
    finally:
        master.close()


def test_write_single_coil_takes_ff00_and_0000_only(plant: Any, where: tuple[str, int], sers_map: ModbusMap) -> None:
    """§6.5: "A value of FF 00 hex requests the output to be ON. A value of 00 00 requests it to be
    OFF. All other values are illegal"; the normal response is an echo of the request."""
    coil = sers_map.by_name["input.I3"].address.to_bytes(2, "big")
    with socket.create_connection(where, timeout=5) as sock:
        for value, state in ((b"\xff\x00", True), (b"\x12\x34", True), (b"\x00\x00", False), (b"\x00\x01", False)):
            request = b"\x05" + coil + value
            sock.sendall(mbap(1, request))
            expected = request if value in (b"\xff\x00", b"\x00\x00") else b"\x85\x03"
            assert receive(sock) == mbap(1, expected)
            assert plant.runtime.read("drive", "input.I3") is state


def test_several_requests_in_one_segment_are_each_answered_in_order(where: tuple[str, int],
                                                                    sers_map: ModbusMap) -> None:
    supply = sers_map.by_name["quantity.supply_voltage"].address
    requests = [mbap(10, struct.pack(">BHH", 3, supply, 2)),
                mbap(11, bytes.fromhex("55")),
                mbap(12, struct.pack(">BHH", 3, supply + 1, 1), unit=0xFF)]
    with socket.create_connection(where, timeout=5) as sock:
        sock.sendall(b"".join(requests))  # one send, one segment on loopback
        answers = [receive(sock) for _ in requests]
    assert answers == [mbap(10, bytes.fromhex("03 04 0001 09A0")),  # 68 000 = 0001 09A0h
                       mbap(11, bytes.fromhex("D5 01")),
                       mbap(12, bytes.fromhex("03 02 09A0"), unit=0xFF)]


def test_a_protocol_identifier_other_than_0_is_discarded(where: tuple[str, int]) -> None:
    """Messaging on TCP/IP §4.4.2.2: "The Protocol Identifier field has to be checked: If it is
    different from MODBUS protocol type, the indication is simply discarded."  Discarded, framed
    by its length: no answer to it, and the requests before and after it on the same connection
    are answered (the connection was closed, so request 3 and 5 went unanswered)."""
    read = struct.pack(">BHH", 3, 2, 2)
    answer = bytes.fromhex("03 04 0001 09A0")  # 68 000 = 0001 09A0h (§6.3)
    with socket.create_connection(where, timeout=5) as sock:
        sock.sendall(mbap(1, read) + mbap(2, read, protocol=1) + mbap(3, read))
        assert receive(sock) == mbap(1, answer)
        assert receive(sock) == mbap(3, answer)  # nothing for 2
        sock.sendall(mbap(4, read, protocol=0x1234))
        sock.sendall(mbap(5, read))
        assert receive(sock) == mbap(5, answer)


@pytest.mark.parametrize("length", [0, 1, 255, 0xFFFF])
def test_an_mbap_length_outside_2_to_254_closes_the_connection(where: tuple[str, int], length: int) -> None:
    """Application Protocol §4.1: a PDU is at most 253 bytes, so the length field (§3.1.3 of the
    guide: the unit identifier and the PDU) is 2 … 254; past one outside that the stream cannot be
    framed: the indication is discarded (guide §4.4.2.2) and the connection closed."""
    with socket.create_connection(where, timeout=5) as sock:
        sock.sendall(struct.pack(">HHHB", 6, 0, length, 1) + struct.pack(">BHH", 3, 2, 2))
        assert sock.recv(100) == b""


@pytest.mark.parametrize("unit", [1, 0xFF, 0])
def test_tcp_unit_ff_and_0_address_the_device(where: tuple[str, int], unit: int) -> None:
    """§4.4.1.2: 0xFF is the unit id of a server addressed by its IP address; "the value 0 is also
    accepted to communicate directly to a MODBUS/TCP device".  The response carries the request's
    unit id (§4.4.2.5)."""
    with socket.create_connection(where, timeout=5) as sock:
        sock.sendall(mbap(9, struct.pack(">BHH", 3, 2, 2), unit=unit))
        assert receive(sock) == mbap(9, bytes.fromhex("03 04 0001 09A0"), unit=unit)
    if unit:
        master = TcpMaster(where[0], where[1], timeout_in_sec=5.0)
        try:
            assert master.execute(unit, cst.READ_HOLDING_REGISTERS, 2, 2) == (1, 68000 - 65536)
        finally:
            master.close()


def test_tcp_another_unit_id_is_exception_0b(where: tuple[str, int]) -> None:
    """Any other unit id names a device behind a gateway that is not there: §4.4.2.5's 0B."""
    master = TcpMaster(where[0], where[1], timeout_in_sec=5.0)
    try:
        with pytest.raises(ModbusError) as absent:
            master.execute(7, cst.READ_HOLDING_REGISTERS, 2, 2)
        assert absent.value.get_exception_code() == 0x0B
    finally:
        master.close()


def test_rtu_a_frame_cut_short_does_not_hold_up_the_next() -> None:
    """A request cut short (a host that gave up, noise) and an unknown function's frame without a
    valid CRC, each followed by a whole request: the whole one is answered at once, not after
    the line has brought enough bytes to fill the partial frame."""
    with plant_running(spec({"rtu": {}, "line": "115200 8N1"}), virtual=True) as running, \
            serial.Serial(running.port("drive.modbus"), 115200, timeout=2) as port:
        read = bytes.fromhex("01 03 0002 0002")
        answer = bytes.fromhex("01 03 04 0001 09A0")  # 68 000 V/1000 (Application Protocol §6.3)
        for junk in (bytes.fromhex("01 10 0002 007B F6 0000"), bytes.fromhex("01 55 12 34 56")):
            port.write(junk + read + crc(read))
            assert port.read(9) == answer + crc(answer), junk.hex()
