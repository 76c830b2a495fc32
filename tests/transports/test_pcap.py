"""pcap traces: the packet bytes (parsed back here with struct), the writer, the runtime's
choice by suffix, and what tshark (Wireshark's decoder) makes of a real Ether-S-Bus exchange."""

from __future__ import annotations

import socket
import struct
import subprocess
from pathlib import Path

import pytest

from devsim.runtime import Runtime
from devsim.transports.pcap import (
    LINKTYPE_IPV4,
    MAX_PAYLOAD,
    PcapTracer,
    checksum,
    global_header,
    invented_port,
    ipv4_udp_packet,
    packet_record,
)
from devsim.transports.trace import Tracer
from devsim.transports.tracing import open_trace
from devsim.transports.udp import UdpTransport
from tests.support.programs import needs_program

REQUEST = bytes.fromhex("00000010 01 00 0001 00 01 06 00 00D5 9409")
REPLY = bytes.fromhex("0000000F 01 00 0001 01 000003E8 7B16")
ETHERBUS = "etherbus=tests.support.etherbus:EtherBusDevice"


def _sum16(data: bytes) -> int:
    data += b"\0" * (len(data) % 2)
    total = sum(struct.unpack(f"!{len(data) // 2}H", data))
    while total >> 16:
        total = (total & 0xFFFF) + (total >> 16)
    return total


def parse_packet(packet: bytes) -> tuple[tuple[str, int], tuple[str, int], bytes]:
    """(source, destination, payload) of one IPv4/UDP packet; checks lengths and checksums."""
    version_ihl, _tos, total, _ident, flags, ttl, proto, _sum, src, dst = struct.unpack("!BBHHHBBH4s4s", packet[:20])
    assert version_ihl == 0x45 and proto == 17 and ttl == 64 and flags == 0x4000
    assert total == len(packet)
    assert _sum16(packet[:20]) == 0xFFFF  # a valid header checksum sums to all ones
    sport, dport, length, udp_sum = struct.unpack("!HHHH", packet[20:28])
    assert length == len(packet) - 20
    if udp_sum:
        pseudo = src + dst + struct.pack("!BBH", 0, 17, length)
        assert _sum16(pseudo + packet[20:]) == 0xFFFF
    return (socket.inet_ntoa(src), sport), (socket.inet_ntoa(dst), dport), packet[28:]


def read_pcap(path: Path) -> list[tuple[float, tuple[str, int], tuple[str, int], bytes]]:
    """Every packet of a classic little-endian microsecond pcap file of raw IPv4."""
    data = path.read_bytes()
    magic, major, minor, _zone, _sigfigs, snaplen, linktype = struct.unpack("<IHHiIII", data[:24])
    assert (magic, major, minor, snaplen, linktype) == (0xA1B2C3D4, 2, 4, 65535, 228)
    packets, offset = [], 24
    while offset < len(data):
        seconds, micros, caplen, origlen = struct.unpack("<IIII", data[offset : offset + 16])
        assert caplen == origlen and micros < 1_000_000
        packet = data[offset + 16 : offset + 16 + caplen]
        offset += 16 + caplen
        packets.append((seconds + micros / 1e6, *parse_packet(packet)))
    return packets


# -- pure packet building --------------------------------------------------------------------
def test_checksum_is_rfc_1071() -> None:
    # the example of RFC 1071 section 3: words 0001 f203 f4f5 f6f7 sum to ddf2 (one's complement)
    assert checksum(bytes.fromhex("0001f203f4f5f6f7")) == 0xFFFF - 0xDDF2
    assert checksum(b"\x01") == 0xFFFF - 0x0100  # odd length: padded


def test_one_packet_is_a_valid_ipv4_udp_datagram() -> None:
    packet = ipv4_udp_packet(("127.0.0.1", 40000), ("10.1.2.3", 5050), REQUEST, ident=7)
    assert len(packet) == 20 + 8 + len(REQUEST)
    assert parse_packet(packet) == (("127.0.0.1", 40000), ("10.1.2.3", 5050), REQUEST)
    assert struct.unpack("!H", packet[4:6])[0] == 7
    assert ipv4_udp_packet(("127.0.0.1", 1), ("127.0.0.1", 2), b"")[-8:] != b""  # empty payload: header only


