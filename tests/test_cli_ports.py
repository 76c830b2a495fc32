"""`devsim run` with network ports: a kind's declared default transport (UDP), `--port NAME=SPEC`
overrides, and pcap traces per port."""

from __future__ import annotations

import socket
from collections.abc import Iterator
from pathlib import Path

import pytest
import serial
from click.testing import CliRunner

from devsim.cli import cli
from devsim.cli.serve import _trace_for
from tests.test_cli import ECHO, TWOPORT, Sim
from tests.transports.test_pcap import read_pcap

ETHERBUS = "etherbus=tests.support.etherbus:EtherBusDevice"
REQUEST = bytes.fromhex("00000010 01 00 0001 00 01 06 00 00D5 9409")
REPLY = bytes.fromhex("0000000F 01 00 0001 01 000003E8 7B16")


@pytest.fixture(autouse=True)
def _kinds(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("DEVSIM_EXTRA_KINDS", f"{ECHO},{TWOPORT},{ETHERBUS}")


@pytest.fixture
def udp_client() -> Iterator[socket.socket]:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
        sock.settimeout(10)
        sock.bind(("127.0.0.1", 0))
        yield sock


def free_udp_port() -> int:
    """A port number nobody holds now, for the test kind's declared default (not 5050, which the
    machine running the tests may use)."""
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
        sock.bind(("127.0.0.1", 0))
        return int(sock.getsockname()[1])


def ask(sock: socket.socket, url: str) -> bytes:
    scheme, _, rest = url.partition("://")
    assert scheme == "udp"
    host, _, number = rest.rpartition(":")
    sock.sendto(REQUEST, (host, int(number)))
    return sock.recv(100)


@pytest.mark.parametrize(
    ("args", "expected"),
    [
        (["--port", "nope=udp:1"], "--port: the kind has no port 'nope' (ports: serial, ether)"),
        (["--port", "ether"], "--port: expected NAME=SPEC (e.g. ether=udp:5050), got 'ether'"),
        (["--port", "ether=udp:x"], "--port ether: expected [HOST:]PORT, got 'x'"),
        (["--port", "ether=udp:70000"], "--port ether: port 70000 is not in 0..65535"),
        (["--port", "ether=serial:1"], "--port ether: expected pty, udp:[HOST:]PORT, tcp:[HOST:]PORT"),
        (["--port", "ether=pty:/tmp/x"], "--port ether: pty takes no address"),
        (["--port", "ether=udp:1", "--port", "ether=pty"], "--port: port 'ether' given twice"),
    ],
)
def test_port_option_errors_are_one_line_exit_2(args: list[str], expected: str) -> None:
    result = CliRunner().invoke(cli, ["run", "etherbus", *args], prog_name="devsim")
    assert result.exit_code == 2
    assert result.stderr.count("\n") == 1 and result.stderr.startswith("Error: ")
    assert expected in result.stderr


def test_a_declared_udp_port_is_served_on_its_default(udp_client: socket.socket) -> None:
    number = free_udp_port()
    sim = Sim("etherbus", extra_env={"DEVSIM_EXTRA_KINDS": ETHERBUS, "DEVSIM_TEST_ETHER_PORT": str(number)})
    try:
        seen = sim.read_until("etherbus.ether:")
        assert seen["etherbus.ether"] == f"udp udp://127.0.0.1:{number}"
        kind, _, path = seen["etherbus.serial"].partition(" ")
        assert kind == "pty" and path.startswith("/dev/")  # the port without a default: as before
        assert ask(udp_client, seen["etherbus.ether"].split()[1]) == REPLY
        with serial.Serial(path, 9600, timeout=5) as port:
            port.write(b"hi\r")
            assert port.read(3) == b"hi\r"
    finally:
        code, err = sim.stop()
    assert code == 0, err


def test_port_overrides_and_a_pcap_trace_per_port(udp_client: socket.socket, tmp_path: Path) -> None:
    trace = tmp_path / "line.pcap"
    sim = Sim("etherbus", "--port", "ether=udp:127.0.0.1:0", "--port", "serial=tcp:0", "--trace", str(trace),
              extra_env={"DEVSIM_EXTRA_KINDS": ETHERBUS, "DEVSIM_TEST_ETHER_PORT": "5050"})
    try:
        seen = sim.read_until("etherbus.ether:")
        scheme, _, url = seen["etherbus.ether"].partition(" ")
        assert scheme == "udp" and url.startswith("udp://127.0.0.1:") and not url.endswith(":5050")
        assert seen["etherbus.serial"].startswith("tcp socket://127.0.0.1:")
        assert ask(udp_client, url) == REPLY
    finally:
        code, err = sim.stop()
    assert code == 0, err
    me = udp_client.getsockname()
    device = ("127.0.0.1", int(url.rpartition(":")[2]))
    packets = read_pcap(tmp_path / "line-ether.pcap")  # the second port's trace, beside the first
    assert [(p[1], p[2], p[3]) for p in packets] == [(me, device, REQUEST), (device, me, REPLY)]
    assert read_pcap(trace) == []  # the serial port's: nothing crossed it


def test_a_declared_port_can_go_back_to_a_pty() -> None:
    sim = Sim("etherbus", "--port", "ether=pty", "--tcp", "0",
              extra_env={"DEVSIM_EXTRA_KINDS": ETHERBUS, "DEVSIM_TEST_ETHER_PORT": "5050"})
    try:
        seen = sim.read_until("etherbus.ether:")
        assert seen["etherbus.ether"].startswith("pty /dev/")
        assert seen["etherbus.serial"].startswith("tcp socket://127.0.0.1:")  # --tcp: the other ports
    finally:
        code, err = sim.stop()
    assert code == 0, err


def test_trace_names_per_port() -> None:
    assert _trace_for("x.trace", "b", 0) == "x.trace"
    assert _trace_for("x.trace", "b", 1) == "x.trace-b"  # as before
    assert _trace_for("dir/line.pcap", "ether", 1) == "dir/line-ether.pcap"  # still a pcap file
    assert _trace_for(None, "b", 1) is None
