"""The pcap records (devsim.transports.pcap) at their limits, by property, against the rules
written here as small oracles: the Internet checksum (RFC 1071) as a sum modulo 65535, the
IPv4/UDP packet of RFC 791/768 (a UDP payload of at most 65,507 bytes; a computed checksum of 0
sent as FFFFh), the libpcap record header (microseconds, never negative), and the 16-byte devsim
header of a serial record (docs/wireshark.md: every field's range, both directions)."""

from __future__ import annotations

import math
import struct
import zlib
from pathlib import Path

import hypothesis.strategies as hs
import pytest
from hypothesis import example, given, settings

from devsim.transports import pcap


def _ones_complement_sum(data: bytes) -> int:
    """RFC 1071 §1: the one's complement sum of the 16-bit words, as a sum modulo 65535 (all ones
    for a non-zero multiple)."""
    if len(data) % 2:
        data += b"\0"
    total = sum(int.from_bytes(data[i : i + 2], "big") for i in range(0, len(data), 2))
    if total == 0:
        return 0
    return total % 0xFFFF or 0xFFFF


@settings(deadline=None)  # the longest example takes a while where a mutation tool traces every line
@given(hs.binary(max_size=64))
@example(b"")
@example(b"\xff")
@example(b"\xff\xff" * 40_000)  # the sum carries out of 16 bits many times over
@example(b"\x00\x01\xff\xff")
@example(b"\x01")  # an odd length is padded with a zero byte, not before
def test_the_internet_checksum(data: bytes) -> None:
    assert pcap.checksum(data) == ~_ones_complement_sum(data) & 0xFFFF


def _valid_ipv4_udp(packet: bytes, src: pcap.Address, dst: pcap.Address, payload: bytes, ident: int) -> None:
    header, udp = packet[:20], packet[20:]
    assert struct.unpack("!BBHHHBB", header[:10]) == (0x45, 0, 28 + len(payload), ident & 0xFFFF, 0x4000, 64, 17)
    assert header[12:16] == bytes(map(int, src[0].split("."))) and header[16:20] == bytes(map(int, dst[0].split(".")))
    assert _ones_complement_sum(header) == 0xFFFF  # the header checksum makes the header sum to all ones
    assert struct.unpack("!HHH", udp[:6]) == (src[1], dst[1], 8 + len(payload)) and udp[8:] == payload
    pseudo = header[12:20] + struct.pack("!BBH", 0, 17, 8 + len(payload))
    assert udp[6:8] != b"\0\0" and _ones_complement_sum(pseudo + udp) == 0xFFFF


@given(src=hs.tuples(hs.sampled_from(["127.0.0.2", "10.1.2.3", "255.255.255.255", "0.0.0.0"]), hs.integers(0, 65535)),
       dst=hs.tuples(hs.sampled_from(["127.0.0.1", "192.168.0.200"]), hs.integers(0, 65535)),
       payload=hs.binary(max_size=40), ident=hs.sampled_from([0, 1, 0xFFFF, 0x10000, 0x12345]))
def test_an_ipv4_udp_packet_of_every_field(src: pcap.Address, dst: pcap.Address, payload: bytes, ident: int) -> None:
    _valid_ipv4_udp(pcap.ipv4_udp_packet(src, dst, payload, ident), src, dst, payload, ident)


def test_a_udp_checksum_of_zero_is_sent_as_ffff() -> None:
    src, dst = ("127.0.0.2", 1), ("127.0.0.1", 2)
    pseudo = bytes((127, 0, 0, 2, 127, 0, 0, 1)) + struct.pack("!BBH", 0, 17, 10)
    for word in range(65536):  # the payload word whose packet sums to all ones: checksum 0
        if _ones_complement_sum(pseudo + struct.pack("!HHHHH", 1, 2, 10, 0, word)) == 0xFFFF:
            break
    packet = pcap.ipv4_udp_packet(src, dst, word.to_bytes(2, "big"))
    assert packet[26:28] == b"\xff\xff"  # 0 would say "no checksum" (RFC 768)


