"""Manual statements about the data channel (page 4) that the named items of issue 28 touch
(§7.2.2 error 22, §6.2.4 observe on the data channel), driven through the real PG pty and the
PLC side's TCP endpoint."""

from __future__ import annotations

from typing import Any

import pytest

from devsim.devices.ip247.client import AgClient
from tests.ip247.helpers import START, Module


def directory(mod: Module) -> bytes:
    """BA65: the program directory (number, length in words per program)."""
    return mod.client.read_record(4, 65)[8:]


@pytest.mark.manual("§7.2.2", "error 22: while an axis is in teach-in no program can be changed, deleted or "
                    "transferred over the data channel")
def test_deleting_a_program_during_teach_in_is_error_22(mod: Module) -> None:
    mod.ready()
    assert mod.store(5, "%  5\nN1 X10 F1000\nN2 M02\n")[8:] == bytes(4)
    listed = directory(mod)
    assert mod.operate(1, 10, START, b=9)[4] == 0  # teach-in on for program 9
    answer = mod.client.delete_record(4, 23, 5)
    assert answer[4] == 22
    assert directory(mod) == listed  # program 5 is still there
    assert mod.operate(1, 11, START, b=9)[4] == 0  # teach-in off
    assert mod.client.delete_record(4, 23, 5)[4] == 0
    assert mod.client.read_record(4, 69, 5)[8:] == b""  # gone now


@pytest.mark.manual("§7.2.2", "error 22: while an axis is in teach-in no program can be transferred over the "
                    "data channel")
def test_storing_a_program_during_teach_in_is_error_22(mod: Module) -> None:
    mod.ready()
    assert mod.operate(1, 10, START, b=9)[4] == 0
    assert mod.store(5, "%  5\nN1 X10 F1000\nN2 M02\n")[4] == 22
    assert mod.client.read_record(4, 69, 5)[8:] == b""


@pytest.mark.manual("§6.2.4", "the observe functions 71 and 73 are also negatively acknowledged on the data "
                    "channel (PAFE at FB164)")
def test_observe_on_the_data_channel_from_the_plc_is_refused(devsim_device: Any) -> None:
    module = devsim_device("ip247", {"sys_id": {"module": 11}, "base_page": 8}, transport="tcp")
    host, port = module.port_url("ag").removeprefix("socket://").rsplit(":", 1)
    with AgClient(host, int(port)) as plc:
        assert plc.observe(11)[0] == 0x80  # page 4 of the module: the data channel
        assert plc.observe(8)[0] == 0x00  # an axis page is observed
        assert len(plc.observe(8)) == 8 + 14
