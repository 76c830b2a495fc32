"""The Modbus facade on real ports (issue 13): Modbus TCP and Modbus RTU on a pty, beside the
device's own serial port, through pymodbus's client and modbus-tk (a second client nobody here
wrote); a write acts as the control API's ``set``, refused values and unmapped addresses get the
standard exception codes."""

from __future__ import annotations

import re
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

import pytest
import serial
from modbus_tk import defines as cst
from modbus_tk.exceptions import ModbusError
from modbus_tk.modbus_rtu import RtuMaster
from modbus_tk.modbus_tcp import TcpMaster
from pymodbus.client import ModbusSerialClient, ModbusTcpClient

from devsim.scenario.plant import plant_running
from devsim.scenario.schema import PlantSpec


def spec(modbus: dict[str, Any], **device: Any) -> PlantSpec:
    return PlantSpec.parse({"devices": [{"name": "drive", "kind": "sers", "modbus": modbus, **device}]})


@contextmanager
def modbus_tcp(plant_spec: PlantSpec, device: str) -> Iterator[tuple[Any, ModbusTcpClient]]:
    """A plant (virtual time) and pymodbus's client on ``device``'s Modbus TCP facade."""
    with plant_running(plant_spec, virtual=True) as plant:
        host, _, port = plant.port(f"{device}.modbus").removeprefix("socket://").rpartition(":")
        client = ModbusTcpClient(host, port=int(port), timeout=5)
        assert client.connect()
        try:
            yield plant, client
        finally:
            client.close()


@pytest.fixture
def tcp() -> Iterator[tuple[Any, ModbusTcpClient]]:
    with modbus_tcp(spec({"tcp": {"port": 0}}), "drive") as both:
        yield both


def address(plant: Any, name: str) -> int:
    from devsim.facades.modbus_map import ModbusMap

    return ModbusMap.generate(plant.devices["drive"].points).by_name[name].address


def test_tcp_reads_and_writes_through_the_points(tcp: tuple[Any, ModbusTcpClient]) -> None:
    plant, client = tcp
    supply = address(plant, "quantity.supply_voltage")
    assert client.read_holding_registers(supply, count=2, device_id=1).registers == [1, 68000 - 65536]  # 68.000 V
    assert not client.write_registers(supply, [0, 50_000], device_id=1).isError()
    assert plant.runtime.read("drive", "quantity.supply_voltage") == 50.0
    refused = client.write_registers(supply, [0xFFFF, 0xFFFF], device_id=1)  # −0.001 V: below the minimum
    assert refused.isError() and refused.exception_code == 3
    assert plant.runtime.read("drive", "quantity.supply_voltage") == 50.0
    assert not client.write_register(supply + 1, 45_000, device_id=1).isError()  # FC 06: the low word alone
    assert plant.runtime.read("drive", "quantity.supply_voltage") == 45.0
    i1 = address(plant, "input.I1")
    assert not client.write_coil(i1, True, device_id=1).isError()
    assert plant.runtime.read("drive", "input.I1") is True
    plant.runtime.set("drive", "input.I2", True)
    assert client.read_coils(i1, count=2, device_id=1).bits[:2] == [True, True]
    missing = client.read_holding_registers(60_000, count=2, device_id=1)
    assert missing.isError() and missing.exception_code == 2


def test_tcp_sees_the_axis_move_that_the_serial_port_commands(tcp: tuple[Any, ModbusTcpClient]) -> None:
    plant, client = tcp
    plant.runtime.advance(3.0)  # the drive's 2 s initialisation
    port = serial.serial_for_url(plant.port("drive"), baudrate=9600, timeout=2)
    try:
        port.write(b"#1 ON V=60 WR=360 E\r")
        assert port.read_until(b"\r")  # the echo: the line is taken
    finally:
        port.close()
    position = address(plant, "axis.position")
    plant.runtime.advance(5.0)
    words = client.read_input_registers(position, count=2, device_id=1).registers
    value = (words[0] << 16 | words[1]) - (1 << 32 if words[0] & 0x8000 else 0)
    assert value == round(plant.runtime.read("drive", "axis.position") * 1000) != 0


