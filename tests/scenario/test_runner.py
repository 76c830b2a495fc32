"""The scenario runner: triggers, actions, expectations, time modes, reports and JUnit."""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any

import pytest
from click.testing import CliRunner

from devsim.cli import cli, exits
from devsim.scenario.report import format_report, write_junit
from devsim.scenario.runner import ScenarioResult, run_scenario
from devsim.scenario.schema import scenario_from_dict

DEG = 12800 / 360


def scenario(steps: list[dict[str, Any]], **extra: Any) -> Any:
    data: dict[str, Any] = {"devices": [{"name": "x", "kind": "sers", "config": {"address": 1}}], "steps": steps}
    data.update(extra)
    return scenario_from_dict(data, "test")


def run(steps: list[dict[str, Any]], mode: str = "virtual", **extra: Any) -> ScenarioResult:
    return run_scenario(scenario(steps, **extra), mode=mode)


def statuses(result: ScenarioResult) -> list[str]:
    return [step.status for step in result.steps]


def test_send_and_expect_exact_bytes_and_regex() -> None:
    result = run([
        {"send": "#1 ON\r"},
        {"expect": "#1 ON\r\nok1\n\r"},
        {"send": {"line": "#P11?"}},
        {"expect": {"regex": "P11=0\n\r\nok1", "timeout": "100ms"}},
    ])
    assert result.passed, format_report(result)
    assert statuses(result) == ["done", "pass", "done", "pass"]


def test_a_wrong_answer_fails_with_a_clear_message() -> None:
    result = run([{"send": "#1 ON\r"}, {"expect": "#1 ON\r\nok0\n\r"}])
    assert not result.passed
    assert result.failures[0].message == r"""expected b'#1 ON\r\nok0\n\r', got b'#1 ON\r\nok1\n\r'"""
    report = format_report(result)
    assert "FAIL" in report and "FAILED: 0 of 1 checks passed" in report


def test_expect_times_out_in_simulated_time() -> None:
    result = run([{"send": "#1 ON\r"}, {"expect": {"regex": "@1POS=1", "timeout": "3s"}}])
    assert result.failures[0].message.startswith("no match for /@1POS=1/ within 3s; got b'#1 ON")
    assert result.steps[-1].time == pytest.approx(3.0)


def test_time_mode_defaults() -> None:
    assert scenario([{"send": "#1 ON\r"}]).mode() == "virtual"  # the host is scripted
    assert scenario([{"wait": 1}]).mode() == "realtime"  # an external host drives the plant
    assert scenario([{"wait": 1}], time="virtual").mode() == "virtual"


def test_at_after_and_wait_move_simulated_time() -> None:
    result = run([
        {"at": "1.5s", "log": "a"},
        {"after": "250ms", "log": "b"},
        {"wait": 2},
        {"at": "1s", "log": "late: runs at once"},
    ])
    assert [round(step.time, 6) for step in result.steps] == [1.5, 1.75, 3.75, 3.75]


def test_when_trigger_and_its_timeout() -> None:
    result = run([
        {"send": "#1 ON V=1000 W=2500 E\r"},
        {"when": {"device": "x", "name": "motion.kind", "equals": None}, "timeout": "5s"},
        {"expect_state": {"device": "x", "name": "param.P51", "approx": 2500, "tolerance": 0.01}},
        {"expect_timing": {"device": "x", "event": "move_end", "between": ["1.31s", "1.33s"]}},
    ])
    assert result.passed, format_report(result)
    assert result.steps[1].time == pytest.approx(1.321, abs=1e-3)
    failing = run([
        {"when": {"device": "x", "name": "P11", "ge": 1}, "timeout": "2s"},
        {"log": "never reached"},
    ])
    assert failing.failures[0].message == "condition not met within 2s: x.P11 >= 1.0 (is 0)"
    assert statuses(failing) == ["fail", "skipped"]


