"""The command line: `devsim list`, `devsim run` (as a real process), `devsim ctl`."""

from __future__ import annotations

import json
import os
import queue
import signal
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Iterator
from pathlib import Path

import pytest
import serial
from click.testing import CliRunner

from devsim.cli import cli, exits
from devsim.runtime.client import ControlClient, ControlError

ROOT = Path(__file__).resolve().parents[1]
ECHO = "echo=tests.support.echo:EchoDevice"
TWOPORT = "twoport=tests.support.twoport:TwoPortDevice"


@pytest.fixture(autouse=True)
def _echo_kind(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("DEVSIM_EXTRA_KINDS", ECHO)


@pytest.fixture
def sockdir() -> Iterator[str]:
    with tempfile.TemporaryDirectory(prefix="dsl") as path:
        yield path


def invoke(*args: str) -> tuple[int, str, str]:
    result = CliRunner().invoke(cli, list(args), prog_name="devsim")
    return result.exit_code, result.stdout, result.stderr


# -- in process (CliRunner) ----------------------------------------------------------------
def test_list_shows_kinds_with_descriptions() -> None:
    code, out, _ = invoke("list")
    assert code == 0
    lines = out.splitlines()
    echo = [line for line in lines if line.split()[0] == "echo"]
    assert echo and echo[0].split(None, 1)[1] == "Echoes every byte back (test device)"
    assert any(line.split()[0] == "sers" for line in lines)


@pytest.mark.parametrize(
    ("args", "expected"),
    [
        (["run", "nokind"], "unknown device kind 'nokind'"),
        (["run", "echo", "--tcp", "4001", "--pty"], "choose one port"),
        (["run", "echo", "--tcp", "x:y"], "--tcp: expected [HOST:]PORT"),
        (["run", "echo", "--rfc2217", "70000"], "--rfc2217: port 70000"),
        (["run", "echo", "--drives", "1,a"], "--drives: expected addresses like 1,2,3"),
        (["run", "echo", "--drives", "1,2,1"], "--drives: address 1 given twice"),
        (["run", "echo", "--drives", "1,200"], "--drives: address: Input should be less than or equal to 127"),
        (["run", "ip247", "--drives", "1,2"], "--drives: ip247 has no address on its port 'pg': one device per line"),
        (["run", "gms96", "--drives", "3,32"], "--drives: dil.address: Input should be less than or equal to 31"),
        (["run", "echo", "--speed", "0"], "--speed: must be positive"),
        (["run", "echo", "--speed", "fast"], "'fast' is not a valid float"),
        # (nan and inf passed 'speed <= 0': the device time was NaN, a real-time scenario ran past its timeout)
        (["run", "echo", "--speed", "nan"], "--speed: must be positive"),
        (["run", "echo", "--speed", "inf"], "--speed: must be finite"),
        (["scenario", "run", "--realtime", "--speed", "nan", str(ROOT / "scenarios/sers/absolute_positioning.yaml")],
         "--speed: must be positive"),
        (["up", str(ROOT / "scenarios/sers/absolute_positioning.yaml"), "--speed", "inf"], "--speed: must be finite"),
        (["run", "echo", "--control", "0.0.0.0:7000"], "--control: refusing non-loopback host '0.0.0.0'"),
        (["run", "echo", "--control", "nowhere"], "--control: 'nowhere': expected unix:/path/to.sock"),
        (["run", "echo", "--bogus"], "No such option"),
        # (str.isdigit took the superscript, int() did not: a ValueError traceback; and int() read ٥)
        (["run", "echo", "--canopen", "\u00b2"], "--canopen: expected NODE"),
        (["run", "echo", "--canopen", "\u0665"], "--canopen: expected NODE"),
    ],
)
def test_option_errors_are_one_line_exit_2(args: list[str], expected: str) -> None:
    code, out, err = invoke(*args)
    assert code == 2
    assert out == ""
    assert err.count("\n") == 1, err
    assert err.startswith("Error: ")
    assert expected in err
    assert "Traceback" not in err


def test_config_error_names_file_line_and_field(tmp_path: Path) -> None:
    path = tmp_path / "config.yaml"
    path.write_text("address: 2\nbaud: 9600\naxis:\n  limit_left: -10\n  limit_right: far\n")
    code, out, err = invoke("run", "echo", "--config", str(path))
    assert code == exits.BAD_FILE
    assert err == f"Error: {path}:5: axis.limit_right: Input should be a valid number, unable to parse string as a number\n"


def test_config_validator_message(tmp_path: Path) -> None:
    path = tmp_path / "config.yaml"
    path.write_text("# echo\naddress: 2\nbaud: 9601\n")
    code, _, err = invoke("run", "echo", "--config", str(path))
    assert code == exits.BAD_FILE
    assert err == f"Error: {path}:3: baud: baud must be one of 1200, 2400, 4800, 9600, 19200\n"


def test_config_yaml_syntax_error(tmp_path: Path) -> None:
    path = tmp_path / "bad.yaml"
    path.write_text("address: 2\naxis:\n  limit_left: 1\n limit_right: 2\n")
    code, _, err = invoke("run", "echo", "--config", str(path))
    assert code == exits.BAD_FILE
    assert err.startswith(f"Error: {path}:4: ") and err.count("\n") == 1


def test_missing_config_file(tmp_path: Path) -> None:
    code, _, err = invoke("run", "echo", "--config", str(tmp_path / "nope.yaml"))
    assert code == exits.BAD_FILE
    assert err == f"Error: {tmp_path / 'nope.yaml'}: no such file\n"


def test_sers_config_error(tmp_path: Path) -> None:
    path = tmp_path / "config.yaml"
    path.write_text("address: 3\nparams:\n  P1017: 2\nbaud: 9601\n")
    code, _, err = invoke("run", "sers", "--config", str(path))
    assert code == exits.BAD_FILE
    assert err.startswith(f"Error: {path}:4: baud: baud must be one of 1200, 2400,")


def test_ctl_cannot_connect(sockdir: str) -> None:
    code, out, err = invoke("ctl", "--control", f"unix:{sockdir}/none.sock", "now")
    assert code == exits.UNREACHABLE
    assert err.startswith(f"Error: cannot connect to unix:{sockdir}/none.sock") and err.count("\n") == 1


# -- devsim run as a real process ----------------------------------------------------------
class Sim:
    """A `devsim run` subprocess whose stdout lines are collected by a thread."""

    def __init__(self, *args: str, extra_env: dict[str, str] | None = None) -> None:
        env = dict(os.environ)
        env["PYTHONPATH"] = os.pathsep.join(p for p in (str(ROOT), env.get("PYTHONPATH", "")) if p)
        env["DEVSIM_EXTRA_KINDS"] = f"{ECHO},{TWOPORT}"
        env.update(extra_env or {})
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "devsim", "run", *args],
            cwd=ROOT,
            env=env,
            stdin=subprocess.DEVNULL,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        self.lines: queue.Queue[str | None] = queue.Queue()
        threading.Thread(target=self._pump, daemon=True).start()

    def _pump(self) -> None:
        assert self.proc.stdout is not None
        for line in self.proc.stdout:
            self.lines.put(line.rstrip("\n"))
        self.lines.put(None)

    def read_until(self, prefix: str, timeout: float = 15.0) -> dict[str, str]:
        """Collect `name: value` lines until one starts with ``prefix``."""
        seen: dict[str, str] = {}
        deadline = time.monotonic() + timeout
        while True:
            try:
                line = self.lines.get(timeout=max(0.01, deadline - time.monotonic()))
            except queue.Empty:
                raise AssertionError(f"no {prefix!r} line; got {seen}; stderr: {self.stop()[1]}") from None
            if line is None:
                raise AssertionError(f"simulator ended early: {self.stop()[1]}")
            name, _, value = line.partition(": ")
            seen.setdefault(name, value)
            if line.startswith(prefix):
                return seen

    def stop(self, signum: int = signal.SIGINT) -> tuple[int, str]:
        if self.proc.poll() is None:
            self.proc.send_signal(signum)
        try:
            self.proc.wait(timeout=15)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()
        assert self.proc.stderr is not None
        return self.proc.returncode, self.proc.stderr.read()


