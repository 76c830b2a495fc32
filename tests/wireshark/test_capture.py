"""pcap captures of every serial port of every kind in devsim's serial encapsulation (link type
USER0, a 16-byte header, docs/wireshark.md), read back by tshark: one record per chunk, the
header's direction, protocol, port and the host's line settings, device-clock timestamps, the
bytes exactly; and ``devsim plot``'s reader taking the direction from the header."""

from __future__ import annotations

import os
import signal
import struct
import subprocess
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
import serial

from devsim.core.registry import device_class
from devsim.observe.plot_data import read_pcap_trace
from devsim.runtime import Runtime
from devsim.transports.pcap import (
    HEADER_SIZE,
    LINKTYPE_USER0,
    PROTOCOLS,
    SerialPcapTracer,
    parse_serial_header,
    serial_header,
    serial_record,
)
from devsim.transports.pty import PtyTransport
from tests.support.process import wait_until
from tests.support.programs import needs_program

#: Every serial port of every kind, what a host sends there, whether the device answers it.
CASES: list[tuple[str, str, bytes, bool]] = [
    ("sers", "main", b"#RF\r", True),  # a SERS statement: "#RF\r\nok0\n\r"
    ("gms96", "main", bytes.fromhex("10 01 03 04 16"), True),  # an FT1.2 short frame to card 3: status
    ("poselesta", "v6", b"%\r\nN10 X1\r\n", False),
    ("poselesta", "v7", b"%\r\nN20 Y2\r\n", False),
    ("poselesta", "v8", b"K", False),
    ("ip247", "pg", b"\x02", True),  # AS511: STX, the module answers DLE ACK
    ("pcd4h3", "sbus", bytes.fromhex("b5 00 06 00 00 00 00"), False),
]

#: The protocol byte each kind's serial ports declare (docs/wireshark.md).
KIND_PROTOCOLS = {"sers": 1, "gms96": 2, "poselesta": 3, "ip247": 4, "pcd4h3": 5, "modbus_rtu": 16}


def end_session(proc: subprocess.Popen[str]) -> None:
    """End a program started with ``start_new_session=True`` and all it started (tshark's dumpcap
    and the extcap hold its pipes: killing tshark alone would leave ``communicate`` waiting for
    them), then reap it."""
    try:
        os.killpg(proc.pid, signal.SIGKILL)
    except ProcessLookupError:
        pass  # the whole session has ended already
    if proc.stdout is not None and not proc.stdout.closed:
        proc.communicate(timeout=30)
    else:
        proc.wait(timeout=30)


def tshark_env(home: Path) -> dict[str, str]:
    """tshark's environment with its personal configuration and plugins under ``home`` (never
    the user's own)."""
    env = dict(os.environ)
    env.update(HOME=str(home), XDG_CONFIG_HOME=str(home / ".config"), WIRESHARK_CONFIG_DIR=str(home / ".config"
                                                                                            / "wireshark"))
    return env


def tshark_records(path: Path, home: Path, *options: str) -> list[tuple[float, bytes]]:
    """``(time, bytes)`` of every record tshark reads in ``path`` (the devsim header included: with
    no dissector for USER0 configured, tshark shows the whole record as data)."""
    program = needs_program("tshark")
    result = subprocess.run(
        [program, "-r", str(path), *options, "-T", "fields", "-E", "separator=|", "-e", "frame.time_epoch",
         "-e", "frame.len", "-e", "frame.protocols", "-e", "data"],
        capture_output=True, text=True, timeout=60, stdin=subprocess.DEVNULL, check=False, env=tshark_env(home),
    )
    assert result.returncode == 0, result.stderr
    records = []
    for line in result.stdout.splitlines():
        when, length, protocols, data = line.split("|")
        assert protocols == "user_dlt:data" and len(data) == 2 * int(length), line
        records.append((float(when), bytes.fromhex(data)))
    return records


# -- the pure codec ----------------------------------------------------------------------------
def test_the_header_is_the_fixed_encapsulation() -> None:
    header = serial_header("D>H", KIND_PROTOCOLS["gms96"], 0, 9600, 8, "E", 1, True)
    assert header == bytes.fromhex("6473 01 01 02 00 00002580 08 45 0a 01 0000")
    assert len(header) == HEADER_SIZE == 16 and LINKTYPE_USER0 == 147
    assert serial_header("H>D", 3, 7, 0, 0, "", 0, False) == bytes.fromhex("6473 01 00 03 07 00000000 00 00 00 00 0000")
    assert serial_header("H>D", 1, 0, 19200, 7, "O", 1.5, False)[10:13] == bytes([7, ord("O"), 15])
    assert PROTOCOLS == {"unknown": 0, "SERS": 1, "GMS96": 2, "POSELESTA": 3, "IP247 PG": 4, "PCD4.H3 S-Bus": 5,
                         "Modbus RTU": 16}
    assert parse_serial_header(header) == {"direction": "D>H", "protocol": 2, "port": 0, "baud": 9600, "bits": 8,
                                           "parity": "E", "stop": 1.0, "mismatch": True}
    for wrong in ({"direction": "X"}, {"parity": "Q"}, {"baud": -1}, {"bits": 9}, {"protocol": 256}):
        args: dict[str, Any] = {"direction": "H>D", "protocol": 1, "port": 0, "baud": 9600, "bits": 8, "parity": "N",
                                "stop": 1, "mismatch": False, **wrong}
        with pytest.raises(ValueError):
            serial_header(**args)
    with pytest.raises(ValueError, match="not a devsim serial header"):
        parse_serial_header(b"xx" + header[2:])