def test_a_payload_too_big_for_one_datagram_is_refused() -> None:
    with pytest.raises(ValueError, match="at most 65507"):
        ipv4_udp_packet(("127.0.0.1", 1), ("127.0.0.1", 2), bytes(MAX_PAYLOAD + 1))


def test_headers() -> None:
    assert global_header() == bytes.fromhex("d4c3b2a1 0200 0400 00000000 00000000 ffff0000 e4000000")
    assert LINKTYPE_IPV4 == 228
    record = packet_record(12.3456789, b"abc")
    assert struct.unpack("<IIII", record[:16]) == (12, 345679, 3, 3) and record[16:] == b"abc"
    assert struct.unpack("<II", packet_record(0.9999999, b"")[:8]) == (1, 0)  # rounds into the next second


def test_invented_ports_are_stable_and_in_the_dynamic_range() -> None:
    assert invented_port("pcd.sbus") == invented_port("pcd.sbus")
    assert invented_port("pcd.sbus") != invented_port("pcd.ether_udp")
    assert all(49152 <= invented_port(name) <= 65535 for name in ("a", "b", "sers", "cnc.v7"))


# -- the writer ------------------------------------------------------------------------------
def test_the_tracer_writes_what_it_is_given_between_the_peers(tmp_path: Path) -> None:
    peers = (("127.0.0.1", 40000), ("127.0.0.1", 5050))
    with PcapTracer(tmp_path / "t.pcap", peers=lambda: peers) as tracer:
        tracer.record("H>D", REQUEST, 1.5)
        tracer.note("host settings 9600 8N1", 1.6)  # no place in pcap: left out
        tracer.record("D>H", REPLY, 1.502)
        tracer.record("D>H", b"", 1.6)
        with pytest.raises(ValueError, match="direction"):
            tracer.record("X", b"x", 1.7)
    assert read_pcap(tmp_path / "t.pcap") == [
        (1.5, peers[0], peers[1], REQUEST),
        (1.502, peers[1], peers[0], REPLY),
    ]


def test_unknown_or_ipv6_peers_get_invented_loopback_addresses(tmp_path: Path) -> None:
    known: list[tuple[tuple[str, int], tuple[str, int]] | None] = [None]
    with PcapTracer(tmp_path / "t.pcap", peers=lambda: known[0], name="dev.sbus") as tracer:
        tracer.record("H>D", b"a", 0.0)
        known[0] = (("::1", 40000), ("::1", 5050))
        tracer.record("D>H", b"b", 0.0)
    port = invented_port("dev.sbus")
    assert [p[1:] for p in read_pcap(tmp_path / "t.pcap")] == [
        (("127.0.0.2", port), ("127.0.0.1", port), b"a"),
        (("127.0.0.1", 5050), ("127.0.0.2", 40000), b"b"),
    ]


def test_a_big_chunk_becomes_several_packets(tmp_path: Path) -> None:
    data = bytes(range(256)) * 300  # 76800 bytes
    with PcapTracer(tmp_path / "big.pcap") as tracer:
        tracer.record("H>D", data, 2.0)
    packets = read_pcap(tmp_path / "big.pcap")
    assert [len(p[3]) for p in packets] == [MAX_PAYLOAD, len(data) - MAX_PAYLOAD]
    assert b"".join(p[3] for p in packets) == data


def test_the_factory_picks_the_form_by_suffix(tmp_path: Path) -> None:
    pcap, text, upper = open_trace(tmp_path / "a.pcap"), open_trace(tmp_path / "a.trace"), open_trace(tmp_path / "B.PCAP")
    try:
        assert isinstance(pcap, PcapTracer) and isinstance(upper, PcapTracer) and isinstance(text, Tracer)
    finally:
        for tracer in (pcap, text, upper):
            tracer.close()


