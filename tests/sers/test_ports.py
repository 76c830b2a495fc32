"""A SERS behind TCP, RFC 2217 and a multidrop pty started by the CLI."""

from __future__ import annotations

import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import serial

from devsim.runtime import Runtime
from devsim.transports.rfc2217 import Rfc2217Transport
from devsim.transports.tcp import TcpTransport
from tests.sers.conftest import ACK


def _read_ack(port: serial.SerialBase) -> bytes:
    buf = b""
    while not ACK.search(buf):
        chunk = port.read(1)
        assert chunk, f"no acknowledgement, got {buf!r}"
        buf += chunk
    return buf


def test_sers_over_raw_tcp() -> None:
    runtime = Runtime(virtual=True).start()
    try:
        device = runtime.add_device("sers", "sers", {"boot_time": 0})
        transport = TcpTransport()
        runtime.serve_sync(device, transport)
        with serial.serial_for_url(transport.url, timeout=2) as port:
            port.write(b"#ON V=1000 W=2500 E\r")
            assert _read_ack(port) == b"#ON V=1000 W=2500 E\r\nok0\n\r"
            runtime.advance(1.4)
            port.write(b"#POS?\r")
            assert _read_ack(port) == b"#POS?\rPOS=1\n\r\nok1\n\r"
    finally:
        runtime.stop()


def test_sers_over_rfc2217_reports_the_host_baud_rate() -> None:
    runtime = Runtime(virtual=True).start()
    try:
        device = runtime.add_device("sers", "sers", {"boot_time": 0, "baud": 19200})
        transport = Rfc2217Transport()
        runtime.serve_sync(device, transport)
        with serial.serial_for_url(transport.url, baudrate=19200, timeout=2) as port:
            port.write(b"#P11?\r")
            assert _read_ack(port) == b"#P11?\rP11=0\n\r\nok1\n\r"
            assert runtime.read("sers", "line.mismatch") is False
            port.baudrate = 9600
            port.write(b"#ON\r")
            deadline = time.monotonic() + 5
            while runtime.state("sers")["line"]["bytes_in"] < 10:
                assert time.monotonic() < deadline, "the bytes never arrived"
                time.sleep(0.001)
            assert runtime.state("sers")["line"]["mismatch"] is True
            assert runtime.read("sers", "energized") is False
    finally:
        runtime.stop()


def test_cli_multidrop_three_drives_on_one_pty(tmp_path: Path) -> None:
    config = tmp_path / "sers.yaml"
    config.write_text("boot_time: 0\n")
    proc = subprocess.Popen(
        [sys.executable, "-m", "devsim", "run", "sers", "--pty", "--drives", "1,2,3", "--config", str(config)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        assert proc.stdout is not None
        ports = {}
        while len(ports) < 3:
            line = proc.stdout.readline()
            assert line, proc.stderr.read() if proc.stderr else "no output"
            match = re.match(r"(sers\d): pty (\S+)", line)
            if match:
                ports[match.group(1)] = match.group(2)
        assert set(ports) == {"sers1", "sers2", "sers3"}
        assert len(set(ports.values())) == 1  # one line for all three
        with serial.Serial(ports["sers1"], 9600, timeout=2) as port:
            for address in (1, 2, 3):
                port.write(f"#{address} V={address * 100}\r".encode())
                assert _read_ack(port) == f"#{address} V={address * 100}\r\nok1\n\r".encode()
            port.write(b"#2 V?\r")
            assert _read_ack(port) == b"#2 V?\rV=200U/min\n\r\nok1\n\r"
            port.write(b"#V?\r")  # drive 2 stays selected
            assert _read_ack(port) == b"#V?\rV=200U/min\n\r\nok1\n\r"
    finally:
        proc.send_signal(signal.SIGINT)
        _out, err = proc.communicate(timeout=10)
    assert proc.returncode == 0, err
    assert "Traceback" not in err
