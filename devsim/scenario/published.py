"""A running scenario's progress where the control API can read it (op ``scenario``): what the
web page's scenario view (:mod:`devsim.web`) and ``devsim ctl scenario`` show.

:class:`PublishedProgress` is a step hook of the runner (``on_step(step, now)``, loop thread) that
keeps :attr:`devsim.runtime.Runtime.scenario` up to date: every step of the file with its label,
``pending`` until it has run, then its outcome (``pass``, ``fail``, ``done``, ``skipped``), time
and message; how many have run; the timeline time of the last one and the timeline's length
(:func:`timeline_length`); ``running`` until the run ends, then ``passed``.
"""

from __future__ import annotations

from typing import Any

from devsim.scenario.schema import Scenario

__all__ = ["PublishedProgress", "timeline_length"]


def timeline_length(scenario: Scenario) -> float:
    """Seconds the timeline takes by its ``at``, ``after`` and ``wait`` steps (``when`` steps
    and expectations count as instant)."""
    end = 0.0
    for step in scenario.steps:
        if step.at is not None:
            end = max(end, step.at)
        elif step.after is not None:
            end += step.after
        if step.wait is not None:
            end += step.wait
    return end


class PublishedProgress:
    """Publishes the run of ``scenario`` on ``runtime`` (its ``scenario`` attribute); ``labels``:
    each step's label as the report writes it."""

    def __init__(self, runtime: Any, scenario: Scenario, mode: str, labels: list[str]) -> None:
        self.runtime = runtime
        self.record: dict[str, Any] = {
            "name": scenario.name or "scenario", "path": scenario.path, "mode": mode,
            "steps": [{"index": index, "line": step.line, "label": label, "status": "pending", "time": None,
                       "message": ""}
                      for index, (step, label) in enumerate(zip(scenario.steps, labels, strict=True), start=1)],
            "total": len(scenario.steps), "done": 0, "now": 0.0, "end": timeline_length(scenario),
            "started": False, "running": True, "passed": None, "error": "",
        }
        runtime.scenario = self.record

    def step(self, step: Any, now: float) -> None:
        """The runner's hook: ``step`` (a :class:`~devsim.scenario.runner.StepResult`, None when
        the timeline starts) at timeline time ``now``."""
        record = self.record
        record["now"] = round(now, 6)
        record["started"] = True
        if step is None:
            return
        row = record["steps"][step.index - 1]
        row.update(status=step.status, time=round(step.time, 6), message=step.message)
        record["done"] = sum(1 for s in record["steps"] if s["status"] != "pending")

    def finish(self, result: Any) -> None:
        """The run has ended with ``result`` (a :class:`~devsim.scenario.runner.ScenarioResult`)."""
        for step in result.steps:
            row = self.record["steps"][step.index - 1]
            row.update(status=step.status, time=round(step.time, 6), message=step.message)
        self.record.update(done=sum(1 for s in self.record["steps"] if s["status"] != "pending"),
                           running=False, passed=result.passed, error=result.error, now=round(result.sim_time, 6))