def test_set_pulse_and_expect_state() -> None:
    result = run([
        {"set": {"device": "x", "values": {"input.I1": True, "input.I4": True}}},
        {"expect_state": {"device": "x", "name": "param.P1300", "equals": 9}},
        {"pulse": {"device": "x", "input": "I2", "width": "50ms"}},
        {"expect_state": {"device": "x", "name": "input.I2", "equals": True}},
        {"after": "60ms", "expect_state": {"device": "x", "name": "input.I2", "equals": False}},
        {"expect_state": {"device": "x", "name": "param.P1300", "equals": 9}},
    ])
    assert result.passed, format_report(result)
    assert result.failures == [] and statuses(result)[-1] == "pass"
    wrong = run([{"expect_state": {"device": "x", "name": "param.P1300", "equals": 1}}])
    assert wrong.failures[0].message == "x.param.P1300 == 1: is 0"


def test_overlapping_pulses_on_one_input_are_one_pulse_to_the_last_end() -> None:
    """Two pulses on I2, 0 … 100 ms and 50 … 150 ms: I2 stays on to 150 ms (the first one's end
    does not cut the second), then off (the second does not put back the first one's on)."""
    result = run([
        {"pulse": {"device": "x", "input": "I2", "width": "100ms"}},
        {"after": "50ms", "pulse": {"device": "x", "input": "I2", "width": "100ms"}},
        {"after": "75ms", "expect_state": {"device": "x", "name": "input.I2", "equals": True}},  # 125 ms
        {"after": "50ms", "expect_state": {"device": "x", "name": "input.I2", "equals": False}},  # 175 ms
        {"after": "1s", "expect_state": {"device": "x", "name": "input.I2", "equals": False}},
        {"pulse": {"device": "x", "input": "I2", "width": "10ms"}},  # and a pulse after them as before
        {"after": "20ms", "expect_state": {"device": "x", "name": "input.I2", "equals": False}},
    ])
    assert result.passed, format_report(result)


def test_device_faults() -> None:
    result = run([
        {"send": "#1 ON V=60 W=360 E\r"},
        {"after": "100ms", "fault": {"device": "x", "kind": "emergency_stop", "duration": "1s"}},
        {"when": {"device": "x", "name": "motion.kind", "equals": None}, "timeout": "1s"},
        {"expect_state": {"device": "x", "name": "display", "equals": {"char": "5", "blinking": True}}},
        {"after": "1s", "expect_state": {"device": "x", "name": "input.stop", "equals": False}},
        {"fault": {"device": "x", "kind": "power_cycle"}},
        {"expect_state": {"device": "x", "name": "display", "regex": "'-'"}},
        {"after": "2s", "expect_state": {"device": "x", "name": "energized", "equals": False}},
    ])
    assert result.passed, format_report(result)


def test_blocked_axis_builds_a_following_error() -> None:
    result = run(
        [
            {"send": "#1 ON V=60 W=360 E\r"},
            {"after": "100ms", "fault": {"device": "x", "kind": "blocked_axis"}},
            {"when": {"device": "x", "name": "P11", "equals": 32}, "timeout": "1s"},
            {"expect_state": {"device": "x", "name": "load_angle", "approx": 255, "tolerance": 1e-6}},
        ],
        devices=[{"name": "x", "kind": "sers", "config": {"options": ["E50"], "params": {"P1053": 8, "P1029": 1}}}],
    )
    assert result.passed, format_report(result)


def test_power_cycle_keeps_or_wipes_memory(tmp_path: Path) -> None:
    steps = [
        {"send": "#1 V=1234 PSAVE\r"},
        {"expect": {"regex": "ok"}},
        {"power_cycle": {"device": "x"}},
        {"after": "2s", "send": "#1 V?\r"},
        {"expect": {"regex": "V=1234U/min"}},
        {"power_cycle": {"device": "x", "wipe": True}},
        {"after": "2s", "send": "#1 V?\r"},
        {"expect": {"regex": "V=100U/min"}},
    ]
    result = run_scenario(scenario(steps), state_dir=tmp_path)
    assert result.passed, format_report(result)


def test_line_fault_corrupt_and_traffic_expectation() -> None:
    result = run([
        {"line_fault": {"kind": "corrupt", "count": 3, "direction": "to_device"}},
        {"send": "#1 ON\r"},
        {"wait": "10ms"},
        {"expect_state": {"device": "x", "name": "energized", "equals": False}},
        {"send": "#1 ON\r"},
        {"expect": {"regex": "#1 ON\r\nok[13]\n\r"}},
        {"expect_traffic": {"direction": "host", "regex": "#1 ON", "count": 2}},
        {"expect_traffic": {"direction": "device", "regex": "ok"}},
    ])
    assert result.passed, format_report(result)
    missing = run([{"expect_traffic": {"direction": "host", "regex": "PSAVE"}}])
    assert missing.failures[0].message == "the host never sent anything matching /PSAVE/"


