"""Several serial ports per device, shown with the two-port test kind (tests/support/twoport.py)."""

from __future__ import annotations

import json
import os
import socket
import time
from pathlib import Path

import pytest
import serial
from click.testing import CliRunner

from devsim.cli import cli, exits
from devsim.core.config import ConfigError
from devsim.scenario.plant import plant_running
from devsim.scenario.runner import run_scenario
from devsim.scenario.schema import load_plant, scenario_from_dict
from tests.support.process import free_port
from tests.test_cli import ECHO, TWOPORT, Sim, ctl

pytestmark = pytest.mark.skipif(os.name != "posix", reason="ptys")


@pytest.fixture(autouse=True)
def _kinds(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("DEVSIM_EXTRA_KINDS", f"{ECHO},{TWOPORT}")


def test_run_gives_each_port_its_own_pty_and_says_ready(tmp_path: Path) -> None:
    addr = f"unix:{tmp_path}/ctl.sock"
    sim = Sim("twoport", "--pty", "--control", addr)
    try:
        seen = sim.read_until("twoport: ready")
        assert seen["control"] == addr
        kind_a, _, path_a = seen["twoport.a"].partition(" ")
        kind_b, _, path_b = seen["twoport.b"].partition(" ")
        assert kind_a == kind_b == "pty" and path_a != path_b
        with serial.Serial(path_a, 9600, timeout=5) as a, serial.Serial(path_b, 9600, timeout=5) as b:
            a.write(b"hello")
            assert a.read(5) == b"hello"  # port a echoes
            b.write(b"?\r")
            assert b.read(2) == b"5\r"  # port b reports what port a counted: one model
        devices = json.loads(ctl(addr, "--json", "devices").stdout)
        assert devices[0]["ports"] == {"a": path_a, "b": path_b}
        line_b = json.loads(ctl(addr, "--json", "line", "twoport", "--port", "b").stdout)
        assert line_b["bytes_in"] == 2 and line_b["bytes_out"] == 2
        assert ctl(addr, "fault", "twoport", "jam", "on").returncode == 0
        assert json.loads(ctl(addr, "--json", "read", "twoport", "jammed").stdout) is True
        done = ctl(addr, "fault", "twoport", "nope", "on")
        assert done.returncode == exits.REFUSED and "declared: jam" in done.stderr
    finally:
        code, err = sim.stop()
    assert code == 0 and "Traceback" not in err


def test_plant_maps_each_port_to_a_transport(tmp_path: Path) -> None:
    tcp = free_port()
    plant_file = tmp_path / "plant.yaml"
    plant_file.write_text(
        "name: two ports\n"
        "devices:\n"
        "  - name: x\n"
        "    kind: twoport\n"
        f"    ports: {{a: {{pty: {{link: {tmp_path}/x-a}}}}, b: {{tcp: {{port: {tcp}}}}}}}\n"
    )
    spec = load_plant(plant_file)
    assert spec.name == "two ports"
    with plant_running(spec, virtual=True, trace_dir=tmp_path / "traces") as plant:
        assert sorted(plant.transports) == ["x.a", "x.b"]
        assert plant.kinds == {"x.a": "pty", "x.b": "tcp"}
        assert plant.port_of("x", "b") == "x.b" and plant.port_of("x") == "x.a"
        with serial.Serial(str(tmp_path / "x-a"), 9600, timeout=5) as a:
            a.write(b"abc")
            assert a.read(3) == b"abc"
        with socket.create_connection(("127.0.0.1", tcp), timeout=5) as b:
            b.sendall(b"\r")
            assert b.recv(16) == b"3\r"
        assert plant.runtime.line_status("x", "b")["bytes_out"] == 2
    traces = sorted(p.name for p in (tmp_path / "traces").iterdir())
    assert traces == ["x.a.trace", "x.b.trace"]


def test_plant_refuses_a_port_the_kind_does_not_declare(tmp_path: Path) -> None:
    plant_file = tmp_path / "plant.yaml"
    plant_file.write_text("devices:\n  - name: x\n    kind: twoport\n    ports: {c: {pty: {}}}\n")
    with pytest.raises(ConfigError, match=r"has no port 'c' \(ports: a, b\)"):
        load_plant(plant_file)


def test_line_fault_hits_only_its_port() -> None:
    scenario = scenario_from_dict(
        {
            "devices": [{"name": "x", "kind": "twoport"}],
            "steps": [
                {"line_fault": {"port": "x.a", "kind": "unplug", "duration": "1s"}},
                {"send": {"port": "x.a", "data": "zz"}},
                {"send": {"port": "x.b", "line": ""}},
                {"expect": {"port": "x.b", "bytes": "0\r", "timeout": "100ms"}},
                {"after": "2s", "send": {"port": "x.a", "data": "yy"}},
                {"expect": {"port": "x.a", "bytes": "yy", "timeout": "100ms"}},
                {"expect_state": {"device": "x", "name": "count", "equals": 2}},
            ],
        }
    )
    result = run_scenario(scenario, mode="virtual")
    assert result.passed, [s.message for s in result.steps if not s.passed]


def test_scenario_fault_must_be_declared() -> None:
    with pytest.raises(ValueError, match=r"twoport has no fault 'blocked_axis' \(declared: jam"):
        scenario_from_dict(
            {"devices": [{"name": "x", "kind": "twoport"}], "steps": [{"fault": {"device": "x", "kind": "blocked_axis"}}]}
        )


def test_doc_lists_ports_names_and_faults() -> None:
    result = CliRunner().invoke(cli, ["doc", "twoport"])
    assert result.exit_code == 0, result.output
    assert "| `a` | echoes and counts |" in result.output
    assert "| `count` | int |  | r |" in result.output
    assert "| `jam` | port a stops echoing |" in result.output


def test_fixture_serves_every_port_and_switches_faults(devsim_device) -> None:  # noqa: ANN001
    drive = devsim_device("twoport")
    assert drive.names() == ["count", "jammed"]
    with serial.serial_for_url(drive.port_url("a"), timeout=5) as a, serial.serial_for_url(
        drive.port_url("b"), timeout=5
    ) as b:
        drive.fault("jam", True)
        before = drive.runtime.line_status("twoport", "a")["bytes_in"]
        a.write(b"xy")
        deadline = time.monotonic() + 10
        while drive.runtime.line_status("twoport", "a")["bytes_in"] < before + 2:
            assert time.monotonic() < deadline  # a's bytes are in before b asks (two fds: no order)
        b.write(b"\r")
        assert b.read(2) == b"2\r"  # both counted on a (so a's input was handled) ...
        assert a.in_waiting == 0  # ... but a is jammed: no echo
        drive.fault("jam", False)
        a.write(b"z")
        assert a.read(1) == b"z"
    assert drive.read("jammed") is False


def test_line_faults_from_the_control_api_and_the_fixture(devsim_device, tmp_path: Path) -> None:  # noqa: ANN001
    drive = devsim_device("twoport")
    with serial.serial_for_url(drive.port_url("a"), timeout=5) as a, serial.serial_for_url(
        drive.port_url("b"), timeout=5
    ) as b:
        drive.line_fault("drop", port="a", count=2)  # the next two bytes on port a vanish
        a.write(b"xyz")
        assert a.read(1) == b"z"
        b.write(b"\r")
        assert b.read(2) == b"1\r"  # port b is not affected, and only z reached the model
        drive.line_fault("unplug", port="b")
        before = drive.runtime.line_status("twoport", "b")["bytes_in"]
        b.write(b"\r")
        deadline = time.monotonic() + 10
        while drive.runtime.line_status("twoport", "b")["bytes_in"] == before:
            assert time.monotonic() < deadline  # until the line has taken the byte (and lost it)
        drive.line_fault("unplug", False, port="b")
        b.write(b"\r")
        assert b.read(2) == b"1\r"  # the first question was lost with the cable out
        assert b.in_waiting == 0
    with pytest.raises(ValueError, match="a noise fault needs rate"):
        drive.line_fault("noise", port="a")


def test_ctl_line_fault(tmp_path: Path) -> None:
    addr = f"unix:{tmp_path}/ctl.sock"
    sim = Sim("twoport", "--pty", "--control", addr)
    try:
        seen = sim.read_until("twoport: ready")
        path_a = seen["twoport.a"].split()[1]
        done = ctl(addr, "line-fault", "twoport", "drop", "on", "--port", "a", "--count", "1")
        assert done.returncode == 0, done.stderr
        with serial.Serial(path_a, 9600, timeout=5) as a:
            a.write(b"pq")
            assert a.read(1) == b"q"
        done = ctl(addr, "line-fault", "twoport", "noise", "on")
        assert done.returncode == exits.REFUSED and "no port 'main'" in done.stderr
    finally:
        code, err = sim.stop()
    assert code == 0 and "Traceback" not in err
