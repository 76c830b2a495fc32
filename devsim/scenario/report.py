"""Scenario results as a readable report and as JUnit XML."""

from __future__ import annotations

import os
import xml.etree.ElementTree as ET
from collections.abc import Sequence
from pathlib import Path

from devsim.scenario.runner import ScenarioResult, StepResult

__all__ = ["format_report", "format_step", "write_junit"]

_MARK = {"pass": "PASS", "fail": "FAIL", "done": "ok", "skipped": "skipped"}


def format_report(result: ScenarioResult) -> str:
    """Each step with its simulated time and outcome, failures explained, then a summary."""
    where = f" ({result.path})" if result.path else ""
    mode = "real" if result.mode == "realtime" else result.mode
    lines = [f"scenario {result.name}{where}, {mode} time"]
    for step in result.steps:
        lines.extend(format_step(step))
    if result.error:
        lines.append(f"  error: {result.error}")
    checked = [s for s in result.steps if s.checked]
    failed = result.failures
    verdict = "PASSED" if result.passed else "FAILED"
    lines.append(
        f"{verdict}: {len(checked) - len(failed)} of {len(checked)} checks passed, "
        f"{len(result.steps)} steps, {result.sim_time:.3f} s simulated in {result.wall_time:.2f} s"
    )
    return "\n".join(lines)


def format_step(step: StepResult) -> list[str]:
    """One step of a report: its line, and the explanation of a failure."""
    place = f"line {step.line}" if step.line else f"step {step.index}"
    lines = [f"  [{step.time:9.3f}s] {place:>8}: {step.label}  {_MARK[step.status]}"]
    if step.message:
        lines.append(f"  {'':12}   {'':>8}  → {step.message}")
    return lines


def write_junit(results: Sequence[ScenarioResult], path: str | os.PathLike[str]) -> None:
    """One ``testsuite`` per scenario, one ``testcase`` per checking step."""
    suites = ET.Element("testsuites")
    for result in results:
        checked = [s for s in result.steps if s.checked or s.status == "skipped"]
        suite = ET.SubElement(
            suites,
            "testsuite",
            name=result.name,
            tests=str(len(checked) + (1 if result.error else 0)),
            failures=str(len(result.failures)),
            errors="1" if result.error else "0",
            skipped=str(sum(1 for s in checked if s.status == "skipped")),
            time=f"{result.wall_time:.3f}",
        )
        suite.set("file", result.path)
        for step in checked:
            case = ET.SubElement(
                suite,
                "testcase",
                classname=result.name,
                name=f"line {step.line}: {step.label}" if step.line else f"step {step.index}: {step.label}",
                time="0",
            )
            case.set("simulated_time", f"{step.time:.6f}")
            if step.status == "fail":
                failure = ET.SubElement(case, "failure", message=step.message)
                failure.text = step.message
            elif step.status == "skipped":
                ET.SubElement(case, "skipped", message="not reached")
        if result.error:
            case = ET.SubElement(suite, "testcase", classname=result.name, name="run", time="0")
            error = ET.SubElement(case, "error", message=result.error)
            error.text = result.error
    tree = ET.ElementTree(suites)
    ET.indent(tree)
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    tree.write(path, encoding="utf-8", xml_declaration=True)