def test_unplug_then_reconnect() -> None:
    result = run([
        {"send": "#1 ON\r"},
        {"expect": {"regex": "ok1"}},
        {"line_fault": {"kind": "unplug", "duration": "1s"}},
        {"send": "#1 OFF\r"},
        {"wait": "100ms"},
        {"expect_state": {"device": "x", "name": "energized", "equals": True}},
        {"after": "1s", "send": "#1 P134?\r"},
        {"expect": {"regex": "P134=7"}},
    ])
    assert result.passed, format_report(result)


def test_multidrop_bus_and_tcp_ports() -> None:
    data = {
        "devices": [
            {"name": "a", "kind": "sers", "config": {"address": 1}, "transport": {"bus": "line"}},
            {"name": "b", "kind": "sers", "config": {"address": 2}, "transport": {"bus": "line"}},
            {"name": "c", "kind": "sers", "config": {"address": 3}, "transport": {"tcp": {}}},
        ],
        "buses": [{"name": "line"}],
        "host": {"port": "line"},
        "steps": [
            {"send": "#2 V=222\r"},
            {"expect": "#2 V=222\r\nok1\n\r"},
            {"send": {"port": "c", "line": "#3 V=333"}},
            {"expect": {"port": "c", "bytes": "#3 V=333\r\nok1\n\r"}},
            {"expect_state": {"device": "a", "name": "param.V", "equals": 100}},
            {"expect_state": {"device": "b", "name": "param.V", "equals": 222}},
            {"expect_state": {"device": "c", "name": "param.V", "equals": 333}},
        ],
    }
    result = run_scenario(scenario_from_dict(data, "bus"))
    assert result.passed, format_report(result)
    assert result.ports["c"].startswith("socket://127.0.0.1:")


def test_initial_state_and_axis_geometry() -> None:
    data = {
        "devices": [{
            "name": "x", "kind": "sers", "axis": {"limit_right": 90 * DEG},
            "state": {"input.I3": True, "program": ["ON V=100", "W=360 E"]},
        }],
        "steps": [
            {"expect_state": {"device": "x", "name": "input.I3", "equals": True}},
            {"send": "#1 LIST\r"},
            {"expect": {"regex": "1: ON\n\r2: V=100.0000\n\r3: W=360.0000\n\r4: E\n\r\nok1"}},
            {"send": "#1 ON W=360 E\r"},
            {"when": {"device": "x", "name": "P11", "equals": 8192}, "timeout": "2s"},
            {"expect_state": {"device": "x", "name": "axis.position", "approx": 90 * DEG, "tolerance": 1e-6}},
        ],
    }
    result = run_scenario(scenario_from_dict(data, "state"))
    assert result.passed, format_report(result)
    v, a, d = 100 * 2 * math.pi / 60, 100.0, math.pi / 2  # rad/s, rad/s², 90° in rad
    assert result.steps[4].time == pytest.approx(v / a + (d - v * v / (2 * a)) / v, rel=1e-9)


def test_same_result_in_virtual_and_real_time() -> None:
    steps = [
        {"send": "#1 ON V=600 A=1000 W=90 E\r"},
        {"expect": {"regex": "ok0"}},
        {"when": {"device": "x", "name": "motion.kind", "equals": None}, "timeout": "2s"},
        {"expect_state": {"device": "x", "name": "param.P51", "equals": 90}},
        {"expect_timing": {"device": "x", "event": "move_end", "between": ["0.05s", "0.2s"]}},
        {"send": "#1 POS?\r"},
        {"expect": {"regex": "POS=1\n\r\nok1"}},
    ]
    fast_boot = [{"name": "x", "kind": "sers", "config": {"address": 1, "boot_time": 0.1}}]
    virtual = run(steps, mode="virtual", devices=fast_boot)
    real = run(steps, mode="realtime", devices=fast_boot)
    assert virtual.mode == "virtual" and real.mode == "realtime"
    assert virtual.passed, format_report(virtual)
    assert real.passed, format_report(real)
    assert statuses(virtual) == statuses(real)
    # Real time notices the move's end when the loop gets to it (later on a loaded machine), never
    # before the physics ends it; the step's 2 s timeout bounds it from above.
    assert real.steps[2].time >= virtual.steps[2].time - 0.005


