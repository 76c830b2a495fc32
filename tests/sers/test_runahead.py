"""A looping program run ahead while nobody looks is the program run step by step (issue 31).

Two drives get the same program: one runs it statement by statement, the other is told that
nobody looks before the next observation (as the scenario runner tells it while it waits) and
jumps the passes of its loop.  At every observation the two are compared whole: every value the
drive holds (:class:`~devsim.devices.sers.runahead._Walk` takes them all down: parameters,
program position, motion, the axis's plan and history, pending timers and their times), the
event log, and what a host reads.
"""

from __future__ import annotations

import asyncio
import math
import types
from typing import Any

from hypothesis import given, settings
from hypothesis import strategies as st

from devsim.core.clock import VirtualClock
from devsim.devices.sers import SersDevice
from devsim.devices.sers.runahead import LOG_CUT, LOG_LIMIT, _extend_log, _Walk
from devsim.runtime import Runtime
from devsim.scenario.report import format_report
from devsim.scenario.runner import run_scenario_async
from devsim.scenario.schema import scenario_from_dict

#: Statements of a loop's body: moves relative and absolute, speeds, accelerations, delays, a
#: ramp shape, conditions, the non-blocking timer D2 and its bit, an output switched (a signal
#: change: no jump over it), a counter (never the same twice: no jump).
BODY = st.sampled_from([
    "WR=180 E", "WR=-180 E", "WR=90 E", "WR=-45 E", "WA=0 E", "WA=270 E", "V=60", "V=300", "A=100",
    "A=1000", "D=1", "D=3", "P1032=1", "P1032=0", "O1=1", "O1=0", "C1=C1+1", "X=X+1", "W=10 E",
    "WAIT I1=0", "IF P12<>0 O1=1", "IF I5=0", "D2=3", "WAIT DB=1",
])
READS = ["axis.position", "axis.velocity", "param.P51", "param.P0", "param.W", "param.P1032", "param.C1",
         "motion.kind", "output.O1", "display"]


def _drive(program: list[str], slow: bool) -> tuple[SersDevice, VirtualClock, bytearray]:
    clock = VirtualClock()
    device = SersDevice(clock=clock, config={"boot_time": 0})
    out = bytearray()
    device.attach(out.extend)
    if slow:
        device.feed(b"#P1127=1\r")
    device.apply_state({"program": program})
    device.feed(b"#RUN\r")
    return device, clock, out


def _plain(leaf: Any) -> Any:
    """A leaf as two drives can share it: functions by name, shared objects without identity."""
    if isinstance(leaf, tuple) and leaf and leaf[0] == "shared":
        return "shared"
    if isinstance(leaf, (types.FunctionType, types.MethodType, types.BuiltinFunctionType)):
        return leaf.__qualname__
    return leaf


def _state(device: SersDevice, clock: VirtualClock) -> list[Any]:
    walk = _Walk(clock)
    walk.visit(device.model)
    return [_plain(leaf) for leaf in walk.leaves]


def _observe(device: SersDevice, clock: VirtualClock, out: bytearray) -> tuple[Any, ...]:
    return (clock.now(), _state(device, clock), list(device.model.events), bytes(out),
            [device.read(name) for name in READS])


def _both(program: list[str], looks: list[float], slow: bool = False) -> int:
    """Run ``program`` on two drives, one told nobody looks before each of ``looks``; compare
    them at each look; the passes jumped."""
    stepwise, clock_a, out_a = _drive(program, slow)
    ahead, clock_b, out_b = _drive(program, slow)
    for when in looks:
        clock_a.advance_to(when)
        ahead.unobserved_until(when)
        clock_b.advance_to(when)
        ahead.unobserved_until(-math.inf)
        assert _observe(ahead, clock_b, out_b) == _observe(stepwise, clock_a, out_a)
    return int(ahead.model.runahead.jumped)


def test_the_benchmark_loop_run_ahead_for_an_hour_is_the_loop_step_by_step() -> None:
    """The loop of ``benchmarks/virtual.py``, looked at after one hour and at three moments on
    the way (each in another binade)."""
    jumped = _both(["ON", "L1", "WR=180 E", "WR=-180 E", "GT1", "PE"], [100.5, 700.25, 2049.0, 3600.0])
    assert jumped > 4000  # of about 4,400 passes


def test_with_p1127_each_statement_takes_two_milliseconds() -> None:
    assert _both(["ON", "L7", "V=120", "WR=30 E", "D=1", "WR=-30 E", "GT7"], [40.0, 333.3], slow=True) > 0


def test_a_loop_that_never_moves_the_axis() -> None:
    assert _both(["L1", "P1032=1", "D=1", "P1032=0", "GT1"], [150.0, 700.0]) > 1000


def test_a_counter_never_repeats_so_nothing_is_jumped() -> None:
    assert _both(["ON", "L1", "C1=C1+1", "WR=10 E", "GT1"], [90.0]) == 0


