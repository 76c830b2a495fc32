"""The ``devsim`` dissector itself (docs/wireshark-dissectors.md): the 16-byte header's fields,
dispatch on the protocol byte (Modbus RTU to Wireshark's own mbrtu, PCD4.H3 serial S-Bus shown as
data), and the layout ``devsim wireshark --install`` makes: every .lua file of devsim/wireshark in
Wireshark's personal plugins folder, where Wireshark loads each file on its own."""

from __future__ import annotations

import subprocess
from pathlib import Path

from devsim.devices.gms96 import codec
from devsim.wireshark import install, personal_plugins_dir
from tests.support.programs import needs_program
from tests.wireshark.captures import DISSECTOR, tshark_fields, write_pcap
from tests.wireshark.test_dissect_gms96 import ADDRESS

#: Modbus RTU: unit 1 reads 2 holding registers from 0, and the answer (42, 7); the CRC is added below.
READ = bytes.fromhex("01 03 00 00 00 02")
ANSWER = bytes.fromhex("01 03 04 00 2A 00 07")


def crc16(data: bytes) -> bytes:
    """Modbus RTU CRC-16 (polynomial A001h, low byte first)."""
    crc = 0xFFFF
    for byte in data:
        crc ^= byte
        for _ in range(8):
            crc = (crc >> 1) ^ 0xA001 if crc & 1 else crc >> 1
    return crc.to_bytes(2, "little")


def test_the_header_fields_are_filterable(tmp_path: Path) -> None:
    needs_program("tshark")
    capture = write_pcap(tmp_path / "h.pcap", "sers", [("H>D", b"#P1?\r"), ("D>H", b"ok1\n\r")])
    rows = tshark_fields(capture, ["devsim.magic", "devsim.version", "devsim.dir", "devsim.protocol", "devsim.port",
                                   "devsim.baud", "devsim.bits", "devsim.parity", "devsim.stop", "devsim.mismatch"])
    assert rows == [["ds", "1", "0", "1", "0", "9600", "8", "0x4e", "1", "0"],
                    ["ds", "1", "1", "1", "0", "9600", "8", "0x4e", "1", "0"]]
    assert tshark_fields(capture, ["frame.number"], display_filter="devsim.dir == 1") == [["2"]]


def test_modbus_rtu_goes_to_wiresharks_mbrtu(tmp_path: Path) -> None:
    needs_program("tshark")
    capture = write_pcap(tmp_path / "m.pcap", "modbus_rtu", [("H>D", READ + crc16(READ)),
                                                              ("D>H", ANSWER + crc16(ANSWER))])
    rows = tshark_fields(capture, ["mbrtu.unit_id", "modbus.func_code", "modbus.regval_uint16"])
    assert rows == [["1", "3", ""], ["1", "3", "42|7"]]


def test_pcd4h3_serial_s_bus_is_shown_as_data(tmp_path: Path) -> None:
    needs_program("tshark")
    capture = write_pcap(tmp_path / "p.pcap", "pcd4h3", [("H>D", bytes.fromhex("b5 01 06 00"))])
    assert tshark_fields(capture, ["devsim.protocol", "data.data"]) == [["5", "b5010600"]]


def test_the_plugins_folder_layout_loads_each_file_on_its_own(tmp_path: Path) -> None:
    """Wireshark loads every .lua file of its personal plugins folder (HOME/.local/lib/wireshark/
    plugins); the kinds' files and the tables then do nothing on their own, devsim.lua loads them;
    a second copy given with -X lua_script is ignored."""
    tshark = needs_program("tshark")
    written = install(personal_plugins_dir(tmp_path))
    assert {path.name for path in written} >= {"devsim.lua", "gms96.lua", "sers.lua", "as511.lua", "poselesta.lua",
                                                "gms96_tables.lua", "sers_tables.lua", "ip247_tables.lua",
                                                "poselesta_tables.lua"}

    capture = write_pcap(tmp_path / "g.pcap", "gms96", [
        ("H>D", codec.encode(codec.LongFrame(codec.control_host(1), ADDRESS, codec.letter("T", 5, 15))))])
    for extra in ([], ["-X", f"lua_script:{DISSECTOR}"]):
        result = subprocess.run([tshark, "-n", "-r", str(capture), *extra, "-T", "fields", "-e", "gms96.command",
                                 "-e", "gms96.n"], capture_output=True, text=True, timeout=60, check=False,
                                env={"HOME": str(tmp_path), "PATH": "/usr/bin:/bin"})
        assert result.returncode == 0 and "Lua" not in result.stderr, result.stderr
        assert result.stdout.split() == ["T", "15"]