def test_modbus_tk_over_tcp(tcp: tuple[Any, ModbusTcpClient]) -> None:
    plant, _client = tcp
    host, _, port = plant.port("drive.modbus").removeprefix("socket://").rpartition(":")
    master = TcpMaster(host, int(port), timeout_in_sec=5.0)
    try:
        supply = address(plant, "quantity.supply_voltage")
        assert master.execute(1, cst.READ_HOLDING_REGISTERS, supply, 2) == (1, 68000 - 65536)
        master.execute(1, cst.WRITE_MULTIPLE_REGISTERS, supply, output_value=[0, 55_000])
        assert plant.runtime.read("drive", "quantity.supply_voltage") == 55.0
        with pytest.raises(ModbusError) as refused:
            master.execute(1, cst.WRITE_MULTIPLE_REGISTERS, supply, output_value=[0xFFFF, 0xFFFF])  # −0.001 V
        assert refused.value.get_exception_code() == 3
        with pytest.raises(ModbusError) as missing:
            master.execute(1, cst.READ_INPUT_REGISTERS, 30_000, 2)
        assert missing.value.get_exception_code() == 2
    finally:
        master.close()


def test_rtu_on_a_pty() -> None:
    """pymodbus's serial client, at 19200 8N1 on the default 19200 8E1 line (docs/facades/modbus.md):
    it sets the inter-byte timeout right after opening, and a second parity request that soon on
    a Linux pty fails with EINVAL before the transport can re-arm it (see devsim.transports.pty);
    a pty shows no parity, so the device takes the host's 8N1 to be its own 8E1."""
    with plant_running(spec({"rtu": {}}), virtual=True) as plant:
        assert plant.runtime.lines["drive.modbus"].device_settings.describe() == "19200 8E1"
        path = plant.port("drive.modbus")
        supply = address(plant, "quantity.supply_voltage")
        client = ModbusSerialClient(port=path, baudrate=19200, parity="N", timeout=2)
        assert client.connect()
        try:
            assert client.read_holding_registers(supply, count=2, device_id=1).registers == [1, 68000 - 65536]
            assert not client.write_registers(supply, [0, 48_000], device_id=1).isError()
            assert plant.runtime.read("drive", "quantity.supply_voltage") == 48.0
        finally:
            client.close()


@pytest.mark.parametrize(("line", "message"), [
    ("fast", "line settings are like '19200 8E1', not 'fast'"),
    ("19200 8X1", "line settings '19200 8X1': parity 'X' is not N, E, O, M or S"),
    ("0 8E1", "line settings '0 8E1': baudrate 0 is no baud rate"),
    ("19200 9E1", "line settings '19200 9E1': bytesize 9 is not 5, 6, 7 or 8"),
    ("19200 8E3", "line settings '19200 8E3': stopbits 3 is not 1, 1.5 or 2"),
])
def test_a_plant_file_with_bad_rtu_line_settings_is_refused(line: str, message: str) -> None:
    """Found by fuzzing the RTU line's options: ``line: fast`` passed ``devsim check`` and ``devsim
    up`` died with a traceback when it opened the line; ``19200 8X1`` and ``0 8E1`` were served.
    The plant file is refused as it is read, naming the settings and what is wrong with them."""
    with pytest.raises(ValueError, match=re.escape(message)):
        spec({"rtu": {}, "line": line})
    assert spec({"rtu": {}, "line": "9600 7o1.5"}).devices[0].modbus is not None  # (any case, 1.5 stop bits)


def test_rtu_frames_back_to_back() -> None:
    """A request to another unit and one to ours written in one go: exactly one answer, ours."""
    from pymodbus.framer import FramerRTU

    crc = FramerRTU.compute_CRC
    with plant_running(spec({"rtu": {}, "line": "19200 8N1"}), virtual=True) as plant:
        supply = address(plant, "quantity.supply_voltage")
        with serial.Serial(plant.port("drive.modbus"), 19200, timeout=2) as raw:
            other = bytes((7, 3)) + supply.to_bytes(2, "big") + (2).to_bytes(2, "big")
            ours = bytes((1, 3)) + supply.to_bytes(2, "big") + (2).to_bytes(2, "big")
            raw.write(b"".join(frame + crc(frame).to_bytes(2, "big") for frame in (other, ours)))
            answer = bytes((1, 3, 4, 0, 1)) + (68000 - 65536).to_bytes(2, "big")
            assert raw.read(9) == answer + crc(answer).to_bytes(2, "big")


