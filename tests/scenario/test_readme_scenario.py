"""The scenario shown in the docs (docs/scenarios.md) validates and passes."""

from __future__ import annotations

import re
from pathlib import Path

from devsim.scenario.report import format_report
from devsim.scenario.runner import run_scenario
from devsim.scenario.schema import load_scenario

README = Path(__file__).resolve().parents[2] / "docs" / "scenarios.md"


def test_readme_scenario_runs(tmp_path: Path) -> None:
    text = README.read_text(encoding="utf-8")
    section = text[text.index("# Scenarios and plants") :]
    block = re.search(r"```yaml\n(.*?)```", section, re.S)
    assert block is not None
    path = tmp_path / "readme.yaml"
    path.write_text(block.group(1))
    result = run_scenario(load_scenario(path))
    assert result.passed, format_report(result)
    assert len(result.steps) == 7
