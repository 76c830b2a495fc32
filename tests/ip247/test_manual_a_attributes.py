"""Walk of manual §2.7 (the axis attributes) and §2.8.1 (the outputs to the power unit), driven
through the PG port on a real pty: OBSERVE (62H) shows the attributes byte, the actual value and
the residual distance as FB164 and COM247's test screen show them."""

from __future__ import annotations

import struct

import pytest

from tests.ip247.helpers import FORWARD, START, STOP, Module


def observed(mod: Module, page: int = 1) -> tuple[int, int, int]:
    """(attributes RMLD, actual value, residual) of a page, as OBSERVE returns them."""
    answer = mod.call(0x62, bytes((page,)))
    position, residual = struct.unpack(">ii", answer[8:16])
    return answer[6], position, residual


@pytest.mark.manual("§2.7.7", "a positioning stopped before its target leaves the residual distance to the "
                    "target standing; a tool offset made afterwards updates it")
@pytest.mark.manual("§2.7.7", "a relative move by the residual shown then reaches the originally wanted target")
def test_tool_offset_after_a_stop_updates_the_residual(mod: Module) -> None:
    mod.ready()
    assert mod.operate(1, 6, START, w=1000, dd=50_000)[4] == 0
    mod.clock.advance(1.0)
    mod.operate(1, 6, STOP)
    mod.clock.advance(5)
    _, actual, residual = observed(mod)
    assert residual > 0 and actual + residual == 50_000
    assert mod.operate(1, 15, FORWARD, dd=5_000)[4] == 0  # the tool tip now 5 mm further forward
    _, actual, residual = observed(mod)
    assert actual + residual == 50_000
    mod.operate(1, 7, FORWARD, w=1000, dd=residual)
    mod.clock.advance(60)
    _, actual, residual = observed(mod)
    assert actual == 50_000 and residual == 0 and mod.device.read("output.PE1") is True
