"""What survives a power-off and a power-on of the SERS (manual §3.5, §4.8.1.1 P1023, §4.8.3.2
P403, §4.8.4.5, §4.8.6.6), through the pty on virtual time.

A real drive loses everything volatile with its logic supply: a timer due a cycle later, a homing
run, the load-angle monitoring of a stalled rotor.  Nothing of it may act after the supply is back.
"""

from __future__ import annotations

import pytest

from tests.sers.conftest import Plant
from tests.sers.test_programs import download, out, query


def _supply(plant: Plant, on: bool) -> None:
    plant.runtime.fault(plant.name, "power", not on)


@pytest.mark.manual("§4.8.1.1", "P1023=1: the program starts while the start input I8 is set (static)")
@pytest.mark.manual("§3.5", "after power-on the display shows '-' for 2 s; no program runs before "
                    "(only the autostart DIP switch starts one, after the initialisation)")
def test_a_level_start_due_at_power_off_does_not_run_after_power_on(plant_factory) -> None:
    plant = plant_factory({"params": {"P1021": 128, "P1023": 1}})
    host = plant.host
    download(host, "O1=1", "D=5", "O1=0")
    dev = plant.runtime.device(plant.name)
    plant.set("input.I8", True)  # held: the program runs again and again (level start)
    assert plant.runtime.run_until(lambda: dev.read("param.P0") == 1, 1.0)
    # the program ends; the next start is due one control cycle later: cut the supply now
    assert plant.runtime.run_until(lambda: dev.read("param.P0") == 0, 1.0)
    _supply(plant, False)
    _supply(plant, True)
    plant.advance(1.0)  # still initialising (display '-')
    assert plant.read("display")["char"] == "-"
    assert plant.read("param.P0") == 0
    assert out(plant, 1) is False


@pytest.mark.manual("§4.8.3.2", "after a power-on reset (no successful homing run yet) P403 = 3")
@pytest.mark.manual("§4.8.4.5", "after H the drive runs to the reference switch (a power loss ends the run)")
def test_a_homing_run_does_not_survive_a_power_off(plant_factory) -> None:
    plant = plant_factory({"axis": {"reference_low": 500000}})
    host = plant.host
    host.ask("#ON H\r")
    plant.advance(0.2)
    assert plant.read("homing") == "seek"
    _supply(plant, False)
    assert plant.read("homing") is None  # the run is over with the logic supply
    standing = plant.read("axis.position")
    plant.set("input.reference", True)  # the cam closes while the drive is off
    plant.set("input.reference", False)
    plant.advance(1.0)
    assert plant.read("axis.position") == standing
    _supply(plant, True)
    plant.advance(2.0)
    assert query(host, "P403") == "3"
    assert plant.read("homing") is None
    plant.set("input.reference", True)
    plant.advance(1.0)
    assert plant.read("axis.position") == standing  # no stale run takes the edge after power-on
    assert plant.read("motion.kind") is None


@pytest.mark.manual("§4.8.6.6", "the step monitoring (P1029) reports a step loss when the load angle exceeds "
                    "P1002; after a power-on the monitoring starts afresh")
def test_a_load_angle_watch_does_not_fire_after_a_power_cycle(plant_factory) -> None:
    plant = plant_factory({"options": ["E50"], "params": {"P1053": 8, "P1029": 1}})
    host = plant.host
    host.ask("#ON V=60 W=360 E\r")
    plant.advance(0.2)
    plant.set("quantity.stall", True)  # the load blocks the rotor: a watch at P1002 ahead
    plant.advance(0.001)
    _supply(plant, False)
    _supply(plant, True)
    plant.set("quantity.stall", False)
    plant.advance(2.0)
    assert plant.read("P11") == 0
    host.ask("#ON V=60 W=360 E\r")  # the axis passes where the old load-angle watch was
    plant.settle()
    assert plant.read("P11") == 0
    assert plant.read("P12") & 32 == 0
    assert query(host, "P51").startswith("360")


@pytest.mark.manual("§4.5.2", "a sequence program runs only while the SERS is powered: a power loss ends it, and "
                    "none of its pending delays (D, D2) acts while the supply is off or after it returns")
def test_a_program_and_its_timers_end_with_the_supply(plant_factory) -> None:
    plant = plant_factory({})
    host = plant.host
    download(host, "D2=5 GT 60", "O1=1", "D=10", "O2=1", "PE", "L60", "O3=1", "PE")
    dev = plant.runtime.device(plant.name)
    host.ask("#RUN\r")
    assert plant.runtime.run_until(lambda: dev.read("output.O1"), 1.0)
    _supply(plant, False)
    plant.advance(3.0)  # D (1.2 s) and D2 (0.5 s) would both have run out
    assert plant.read("param.P0") == 0
    _supply(plant, True)
    plant.advance(3.0)
    assert (out(plant, 1), out(plant, 2), out(plant, 3)) == (False, False, False)
    assert plant.read("param.P0") == 0