def ctl(addr: str, *args: str) -> subprocess.CompletedProcess[str]:
    env = dict(os.environ)
    env["PYTHONPATH"] = str(ROOT)
    return subprocess.run(
        [sys.executable, "-m", "devsim", "ctl", "--control", addr, *args],
        cwd=ROOT, env=env, capture_output=True, text=True, timeout=30, stdin=subprocess.DEVNULL,
    )


def test_run_pty_control_and_clean_sigint(sockdir: str) -> None:
    addr = f"unix:{sockdir}/ctl.sock"
    sim = Sim("echo", "--pty", "--control", addr)
    try:
        seen = sim.read_until("control:")
        assert seen["control"] == addr
        kind, _, path = seen["echo"].partition(" ")
        assert kind == "pty" and path.startswith("/dev/")
        with serial.Serial(path, 9600, timeout=5) as port:
            port.write(b"#P11?\r")
            assert port.read(6) == b"#P11?\r"
        with ControlClient(addr) as client:
            assert client.read("echo", "received") == 6
            client.set("echo", "input.mute", True)
            assert client.devices() == [{"name": "echo", "kind": "echo", "port": path, "ports": {"main": path}, "faults": []}]
            with pytest.raises(ControlError) as info:
                client.read("echo", "nothing")
            assert info.value.type == "UnknownName"
        done = ctl(addr, "read", "echo", "input.mute")
        assert (done.returncode, done.stdout) == (0, "input.mute = true\n")
        done = ctl(addr, "set", "echo", "input.mute", "false")
        assert (done.returncode, done.stdout) == (0, "ok\n"), done.stderr
        assert ctl(addr, "set", "echo", "value", "2.5").returncode == 0
        done = ctl(addr, "set", "echo", "value", "-2.5")  # a negative number is a value, not an option
        assert done.returncode == 0, done.stderr
        assert json.loads(ctl(addr, "--json", "read", "echo", "value").stdout) == -2.5
        assert ctl(addr, "set", "echo", "value", "2.5").returncode == 0
        done = ctl(addr, "set", "echo", "value", "hello")  # checked before it takes effect
        assert done.returncode == exits.REFUSED and "expects a number" in done.stderr
        assert json.loads(ctl(addr, "--json", "read", "echo", "value").stdout) == 2.5
        state = json.loads(ctl(addr, "state", "echo", "--json").stdout)
        assert state["input"]["mute"] is False
        done = ctl(addr, "read", "echo", "nothing")
        assert done.returncode == exits.REFUSED
        assert done.stderr.startswith("Error: UnknownName: ") and done.stderr.count("\n") == 1
        done = ctl(addr, "advance", "1")
        assert done.returncode == exits.REFUSED and "RuntimeError" in done.stderr
        assert float(ctl(addr, "--json", "now").stdout) > 0
        assert ctl(addr, "power-cycle", "echo", "--wipe").returncode == 0
    finally:
        code, err = sim.stop(signal.SIGINT)
    assert code == 0, err
    assert "Traceback" not in err
    assert not os.path.exists(f"{sockdir}/ctl.sock")


