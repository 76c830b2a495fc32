"""The motion log (devsim/observe/motion_log.py): a SERS move in virtual time against the closed-form
trapezoid, event rows at the exact event times, the axes every kind declares, no sampling without
a log, and ``devsim run --motion-log`` as a real process."""

from __future__ import annotations

import csv
import math
import os
import tempfile
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
import serial

from devsim.core.registry import device_class, kinds
from devsim.observe.motion_log import HEADER, MotionLog, axis_columns, motion_log_problem
from devsim.runtime import Runtime
from devsim.runtime.client import ControlClient
from devsim.scenario.runner import run_scenario
from devsim.scenario.schema import load_scenario
from tests.support.process import DevsimProcess

ROOT = Path(__file__).resolve().parents[1]
SCENARIO = ROOT / "scenarios" / "sers" / "absolute_positioning.yaml"
INC_PER_REV = 12800.0
V = 60 / 60 * INC_PER_REV  # V=60 rpm
A = 100 * INC_PER_REV / (2 * math.pi)  # A=100 rad/s²


def trapezoid(t: float, start: float, distance: float) -> float:
    """Closed-form position of a trapezoidal move of ``distance`` from rest at time 0."""
    sign = 1.0 if distance >= 0 else -1.0
    d = abs(distance)
    t_acc = V / A
    if d < V * t_acc:  # a triangle (not used by these moves, kept for completeness)
        t_acc = math.sqrt(d / A)
    v_peak = A * t_acc
    t_const = (d - v_peak * t_acc) / v_peak
    total = 2 * t_acc + t_const
    t = min(max(t, 0.0), total)
    if t <= t_acc:
        s = A * t * t / 2
    elif t <= t_acc + t_const:
        s = v_peak * t_acc / 2 + v_peak * (t - t_acc)
    else:
        rest = total - t
        s = d - A * rest * rest / 2
    return start + sign * s


def rows_of(path: Path) -> list[dict[str, str]]:
    with open(path, newline="") as stream:
        reader = csv.DictReader(stream)
        assert tuple(reader.fieldnames or ()) == HEADER
        return list(reader)


@pytest.fixture(scope="module")
def sers_run(tmp_path_factory: pytest.TempPathFactory) -> tuple[list[dict[str, str]], list[tuple[float, str]]]:
    """The shipped absolute-positioning scenario, logged at 10 ms: (rows, the device's events)."""
    path = tmp_path_factory.mktemp("motion") / "move.csv"
    events: list[tuple[float, str]] = []

    def announce(plant: Any) -> None:
        log = MotionLog(path, 0.01)
        log.add(plant.devices["x"])
        plant.runtime.add_closer(_async(log.close))
        events_ref.append(plant.devices["x"].events)

    events_ref: list[list[tuple[float, str]]] = []
    result = run_scenario(load_scenario(SCENARIO), mode="virtual", announce=announce)
    assert result.passed, result.failures
    events = list(events_ref[0])
    return rows_of(path), events


def _async(fn: Any) -> Any:
    async def close() -> None:
        fn()

    return close


def test_event_rows_are_at_the_exact_move_times(sers_run: Any) -> None:
    rows, events = sers_run
    logged = [(float(r["time"]), r["event"]) for r in rows if r["event"].startswith("move_")]
    moves = [(when, name) for when, name in events if name.startswith("move_")]
    assert logged == moves  # exact: the log writes the device clock's float unchanged
    assert [name for _, name in logged] == ["move_start", "move_end", "move_start", "move_end"]
    (t0, _), (t1, _), (t2, _), (t3, _) = logged
    # the spec's own closed form: d/v + v/a for the 90° move, 180° back
    assert t1 - t0 == pytest.approx(3200 / V + V / A, abs=1e-9)
    assert t3 - t2 == pytest.approx(6400 / V + V / A, abs=1e-9)
    by_time = {float(r["time"]): r for r in rows if r["event"]}
    assert float(by_time[t1]["position"]) == pytest.approx(3200.0, abs=1e-6)
    assert float(by_time[t3]["position"]) == pytest.approx(-3200.0, abs=1e-6)
    assert float(by_time[t1]["velocity"]) == 0.0


def test_sampled_positions_follow_the_trapezoid(sers_run: Any) -> None:
    rows, events = sers_run
    starts = [when for when, name in events if name == "move_start"]
    sampled = [r for r in rows if not r["event"]]
    moving = 0
    for row in sampled:
        t = float(row["time"])
        assert abs(t / 0.01 - round(t / 0.01)) < 1e-6, t  # on the 10 ms grid of the device clock
        start, begin, distance = (3200.0, starts[1], -6400.0) if t >= starts[1] else (0.0, starts[0], 3200.0)
        expected = trapezoid(t - begin, start, distance) if t >= begin else start
        assert float(row["position"]) == pytest.approx(expected, abs=1e-6), t
        moving += t > starts[0] and abs(float(row["velocity"])) > 0
    assert moving >= 80  # 0.313 s + 0.563 s of motion at 10 ms
    assert all(r["device"] == "x" and r["axis"] == "axis" and r["following_error"] == "" for r in rows)


