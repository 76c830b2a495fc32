"""``devsim up --workers N``: a plant over several processes behind one control address."""

from __future__ import annotations

import os
import queue
import signal
import socket
import subprocess
import sys
import threading
from pathlib import Path

import pytest

from devsim.runtime.client import ControlClient, ControlError
from devsim.scenario.schema import load_plant
from devsim.scenario.workers import split_plant

ROOT = Path(__file__).resolve().parents[2]
ECHO = "echo=tests.support.echo:EchoDevice"


def _plant(tmp_path: Path) -> Path:
    path = tmp_path / "plant.yaml"
    path.write_text(
        "name: lab\n"
        "devices:\n"
        + "".join(f"  - {{name: e{i}, kind: echo, transport: {{tcp: {{port: 0}}}}, config: {{address: {i}}}}}\n"
                  for i in range(4))
        + "  - {name: b1, kind: echo, transport: {bus: line}, config: {address: 1}}\n"
        "  - {name: b2, kind: echo, transport: {bus: line}, config: {address: 2}}\n"
        "buses:\n  - {name: line, transport: {tcp: {port: 0}}}\n"
    )
    return path


def test_split_keeps_a_bus_whole(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("DEVSIM_EXTRA_KINDS", ECHO)
    shares = split_plant(load_plant(_plant(tmp_path)), 2)
    assert len(shares) == 2
    names = [sorted(d["name"] for d in s["devices"]) for s in shares]
    assert sorted(sum(names, [])) == ["b1", "b2", "e0", "e1", "e2", "e3"]
    holder = [s for s in shares if s["buses"]]
    assert len(holder) == 1 and {"b1", "b2"} <= {d["name"] for d in holder[0]["devices"]}


def test_split_keeps_a_canopen_network_in_one_worker() -> None:
    from devsim.scenario.schema import PlantSpec

    spec = PlantSpec.parse({"devices": [
        {"name": "a", "kind": "sers", "canopen": {"node": 1, "network": "29600"}},
        {"name": "b", "kind": "sers"},
        {"name": "c", "kind": "sers", "canopen": {"node": 2, "network": "29600"}},
        {"name": "d", "kind": "sers", "canopen": {"node": 1, "network": "29601"}},
    ]})
    shares = split_plant(spec, 3)
    names = [sorted(d["name"] for d in s["devices"]) for s in shares]
    assert sorted(sum(names, [])) == ["a", "b", "c", "d"] and len(shares) == 3
    assert ["a", "c"] in names  # one network, one process


def test_workers_serve_ports_and_one_control_address(tmp_path: Path) -> None:
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(p for p in (str(ROOT), env.get("PYTHONPATH", "")) if p)
    env["DEVSIM_EXTRA_KINDS"] = ECHO
    addr = f"unix:{tmp_path}/ctl.sock"
    proc = subprocess.Popen(
        [sys.executable, "-m", "devsim", "up", str(_plant(tmp_path)), "--workers", "2", "--control", addr,
         "--trace-dir", str(tmp_path / "traces")],
        cwd=ROOT, env=env, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )
    lines: queue.Queue[str] = queue.Queue()
    threading.Thread(target=lambda: [lines.put(x.rstrip("\n")) for x in proc.stdout], daemon=True).start()  # type: ignore[union-attr]
    seen: dict[str, str] = {}
    try:
        while "control" not in seen or len([k for k in seen if k.endswith("ready")]) < 6:
            line = lines.get(timeout=30)
            name, _, value = line.partition(": ")
            seen[f"{name} ready" if value == "ready" else name] = value
        assert seen["control"] == addr
        with ControlClient(addr) as client:
            rows = client.devices()
            assert sorted(r["name"] for r in rows) == ["b1", "b2", "e0", "e1", "e2", "e3"]
            assert {r["worker"] for r in rows} == {0, 1}
            for row in rows:
                assert client.read(row["name"], "address") == int(row["name"][1:])  # (b1, b2 at 1, 2 on their bus)
            client.set("e3", "input.mute", True)
            assert client.read("e3", "input.mute") is True
            with pytest.raises(ControlError) as info:
                client.read("nobody", "address")
            assert info.value.type == "UnknownDevice"
            host, port = seen["e2"].split()[-1].removeprefix("socket://").rsplit(":", 1)
            with socket.create_connection((host, int(port)), timeout=5) as sock:
                sock.sendall(b"hi")
                assert sock.recv(2) == b"hi"
            assert client.read("e2", "received") == 2
    finally:
        proc.send_signal(signal.SIGINT)
        _out, err = proc.communicate(timeout=30)
    assert proc.returncode == 0, err
    assert "Traceback" not in err
    traces = sorted(p.name for p in (tmp_path / "traces").iterdir())
    assert traces == ["e0.trace", "e1.trace", "e2.trace", "e3.trace", "line.trace"]


def test_virtual_time_stays_in_one_process(tmp_path: Path) -> None:
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(p for p in (str(ROOT), env.get("PYTHONPATH", "")) if p)
    env["DEVSIM_EXTRA_KINDS"] = ECHO
    proc = subprocess.Popen(
        [sys.executable, "-m", "devsim", "up", str(_plant(tmp_path)), "--workers", "2", "--virtual"],
        cwd=ROOT, env=env, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )
    try:
        assert proc.stderr is not None
        assert proc.stderr.readline() == "devsim: under virtual time a plant stays in one process (--workers ignored)\n"
        assert proc.stdout is not None
        line = proc.stdout.readline()
        while line != "b2: ready\n":  # one process: served and booted
            assert line, "devsim up ended early"
            line = proc.stdout.readline()
    finally:
        proc.send_signal(signal.SIGINT)
        proc.communicate(timeout=30)
    assert proc.returncode == 0


def test_a_port_in_use_in_a_worker_is_one_error_and_no_traceback(tmp_path: Path) -> None:
    """(The error and status 6 were right, but an asyncio traceback followed them: a future the
    start waited on was left pending.)"""
    from devsim.cli import exits

    with socket.socket() as held:
        held.bind(("127.0.0.1", 0))
        held.listen()
        port = held.getsockname()[1]
        plant = tmp_path / "busy.yaml"
        plant.write_text(f"devices:\n  - {{name: a, kind: echo, transport: {{tcp: {{port: {port}}}}}}}\n"
                         "  - {name: b, kind: echo, transport: {tcp: {port: 0}}}\n")
        env = dict(os.environ)
        env["PYTHONPATH"] = os.pathsep.join(p for p in (str(ROOT), env.get("PYTHONPATH", "")) if p)
        env["DEVSIM_EXTRA_KINDS"] = ECHO
        done = subprocess.run([sys.executable, "-m", "devsim", "up", str(plant), "--workers", "2", "--no-control"],
                              cwd=ROOT, env=env, stdin=subprocess.DEVNULL, capture_output=True, text=True, timeout=60)
    assert done.returncode == exits.SYSTEM, done.stderr
    assert "Address already in use" in done.stderr and "Traceback" not in done.stderr, done.stderr


def test_the_up_line_counts_one_worker_and_one_device_in_the_singular(tmp_path: Path) -> None:
    """A plant of one device gets one worker, whatever --workers asks; stderr said `1 worker
    processes (1 devices)` (`devsim up` alone says `(1 device)`)."""
    from tests.support.process import DevsimProcess

    plant = tmp_path / "one.yaml"
    plant.write_text("devices:\n  - {name: a, kind: sers, config: {boot_time: 0}}\n")
    proc = DevsimProcess("up", str(plant), "--workers", "2", "--no-control")
    try:
        line = proc.next_match(proc.err, lambda text: text.startswith("devsim: plant up in "), 30, "the up line")
        assert line == "devsim: plant up in 1 worker process (1 device); Ctrl-C to stop"
    finally:
        assert proc.interrupt() == 0
