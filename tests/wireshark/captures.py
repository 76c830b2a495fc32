"""Helpers of the dissector tests: a ``devsim run KIND --trace`` session in its own process
(:class:`Session`), tshark with devsim's Lua dissectors on a capture and its fields read back
(:func:`tshark_fields`), hand-made captures in devsim's serial encapsulation (:func:`write_pcap`,
for what no real session produces on demand: split frames, wrong checksums), and the chunks of a
capture as a TCP stream for a built-in dissector that only Decode As reaches (:func:`as_tcp`)."""

from __future__ import annotations

import re
import struct
import subprocess
import sys
from pathlib import Path

from tests.support.process import ROOT, DevsimProcess, devsim_env

__all__ = ["DISSECTOR", "PROTOCOLS", "Session", "as_tcp", "read_records", "tshark_fields", "write_pcap"]

DISSECTOR = ROOT / "devsim" / "wireshark" / "devsim.lua"
PROTOCOLS = {"sers": 1, "gms96": 2, "poselesta": 3, "ip247": 4, "pcd4h3": 5, "modbus_rtu": 16}


def write_pcap(path: Path, protocol: str, chunks: list[tuple[str, bytes]], port: int = 0) -> Path:
    """A capture of ``chunks`` (direction ``"H>D"`` / ``"D>H"``, bytes), one record each, 10 ms
    apart, at 9600 8N1, written with devsim's own pcap functions."""
    from devsim.transports.pcap import LINKTYPE_USER0, global_header, serial_header, serial_record

    records = [global_header(LINKTYPE_USER0)]
    for i, (direction, data) in enumerate(chunks):
        head = serial_header(direction, PROTOCOLS[protocol], port, 9600, 8, "N", 1, False)
        records.append(serial_record(0.01 * (i + 1), head, data))
    path.write_bytes(b"".join(records))
    return path


def tshark_fields(capture: Path, fields: list[str], *, lua: bool = True, options: tuple[str, ...] = (),
                  display_filter: str = "") -> list[list[str]]:
    """tshark's ``-T fields`` output: one row per packet, one column per field (occurrences joined
    by ``|``); with ``lua`` devsim's dissectors are loaded."""
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


def read_records(capture: Path) -> list[tuple[float, bytes]]:
    """The (time, record) pairs of a classic little-endian pcap file."""
    data = capture.read_bytes()
    assert data[:4] == b"\xd4\xc3\xb2\xa1", "not a little-endian classic pcap"
    records, i = [], 24
    while i + 16 <= len(data):
        sec, usec, incl, _orig = struct.unpack_from("<IIII", data, i)
        records.append((sec + usec / 1e6, data[i + 16 : i + 16 + incl]))
        i += 16 + incl
    return records



def _ipv4_tcp(src: tuple[str, int], dst: tuple[str, int], seq: int, ack: int, payload: bytes, ident: int) -> bytes:
    """An IPv4/TCP segment (PSH ACK) carrying ``payload``; the TCP checksum left 0 (tshark does
    not check it by default)."""
    import ipaddress

    from devsim.transports.pcap import checksum

    tcp = struct.pack("!HHIIBBHHH", src[1], dst[1], seq, ack, 5 << 4, 0x18, 65535, 0, 0) + payload
    ip = struct.pack("!BBHHHBBH4s4s", 0x45, 0, 20 + len(tcp), ident & 0xFFFF, 0x4000, 64, 6, 0,
                     ipaddress.IPv4Address(src[0]).packed, ipaddress.IPv4Address(dst[0]).packed)
    ip = ip[:10] + struct.pack("!H", checksum(ip)) + ip[12:]
    return ip + tcp


def as_tcp(capture: Path, out: Path, port: int = 2404) -> Path:
    """The same chunks (devsim header removed) as one TCP stream each way, in a raw-IPv4 capture,
    host to device ``port`` and back: built-in dissectors that only Decode As reaches
    (``-d tcp.port==2404,iec60870_101`` in tshark 4.0) read them there."""
    from devsim.transports.pcap import global_header, packet_record

    host, device = ("127.0.0.2", 50000), ("127.0.0.1", port)
    seq = {0: 1000, 1: 5000}
    out_records = [global_header()]
    for ident, (when, record) in enumerate(read_records(capture)):
        d = record[3]
        src, dst = (host, device) if d == 0 else (device, host)
        payload = record[16:]
        out_records.append(packet_record(when, _ipv4_tcp(src, dst, seq[d], seq[1 - d], payload, ident)))
        seq[d] += len(payload)
    out.write_bytes(b"".join(out_records))
    return out


class Session:
    """``devsim run KIND --pty --trace DIR/KIND.pcap [ARGS]`` in its own process: its ports by
    name (``ports["v7"]`` the pty's path), ``ctl(...)`` for ``devsim ctl`` on its control socket;
    on leaving, the process is interrupted (which closes the capture)."""

    def __init__(self, tmp_path: Path, kind: str, *args: str) -> None:
        self.capture = tmp_path / f"{kind}.pcap"
        self.control = f"unix:{tmp_path / 'control.sock'}"
        self.sim = DevsimProcess("run", kind, "--pty", "--trace", str(self.capture), "--control", self.control,
                                 *args)
        self.ports: dict[str, str] = {}

    def __enter__(self) -> Session:
        seen: list[str] = []
        self.sim.next_match(self.sim.out, lambda line: line.endswith(": ready"), 30,
                            "the ready line", seen)
        for line in seen:
            match = re.match(r"\s*(\S+): pty (\S+)", line)
            if match:
                self.ports[match[1]] = match[2]
        assert self.ports, seen
        return self

    def ctl(self, *args: str) -> str:
        result = subprocess.run([sys.executable, "-m", "devsim", "ctl", "--control", self.control, *args],
                                capture_output=True, text=True, timeout=30, env=devsim_env(), cwd=ROOT, check=False)
        assert result.returncode == 0, result.stderr
        return result.stdout

    def __exit__(self, *exc: object) -> None:
        assert self.sim.interrupt() == 0