def test_an_output_switched_in_the_loop_is_a_change_someone_may_see() -> None:
    assert _both(["ON", "L1", "O1=1", "WR=10 E", "O1=0", "WR=-10 E", "GT1"], [90.0]) == 0


def test_a_message_to_the_host_each_pass_is_never_jumped() -> None:
    """P1121=1: ``@1POS=1`` after each move goes to the host (§4.8.6.11)."""
    assert _both(["ON", "P1121=1", "L1", "WR=10 E", "WR=-10 E", "GT1"], [60.0]) == 0


@settings(max_examples=25, deadline=None)
@given(body=st.lists(BODY, min_size=1, max_size=4),
       looks=st.lists(st.floats(min_value=0.5, max_value=300.0), min_size=1, max_size=3),
       slow=st.booleans())
def test_any_loop_looked_at_any_time_is_the_loop_step_by_step(body: list[str], looks: list[float], slow: bool) -> None:
    _both(["ON", "L1", *body, "GT1", "PE"], sorted(looks), slow)


@settings(max_examples=200, deadline=None)
@given(length=st.integers(0, LOG_LIMIT), per=st.integers(1, 3), passes=st.integers(0, 7000))
def test_the_log_of_the_passes_jumped_is_cut_as_the_drive_cuts_it(length: int, per: int, passes: int) -> None:
    old = [(float(i), "old") for i in range(length)]
    during = [(1000.0 + i, f"e{i}") for i in range(per)]
    expected = list(old)
    for j in range(passes):
        for when, name in during:
            expected.append((when + (j + 1) * 2.0, name))
            if len(expected) > LOG_LIMIT:
                del expected[:LOG_CUT]
    log = list(old)
    _extend_log(log, during, 2.0, passes)
    assert log == expected


def _scenario_run(observed: bool) -> tuple[Any, ...]:
    """Three SERS on one bus looping different programs; the host waits, asks, waits and looks.
    ``observed``: something else is attached to the runtime (as a facade or a log would be)."""
    devices = [{"name": f"d{i}", "kind": "sers", "transport": {"bus": "line"}, "config": {"address": i},
                "state": {"program": ["ON", "L1", f"WR={40 * i} E", f"WR=-{40 * i} E", "GT1", "PE"]}}
               for i in (1, 2, 3)]
    data = {"devices": devices, "buses": [{"name": "line"}], "host": {"port": "line"}, "timeout": "2000s",
            "steps": [{"send": "#1 RUN\r#2 RUN\r#3 RUN\r"}, {"after": "700.3s"}, {"send": "#2 P51?\r"},
                      {"expect": {"regex": "P51="}}, {"after": "333s"},
                      {"expect_state": {"device": "d3", "name": "param.P0", "equals": 1}}]}

    async def go() -> tuple[Any, ...]:
        async with Runtime(clock=VirtualClock()) as runtime:
            if observed:
                runtime.add_closer(_nothing)
            result = await run_scenario_async(scenario_from_dict(data, "loops"), runtime)
            assert result.passed, format_report(result)
            drives = [runtime.device(f"d{i}") for i in (1, 2, 3)]
            return (runtime.clock.now(), [(_state(d, runtime.clock), list(d.model.events)) for d in drives],
                    [int(d.model.runahead.jumped) for d in drives])

    return asyncio.run(go())


async def _nothing() -> None:
    return None


def test_a_scenario_waiting_runs_the_loops_ahead_and_ends_as_step_by_step() -> None:
    ahead, stepwise = _scenario_run(observed=False), _scenario_run(observed=True)
    assert ahead[:2] == stepwise[:2]
    assert min(ahead[2]) > 500 and stepwise[2] == [0, 0, 0]


def test_no_slave_runs_ahead_beside_a_master_that_may_talk_to_it() -> None:
    """A master (address 0) on the bus may send statements to the slaves at any moment (§3.6.2)."""
    data = {"devices": [{"name": "m", "kind": "sers", "transport": {"bus": "line"}, "config": {"address": 0}},
                        {"name": "s", "kind": "sers", "transport": {"bus": "line"}, "config": {"address": 1},
                         "state": {"program": ["ON", "L1", "WR=40 E", "WR=-40 E", "GT1"]}}],
            "buses": [{"name": "line"}], "host": {"port": "line"},
            "steps": [{"send": "#1 RUN\r"}, {"after": "200s"},
                      {"expect_state": {"device": "s", "name": "param.P0", "equals": 1}}]}

    async def go() -> int:
        async with Runtime(clock=VirtualClock()) as runtime:
            result = await run_scenario_async(scenario_from_dict(data, "master"), runtime)
            assert result.passed, format_report(result)
            return int(runtime.device("s").model.runahead.jumped)

    assert asyncio.run(go()) == 0