def test_junit_output(tmp_path: Path) -> None:
    good = run([{"send": "#1 ON\r"}, {"expect": {"regex": "ok1"}}])
    bad = run([{"expect_state": {"device": "x", "name": "P11", "equals": 1}}])
    out = tmp_path / "junit.xml"
    write_junit([good, bad], out)
    root = ET.parse(out).getroot()
    suites = root.findall("testsuite")
    assert [s.get("failures") for s in suites] == ["0", "1"]
    failure = suites[1].find("testcase/failure")
    assert failure is not None and failure.get("message") == "x.P11 == 1: is 0"


def test_cli_scenario_run_reports_and_exit_status(tmp_path: Path) -> None:
    text = (
        "devices:\n  - {name: x, kind: sers}\nsteps:\n"
        "  - send: \"#1 ON\\r\"\n  - expect: {regex: ok1}\n"
        "  - expect_state: {device: x, name: energized, equals: false}\n"
    )
    path = tmp_path / "s.yaml"
    path.write_text(text)
    junit = tmp_path / "out.xml"
    result = CliRunner().invoke(cli, ["scenario", "run", str(path), "--junit", str(junit)])
    assert result.exit_code == exits.FAILED
    assert "line 6: expect x.energized == False  FAIL" in result.output
    assert "→ x.energized == False: is True" in result.output
    assert junit.exists()
    path.write_text(text.replace("equals: false", "equals: true"))
    result = CliRunner().invoke(cli, ["scenario", "run", str(path)])
    assert result.exit_code == 0, result.output
    assert "PASSED: 2 of 2 checks passed" in result.output


def test_realtime_run_waits_for_an_external_host() -> None:
    """No host actions: the plant runs in real time and the timeline waits for real host software."""
    import threading

    import serial

    data = {
        "devices": [{"name": "x", "kind": "sers", "config": {"boot_time": 0.05}}],
        "steps": [
            {"when": {"device": "x", "name": "energized", "equals": True}, "timeout": "10s"},
            {"when": {"device": "x", "name": "param.V", "equals": 500}, "timeout": "10s"},
            {"expect_traffic": {"direction": "host", "regex": "#1 V=500"}},
        ],
    }
    ports: list[str] = []
    ready = threading.Event()

    def announce(plant: Any) -> None:
        ports.append(plant.path("x"))
        ready.set()

    def host() -> None:
        assert ready.wait(10)
        with serial.Serial(ports[0], 9600, timeout=2) as port:
            for line in (b"#1 ON\r", b"#1 V=500\r"):
                # retry until the drive has booted and acknowledges
                reply = b""
                for _ in range(50):
                    port.write(line)
                    reply = port.read_until(b"ok1\n\r")
                    if b"ok" in reply:
                        break
                assert b"ok" in reply

    thread = threading.Thread(target=host)
    thread.start()
    result = run_scenario(scenario_from_dict(data, "external"), announce=announce)
    thread.join(10)
    assert result.mode == "realtime"
    assert result.passed, format_report(result)


def test_when_sees_positions_between_events() -> None:
    """A condition on a position that changes during a cruise is met when it is reached."""
    result = run([
        {"send": "#1 ON V=60 WR=3600 E\r"},
        {"when": {"device": "x", "name": "axis.position", "ge": 12800}, "timeout": "20s"},
        {"when": {"device": "x", "name": "homing", "not_equals": "creep"}},
    ])
    assert result.passed, format_report(result)
    # one revolution (2π rad) at 60 rpm = 2π rad/s with A = 100 rad/s², seen within 1 ms
    v, a = 2 * math.pi, 100.0
    reached = v / a + (2 * math.pi - v * v / (2 * a)) / v
    assert reached <= result.steps[1].time <= reached + 0.001


