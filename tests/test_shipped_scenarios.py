"""Every shipped scenario (``scenarios/**/*.yaml``) loads and passes in virtual time."""

from __future__ import annotations

from pathlib import Path

import pytest

from devsim.scenario.report import format_report
from devsim.scenario.runner import run_scenario
from devsim.scenario.schema import load_scenario

ROOT = Path(__file__).resolve().parents[1]
SCENARIOS = sorted((ROOT / "scenarios").glob("**/*.yaml"))
IDS = [path.relative_to(ROOT / "scenarios").as_posix() for path in SCENARIOS]


def test_scenarios_are_shipped() -> None:
    assert SCENARIOS, f"no scenario files under {ROOT / 'scenarios'}"


@pytest.mark.parametrize("path", SCENARIOS, ids=IDS)
def test_shipped_scenario_passes(path: Path) -> None:
    scenario = load_scenario(path)
    assert scenario.name, f"{path}: no name"
    assert scenario.description.strip(), f"{path}: no description"
    result = run_scenario(scenario)
    assert result.passed, format_report(result)