def test_a_pcap_trace_never_truncates_through_a_symlink(tmp_path: Path) -> None:
    precious = tmp_path / "precious.txt"
    precious.write_text("keep me\n")
    (tmp_path / "line.pcap").symlink_to(precious)
    with pytest.raises(OSError, match="refusing to write a trace through the symlink"):
        open_trace(tmp_path / "line.pcap")
    assert precious.read_text() == "keep me\n"


def test_an_old_pcap_file_is_truncated(tmp_path: Path) -> None:
    old = tmp_path / "x.pcap"
    old.write_bytes(b"old run" * 100)
    PcapTracer(old).close()
    assert old.read_bytes() == global_header()


# -- through the runtime, and tshark -----------------------------------------------------------
def _exchange(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> tuple[Path, int, tuple[str, int]]:
    """A real UDP port with a device that answers Ether-S-Bus; one request and its answer, the
    runtime writing ``ether.pcap``.  Returns the file, the device's port and the client's address."""
    monkeypatch.setenv("DEVSIM_EXTRA_KINDS", ETHERBUS)
    runtime = Runtime(virtual=True).start()
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sock.settimeout(3)
    sock.bind(("127.0.0.1", 0))
    path = tmp_path / "ether.pcap"
    try:
        device = runtime.add_device("etherbus", "pcd")
        port = UdpTransport()
        runtime.serve_sync(device, port, port="ether", trace=path)
        runtime.advance(2.25)  # the packets carry the device clock's time
        sock.sendto(REQUEST, ("127.0.0.1", port.port))
        assert sock.recv(100) == REPLY
        return path, port.port, sock.getsockname()
    finally:
        sock.close()
        runtime.stop()


def test_the_runtime_writes_a_pcap_trace_with_the_real_udp_peers(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    path, number, me = _exchange(tmp_path, monkeypatch)
    device = ("127.0.0.1", number)
    assert read_pcap(path) == [(2.25, me, device, REQUEST), (2.25, device, me, REPLY)]


def tshark() -> str:
    """tshark's path: the pcap traces are checked with Wireshark's own decoder (skipped where it
    is missing, a failure under CI=true: tests/support/programs.py)."""
    return needs_program("tshark")


def test_tshark_decodes_the_trace_as_ether_s_bus(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    program = tshark()
    path, number, _me = _exchange(tmp_path, monkeypatch)
    fields = ["ip.checksum.status", "udp.checksum.status", "sbus.len", "sbus.vers", "sbus.seq", "sbus.att",
              "sbus.cmd", "sbus.rcount", "sbus.addr_RTC", "sbus.data_rtc", "sbus.crc", "sbus.crc.status"]
    result = subprocess.run(
        [program, "-r", str(path), "-d", f"udp.port=={number},sbus",
         "-o", "ip.check_checksum:TRUE", "-o", "udp.check_checksum:TRUE",
         "-T", "fields", "-E", "separator=|", *[arg for name in fields for arg in ("-e", name)]],
        capture_output=True, text=True, timeout=60, stdin=subprocess.DEVNULL, check=False,
    )
    assert result.returncode == 0, result.stderr
    rows = [dict(zip(fields, line.split("|"), strict=True)) for line in result.stdout.splitlines()]
    assert len(rows) == 2, result.stdout
    request, reply = rows
    good = {"ip.checksum.status": "1", "udp.checksum.status": "1", "sbus.crc.status": "1"}
    assert {k: request[k] for k in good} == good and {k: reply[k] for k in good} == good
    assert (request["sbus.len"], request["sbus.vers"], request["sbus.seq"], request["sbus.att"]) == ("16", "1", "1", "0x00")
    assert (request["sbus.cmd"], request["sbus.rcount"], request["sbus.addr_RTC"]) == ("0x06", "1", "213")
    assert request["sbus.crc"] == "0x9409"
    assert (reply["sbus.len"], reply["sbus.seq"], reply["sbus.att"]) == ("15", "1", "0x01")
    assert (reply["sbus.data_rtc"], reply["sbus.crc"]) == ("1000", "0x7b16")
