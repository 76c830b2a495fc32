"""Walk of manual §2.7 (the axis attributes) and §2.8.1 (the outputs to the power unit), driven
through the PG port on a real pty: OBSERVE (62H) shows the attributes byte, the actual value and
the residual distance as FB164 and COM247's test screen show them."""

from __future__ import annotations

import struct

import pytest

from tests.ip247.helpers import FORWARD, START, STOP, Make, Module


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


@pytest.mark.manual("§2.8.1", "as long as there are no machine data on the module, the output Rücksetzen (RS) "
                    "carries a high signal")
@pytest.mark.manual("§2.8.1", "as soon as valid machine data are on the axis, RS goes low")
def test_rs_is_high_until_valid_machine_data(mod: Module) -> None:
    mod.clock.advance(2)
    assert all(mod.device.read(f"output.RS{n}") is True for n in (1, 2, 3))
    assert mod.load_md()[8] == 0
    mod.clock.advance(1)
    assert mod.device.read("output.RS1") is False
    assert mod.device.read("output.RS2") is True and mod.device.read("output.RS3") is True


@pytest.mark.manual("§2.8.1", "RS stays high while the machine data on the axis are faulty")
def test_rs_stays_high_with_faulty_machine_data(make: Make) -> None:
    mod = make({"sys_id": {"module": 5}})  # the record names module 11: MD error 12
    assert mod.load_md()[8] == 12
    mod.clock.advance(1)
    assert mod.device.read("output.RS1") is True


@pytest.mark.manual("§2.8.1", "deleting the machine data puts RS high again")
def test_rs_high_again_after_deleting_the_machine_data(mod: Module) -> None:
    mod.load_md()
    mod.clock.advance(1)
    assert mod.device.read("output.RS1") is False
    assert mod.client.delete_record(1, 21, 101)[4] == 0
    assert mod.device.read("output.RS1") is True


@pytest.mark.manual("§2.8.1", "at the start of the reference run RS is high for 100 ms")
def test_rs_pulse_of_100_ms_at_the_reference_run(make: Make) -> None:
    mod = make({"axes": {1: {"cam": [20_000.0, 30_000.0]}}})
    mod.load_md()
    mod.clock.advance(1)
    assert mod.operate(1, 5, START, b=0)[4] == 0
    assert mod.device.read("output.RS1") is True
    mod.clock.advance(0.099)
    assert mod.device.read("output.RS1") is True
    mod.clock.advance(0.002)
    assert mod.device.read("output.RS1") is False
