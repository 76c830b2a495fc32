"""The Modbus RTU facade's line captured in devsim's serial encapsulation (protocol 16) and decoded
by Wireshark's own Modbus RTU dissector: tshark with a User DLT entry (header size 16, payload
dissector ``mbrtu``) reads the unit, function codes, register addresses and values that pymodbus's
serial client sent and the facade answered."""

from __future__ import annotations

import subprocess
from pathlib import Path

from pymodbus.client import ModbusSerialClient

from devsim.facades.modbus_map import ModbusMap
from devsim.scenario.plant import plant_running
from devsim.scenario.schema import PlantSpec
from devsim.transports.pcap import parse_serial_header
from tests.support.programs import needs_program
from tests.wireshark.test_capture import tshark_env, tshark_records

#: Wireshark's User DLTs table: USER0 (147) → header 16 bytes, then the built-in Modbus RTU dissector.
USER_DLT = 'uat:user_dlts:"User 0 (DLT=147)","mbrtu","16","","0",""'
FIELDS = ["mbrtu.unit_id", "modbus.func_code", "modbus.reference_num", "modbus.word_cnt", "modbus.byte_cnt",
          "modbus.regval_uint16", "mbrtu.crc16.status"]


def test_tshark_decodes_the_modbus_rtu_capture_with_its_own_dissector(tmp_path: Path) -> None:
    program = needs_program("tshark")
    spec = PlantSpec.parse({"devices": [{"name": "drive", "kind": "sers",
                                         "modbus": {"rtu": {}, "line": "19200 8N1", "unit": 7}}]})
    with plant_running(spec, virtual=True, trace_dir=tmp_path, trace_format="pcap") as plant:
        supply = ModbusMap.generate(plant.devices["drive"].points).by_name["quantity.supply_voltage"].address
        client = ModbusSerialClient(port=plant.port("drive.modbus"), baudrate=19200, parity="N", timeout=2)
        assert client.connect()
        try:
            assert client.read_holding_registers(supply, count=2, device_id=7).registers == [1, 68000 - 65536]
            assert not client.write_registers(supply, [0, 48_000], device_id=7).isError()
        finally:
            client.close()
    trace = tmp_path / "drive.modbus.pcap"

    headers = [parse_serial_header(data) for _, data in tshark_records(trace, tmp_path)]
    assert [h["direction"] for h in headers] == ["H>D", "D>H", "H>D", "D>H"]  # one chunk per frame here
    assert {(h["protocol"], h["port"], h["baud"], h["stop"], h["mismatch"]) for h in headers} == {(16, 0, 19200, 1.0,
                                                                                                  False)}
    result = subprocess.run(
        [program, "-r", str(trace), "-o", USER_DLT, "-o", "mbrtu.crc_verification:TRUE", "-T", "fields",
         "-E", "separator=|", "-E", "aggregator=,", *[arg for name in FIELDS for arg in ("-e", name)]],
        capture_output=True, text=True, timeout=60, stdin=subprocess.DEVNULL, check=False, env=tshark_env(tmp_path),
    )
    assert result.returncode == 0, result.stderr
    rows = [dict(zip(FIELDS, line.split("|"), strict=True)) for line in result.stdout.splitlines()]
    assert len(rows) == 4, result.stdout
    read, answer, write, written = rows
    assert all(row["mbrtu.unit_id"] == "7" for row in rows)
    assert all(row["mbrtu.crc16.status"] == "1" for row in rows)  # the CRC checked and good
    assert (read["modbus.func_code"], read["modbus.reference_num"], read["modbus.word_cnt"]) == ("3", str(supply), "2")
    assert (answer["modbus.func_code"], answer["modbus.byte_cnt"], answer["modbus.regval_uint16"]) == ("3", "4",
                                                                                                       "1,2464")
    assert (write["modbus.func_code"], write["modbus.reference_num"], write["modbus.word_cnt"],
            write["modbus.regval_uint16"]) == ("16", str(supply), "2", "0,48000")
    assert (written["modbus.func_code"], written["modbus.reference_num"], written["modbus.word_cnt"]) == (
        "16", str(supply), "2")


def test_devsim_run_traces_the_modbus_rtu_line_beside_the_device_port(tmp_path: Path) -> None:
    """``devsim run KIND --modbus rtu --trace FILE.pcap``: the device's port in FILE.pcap, the
    Modbus RTU line in FILE-modbus.pcap (protocol 16)."""
    from tests.test_cli import Sim

    trace = tmp_path / "line.pcap"
    sim = Sim("sers", "--virtual", "--modbus", "rtu", "--trace", str(trace))
    try:
        rtu = sim.read_until("sers.modbus:")["sers.modbus"].split()[-1]
        client = ModbusSerialClient(port=rtu, baudrate=19200, parity="N", timeout=5)  # a pty shows no parity
        assert client.connect()
        try:
            assert not client.read_holding_registers(0, count=1, device_id=1).isError()
        finally:
            client.close()
    finally:
        code, err = sim.stop()
    assert code == 0, err
    records = tshark_records(tmp_path / "line-modbus.pcap", tmp_path)
    assert [parse_serial_header(data)["protocol"] for _, data in records] == [16, 16]
    assert records[0][1][16:18] == bytes([1, 3])  # unit 1, read holding registers
    assert tshark_records(trace, tmp_path) == []  # the SERS port: nothing crossed it
