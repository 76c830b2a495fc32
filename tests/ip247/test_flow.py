"""The order of an IP247 program's blocks and the M function shown (spec ip247.md §4.11.5,
§4.11.8; the manual's examples)."""

from __future__ import annotations

from itertools import islice

import pytest

from devsim.devices.ip247.flow import FlowError, steps
from devsim.devices.ip247.program import parse


def programs(**texts: str) -> dict[int, object]:
    return {int(k[1:]): parse(v) for k, v in texts.items()}


def test_the_m_functions_of_the_manuals_example() -> None:
    """§4.11.8: M255 until the first traverse with an M, then held until the next one."""
    main = parse("%  1\nN05 G91\nN10 G74\nN15 G24 F1\nN20 X1000 F2000 M10\nN30 G57\nN35 X-500 F2000\nN45 G20\n"
                 "N50 G74 M20\nN60 X500 F100 M30\nN65 G26\nN70 X1000 F2000 M60\nN75 M02\n")
    shown = [(block.number, m) for _, block, m in steps({1: main}, 1)]
    assert shown == [(5, 255), (10, 255), (15, 255), (20, 10), (30, 10), (35, 10), (45, 10), (50, 20), (60, 30),
                     (65, 30), (70, 60), (75, 60)]


def test_loops_and_calls_of_the_manuals_loop_example() -> None:
    """§4.11.5: an endless outer loop with a 5-pass inner loop calling L30 twice per pass."""
    progs = programs(
        p1="%  1\nN10 G24 F0\nN20 G74\nN30 G24 F5\nN40 L30\nN50 G04 F10\nN60 L30\nN70 G20\nN80 G20\nN90 M02\n",
        p30="L 30\nN1 X10 F100\nN2 M02\n",
    )
    run = [(p, b.number) for p, b, _ in islice(steps(progs, 1), 60)]
    assert run[:8] == [(1, 10), (1, 20), (1, 30), (1, 40), (30, 1), (30, 2), (1, 50), (1, 60)]
    first = run[: run.index((1, 80))]
    assert first.count((30, 1)) == 10 and first.count((1, 70)) == 5  # 5 passes, L30 twice in each
    assert run[run.index((1, 80)) + 1] == (1, 20)  # the endless loop goes round


def test_flow_errors() -> None:
    with pytest.raises(FlowError) as missing:
        list(steps(programs(p1="%  1\nN1 L7\nN2 M02\n"), 1))
    with pytest.raises(FlowError) as endless:
        list(steps(programs(p1="%  1\nN1 L2\nN2 M02\n", p2="L  2\nN1 G24 F0\nN2 X1 F1\nN3 G20\nN4 M02\n"), 1))
    deep = {n: f"L{n:3d}\nN1 L{n + 1}\nN2 M02\n" for n in range(1, 7)}
    with pytest.raises(FlowError) as nested:
        list(steps({n: parse(t) for n, t in deep.items()} | {7: parse("L  7\nN1 M02\n")}, 1))
    assert (missing.value.error, endless.value.error, nested.value.error) == (19, 38, 39)
