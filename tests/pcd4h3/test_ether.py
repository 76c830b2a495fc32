"""Ether-S-Bus on real UDP and TCP ports (spec pcd4h3.md §9.3, §9.4 EV1–EV14), and the UDP
traffic as a .pcap that Wireshark's own S-Bus dissector (tshark) decodes."""

from __future__ import annotations

import socket
import subprocess
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from devsim.scenario.plant import plant_running
from devsim.scenario.schema import PlantSpec
from tests.pcd4h3.helpers import EXAMPLE, hexbytes
from tests.transports.test_pcap import tshark

EV = {
    "EV1": ("00 00 00 14 01 00 00 01 00 01 0E 05 00 CF 00 00 03 E8 05 B1", "00 00 00 0D 01 00 00 01 02 00 00 F6 D1"),
    "EV2": ("00 00 00 12 01 00 00 01 00 01 0B 03 00 CF 00 01 FB D2", "00 00 00 0D 01 00 00 01 02 00 00 F6 D1"),
    "EV3": ("00 00 00 12 01 00 00 01 00 01 0B 03 00 E4 00 01 8D E5", "00 00 00 0D 01 00 00 01 02 00 00 F6 D1"),
    "EV4": ("00 00 00 10 01 00 00 01 00 01 02 04 00 C8 41 A4", "00 00 00 0C 01 00 00 01 01 01 03 EB"),
    "EV14": ("00 00 00 0D 01 00 00 01 00 01 1B 08 DA", "00 00 00 0C 01 00 00 01 01 52 69 7D"),
}
EV6 = ("00 00 00 10 01 00 00 01 00 01 06 00 00 D5 94 09", "00 00 00 0F 01 00 00 01 01 00 00 03 E8 7B 16")
NAK = "00 00 00 0D 01 00 00 01 02 00 01 E6 F0"


def spec(**config: Any) -> PlantSpec:
    return PlantSpec.parse({"devices": [{"name": "pcd", "kind": "pcd4h3", "config": {**EXAMPLE, **config}}]})


@pytest.fixture
def plant() -> Iterator[Any]:
    with plant_running(spec(), virtual=True) as running:
        yield running


def address(url: str) -> tuple[str, int]:
    host, _, number = url.partition("://")[2].rpartition(":")
    return host, int(number)


def udp(url: str, request: bytes) -> bytes:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
        sock.settimeout(5)
        sock.sendto(request, address(url))
        return sock.recv(1024)


def test_the_ether_ports_default_to_udp_and_tcp(plant: Any) -> None:
    assert plant.kinds["pcd.ether_udp"] == "udp" and plant.kinds["pcd.ether_tcp"] == "tcp"
    assert plant.kinds["pcd.sbus"] == "pty"


@pytest.mark.parametrize("name", list(EV))
def test_ether_vectors_over_udp(plant: Any, name: str) -> None:
    request, reply = EV[name]
    assert udp(plant.port("pcd.ether_udp"), hexbytes(request)) == hexbytes(reply)


def test_ev6_after_example_1_and_nak_over_udp(plant: Any) -> None:
    url = plant.port("pcd.ether_udp")
    for name in ("EV1", "EV2", "EV3"):
        udp(url, hexbytes(EV[name][0]))
    assert plant.runtime.run_until(lambda: plant.runtime.read("pcd", "axis.1.OnDest") is False, 1.0)
    assert plant.runtime.run_until(lambda: plant.runtime.read("pcd", "axis.1.OnDest") is True, 8.0)
    plant.runtime.set("pcd", "axis.1.FRdAP", True)
    plant.runtime.advance(0.5)
    assert udp(url, hexbytes(EV6[0])) == hexbytes(EV6[1])
    unsupported = hexbytes("00 00 00 0D 01 00 00 01 00 01 47")
    from devsim.devices.pcd4h3.sbus import crc16

    assert udp(url, unsupported + crc16(unsupported).to_bytes(2, "big")) == hexbytes(NAK)


def _framed(body: str) -> bytes:
    """An Ether-S-Bus request, sequence 1, station 1: its length field and CRC made here."""
    from devsim.devices.pcd4h3.sbus import crc16

    payload = hexbytes(body)
    frame = (9 + len(payload) + 2).to_bytes(4, "big") + hexbytes("01 00 00 01 00") + payload
    return frame + crc16(frame).to_bytes(2, "big")


