"""Walk of manual §4.1/§4.1.1 (principle of operation, the operator command) and §4.2 (the
operator modes), driven through the PG port on a real pty."""

from __future__ import annotations

import pytest

from tests.ip247.helpers import FORWARD, START, STOP, Module

ACK_QUEUED = 0x01


@pytest.mark.manual("§7.2.2", "error 2: the last job contained an undefined operating mode; the running mode "
                    "is aborted and the error shown")
@pytest.mark.manual("§4.1.1", "BA3 is free (not defined)")
def test_undefined_mode_while_running_aborts_with_2(mod: Module) -> None:
    mod.ready()
    mod.operate(1, 1, FORWARD, w=1000)
    mod.clock.advance(1)
    assert mod.device.read("axis.1.running") is True
    assert mod.operate(1, 3, START)[4] == 2
    mod.clock.advance(5)
    assert mod.device.read("axis.1.running") is False
    assert mod.device.read("axis.1.error") == 2


@pytest.mark.manual("§4.1", "while an axis brakes, further jobs are received into the job list but not "
                    "interpreted; at standstill they are interpreted in arrival order")
def test_a_job_while_braking_is_queued_and_interpreted_at_standstill(mod: Module) -> None:
    mod.ready()
    mod.operate(1, 1, FORWARD, w=1000)
    mod.clock.advance(1)
    mod.operate(1, 1, STOP)
    assert mod.device.read("axis.1.running") is True  # braking
    assert mod.operate(1, 3, START)[0] == ACK_QUEUED
    assert mod.device.read("axis.1.error") == 0  # not interpreted yet
    mod.clock.advance(5)
    assert mod.device.read("axis.1.running") is False and mod.device.read("axis.1.error") == 2
