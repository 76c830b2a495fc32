"""`devsim run KIND --modbus SPEC` (issue 13): the device's Modbus facade beside its own port, and
`devsim doc KIND --modbus`."""

from __future__ import annotations

import json
import tempfile

import pytest
from click.testing import CliRunner
from pymodbus.client import ModbusSerialClient, ModbusTcpClient

from devsim.cli import cli
from tests.test_cli import Sim, ctl


def test_run_serves_modbus_tcp_beside_the_pty() -> None:
    sim = Sim("sers", "--pty", "--modbus", "tcp:127.0.0.1:0")
    try:
        seen = sim.read_until("sers.modbus:")
        assert seen["sers"].startswith("pty /dev/")
        scheme, where = seen["sers.modbus"].split()
        host, _, port = where.rpartition(":")
        assert scheme == "tcp" and host == "127.0.0.1"
        client = ModbusTcpClient(host, port=int(port), timeout=5)
        assert client.connect()
        try:
            words = client.read_holding_registers(2, count=2, device_id=1).registers  # quantity.supply_voltage
            assert words == [1, 68000 - 65536]
        finally:
            client.close()
    finally:
        sim.stop()


@pytest.mark.parametrize(("spec", "message"), [
    ("udp:1", "--modbus: expected tcp:[HOST:]PORT, rtu or rtu:LINK, not 'udp:1'"),
    ("tcp:x", "--modbus: expected [HOST:]PORT, got 'x'"),
])
def test_a_bad_modbus_spec_is_one_line(spec: str, message: str) -> None:
    result = CliRunner().invoke(cli, ["run", "sers", "--modbus", spec])
    assert result.exit_code == 2 and message in result.output


def test_doc_prints_the_modbus_map() -> None:
    result = CliRunner().invoke(cli, ["doc", "sers", "--modbus"])
    assert result.exit_code == 0
    assert "| holding | 2–3 | quantity.supply_voltage | float | ×1000 | V |" in result.output
    assert "| coil | 6 | input.I1 | bool |" in result.output


def test_ctl_telegrams_shows_the_modbus_rtu_line() -> None:
    """``devsim ctl telegrams --port modbus``: the RTU line's frames, as ``ctl line`` and ``ctl
    capture`` take that line (it was refused: 'sers has no port 'modbus'').  pymodbus's serial
    client at 8N1 on the pty (docs/facades/modbus.md); the line declares no framing, so the
    frames come undecoded."""
    sockdir = tempfile.TemporaryDirectory(prefix="dsl")  # a unix socket's path is short
    addr = f"unix:{sockdir.name}/ctl.sock"
    sim = Sim("sers", "--pty", "--modbus", "rtu", "--control", addr)
    try:
        seen = sim.read_until("control:")
        scheme, rtu = seen["sers.modbus"].split()
        assert scheme == "rtu"
        done = ctl(addr, "telegrams", "sers", "--port", "modbus")
        assert (done.returncode, done.stdout) == (0, "(no telegrams yet: the tap starts with the first request)\n"), \
            done.stderr
        client = ModbusSerialClient(port=rtu, baudrate=19200, parity="N", timeout=5)
        assert client.connect()
        try:
            assert client.read_holding_registers(2, count=2, device_id=1).registers == [1, 68000 - 65536]
        finally:
            client.close()
        done = ctl(addr, "--json", "telegrams", "sers", "--port", "modbus")
        assert done.returncode == 0, done.stderr
        request, answer = json.loads(done.stdout)
        assert (request["dir"], request["hex"][:-6]) == ("H>D", "01 03 00 02 00 02")  # (and the CRC)
        assert (answer["dir"], answer["hex"][:-6]) == ("D>H", "01 03 04 00 01 09 a0")
        assert "decoded" not in request
    finally:
        sim.stop()
        sockdir.cleanup()


def test_sigterm_during_a_flood_of_pipelined_requests_stops_the_simulator() -> None:
    """``devsim run --modbus tcp:0`` with four clients that each pipeline 300 KB of reads of 125
    registers and read no answer: a SIGTERM sent then stops it, status 0, no traceback.  (Before:
    each read of 256 KiB of requests was answered in one step of the event loop, 21,845 reads of
    1.4 ms each into an unbounded write buffer, and the SIGTERM waited behind them: half a minute
    for each client's read.)"""
    import signal
    import socket
    import struct

    from tests.support.process import DevsimProcess, stop

    sim = DevsimProcess("run", "sers", "--pty", "--modbus", "tcp:0")
    clients = [socket.socket() for _ in range(4)]
    try:
        line = sim.next_match(sim.out, lambda text: text.startswith("sers.modbus:"), 30, "the Modbus line")
        chunk = b"".join(struct.pack(">HHHBBHH", n, 0, 6, 1, 3, 0, 125) for n in range(1000))
        for client in clients:
            client.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
            client.connect(("127.0.0.1", int(line.rpartition(":")[2])))
        for _ in range(25):  # 300,000 bytes each: more than one read of the server's (256 KiB)
            for client in clients:
                client.sendall(chunk)
        status = stop(sim.proc, signal.SIGTERM, 30)
    finally:
        stop(sim.proc, signal.SIGKILL)
        for client in clients:
            client.close()
    errors = sim.rest_of_err()
    assert status == 0, errors[-10:]
    assert not any("Traceback" in text for text in errors), errors[:20]