def test_an_axis_at_rest_writes_no_rows(sers_run: Any) -> None:
    rows, events = sers_run
    ends = [when for when, name in events if name == "move_end"]
    starts = [when for when, name in events if name == "move_start"]
    between = [float(r["time"]) for r in rows if ends[0] < float(r["time"]) < starts[1]]
    assert len(between) <= 2  # the sample that saw it stop, no 10 ms rows over the 0.5 s rest


def test_resting_values_are_repeated_before_a_change_without_event() -> None:
    """A position redefined through a point (no event): the rest is written again at the sample
    before the change, so a plot does not draw a slope across the rest; a fault is an event row."""
    runtime = Runtime(virtual=True).start()
    try:
        device = runtime.add_device("pcd4h3", "p")
        runtime.advance(3.0)
        with tempfile.TemporaryDirectory() as tmp:
            path = Path(tmp) / "log.csv"
            log = runtime.call(lambda: MotionLog(path, 0.05))
            runtime.call(log.add, device)
            runtime.advance(1.0)
            runtime.set("p", "axis.1.position", 1000)
            runtime.advance(0.2)
            runtime.call(device.fault, "blocked_2", True)
            runtime.advance(0.1)
            runtime.call(log.close)
            rows = rows_of(path)
    finally:
        runtime.stop()
    axis1 = [(float(r["time"]), r["position"], r["event"]) for r in rows if r["axis"] == "axis.1"]
    assert axis1[:3] == [(3.0, "0", ""), (pytest.approx(4.0), "0", ""), (pytest.approx(4.05), "1000", "")]
    assert [r["axis"] for r in rows if r["time"] == "3.0"] == ["axis.1", "axis.2"]
    faults = [r for r in rows if r["event"] == "fault:blocked_2=on"]
    assert [r["axis"] for r in faults] == ["axis.1", "axis.2"]  # an event row for every axis of the device
    assert float(faults[0]["time"]) == pytest.approx(4.2)
    assert float(rows[-1]["time"]) == pytest.approx(4.3)  # the closing rows


def test_every_kind_declares_its_axes_by_the_name_patterns() -> None:
    expected = {
        "sers": {"axis": {"position", "velocity"}},
        "gms96": {"axis": {"setpoint", "position", "velocity", "following_error"}},
        "pcd4h3": {f"axis.{n}": {"setpoint", "position", "velocity", "following_error"} for n in (1, 2)},
        "poselesta": {f"axis.{a}": {"position", "velocity", "following_error"} for a in "xyzd"},
        "ip247": {f"axis.{n}": {"position", "velocity"} for n in (1, 2, 3)},
    }
    assert set(expected) <= set(kinds())
    runtime = Runtime(virtual=True).start()
    try:
        for kind, axes in expected.items():
            device = runtime.add_device(kind, f"{kind}1")
            found = axis_columns(device)
            assert {axis: set(columns) for axis, columns in found.items()} == axes, kind
            for columns in found.values():  # each named point is readable as a number
                for name in columns.values():
                    assert isinstance(runtime.read(device.name, name), int | float), (kind, name)
            assert device_class(kind).points  # the patterns looked at the declared table
    finally:
        runtime.stop()


def test_no_sampling_without_a_log_and_none_after_it_closes(tmp_path: Path) -> None:
    runtime = Runtime(virtual=True).start()
    try:
        device = runtime.add_device("sers", "x")
        runtime.advance(5.0)
        clock = runtime.clock
        assert clock.next_event() is None  # idle: no timer at all
        log = runtime.call(lambda: MotionLog(tmp_path / "log.csv", 0.25))
        runtime.call(log.add, device)
        assert clock.next_event() == pytest.approx(5.25)
        runtime.call(log.close)
        assert clock.next_event() is None
    finally:
        runtime.stop()