def test_a_udp_payload_of_65507_bytes_is_the_most() -> None:
    assert pcap.MAX_PAYLOAD == 65_507
    packet = pcap.ipv4_udp_packet(("127.0.0.2", 1), ("127.0.0.1", 2), b"\xab" * 65_507)
    assert len(packet) == 65_535 and packet[2:4] == b"\xff\xff" and packet[4:6] == b"\0\0"  # identification 0
    with pytest.raises(ValueError, match="at most 65507 bytes, not 65508"):
        pcap.ipv4_udp_packet(("127.0.0.2", 1), ("127.0.0.1", 2), b"\xab" * 65_508)


@pytest.mark.parametrize("linktype", [pcap.LINKTYPE_IPV4, pcap.LINKTYPE_USER0])
def test_the_global_header(linktype: int) -> None:
    assert pcap.global_header(linktype) == bytes.fromhex("d4c3b2a1 0200 0400 00000000 00000000 ffff0000") + struct.pack(
        "<I", linktype)
    assert pcap.global_header() == pcap.global_header(228)


@given(hs.one_of(hs.floats(min_value=-10, max_value=2.0**33), hs.sampled_from([math.nan, math.inf, -math.inf]),
                 hs.sampled_from([0.0, 1e-6, 0.9999994, 0.9999996, 1.0000004, 2.0**32 - 1e-6, 2.0**32, -0.0, -1e-9])),
       hs.binary(max_size=8))
