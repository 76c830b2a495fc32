"""The manual's three example programs run by the simulated PLC itself (spec pcd4h3.md §6.2–§6.5,
manual §9.1–§9.3): the keys are PLC inputs, the host only watches over S-Bus."""

from __future__ import annotations

from collections.abc import Callable

import pytest

from tests.pcd4h3.helpers import Station, reg


def press(pcd: Station, key: int, seconds: float = 0.1) -> None:
    pcd.sim.set(f"I.{key}", True)
    pcd.sim.advance(seconds)
    pcd.sim.set(f"I.{key}", False)


def at(pcd: Station, event: str, after: float) -> list[float]:
    return [t - after for t, name in pcd.sim.device.events if name == event and t > after]


@pytest.mark.manual("§9.1", "Beispiel 1: mit der Taste an Eingang 8 gestartet: 100 mm, 3 s warten, zurück "
                    "auf 0")
def test_example_1_runs_on_the_start_key(make: Callable[..., Station]) -> None:
    pcd = make({"user_program": "example1"})
    pcd.sim.advance(1.0)
    assert pcd.sim.read("axis.1.position") == 0  # nothing without the key
    start = pcd.sim.now()
    press(pcd, 8)
    assert pcd.sim.run_until(lambda d: abs(d.read("axis.1.position") - 100_000) < 5 and d.read("axis.1.OnDest"), 10)
    pcd.sim.advance(12.0)
    assert abs(pcd.sim.read("axis.1.position")) <= 3
    ends = at(pcd, "axis1.OnDest", start)
    assert ends[0] == pytest.approx(6.34, abs=0.08)  # forward
    assert ends[1] == pytest.approx(6.34 + 3.0 + 6.34, abs=0.15)  # 3 s, then back
    pcd.sim.advance(5.0)
    assert abs(pcd.sim.read("axis.1.position")) <= 3  # and it waits for the next key


@pytest.mark.manual("§9.2", "auf der Anzeige PCA2.D14 oben die Istposition, unten die Sollgeschwindigkeit")
def test_example_2_break_position_and_display(make: Callable[..., Station]) -> None:
    pcd = make({"user_program": "example2"})
    start = pcd.sim.now()
    press(pcd, 8)
    pcd.sim.advance(20.0)
    brk = at(pcd, "axis1.BrkPos", start)
    assert brk[0] == pytest.approx(3.88, abs=0.1)
    assert brk[1] == pytest.approx(6.34 + 3.0 + 2.51, abs=0.15)
    assert abs(pcd.read_registers(reg("RActP"))[0]) <= 1
    assert pcd.sim.read("axis.1.display") == ["     0", "     0"]


@pytest.mark.manual("§9.3", "zu jedem Zeitpunkt mit einem Schalter zwischen Automatik und Manuell "
                    "umschalten; die momentane Bewegung wird zu Ende geführt")
@pytest.mark.manual("§9.3", "das Automatikprogramm läuft endlos bis in den Manuellbetrieb umgeschaltet oder "
                    "mit der Stoptaste abgebrochen wird; die Stoptaste stoppt die Achse zu jedem Zeitpunkt")
def test_example_3_automatic_and_manual(make: Callable[..., Station]) -> None:
    pcd = make({"user_program": "example3"})
    start = pcd.sim.now()
    press(pcd, 8)  # I 0 low: automatic; the start key
    pcd.sim.advance(9.8)
    assert pcd.read_registers(reg("RActP"))[0] == pytest.approx(1500, abs=1)
    pcd.sim.advance(2.0 + 5 * 4.5)
    moved = at(pcd, "axis1.FStart", start)[0]
    assert moved < 0.2  # the key, TR 4, ST 2, TR 5, ST 10's flags, AxHndlg: a few PLC cycles
    assert at(pcd, "axis1.BrkPos", start)[0] - moved == pytest.approx(3.50, abs=0.05)
    assert pcd.read_registers(reg("RActP"))[0] == pytest.approx(0, abs=1)
    pcd.sim.advance(3.0)  # endless: motion 1 again
    assert pcd.read_registers(reg("RActP"))[0] > 50
    pcd.sim.set("I.0", True)  # manual: the SB restarts, the running move is completed
    pcd.sim.advance(15.0)
    assert pcd.sim.read("axis.1.position") == pytest.approx(150_000, abs=5)
    pcd.sim.set("I.10", True)  # jog backward while held (2 s to reach 20 mm/s)
    pcd.sim.advance(2.5)
    assert pcd.sim.read("axis.1.velocity") == pytest.approx(-19_980, rel=0.01)
    pcd.sim.set("I.10", False)
    pcd.sim.advance(3.0)
    held = pcd.sim.read("axis.1.position")
    assert 90_000 < held < 140_000 and abs(pcd.sim.read("axis.1.velocity")) < 50
    press(pcd, 11)  # define the zero position
    pcd.sim.advance(0.2)
    assert abs(pcd.sim.read("axis.1.position")) <= 1
    pcd.sim.set("I.9", True)
    pcd.sim.advance(1.0)
    pressed = pcd.sim.now()
    pcd.sim.set("I.15", True)  # the stop key: FStop at once (the SB restarts; I 9 released meanwhile)
    pcd.sim.advance(0.05)
    assert at(pcd, "axis1.FStop", pressed)[0] < 0.05
    pcd.sim.set("I.9", False)
    pcd.sim.advance(3.0)
    assert pcd.sim.read("axis.1.OnDest") and abs(pcd.sim.read("axis.1.velocity")) < 50