def test_a_device_without_axes_adds_no_timer(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    monkeypatch.setenv("DEVSIM_EXTRA_KINDS", "echo=tests.support.echo:EchoDevice")
    runtime = Runtime(virtual=True).start()
    try:
        device = runtime.add_device("echo", "e")
        assert axis_columns(device) == {}
        log = runtime.call(lambda: MotionLog(tmp_path / "log.csv", 0.01))
        runtime.call(log.add, device)
        assert runtime.clock.next_event() is None
        runtime.call(log.close)
    finally:
        runtime.stop()
    assert (tmp_path / "log.csv").read_text() == ",".join(HEADER) + "\n"


@pytest.mark.parametrize("value", [0.0, -1.0, math.inf, math.nan, 1e-6, 1e5])
def test_bad_resolutions_are_refused(value: float) -> None:
    assert motion_log_problem(value) is not None
    with pytest.raises(ValueError, match="--motion-resolution"):
        MotionLog(Path(os.devnull), value)


# -- devsim run --motion-log as a real process ------------------------------------------------------
@pytest.fixture
def sockdir() -> Iterator[str]:
    with tempfile.TemporaryDirectory(prefix="dsm") as path:
        yield path


def test_devsim_run_writes_the_log_and_plot_draws_it(sockdir: str, tmp_path: Path) -> None:
    log_path, trace_path, picture = tmp_path / "run.csv", tmp_path / "run.trace", tmp_path / "run.png"
    addr = f"unix:{sockdir}/ctl.sock"
    sim = DevsimProcess("run", "sers", "--virtual", "--control", addr, "--trace", str(trace_path),
                        "--motion-log", str(log_path), "--motion-resolution", "0.02")
    try:
        seen: list[str] = []
        sim.next_match(sim.out, lambda line: line.startswith("control:"), 60, "the control line", keep=seen)
        pty = dict(line.partition(": ")[::2] for line in seen)["sers"].split(" ", 1)[1]
        with ControlClient(addr) as client, serial.Serial(pty, 9600, timeout=5) as port:
            client.request("advance", seconds=3.0)  # boot
            port.write(b"#1 ON V=60 A=100 WR=90 E\r")
            deadline = time.monotonic() + 10
            reply = b""
            while b"ok0" not in reply and time.monotonic() < deadline:
                reply += port.read(port.in_waiting or 1)
            assert b"ok0" in reply
            client.request("advance", seconds=1.0)
    finally:
        status = sim.interrupt()
    assert status == 0
    rows = rows_of(log_path)
    events = [(float(r["time"]), r["event"]) for r in rows if r["event"].startswith("move_")]
    assert [name for _, name in events] == ["move_start", "move_end"]
    assert events[1][0] - events[0][0] == pytest.approx(3200 / V + V / A, abs=1e-9)
    assert float(rows[-1]["position"]) == pytest.approx(3200.0, abs=1e-6)
    from devsim.observe.plot import render  # (the command itself: tests/test_plot.py)

    render([log_path, trace_path], picture)
    assert picture.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_devsim_up_logs_every_device_of_the_plant(sockdir: str, tmp_path: Path) -> None:
    plant = tmp_path / "plant.yaml"
    plant.write_text("devices:\n  - {name: feeder, kind: sers}\n  - {name: table, kind: pcd4h3}\n")
    log_path = tmp_path / "plant.csv"
    addr = f"unix:{sockdir}/up.sock"
    sim = DevsimProcess("up", str(plant), "--virtual", "--control", addr, "--motion-log", str(log_path),
                        "--motion-resolution", "0.5")
    try:
        sim.next_match(sim.out, lambda line: line.startswith("control:"), 60, "the control line")
        with ControlClient(addr) as client:
            client.request("advance", seconds=3.0)
            client.request("set", device="table", name="axis.2.position", value=500)
            client.request("advance", seconds=1.0)
    finally:
        status = sim.interrupt()
    assert status == 0
    rows = rows_of(log_path)
    assert {(r["device"], r["axis"]) for r in rows} == {("feeder", "axis"), ("table", "axis.1"), ("table", "axis.2")}
    moved = [(float(r["time"]), r["position"]) for r in rows if r["axis"] == "axis.2"]
    assert moved[0] == (0.0, "0") and moved[-1] == (4.0, "500")
    assert (3.5, "500") in moved  # the first sample after the change, on the 0.5 s grid


def test_a_kinds_own_event_announcements_do_not_reach_the_motion_log(tmp_path: Path) -> None:
    """The POSELESTA announces its own topic ``event`` (port, what, detail) when a limit switch
    trips; the log listens to the recorded moments (topic ``recorded``) only, and keeps going."""
    from devsim.core.clock import VirtualClock
    from devsim.devices.poselesta import PoselestaDevice

    clock = VirtualClock()
    device = PoselestaDevice(clock=clock, name="cnc")
    path = tmp_path / "cnc.csv"
    log = MotionLog(path, 0.1)
    log.add(device)
    clock.advance(3.0)
    device.model.announce("event", "limit", "switch", "x")  # what limits.py announces
    device.record_event("probe")
    clock.advance(0.2)
    log.close()
    assert any(row["event"] == "probe" for row in csv.DictReader(path.open()))