def test_a_record_is_the_header_and_the_bytes() -> None:
    header = serial_header("H>D", 1, 0, 9600, 8, "N", 1, False)
    record = serial_record(12.3456789, header, b"#RF\r")
    assert struct.unpack("<IIII", record[:16]) == (12, 345679, 20, 20) and record[16:] == header + b"#RF\r"
    with pytest.raises(ValueError, match="at most 65535"):
        serial_record(0, header, bytes(65535 - 15))


def test_the_tracer_writes_one_record_per_chunk_with_the_settings_of_the_moment(tmp_path: Path) -> None:
    state = {"baud": 9600, "bits": 8, "parity": "E", "stop": 1.0, "mismatch": False}
    with SerialPcapTracer(tmp_path / "t.pcap", protocol=3, port=7, settings=lambda: dict(state)) as tracer:
        tracer.record("H>D", b"%\r\n", 1.5)
        state.update(baud=4800, mismatch=True)
        tracer.record("D>H", b"\x13", 1.75)
        tracer.record("D>H", b"", 1.8)  # nothing crossed: no record
        tracer.note("host settings 4800 8E1", 1.9)  # not data: left out
        tracer.record("H>D", bytes(70000), 2.0)  # more than one record holds
    raw = (tmp_path / "t.pcap").read_bytes()
    assert struct.unpack("<IHHiIII", raw[:24]) == (0xA1B2C3D4, 2, 4, 0, 0, 65535, 147)
    traffic = read_pcap_trace(tmp_path / "t.pcap")
    assert [(t, d, len(b)) for t, d, b in traffic.chunks] == [
        (1.5, "H>D", 3), (1.75, "D>H", 1), (2.0, "H>D", 65535 - 16), (2.0, "H>D", 70000 - 65519)]
    second = raw[24 + 16 + 16 + 3 :]
    assert parse_serial_header(second[16:32])["baud"] == 4800 and second[16 + 13] == 1
    with pytest.raises(ValueError, match="direction"):
        SerialPcapTracer(tmp_path / "u.pcap").record("X", b"x", 0.0)


# -- every kind, through a real pty ------------------------------------------------------------
class Served:
    """One port of a device on a pty, traced as pcap, with a pyserial host."""

    def __init__(self, tmp_path: Path, kind: str, port: str, **host: Any) -> None:
        self.runtime = Runtime(virtual=True).start()
        self.trace = tmp_path / f"{kind}.{port}.pcap"
        self.device = self.runtime.add_device(kind, kind)
        self.transport = PtyTransport()
        self.line = self.runtime.serve_sync(self.device, self.transport, port=port, trace=self.trace)
        self.settings = self.runtime.call(lambda: self.line.device_settings)
        baud = host.pop("baudrate", self.settings.baudrate)
        self.host = serial.Serial(self.transport.address, baudrate=baud, stopbits=self.settings.stopbits,
                                  timeout=0.05, **host)

    def send(self, data: bytes) -> None:
        before = self.runtime.call(lambda: self.line.bytes_in)
        self.host.write(data)
        self.host.flush()
        wait_until(lambda: self.runtime.call(lambda: self.line.bytes_in) >= before + len(data), "bytes at the device")

    def answer(self, timeout: float = 2.0) -> bytes:
        """What the host reads until the line has delivered all the device sent."""
        got = bytearray()
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            got += self.host.read(256)
            if got and len(got) >= self.runtime.call(lambda: self.line.bytes_delivered):
                break
        return bytes(got)

    def close(self) -> None:
        self.host.close()
        self.runtime.stop()


@pytest.fixture
def served(tmp_path: Path) -> Iterator[Any]:
    made: list[Served] = []

    def make(kind: str, port: str, **host: Any) -> Served:
        made.append(Served(tmp_path, kind, port, **host))
        return made[-1]

    yield make
    for one in made:
        one.close()


