"""Helpers of the dissector tests: run tshark with devsim's Lua dissectors on a capture and read
the fields back; a small pure writer of devsim's serial encapsulation (docs/wireshark-dissectors.md:
classic pcap, LINKTYPE_USER0 = 147, the 16-byte devsim header) for hand-made captures
(split frames, bad checksums) that no real session produces on demand."""

from __future__ import annotations

import struct
import subprocess
from pathlib import Path

from tests.support.process import ROOT

__all__ = ["DISSECTOR", "header", "tshark_fields", "write_pcap"]

DISSECTOR = ROOT / "devsim" / "wireshark" / "devsim.lua"
LINKTYPE_USER0 = 147
PROTOCOLS = {"sers": 1, "gms96": 2, "poselesta": 3, "ip247": 4, "pcd4h3": 5, "modbus_rtu": 16}


def header(direction: str, protocol: int, port: int = 0, baud: int = 9600, bits: int = 8, parity: str = "N",
           stop: float = 1, mismatch: bool = False) -> bytes:
    """The 16-byte devsim header (direction ``"H>D"`` or ``"D>H"``)."""
    return (b"ds" + bytes((1, 0 if direction == "H>D" else 1, protocol, port)) + struct.pack(">I", baud)
            + bytes((bits, ord(parity), round(stop * 10), 1 if mismatch else 0, 0, 0)))


def write_pcap(path: Path, protocol: str, chunks: list[tuple[str, bytes]], port: int = 0) -> Path:
    """A capture of ``chunks`` (direction, bytes), one record each, 10 ms apart."""
    out = [struct.pack("<IHHiIII", 0xA1B2C3D4, 2, 4, 0, 0, 65535, LINKTYPE_USER0)]
    for i, (direction, data) in enumerate(chunks):
        record = header(direction, PROTOCOLS[protocol], port) + data
        usec = 10_000 * (i + 1)
        out.append(struct.pack("<IIII", usec // 1_000_000, usec % 1_000_000, len(record), len(record)) + record)
    path.write_bytes(b"".join(out))
    return path


def tshark_fields(capture: Path, fields: list[str], *, lua: bool = True, options: tuple[str, ...] = (),
                  display_filter: str = "") -> list[list[str]]:
    """tshark's ``-T fields`` output: one row per packet, one column per field (occurrences joined
    by ``,``); with ``lua`` devsim's dissectors are loaded."""
    command = ["tshark", "-n", "-r", str(capture), "-T", "fields", "-E", "occurrence=a", "-E", "aggregator=|"]
    if lua:
        command += ["-X", f"lua_script:{DISSECTOR}"]
    command += list(options)
    if display_filter:
        command += ["-Y", display_filter]
    for field in fields:
        command += ["-e", field]
    result = subprocess.run(command, capture_output=True, text=True, timeout=60, check=False)
    assert result.returncode == 0 and "Lua: Error" not in result.stderr, result.stderr
    assert " Error " not in result.stderr, result.stderr
    return [line.split("\t") for line in result.stdout.splitlines()]
