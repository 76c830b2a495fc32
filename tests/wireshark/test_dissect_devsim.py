"""The ``devsim`` dissector itself (docs/wireshark-dissectors.md): the 16-byte header's fields,
dispatch on the protocol byte (Modbus RTU to Wireshark's own mbrtu, an unknown protocol shown as
data), and the layout ``devsim wireshark --install`` makes: every .lua file of devsim/wireshark in
Wireshark's personal plugins folder, where Wireshark loads each file on its own."""

from __future__ import annotations

import random
import subprocess
from pathlib import Path

import pytest

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


def test_an_unknown_protocol_is_shown_as_data(tmp_path: Path) -> None:
    needs_program("tshark")
    capture = tmp_path / "u.pcap"
    write_pcap(capture, "sers", [("H>D", b"\x01\x02")])
    data = bytearray(capture.read_bytes())
    data[24 + 16 + 4] = 0  # the protocol byte: 0, not known
    capture.write_bytes(bytes(data))
    assert tshark_fields(capture, ["devsim.protocol", "data.data"]) == [["0", "0102"]]


def test_the_plugins_folder_layout_loads_each_file_on_its_own(tmp_path: Path) -> None:
    """Wireshark loads every .lua file of its personal plugins folder (HOME/.local/lib/wireshark/
    plugins); the kinds' files and the tables then do nothing on their own, devsim.lua loads them;
    a second copy given with -X lua_script is ignored."""
    tshark = needs_program("tshark")
    written = install(personal_plugins_dir(tmp_path))
    assert {path.name for path in written} >= {"devsim.lua", "gms96.lua", "sers.lua", "as511.lua", "poselesta.lua",
                                                "gms96_tables.lua", "sers_tables.lua", "ip247_tables.lua",
                                                "poselesta_tables.lua", "sbus_serial.lua", "pcd4h3_tables.lua"}

    capture = write_pcap(tmp_path / "g.pcap", "gms96", [
        ("H>D", codec.encode(codec.LongFrame(codec.control_host(1), ADDRESS, codec.letter("T", 5, 15))))])
    for extra in ([], ["-X", f"lua_script:{DISSECTOR}"]):
        result = subprocess.run([tshark, "-n", "-r", str(capture), *extra, "-T", "fields", "-e", "gms96.command",
                                 "-e", "gms96.n"], capture_output=True, text=True, timeout=60, check=False,
                                env={"HOME": str(tmp_path), "PATH": "/usr/bin:/bin"})
        assert result.returncode == 0 and "Lua" not in result.stderr, result.stderr
        assert result.stdout.split() == ["T", "15"]


def test_a_line_without_an_end_is_not_carried_on_for_ever(tmp_path: Path) -> None:
    needs_program("tshark")
    garbage = b"x" * 3000  # a SERS line with no CR or LF: held back while it may still end
    capture = write_pcap(tmp_path / "g.pcap", "sers", [("D>H", garbage), ("D>H", garbage), ("D>H", b"ok1\n\r")])
    rows = tshark_fields(capture, ["devsim.pending", "devsim.unframed", "sers.ack"])
    assert [len(row[0]) // 2 for row in rows] == [3000, 0, 0]
    assert [len(row[1]) // 2 for row in rows] == [0, 6000, 0]  # 6000 > 4096: dropped, not carried on
    assert rows[2][2] == "ok1"


def test_two_passes_show_what_one_pass_shows(tmp_path: Path) -> None:
    """Wireshark dissects a packet again when it is clicked: the state a chunk started with (the
    bytes carried in, the AS511 transaction's step) is kept per packet."""
    needs_program("tshark")
    chunks = [("H>D", b"\x02"), ("D>H", b"\x10\x06"), ("H>D", b"\x61"), ("D>H", b"\x02"), ("H>D", b"\x10\x06"),
              ("D>H", b"\x16\x10\x03"), ("H>D", b"\x10\x06"), ("H>D", bytes.fromhex("01 06 01 00 00 64")),
              ("H>D", bytes.fromhex("00 00 10 10 10 10 10 04"))]
    capture = write_pcap(tmp_path / "a.pcap", "ip247", chunks)
    fields = ["as511.function", "as511.page", "as511.ba", "as511.dd", "devsim.pending"]
    once = tshark_fields(capture, fields)
    assert once[-1][:4] == ["", "1", "6", "4112"]
    assert tshark_fields(capture, fields, options=("-2",)) == once


@pytest.mark.parametrize(("protocol", "port"), [("sers", 0), ("gms96", 0), ("poselesta", 6), ("poselesta", 7),
                                                ("poselesta", 8), ("ip247", 0), ("pcd4h3", 0), ("modbus_rtu", 0)])
def test_garbage_never_breaks_a_dissector(tmp_path: Path, protocol: str, port: int) -> None:
    """400 chunks of random bytes, rich in each protocol's control bytes, both ways: every packet is
    dissected without a Lua error, and everything shown is valid UTF-8 (a line's Latin-1 bytes are
    converted, control characters escaped)."""
    tshark = needs_program("tshark")
    rng = random.Random(f"{protocol}{port}")
    special = bytes((0x02, 0x03, 0x04, 0x06, 0x10, 0x12, 0x15, 0x16, 0x68, 0xE5, 0xB5, 0xC5, 0x0D, 0x0A, 0x23, 0x2A))
    alphabet = special + bytes(range(0x20, 0x7F))
    chunks = []
    for _ in range(400):
        size = rng.choice((1, 1, 2, 3, 5, 8, 20, 60))
        data = bytes(rng.choice(alphabet) if rng.random() < 0.7 else rng.randrange(256) for _ in range(size))
        chunks.append((rng.choice(("H>D", "D>H")), data))
    capture = write_pcap(tmp_path / "garbage.pcap", protocol, chunks, port=port)
    result = subprocess.run([tshark, "-n", "-r", str(capture), "-X", f"lua_script:{DISSECTOR}", "-V"],
                            capture_output=True, timeout=120, check=False)
    assert result.returncode == 0, result.stderr
    shown = result.stdout.decode("utf-8") + result.stderr.decode("utf-8")  # raises on invalid UTF-8
    assert "Lua Error" not in shown and "Lua: Error" not in shown, [
        line for line in shown.splitlines() if "Lua" in line][:5]
    assert shown.count("\nFrame ") + shown.startswith("Frame ") == len(chunks)