def test_a_packet_record(when: float, packet: bytes) -> None:
    record = pcap.packet_record(when, packet)
    micros = round(when * 1_000_000) if math.isfinite(when) and when > 0 else 0
    assert record == struct.pack("<IIII", (micros // 1_000_000) % 2**32, micros % 1_000_000, len(packet),
                                 len(packet)) + packet


# -- the serial record's devsim header ------------------------------------------------------------
FIELDS = hs.fixed_dictionaries({
    "direction": hs.sampled_from(["H>D", "D>H"]),
    "protocol": hs.sampled_from([0, 1, 16, 255]) | hs.integers(0, 255),
    "port": hs.sampled_from([0, 6, 7, 8, 255]),
    "baud": hs.sampled_from([0, 1, 9600, 115_200, 0xFFFF_FFFF]) | hs.integers(0, 0xFFFF_FFFF),
    "bits": hs.integers(0, 8),
    "parity": hs.sampled_from(["", "N", "E", "O", "M", "S"]),
    "stop": hs.sampled_from([0, 1, 1.5, 2, 0.04, 25.5, 25.54]),
    "mismatch": hs.booleans(),
})


def _header_oracle(f: dict) -> bytes:
    """docs/wireshark.md: magic "ds", version 1, direction, protocol, port, baud (big-endian), data
    bits, parity letter, stop bits x 10, flags (bit 0 mismatch), two reserved zero bytes."""
    return (b"ds\x01" + bytes((0 if f["direction"] == "H>D" else 1, f["protocol"], f["port"]))
            + f["baud"].to_bytes(4, "big") + bytes((f["bits"], ord(f["parity"]) if f["parity"] else 0,
                                                    round(f["stop"] * 10), int(f["mismatch"]))) + b"\0\0")


@given(FIELDS)
def test_a_serial_header_both_ways(fields: dict) -> None:
    header = pcap.serial_header(**fields)
    assert len(header) == pcap.HEADER_SIZE == 16 and header == _header_oracle(fields)
    parsed = pcap.parse_serial_header(header + b"data")
    assert parsed == dict(fields, stop=round(fields["stop"] * 10) / 10)


@pytest.mark.parametrize("change, message", [
    ({"direction": "H<D"}, "direction must be 'H>D' or 'D>H', not 'H<D'"), ({"direction": ""}, "direction must be"),
    ({"parity": "X"}, "parity is one of N, E, O, M, S .or '' when not known., not 'X'"), ({"parity": "n"}, "parity"),
    ({"parity": "NE"}, "parity"),
    ({"protocol": -1}, "out of range: protocol -1, port 0, baud 9600, bits 8"), ({"protocol": 256}, "protocol 256"),
    ({"port": -1}, "port -1"), ({"port": 256}, "port 256"), ({"baud": -1}, "baud -1"), ({"baud": 2**32}, "baud 4294967296"),
    ({"bits": -1}, "bits -1"), ({"bits": 9}, "bits 9"), ({"stop": 25.56}, "stop bits out of range: 25.56"),
    ({"stop": -0.1}, "stop bits out of range: -0.1"),
])
def test_a_field_out_of_its_range_is_refused(change: dict, message: str) -> None:
    fields = {"direction": "H>D", "protocol": 1, "port": 0, "baud": 9600, "bits": 8, "parity": "E", "stop": 1,
              "mismatch": False}
    pcap.serial_header(**fields)
    with pytest.raises(ValueError, match=message):
        pcap.serial_header(**dict(fields, **change))


@pytest.mark.parametrize("stop", [math.nan, math.inf, -math.inf, 0.0, 0.04])
def test_a_stop_bit_count_not_known_is_0(stop: float) -> None:
    assert pcap.serial_header("D>H", 1, 0, 0, 0, "", stop, True)[12:14] == b"\x00\x01"


@pytest.mark.parametrize("header, problem", [
    (bytes.fromhex("6473 01 00 01 00 00002580 08 45 0a 00 0000")[:15], "16 bytes, not 15"),
    (bytes.fromhex("6474 01 00 01 00 00002580 08 45 0a 00 0000"), "not a devsim serial header"),
    (bytes.fromhex("6473 02 00 01 00 00002580 08 45 0a 00 0000"), "not a devsim serial header"),
    (bytes.fromhex("6473 00 00 01 00 00002580 08 45 0a 00 0000"), "not a devsim serial header"),
    (bytes.fromhex("6473 01 02 01 00 00002580 08 45 0a 00 0000"), "not a devsim serial header"),
])
def test_what_is_not_a_devsim_header_is_refused(header: bytes, problem: str) -> None:
    with pytest.raises(ValueError, match=problem):
        pcap.parse_serial_header(header)


@pytest.mark.parametrize("flags, mismatch", [(0x00, False), (0x01, True), (0x02, False), (0x03, True), (0xFE, False)])
def test_the_mismatch_is_bit_0_of_the_flags(flags: int, mismatch: bool) -> None:
    header = bytes.fromhex("6473 01 01 01 00 00002580 08 45 0a") + bytes((flags,)) + b"\0\0"
    assert pcap.parse_serial_header(header) == {"direction": "D>H", "protocol": 1, "port": 0, "baud": 9600,
                                                "bits": 8, "parity": "E", "stop": 1.0, "mismatch": mismatch}


def test_a_serial_record_holds_at_most_the_snap_length() -> None:
    header = pcap.serial_header("H>D", 1, 0, 0, 0, "", 0, False)
    record = pcap.serial_record(1.5, header, b"\x01" * (65_535 - 16))
    assert record[:16] == struct.pack("<IIII", 1, 500_000, 65_535, 65_535) and record[16:32] == header
    with pytest.raises(ValueError, match="at most 65535 bytes, not 65536"):
        pcap.serial_record(1.5, header, b"\x01" * (65_536 - 16))


@given(hs.text(max_size=20))
@example("")
@example("main")
def test_an_invented_port_is_in_the_dynamic_range(name: str) -> None:
    port = pcap.invented_port(name)
    assert 49_152 <= port <= 65_535 and port == 49_152 + zlib.crc32(name.encode()) % 16_384


# -- the writers ---------------------------------------------------------------------------------
def _records(path: Path, linktype: int) -> list[tuple[float, bytes]]:
    data = path.read_bytes()
    assert data[:24] == pcap.global_header(linktype)
    out, at = [], 24
    while at < len(data):
        seconds, micros, caplen, origlen = struct.unpack("<IIII", data[at : at + 16])
        assert caplen == origlen
        out.append((seconds + micros / 1e6, data[at + 16 : at + 16 + caplen]))
        at += 16 + caplen
    return out


@pytest.mark.parametrize("size, packets", [(1, 1), (65_507, 1), (65_508, 2), (2 * 65_507 + 1, 3)])
def test_a_chunk_is_cut_into_datagrams_of_65507_bytes(tmp_path: Path, size: int, packets: int) -> None:
    data = bytes(i % 253 for i in range(size))
    with pcap.PcapTracer(tmp_path / "t.pcap", peers=lambda: (("10.0.0.1", 4000), ("10.0.0.2", 5050))) as tracer:
        tracer.record("D>H", data, 2.25)
    records = _records(tmp_path / "t.pcap", pcap.LINKTYPE_IPV4)
    assert len(records) == packets and all(when == 2.25 for when, _ in records)
    for ident, (_when, packet) in enumerate(records, start=1):
        part = data[(ident - 1) * 65_507 : ident * 65_507]
        _valid_ipv4_udp(packet, ("10.0.0.2", 5050), ("10.0.0.1", 4000), part, ident)


def test_the_tracer_names_its_direction_and_writes_nothing_empty_or_closed(tmp_path: Path) -> None:
    tracer = pcap.PcapTracer(tmp_path / "t.pcap", name="main")
    assert not tracer.closed
    port = pcap.invented_port("main")
    assert tracer.addresses() == (("127.0.0.2", port), ("127.0.0.1", port))
    with pytest.raises(ValueError, match="'H>D' or 'D>H'"):
        tracer.record("<>", b"x", 0.0)
    tracer.record("H>D", b"", 0.0)
    tracer.note("a fault", 0.0)
    tracer.record("H>D", b"ab", 0.0)
    tracer.close()
    assert tracer.closed
    tracer.record("H>D", b"cd", 1.0)  # after the close: nothing, no error
    [(_when, packet)] = _records(tmp_path / "t.pcap", pcap.LINKTYPE_IPV4)
    _valid_ipv4_udp(packet, ("127.0.0.2", port), ("127.0.0.1", port), b"ab", 1)
    assert pcap.PcapTracer(tmp_path / "stem.pcap").addresses()[0][1] == pcap.invented_port("stem")


def test_ipv6_peers_keep_their_ports(tmp_path: Path) -> None:
    with pcap.PcapTracer(tmp_path / "t.pcap", peers=lambda: (("::1", 4000), ("127.0.0.1", 5050))) as tracer:
        assert tracer.addresses() == (("127.0.0.2", 4000), ("127.0.0.1", 5050))
    with pcap.PcapTracer(tmp_path / "u.pcap", peers=lambda: (("127.0.0.5", 4000), ("::1", 5050))) as tracer:
        assert tracer.addresses() == (("127.0.0.2", 4000), ("127.0.0.1", 5050))


@pytest.mark.parametrize("size, records", [(1, 1), (65_519, 1), (65_520, 2)])
def test_a_serial_chunk_is_cut_into_records_of_the_snap_length(tmp_path: Path, size: int, records: int) -> None:
    data = bytes(i % 251 for i in range(size))
    state = {"baud": 19_200, "bits": 7, "parity": "E", "stop": 2, "mismatch": True}
    with pcap.SerialPcapTracer(tmp_path / "s.pcap", protocol=2, port=7, settings=lambda: state) as tracer:
        assert not tracer.closed
        tracer.record("H>D", data, 0.5)
        tracer.note("a fault", 0.5)
    assert tracer.closed
    got = _records(tmp_path / "s.pcap", pcap.LINKTYPE_USER0)
    assert len(got) == records
    header = pcap.serial_header("H>D", 2, 7, 19_200, 7, "E", 2, True)
    assert all(when == 0.5 and packet[:16] == header for when, packet in got)
    assert b"".join(packet[16:] for _, packet in got) == data and len(got[0][1]) == min(size, 65_519) + 16


def test_a_serial_trace_without_a_line_knows_no_setting(tmp_path: Path) -> None:
    tracer = pcap.SerialPcapTracer(tmp_path / "s.pcap")
    assert tracer.header("D>H") == pcap.serial_header("D>H", 0, 0, 0, 0, "", 0, False)
    with pytest.raises(ValueError):
        tracer.record("x", b"", 0.0)  # the direction is checked even without data
    tracer.record("D>H", b"", 0.0)
    tracer.close()
    tracer.record("D>H", b"late", 0.0)
    assert _records(tmp_path / "s.pcap", pcap.LINKTYPE_USER0) == []
