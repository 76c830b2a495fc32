"""Walk of manual §2.5.3.10 and §2.8.3 (hardware limit switches), driven through the PG port on
a real pty.  COM247's machine data wire both switches as NC contacts (Öffner): an actuated switch
reads 0 V (``False``)."""

from __future__ import annotations

import pytest

from tests.ip247.helpers import BACKWARD, FORWARD, START, Make, Module, record
from tests.ip247.test_machine_data import words

ANFANG, ENDE = 25, 26  # §7.2 error list: "Endschalter Anfang / Ende überfahren"


def _actuate(mod: Module, name: str) -> None:
    mod.device.set(f"input.{name}1", False)  # an NC contact opens when actuated


@pytest.mark.manual("§2.5.3.10", "a hardware limit switch is seen when the axis moves or is to move towards "
                    "it: jogging towards an already actuated Anfang switch is refused with error 25")
@pytest.mark.manual("§2.8.3", "a limit switch actuated by hand locks its direction of travel")
def test_jog_towards_an_actuated_anfang_at_standstill_is_25(mod: Module) -> None:
    mod.ready()
    _actuate(mod, "ANF")
    before = mod.device.read("axis.1.position")
    assert mod.operate(1, 1, BACKWARD, w=1000)[4] == ANFANG
    mod.clock.advance(2)
    assert mod.device.read("axis.1.running") is False and mod.device.read("axis.1.position") == before


@pytest.mark.manual("§2.5.3.10", "the switch is only seen in the direction of travel: away from an actuated "
                    "switch the axis moves")
def test_jog_away_from_an_actuated_switch_runs(mod: Module) -> None:
    mod.ready()
    _actuate(mod, "ANF")
    assert mod.operate(1, 1, FORWARD, w=1000)[4] == 0
    mod.clock.advance(1)
    assert mod.device.read("axis.1.running") is True
    assert mod.device.read("axis.1.position") > 1_000


@pytest.mark.manual("§2.8.3", "a positioning towards an actuated Ende switch is not carried out: error 26")
def test_positioning_towards_an_actuated_ende_is_26(mod: Module) -> None:
    mod.ready()
    _actuate(mod, "END")
    assert mod.operate(1, 6, START, w=1000, dd=20_000)[4] == ENDE
    assert mod.operate(1, 7, FORWARD, w=1000, dd=5_000)[4] == ENDE
    mod.clock.advance(2)
    assert mod.device.read("axis.1.running") is False and mod.device.read("axis.1.position") == 1_000
    assert mod.operate(1, 7, BACKWARD, w=1000, dd=500)[4] == 0  # (the other direction is free)


@pytest.mark.manual("§2.8.3", "a traverse of a program towards an actuated limit switch aborts the program "
                    "with the limit switch's error")
def test_program_traverse_towards_an_actuated_switch_aborts(mod: Module) -> None:
    mod.ready()
    assert mod.store(7, "%  7\nN1 X0 F1000\nN2 M02\n")[8:] == bytes(4)
    _actuate(mod, "ANF")
    mod.operate(1, 8, START, b=7)
    mod.clock.advance(2)
    assert mod.device.read("axis.1.error") == ANFANG
    assert mod.device.read("axis.1.running") is False and mod.device.read("axis.1.position") == 1_000


@pytest.mark.manual("§2.5.3.10", "without limit switches wired, polarity Schließer (NO) must be set: the open "
                    "inputs then read as not actuated and the axis moves both ways")
def test_no_switches_wired_with_no_contacts(make: Make) -> None:
    mod = make()
    mod.device.set("input.ANF1", False)  # nothing wired: 0 V on both inputs
    mod.device.set("input.END1", False)
    assert mod.write(1, 20, 101, words(record(limit_polarity=0)))[8] == 0
    mod.operate(1, 5, START, b=1)
    assert mod.operate(1, 7, FORWARD, w=1000, dd=2_000)[4] == 0
    mod.clock.advance(5)
    assert mod.operate(1, 7, BACKWARD, w=1000, dd=2_000)[4] == 0
    mod.clock.advance(5)
    assert mod.device.read("axis.1.position") == 1_000 and mod.device.read("axis.1.error") == 0
