"""Scenario and plant files: validation with file:line errors, and `devsim check`."""

from __future__ import annotations

from pathlib import Path

import pytest
from click.testing import CliRunner

from devsim.cli import cli, exits
from devsim.core.config import ConfigError
from devsim.scenario.schema import load_plant, load_scenario, parse_duration

GOOD = """\
name: limit switch mid-move
devices:
  - name: x
    kind: sers
    config: {address: 1}
    axis: {limit_right: 25600}
steps:
  - send: "#1 ON V=60 WR=3600 E\\r"
  - expect: {regex: "ok0"}
  - when: {device: x, name: P11, equals: 8192}
    timeout: 5s
  - expect_state: {device: x, name: display, equals: {char: c, blinking: false}}
"""


def write(tmp_path: Path, text: str, name: str = "x.yaml") -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


def error_of(path: Path) -> ConfigError:
    with pytest.raises(ConfigError) as info:
        load_scenario(path)
    return info.value


@pytest.mark.parametrize(
    ("text", "seconds"),
    [("2s", 2.0), ("150ms", 0.15), ("1.5 min", 90.0), (3, 3.0), ("0.25", 0.25), ("20us", 20e-6)],
)
def test_durations(text: object, seconds: float) -> None:
    assert parse_duration(text) == pytest.approx(seconds)


def test_a_good_scenario_loads_with_step_lines(tmp_path: Path) -> None:
    scenario = load_scenario(write(tmp_path, GOOD))
    assert scenario.name == "limit switch mid-move"
    assert [step.line for step in scenario.steps] == [8, 9, 10, 12]
    assert [step.action for step in scenario.steps] == ["send", "expect", None, "expect_state"]
    assert scenario.mode() == "virtual"  # the host is scripted
    assert scenario.devices[0].device_config()["axis"] == {"limit_right": 25600}


def test_bad_duration_names_file_line_and_field(tmp_path: Path) -> None:
    text = GOOD.replace("    timeout: 5s", "    timeout: 5 parsecs")
    error = error_of(write(tmp_path, text))
    assert str(error) == f"{tmp_path / 'x.yaml'}:11: steps.3.timeout: `timeout` must be a duration like 2s or 150ms"


def test_after_must_be_a_duration(tmp_path: Path) -> None:
    text = GOOD + "  - after: soon\n    log: x\n"
    assert str(error_of(write(tmp_path, text))).endswith(":13: steps.5.after: `after` must be a duration like 2s or 150ms")


def test_two_triggers_and_two_actions_are_refused(tmp_path: Path) -> None:
    text = GOOD + "  - at: 1s\n    after: 2s\n    log: x\n  - send: a\n    wait: 1s\n"
    error = error_of(write(tmp_path, text))
    assert any(":13: steps.5: a step has one trigger, not at and after" in m for m in error.messages)
    assert any(":16: steps.6: a step has exactly one action" in m for m in error.messages)


def test_unknown_field_and_unknown_device(tmp_path: Path) -> None:
    text = GOOD.replace("    config: {address: 1}", "    config: {address: 1}\n    colour: red")
    assert str(error_of(write(tmp_path, text))).endswith(":6: devices.1.colour: unknown field")
    text = GOOD.replace("{device: x, name: P11", "{device: y, name: P11")
    assert ":10: steps.3.when.device: no device named 'y'" in str(error_of(write(tmp_path, text)))


def test_device_config_is_validated_by_its_kind(tmp_path: Path) -> None:
    text = GOOD.replace("config: {address: 1}", "config:\n      address: 1\n      baud: 9601")
    assert str(error_of(write(tmp_path, text))).endswith(
        ":7: devices.1.config.baud: baud must be one of 1200, 2400, 4800, 9600, 19200, 38400, 57600, 115200"
    )
    text = GOOD.replace("kind: sers", "kind: toaster")
    assert ":4: devices.1.kind: unknown device kind 'toaster'" in str(error_of(write(tmp_path, text)))


def test_yaml_syntax_error_has_a_line(tmp_path: Path) -> None:
    assert ":3:" in str(error_of(write(tmp_path, "devices:\n  - name: x\n  kind: [\n")))


def test_bus_references_are_checked(tmp_path: Path) -> None:
    text = "devices:\n  - {name: a, kind: sers, transport: {bus: line}}\n"
    with pytest.raises(ConfigError, match="not defined"):
        load_plant(write(tmp_path, text, "plant.yaml"))
    text += "buses:\n  - {name: line}\n"
    plant = load_plant(write(tmp_path, text, "plant.yaml"))
    assert plant.ports() == ["line"]


def test_devsim_check(tmp_path: Path) -> None:
    good = write(tmp_path, GOOD, "good.yaml")
    bad = write(tmp_path, GOOD.replace("timeout: 5s", "timeout: x"), "bad.yaml")
    result = CliRunner().invoke(cli, ["check", str(good)])
    assert result.exit_code == 0
    assert "good.yaml: ok (scenario, 4 steps, 1 device)" in result.output
    result = CliRunner().invoke(cli, ["check", str(good), str(bad)])
    assert result.exit_code == exits.BAD_FILE
    assert "bad.yaml:11: steps.3.timeout: `timeout` must be a duration like 2s or 150ms" in result.output


def test_check_finds_misspelled_names_and_wrong_types(tmp_path: Path) -> None:
    plant = tmp_path / "plant.yaml"
    plant.write_text(
        "devices:\n"
        "  - name: x\n"
        "    kind: sers\n"
        "    state:\n"
        "      input.limit_rigth: true\n"
    )
    result = CliRunner().invoke(cli, ["check", str(plant)])
    assert result.exit_code == exits.BAD_FILE
    assert "plant.yaml:5: devices.1.state.input.limit_rigth: x has no 'input.limit_rigth' (did you mean " \
        "input.limit_right" in result.output
    scenario = tmp_path / "s.yaml"
    scenario.write_text(
        "devices:\n"
        "  - {name: x, kind: sers}\n"
        "steps:\n"
        "  - set: {device: x, values: {quantity.supply_voltage: hello}}\n"
        "  - expect_state: {device: x, name: axis.positon, equals: 0}\n"
    )
    result = CliRunner().invoke(cli, ["check", str(scenario)])
    assert result.exit_code == exits.BAD_FILE
    assert "s.yaml:4: steps.1.set.values.quantity.supply_voltage: quantity.supply_voltage: expects a number" in result.output