def test_run_tcp_multidrop_virtual_sigterm(sockdir: str) -> None:
    addr = f"unix:{sockdir}/ctl.sock"
    sim = Sim("echo", "--tcp", "0", "--drives", "3,5", "--virtual", "--control", addr)
    try:
        seen = sim.read_until("control:")
        assert seen["echo3"].startswith("tcp socket://127.0.0.1:")
        assert seen["echo5"] == seen["echo3"]
        url = seen["echo3"].split(" ", 1)[1]
        with serial.serial_for_url(url, timeout=5) as port:
            port.write(b"x")
            assert port.read(2) == b"xx"  # two devices on one line, both echo
        with ControlClient(addr) as client:
            assert [d["name"] for d in client.devices()] == ["echo3", "echo5"]
            assert client.read("echo5", "address") == 5
            client.set("echo3", "timer", 2)
            assert client.advance(2) == 2.0
            assert client.read("echo3", "fired") is True
        assert json.loads(ctl(addr, "--json", "advance", "0.5").stdout) == 2.5
    finally:
        code, err = sim.stop(signal.SIGTERM)
    assert code == 0, err
    assert "Traceback" not in err


def test_run_link_config_state_dir(tmp_path: Path, sockdir: str) -> None:
    link = tmp_path / "ttyECHO"
    config = tmp_path / "echo.yaml"
    config.write_text("address: 9\nbaud: 19200\n")
    addr = f"unix:{sockdir}/ctl.sock"
    state = tmp_path / "state"
    sim = Sim("echo", "--link", str(link), "--config", str(config), "--state-dir", str(state), "--control", addr)
    try:
        seen = sim.read_until("control:")
        assert seen["echo"].startswith("pty /dev/")
        with ControlClient(addr) as client:
            assert client.read("echo", "address") == 9
            client.set("echo", "nvram.note", "stored")
        with serial.Serial(str(link), 19200, timeout=5) as port:
            port.write(b"\x00\r\n\x11\x13\x7f")
            assert port.read(6) == b"\x00\r\n\x11\x13\x7f"
    finally:
        code, err = sim.stop()
    assert code == 0, err
    assert json.loads((state / "echo.nvram.json").read_text())["note"] == "stored"
    assert not link.exists()