@pytest.mark.parametrize(("kind", "port", "request_bytes", "answers"), CASES, ids=[f"{k}.{p}" for k, p, _, _ in CASES])
def test_tshark_reads_every_serial_port_of_every_kind(served: Any, tmp_path: Path, kind: str, port: str,
                                                        request_bytes: bytes, answers: bool) -> None:
    tag = next(p for p in device_class(kind).ports if p.name == port).capture
    assert tag is not None and tag.protocol == KIND_PROTOCOLS[kind]
    assert tag.port == (int(port[1:]) if kind == "poselesta" else 0)
    one = served(kind, port)
    now = one.runtime.advance(3.25)  # past every kind's power-on; the records carry the device clock's time
    one.send(request_bytes)
    one.runtime.advance(0.5)  # time for the answer
    answer = one.answer() if answers else b""
    assert bool(answer) == answers
    one.close()

    records = tshark_records(one.trace, tmp_path)
    headers = [parse_serial_header(data) for _, data in records]
    sent = b"".join(data[16:] for (_, data), h in zip(records, headers, strict=True) if h["direction"] == "H>D")
    received = b"".join(data[16:] for (_, data), h in zip(records, headers, strict=True) if h["direction"] == "D>H")
    assert (sent, received) == (request_bytes, answer)
    assert records[0][0] == pytest.approx(now, abs=1e-6)  # the first chunk: when the device clock said now
    settings = one.settings
    seen = one.transport.frame_visible
    for header in headers:
        assert (header["protocol"], header["port"]) == (tag.protocol, tag.port)
        assert (header["baud"], header["stop"], header["mismatch"]) == (settings.baudrate, settings.stopbits, False)
        assert (header["bits"], header["parity"]) == ((settings.bytesize, settings.parity) if seen else (0, ""))


def test_a_host_at_another_baud_rate_is_flagged_a_mismatch(served: Any, tmp_path: Path) -> None:
    one = served("gms96", "main", baudrate=4800)  # the card runs at 9600
    assert one.settings.baudrate == 9600
    one.send(bytes.fromhex("10 01 03 04 16"))
    one.close()
    records = tshark_records(one.trace, tmp_path)
    assert len(records) == 1  # the card read garbage and kept silent
    header = parse_serial_header(records[0][1])
    assert (header["direction"], header["baud"], header["mismatch"]) == ("H>D", 4800, True)
    assert records[0][1][16:] == bytes.fromhex("10 01 03 04 16")  # the bytes the host sent


def test_the_ether_s_bus_ports_stay_ipv4(served: Any, tmp_path: Path) -> None:
    from devsim.transports.udp import UdpTransport

    runtime = Runtime(virtual=True).start()
    try:
        device = runtime.add_device("pcd4h3", "pcd")
        runtime.serve_sync(device, UdpTransport(), port="ether_udp", trace=tmp_path / "ether.pcap")
    finally:
        runtime.stop()
    assert struct.unpack("<I", (tmp_path / "ether.pcap").read_bytes()[20:24]) == (228,)


def test_over_rfc_2217_the_header_carries_all_four_settings(tmp_path: Path) -> None:
    """An RFC 2217 client sends data bits and parity too (a pty hides them): the IP247 PG port's
    9600 8E1 in every record, a host at 8N1 flagged as a mismatch."""
    from devsim.transports.rfc2217 import Rfc2217Transport

    runtime = Runtime(virtual=True).start()
    try:
        device = runtime.add_device("ip247", "ip")
        transport = Rfc2217Transport()
        line = runtime.serve_sync(device, transport, port="pg", trace=tmp_path / "pg.pcap")
        for parity in ("E", "N"):
            host = serial.serial_for_url(transport.url, baudrate=9600, parity=parity, timeout=2)
            try:
                wait_until(lambda p=parity: getattr(runtime.call(lambda: line.host), "parity", None) == p,
                          "the host's settings at the device")
                before = runtime.call(lambda: line.bytes_in)
                host.write(b"\x02")
                wait_until(lambda b=before: runtime.call(lambda: line.bytes_in) > b, "the STX at the device")
            finally:
                host.close()
    finally:
        runtime.stop()
    sent = [parse_serial_header(data) for _, data in tshark_records(tmp_path / "pg.pcap", tmp_path)
            if data[3] == 0]
    assert [(h["baud"], h["bits"], h["parity"], h["stop"], h["mismatch"]) for h in sent] == [
        (9600, 8, "E", 1.0, False), (9600, 8, "N", 1.0, True)]


def test_devsim_plot_decodes_a_serial_capture_by_its_capture_tag(tmp_path: Path) -> None:
    from devsim.observe.plot_data import load, messages
    from devsim.transports.trace import Source

    with SerialPcapTracer(tmp_path / "card.pcap", protocol=2) as tracer:
        tracer.record("H>D", bytes.fromhex("10 01 03 04 16"), 1.0)
        tracer.record("D>H", bytes.fromhex("10 40 03 43 16"), 1.01)
    traffic = load(tmp_path / "card.pcap")
    assert traffic.source == Source(("card",), "main", "gms96") and traffic.label == "card main"
    assert [(t, d) for t, d, _ in messages(traffic)] == [(1.0, "H>D"), (1.01, "D>H")]
    with SerialPcapTracer(tmp_path / "rtu.pcap", protocol=16) as tracer:
        tracer.record("H>D", bytes.fromhex("01 03 00 00 00 01 84 0a"), 1.0)
    rtu = load(tmp_path / "rtu.pcap")
    assert rtu.source is None and messages(rtu) == [] and len(rtu.chunks) == 1  # no kind declares 16
