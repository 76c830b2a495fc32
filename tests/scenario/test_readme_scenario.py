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


#: A file with the five mistakes docs/scenarios.md shows `devsim check` reporting, on its lines.
MISTAKES = """\
devices:
  - name: x
    kind: sers
    transport: {pty: {}}
    state:
      input.limit_rigth: true
  - name: y
    kind: toaster
steps:
  - after: 1s
    log: one
  - after: soon
    log: two
  - wait: 1s
  - fault: {device: x, kind: smoke}
  - wait: 1s
  - wait: 1s
  - sned: x
"""


def test_the_check_output_shown_is_what_check_prints(tmp_path: Path, monkeypatch) -> None:
    """The lines docs/scenarios.md shows `devsim check` printing (a list cut short with `...` in
    the page) are its lines for such a file, and its status is 3."""
    from click.testing import CliRunner

    from devsim.cli import cli

    text = README.read_text(encoding="utf-8")
    shown = re.search(r"^```\n(s\.yaml:.*?)^```", text, re.S | re.M)
    assert shown is not None
    (tmp_path / "s.yaml").write_text(MISTAKES)
    monkeypatch.chdir(tmp_path)
    result = CliRunner().invoke(cli, ["check", "s.yaml"])
    assert result.exit_code == 3
    printed = result.output.splitlines()
    expected = shown.group(1).splitlines()
    assert len(printed) == len(expected), printed
    for line, want in zip(printed, expected, strict=True):
        assert line.startswith(want.removesuffix("...)")) if want.endswith(", ...)") else line == want, (line, want)


def test_the_check_line_of_the_control_page_is_what_check_prints(tmp_path: Path, monkeypatch) -> None:
    """docs/control.md quotes one `devsim check` line (it showed one suggestion of the two printed)."""
    from click.testing import CliRunner

    from devsim.cli import cli

    page = " ".join((README.parent / "control.md").read_text(encoding="utf-8").split())
    quoted = re.search(r"\(`(plant\.yaml:9: [^`]*)`\)", page)
    assert quoted is not None
    (tmp_path / "plant.yaml").write_text(
        "devices:\n  - name: x\n    kind: sers\n    transport: {pty: {}}\n    config: {address: 1}\n"
        "    axis: {limit_right: 25600}\n    # the initial state\n    state:\n      input.limit_rigth: true\n")
    monkeypatch.chdir(tmp_path)
    result = CliRunner().invoke(cli, ["check", "plant.yaml"])
    assert result.exit_code == 3 and result.output == quoted.group(1) + "\n"