@pytest.mark.parametrize("body", [
    "01 0E 05 00 CF 00 00 00 02 00 00 00 03",  # the count says one register, the data are two
    "01 0E 09 00 CF 00 00 00 01",  # the count says two registers, the data are one
    "01 0B 04 00 E4 00 01",  # the count says one more byte than the flag's
    "01 43 00",  # stop, with a byte after it
])
def test_a_telegram_whose_count_disagrees_with_its_data_gets_nak_and_does_nothing(plant: Any, body: str) -> None:
    """§9.2 (spec): a valid telegram with a bad count is NAK 0001h.  A write of one register that
    carried two was acknowledged and wrote both; a stop with a byte after it stopped the PCD."""
    url = plant.port("pcd.ether_udp")
    before = [plant.runtime.read("pcd", name) for name in ("R.207", "R.208", "F.228")]
    assert udp(url, _framed(body)) == hexbytes(NAK)
    assert [plant.runtime.read("pcd", name) for name in ("R.207", "R.208", "F.228")] == before
    assert udp(url, hexbytes(EV["EV14"][0])) == hexbytes(EV["EV14"][1])  # status: still running


def test_broken_datagrams_get_silence_and_the_next_one_an_answer(plant: Any) -> None:
    url = plant.port("pcd.ether_udp")
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
        sock.settimeout(0.3)
        bad_crc = bytearray(hexbytes(EV["EV14"][0]))
        bad_crc[-1] ^= 1
        other_station = hexbytes("00 00 00 0D 01 00 00 01 00 02 1B") + b"\x00\x00"
        for junk in (b"", b"\x00", bytes(bad_crc), hexbytes(EV["EV14"][0])[:8], other_station, b"\xff" * 600):
            sock.sendto(junk, address(url))
        with pytest.raises(TimeoutError):
            sock.recv(1024)
    assert udp(url, hexbytes(EV["EV14"][0])) == hexbytes(EV["EV14"][1])


def test_ether_vectors_over_tcp_back_to_back(plant: Any) -> None:
    """Two telegrams in one segment and one split in two: answered in order (§9.3)."""
    with socket.create_connection(address(plant.port("pcd.ether_tcp")), timeout=5) as sock:
        first, second = hexbytes(EV["EV1"][0]), hexbytes(EV["EV14"][0])
        sock.sendall(first + second[:5])
        sock.sendall(second[5:])
        expected = hexbytes(EV["EV1"][1]) + hexbytes(EV["EV14"][1])
        got = b""
        while len(got) < len(expected):
            chunk = sock.recv(1024)
            assert chunk, got
            got += chunk
        assert got == expected


def test_the_answer_leaves_after_the_response_delay() -> None:
    """Real time, the default 2 ms delay (§9.2): the answer comes, not before the delay."""
    import time

    with plant_running(spec(response_delay_ms=50), virtual=False) as running:
        start = time.monotonic()
        assert udp(running.port("pcd.ether_udp"), hexbytes(EV["EV14"][0])) == hexbytes(EV["EV14"][1])
        assert time.monotonic() - start >= 0.045


def test_tshark_decodes_the_udp_trace(tmp_path: Path) -> None:
    program = tshark()
    with plant_running(spec(), virtual=True, trace_dir=tmp_path, trace_format="pcap") as running:
        url = running.port("pcd.ether_udp")
        assert udp(url, hexbytes(EV["EV1"][0])) == hexbytes(EV["EV1"][1])
        assert udp(url, hexbytes(EV6[0])) == hexbytes("00 00 00 0F 01 00 00 01 01 00 00 00 00 52 63")
    path = tmp_path / "pcd.ether_udp.pcap"
    fields = ["sbus.seq", "sbus.att", "sbus.destination", "sbus.cmd", "sbus.addr_RTC", "sbus.data_rtc", "sbus.nakcode",
              "sbus.crc.status"]
    result = subprocess.run(
        [program, "-r", str(path), "-d", f"udp.port=={address(url)[1]},sbus", "-T", "fields", "-E", "separator=|",
         *[arg for name in fields for arg in ("-e", name)]],
        capture_output=True, text=True, timeout=60, stdin=subprocess.DEVNULL, check=False,
    )
    assert result.returncode == 0, result.stderr
    rows = [dict(zip(fields, line.split("|"), strict=True)) for line in result.stdout.splitlines()]
    assert len(rows) == 4, result.stdout
    write, ack, read, answer = rows
    assert (write["sbus.att"], write["sbus.destination"], write["sbus.cmd"], write["sbus.addr_RTC"]) == \
        ("0x00", "1", "0x0e", "207")
    assert write["sbus.data_rtc"] == "1000"
    assert ack["sbus.att"] == "0x02" and ack["sbus.nakcode"] == "0x0000"
    assert (read["sbus.cmd"], read["sbus.addr_RTC"]) == ("0x06", "213")
    assert answer["sbus.att"] == "0x01" and answer["sbus.data_rtc"] == "0"  # RActP before any FRdAP
    assert all(row["sbus.crc.status"] == "1" for row in rows), rows  # "Good"