def test_power_off_and_on_faults(tmp_path: Path) -> None:
    result = run_scenario(scenario([
        {"send": "#1 V=321 PSAVE\r"},
        {"expect": {"regex": "ok"}},
        {"fault": {"device": "x", "kind": "power_off", "duration": "1s"}},
        {"expect_state": {"device": "x", "name": "powered", "equals": False}},
        {"send": "#1 V?\r"},
        {"wait": "500ms"},
        {"expect_traffic": {"direction": "device", "regex": "V=321U/min", "count": 0}},
        {"after": "600ms", "expect_state": {"device": "x", "name": "booting", "equals": True}},
        {"after": "2s", "send": "#1 V?\r"},
        {"expect": {"regex": "V=321U/min"}},
        {"fault": {"device": "x", "kind": "power_cycle_wipe"}},
        {"after": "2s", "send": "#1 V?\r"},
        {"expect": {"regex": "V=100U/min"}},
    ]), mode="virtual", state_dir=tmp_path)
    assert result.passed, format_report(result)


@pytest.mark.parametrize(
    ("fault", "answered"),
    [
        ({"kind": "drop", "count": 2, "direction": "to_device"}, False),
        ({"kind": "hang", "duration": "1s"}, False),
        ({"kind": "silent", "duration": "1s"}, False),
        ({"kind": "baud_mismatch", "baudrate": 19200, "duration": "1s"}, False),
        ({"kind": "split", "count": 20, "delay": "5ms"}, True),
        ({"kind": "delay", "delay": "200ms", "duration": "1s"}, True),
        ({"kind": "jitter", "delay": "50ms", "duration": "1s", "direction": "to_host"}, True),
    ],
)
def test_line_faults_through_the_runner(fault: dict[str, Any], answered: bool) -> None:
    """Each line fault on the real pty: the query is lost or garbled, or arrives late but intact."""
    steps = [
        {"line_fault": fault},
        {"send": "#1 P11?\r"},
        {"expect": {"regex": "P11=0\n\r\nok1", "timeout": "500ms"}},
    ]
    result = run(steps)
    assert result.steps[-1].status == ("pass" if answered else "fail"), format_report(result)
    # after the fault the line works again
    recovered = run([
        {"line_fault": fault},
        {"wait": "1.5s"},
        {"send": "\r\r#1 P11?\r"},  # a count fault may still swallow two bytes
        {"expect": {"regex": "P11=0\n\r\nok1", "timeout": "500ms"}},
    ])
    assert recovered.passed, format_report(recovered)


def test_every_step_action_of_the_schema_is_a_row_of_the_runners_table() -> None:
    from devsim.scenario import runner, schema

    assert sorted(row.token for row in runner.ACTIONS) == sorted(schema.ACTIONS)


@pytest.mark.parametrize("steps", [[{"wait": 50}], [{"wait": 50}, {"log": "after"}]], ids=["last", "not-last"])
def test_the_scenarios_timeout_holds_for_its_last_step_too(steps: list[dict[str, Any]]) -> None:
    """timeout: the limit on the whole run; a last step that ran past it passed before."""
    result = run(steps, timeout="1s")
    assert not result.passed and result.error == "the scenario ran longer than its timeout of 1s"


def test_a_time_mode_that_is_neither_virtual_nor_realtime_is_refused() -> None:
    """(The pytest marker's mode="Virtual" ran in real time.)"""
    with pytest.raises(ValueError, match="'virtual' or 'realtime', not 'Virtual'"):
        run([{"wait": 1}], mode="Virtual")


def test_a_boolean_equals_only_a_boolean() -> None:
    """(Python's False == 0: ``equals: 0`` held for an input that is off, ``not_equals: 0`` failed.)"""
    result = run([
        {"expect_state": {"device": "x", "name": "input.I1", "equals": False}},
        {"expect_state": {"device": "x", "name": "input.I1", "not_equals": 0}},
        {"expect_state": {"device": "x", "name": "input.I1", "equals": 0}},
        {"expect_state": {"device": "x", "name": "display", "equals": {"char": "4", "blinking": False}}},
        {"expect_state": {"device": "x", "name": "display", "equals": {"char": "4", "blinking": 0}}},  # inside too
    ])
    assert statuses(result) == ["pass", "pass", "fail", "pass", "fail"]
