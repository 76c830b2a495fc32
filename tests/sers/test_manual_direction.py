"""Manual §4.8.2.3, P1134 "Drehrichtungsumkehr", through the pty on virtual time.

"With this parameter the assignment of the motion commands (e.g. RS or LS) and of the position to
the motor's direction of rotation is set.  Changing P1134 has the same effect as swapping the
leads within one motor phase (the motor then physically turns the other way)."

So with P1134=1 the drive counts and commands exactly as before (RS, a positive W and P51 go
positive; the homing direction of P147 is the drive's), and the rotor -- the points
``axis.position`` / ``encoder.position`` and the switches placed along the axis by the
configuration -- turns the other way.
"""

from __future__ import annotations

import pytest

from tests.sers.conftest import Plant
from tests.sers.test_programs import number, refused

DEG = 12800 / 360  # motor increments per degree (default rotational weighting, §4.8.4.6)
SECTION = "§4.8.2.3"


@pytest.mark.manual(SECTION, "P1134=1: a positive move (W > 0, E) turns the motor physically the other way; "
                    "the position P51 still counts the commanded way")
@pytest.mark.parametrize(("p1134", "sense"), [(0, 1), (1, -1)])
def test_a_positive_move_turns_the_motor_the_configured_way(plant_factory, p1134: int, sense: int) -> None:
    plant = plant_factory({"params": {"P1134": p1134}})  # as stored in the EEPROM, read at power-on
    plant.host.ask("#ON V=600 W=90 E\r")
    plant.settle()
    assert number(plant.host, "P51") == pytest.approx(90)
    assert plant.read("axis.position") == pytest.approx(sense * 90 * DEG)
    assert plant.read("encoder.position") == pytest.approx(sense * 90 * DEG)


@pytest.mark.manual(SECTION, "P1134 assigns the jog commands RS/LS to the motor's direction: with P1134=1 "
                    "RS turns the motor physically negative while P51 counts up")
def test_rs_jog_with_p1134_written_by_the_host(sers: Plant) -> None:
    host = sers.host
    host.ask("#P1134=1\r")
    host.ask("#ON P1035=0 RS\r")
    sers.advance(0.5)
    assert sers.read("axis.velocity") < 0  # the rotor turns negative
    host.ask("#S\r")
    sers.settle()
    p51 = number(host, "P51")
    assert p51 > 0
    assert sers.read("axis.position") == pytest.approx(-p51 * DEG, abs=1)
    host.ask("#P1134=0\r")  # back to the standard sense: RS turns the motor positive again
    host.ask("#RS\r")
    sers.advance(0.5)
    assert sers.read("axis.velocity") > 0
    assert number(host, "P51") > p51


@pytest.mark.manual(SECTION, "P1134=1 has the same effect as swapping the motor leads: the motor then "
                    "physically turns the other way, so a positive jog runs into the switch on the physical "
                    "negative side (a limit switch opened: drive error 8192, §4.8.3.1)")
def test_with_p1134_1_rs_runs_into_the_switch_on_the_negative_side(plant_factory) -> None:
    plant = plant_factory({"axis": {"limit_left": -2000}, "params": {"P1134": 1}})
    plant.host.ask("#ON P1035=0 RS\r")
    dev = plant.runtime.device(plant.name)
    assert plant.runtime.run_until(lambda: dev.read("P11") != 0, 5.0)
    assert plant.read("input.limit_left") is True
    assert plant.read("P11") == 8192
    plant.settle()
    assert plant.read("axis.position") <= -2000
    assert number(plant.host, "P51") == pytest.approx(-plant.read("axis.position") / DEG, abs=1 / DEG)  # (whole increments)


@pytest.mark.manual(SECTION, "P1134=1: homing in the positive direction (P147 bit 0 = 0, §4.8.4.5) turns the "
                    "motor physically negative, to a reference switch on that side")
def test_homing_direction_under_inversion(plant_factory) -> None:
    plant = plant_factory({"axis": {"reference_low": -5000, "reference_high": -3000}, "params": {"P1134": 1}})
    plant.host.ask("#ON H\r")
    plant.settle()
    assert plant.read("homed") is True
    # sought positive (physically negative), creeping back: stops where the cam ends, at -3000
    assert plant.read("axis.position") == pytest.approx(-3000, abs=1)
    assert number(plant.host, "P51") == 0


def test_p1134_is_not_written_while_the_drive_moves(sers: Plant) -> None:
    """[SIM-CHOICE: the manual does not say; errno 93 'nicht schreibbar, während der Antrieb positioniert']"""
    host = sers.host
    host.ask("#ON V=60 W=360 E\r")
    refused(host, "#P1134=1\r", 93)
    sers.settle()
    assert sers.read("axis.position") == pytest.approx(360 * DEG)


def test_step_monitoring_is_not_fooled_by_the_inversion(plant_factory) -> None:
    """The encoder sits on the motor shaft; the drive counts it with its motor's sense (§4.8.6.6)."""
    plant = plant_factory({"options": ["E50"], "params": {"P1053": 8, "P1029": 1, "P1134": 1}})
    plant.host.ask("#ON V=60 W=360 E\r")
    plant.settle()
    assert plant.read("P11") == 0
    assert plant.read("load_angle") == pytest.approx(0)