def test_a_flood_of_reads_over_the_limit_is_answered_each() -> None:
    """Reads of 126 registers and more (Application Protocol §6.3: 1 … 125): pymodbus's decoder
    logged each and answered none; each gets exception 03 now, and the next good request its
    answer, with nothing on the log."""
    from pymodbus.framer import FramerRTU

    from devsim.core.clock import VirtualClock
    from devsim.devices.sers import SersDevice
    from devsim.facades.modbus import ModbusFacade, ModbusRtuEndpoint

    crc = FramerRTU.compute_CRC
    answers: list[bytes] = []
    endpoint = ModbusRtuEndpoint(ModbusFacade(SersDevice(clock=VirtualClock(), config={"boot_time": 0})))
    endpoint.attach(answers.append)
    for count in range(200, 500):
        bad = bytes((1, 3, 0, 0)) + count.to_bytes(2, "big")
        endpoint.feed(bad + crc(bad).to_bytes(2, "big"))
    good = bytes((1, 3, 0, 0, 0, 2))
    endpoint.feed(good + crc(good).to_bytes(2, "big"))
    refusal = bytes((1, 0x83, 3))
    assert answers[:300] == [refusal + crc(refusal).to_bytes(2, "big")] * 300
    assert len(answers) == 301 and answers[300][:3] == bytes((1, 3, 4))


def test_modbus_tk_over_rtu_on_a_pty() -> None:
    """8N1 here: modbus-tk sets an inter-byte timeout, which a Linux pty refuses with parity."""
    with plant_running(spec({"rtu": {}, "line": "9600 8N1"}), virtual=True) as plant:
        master = RtuMaster(serial.Serial(plant.port("drive.modbus"), 9600, timeout=2))
        master.set_timeout(2.0)
        try:
            supply = address(plant, "quantity.supply_voltage")
            assert master.execute(1, cst.READ_HOLDING_REGISTERS, supply, 2) == (1, 68000 - 65536)
            master.execute(1, cst.WRITE_SINGLE_COIL, address(plant, "input.I1"), output_value=1)
            assert plant.runtime.read("drive", "input.I1") is True
            assert master.execute(1, cst.READ_COILS, address(plant, "input.I1"), 1) == (1,)
        finally:
            master.close()


def test_a_scenario_speaks_modbus_tcp_to_the_facade() -> None:
    """Plant files' ``modbus:``: the facade is a port of the plant (``drive.modbus``) a scenario can
    send raw Modbus TCP frames to: read the supply voltage, write it, see the device take it."""
    from devsim.scenario.report import format_report
    from devsim.scenario.runner import run_scenario
    from devsim.scenario.schema import scenario_from_dict

    read = bytes.fromhex("0001 0000 0006 01 03 0002 0002")  # MBAP, FC 3, holding 2, 2 registers
    answer = bytes.fromhex("0001 0000 0007 01 03 04 0001 09A0")  # 68 000 = 0001 09A0h
    write = bytes.fromhex("0002 0000 000B 01 10 0002 0002 04 0000 AFC8")  # FC 16: 45 000
    written = bytes.fromhex("0002 0000 0006 01 10 0002 0002")
    data = {
        "devices": [{"name": "drive", "kind": "sers", "modbus": {"tcp": {"port": 0}}}],
        "steps": [
            {"send": {"port": "drive.modbus", "data": read.decode("latin-1")}},
            {"expect": {"port": "drive.modbus", "bytes": answer.decode("latin-1")}},
            {"send": {"port": "drive.modbus", "data": write.decode("latin-1")}},
            {"expect": {"port": "drive.modbus", "bytes": written.decode("latin-1")}},
            {"expect_state": {"device": "drive", "name": "quantity.supply_voltage", "equals": 45.0}},
        ],
    }
    result = run_scenario(scenario_from_dict(data, "modbus"))
    assert result.passed, format_report(result)


def test_shutdown_closes_the_connections_it_serves() -> None:
    """A client still connected when the plant stops is disconnected (and the stop does not wait
    for it: Python 3.12's ``Server.wait_closed`` waits for every connection)."""
    import asyncio
    import socket

    from devsim.core.clock import VirtualClock
    from devsim.devices.sers import SersDevice
    from devsim.facades.modbus import ModbusFacade, serve_tcp

    async def check() -> bytes:
        server, port = await serve_tcp(ModbusFacade(SersDevice(clock=VirtualClock(), config={})), port=0)
        client = socket.create_connection(("127.0.0.1", port), timeout=5)
        client.setblocking(False)
        try:
            while not server.sessions:
                await asyncio.sleep(0)  # (the loop accepts the connection)
            await asyncio.wait_for(server.shutdown(), 5)
            return await asyncio.wait_for(asyncio.get_running_loop().sock_recv(client, 10), 5)
        finally:
            client.close()

    assert asyncio.run(asyncio.wait_for(check(), 10)) == b""