def test_run_port_in_use_is_one_line_exit_system(sockdir: str) -> None:
    import socket

    with socket.socket() as busy:
        busy.bind(("127.0.0.1", 0))
        busy.listen()
        port = busy.getsockname()[1]
        sim = Sim("echo", "--tcp", str(port))
        code = sim.proc.wait(timeout=30)
        _, err = sim.stop()
    assert code == exits.SYSTEM
    assert err.startswith("Error: cannot open the tcp port: ") and err.count("\n") == 1


def test_python_m_devsim_list() -> None:
    env = dict(os.environ, PYTHONPATH=str(ROOT), DEVSIM_EXTRA_KINDS=ECHO)
    done = subprocess.run(
        [sys.executable, "-m", "devsim", "list"], cwd=ROOT, env=env, capture_output=True, text=True, timeout=30
    )
    assert done.returncode == 0
    assert "echo" in done.stdout.split()


def test_run_sers_smoke(tmp_path: Path, sockdir: str) -> None:
    config = tmp_path / "sers.yaml"
    config.write_text("address: 1\nbaud: 9600\nboot_time: 0\naxis:\n  limit_left: -1000\n  limit_right: 5000\n")
    addr = f"unix:{sockdir}/ctl.sock"
    sim = Sim("sers", "--pty", "--config", str(config), "--control", addr)
    try:
        seen = sim.read_until("control:")
        path = seen["sers"].split(" ", 1)[1]
        with serial.Serial(path, 9600, timeout=0.2) as port:
            port.write(b"#P11?\r")
            answer = b""
            deadline = time.monotonic() + 10
            while b"\nok" not in answer and time.monotonic() < deadline:
                answer += port.read(64)
        assert b"\nok" in answer
        done = ctl(addr, "--json", "read", "sers", "axis.position")
        assert done.returncode == 0, done.stderr
        assert isinstance(json.loads(done.stdout), int | float)
    finally:
        code, err = sim.stop()
    assert code == 0, err
    assert "Traceback" not in err


def test_run_says_ready_when_the_sers_has_booted(sockdir: str) -> None:
    """The SERS ignores input for 2 s after power-on; `NAME: ready` tells scripts when it listens."""
    addr = f"unix:{sockdir}/ready.sock"
    sim = Sim("sers", "--pty", "--virtual", "--control", addr)
    try:
        seen = sim.read_until("control:")
        assert "sers ready" not in seen and seen["sers"].startswith("pty ")
        assert ctl(addr, "advance", "1.9").returncode == 0
        assert ctl(addr, "--json", "read", "sers", "booting").stdout == "true\n"
        assert ctl(addr, "advance", "0.2").returncode == 0
        line = sim.lines.get(timeout=15)
        assert line == "sers: ready"
        assert ctl(addr, "power-cycle", "sers").returncode == 0
        assert ctl(addr, "advance", "2.5").returncode == 0
        assert sim.lines.get(timeout=15) == "sers: ready"  # again after each power-on
    finally:
        code, err = sim.stop()
    assert code == 0 and "Traceback" not in err
