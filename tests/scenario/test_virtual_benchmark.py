"""The scenarios ``benchmarks/virtual.py`` times (issue 31): each kind's looping program runs
under virtual time and the last step's check holds; for a loop that never started it fails, so
the benchmark cannot time a device that stands still.  And each schedules only the timers its
events need: a loop sampled while nobody looks shows as a count of timers far above them."""

from __future__ import annotations

import asyncio
import importlib.util
from collections.abc import Callable
from pathlib import Path
from types import ModuleType
from typing import Any

import pytest

from devsim.core.clock import Timer, VirtualClock
from devsim.runtime import Runtime
from devsim.scenario.report import format_report
from devsim.scenario.runner import ScenarioResult, run_scenario, run_scenario_async
from devsim.scenario.schema import load_scenario

ROOT = Path(__file__).resolve().parents[2]


def _benchmark() -> ModuleType:
    spec = importlib.util.spec_from_file_location("virtual_benchmark", ROOT / "benchmarks" / "virtual.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


SCENARIOS = _benchmark().SCENARIOS
#: The step that starts each new kind's loop (the GMS96's p3;1;0, the IP247's BA8, the POSELESTA's NC-Start).
STARTS = {"gms96": r"\x70\x03\x00\x00\x01", "ip247": "ba: 8", "poselesta": "panel.nc_start"}


@pytest.mark.parametrize("kind", sorted(SCENARIOS))
def test_each_kinds_loop_runs_and_is_checked(kind: str, tmp_path: Path) -> None:
    path = tmp_path / f"{kind}.yaml"
    path.write_text(SCENARIOS[kind](120.0))
    result = run_scenario(load_scenario(path))
    assert result.passed, format_report(result)


@pytest.mark.parametrize("kind", sorted(STARTS))
def test_a_loop_that_never_started_fails_the_last_check(kind: str, tmp_path: Path) -> None:
    lines = SCENARIOS[kind](120.0).splitlines(keepends=True)
    start = next(i for i, line in enumerate(lines) if STARTS[kind] in line)
    if lines[start].lstrip().startswith("- send"):
        del lines[start:start + 2]  # the send and the expect of its acknowledge
    elif lines[start].lstrip().startswith("set:"):
        lines[start - 1:start + 1] = ["  - after: 100ms\n    expect_state: {device: cnc, name: program.block, equals: -1}\n"]
    else:
        del lines[start]
    path = tmp_path / f"{kind}.yaml"
    path.write_text("".join(lines))
    result = run_scenario(load_scenario(path))
    assert not result.passed and not result.error
    assert [step.status for step in result.steps][-1] == "fail", format_report(result)
    assert "between" in result.steps[-1].label  # the expect_timing of the loop's last event


class CountingClock(VirtualClock):
    """The virtual clock, counting the timers scheduled on it (as ``benchmarks/virtual.py`` does)."""

    def __init__(self) -> None:
        super().__init__()
        self.scheduled = 0

    def call_at(self, when: float, callback: Callable[[], Any]) -> Timer:
        self.scheduled += 1
        return super().call_at(when, callback)


#: Timers each kind's two minutes may schedule: about twice what they scheduled on 2026-11-30
#: (GMS96 273, IP247 82, PCD4.H3 237, POSELESTA 866, SERS 7,060).  A loop sampled while nobody
#: looks goes far past them: the GMS96 PLC cycled one by one (every 20 ms, as it did after
#: 4a22bde) schedules about 6,100, a timer every 10 ms 12,000 more.
MOST_TIMERS = {"gms96": 600, "ip247": 200, "pcd4h3": 500, "poselesta": 1800, "sers": 14000}


@pytest.mark.parametrize("kind", sorted(SCENARIOS))
def test_each_kinds_loop_schedules_only_the_timers_its_events_need(kind: str, tmp_path: Path) -> None:
    path = tmp_path / f"{kind}.yaml"
    path.write_text(SCENARIOS[kind](120.0))
    clock = CountingClock()

    async def run() -> ScenarioResult:
        async with Runtime(clock=clock) as runtime:
            return await run_scenario_async(load_scenario(path), runtime)

    result = asyncio.run(run())
    assert result.passed, format_report(result)
    assert 10 < clock.scheduled <= MOST_TIMERS[kind]
