"""SERS motion through the pty under virtual time (§4.6.6, §4.8.4, §5 of the spec)."""

from __future__ import annotations

import math

import pytest

from tests.sers.conftest import Plant

DEG = 12800 / 360  # increments per degree at the default weighting


@pytest.mark.manual("§4.6.6", "a W written in the constant phase is added to the old W in relative mode; the drive travels the new total")
def test_w_update_during_constant_phase_adds_to_relative_move(sers: Plant) -> None:
    host = sers.host
    host.ask("#ON V=100 A=1000 WR=3600 E\r")
    sers.advance(1.0)
    assert sers.read("axis.phase") == "const"
    assert host.ask("#W=360\r") == b"#W=360\r\nok0\n\r"
    sers.settle()
    assert sers.read("param.P51") == pytest.approx(3960)


@pytest.mark.manual("§4.6.6", "a W sent in the constant phase must not reverse the motor: it is answered with an "
                    "error message and taken only by the next E after the positioning")
@pytest.mark.parametrize(("line", "w", "after_next_e"), [("WR=3600", "-3600", 0.0), ("WA=3600", "100", 3556)])
def test_a_w_that_would_reverse_waits_for_the_next_e(sers: Plant, line: str, w: str, after_next_e: float) -> None:
    host = sers.host
    host.ask(f"#ON V=100 A=1000 {line} E\r")
    sers.advance(1.0)
    assert sers.read("axis.phase") == "const"
    assert host.ask(f"#W={w}\r") == f"#W={w}\r\n*neuer Restweg zu kurz\n\r".encode()  # errno 87
    sers.settle()
    assert sers.read("axis.position") == pytest.approx(3600 * DEG)  # the move went on to its target
    assert host.ask("#W?\r").startswith(f"#W?\rW={w}°".encode("latin-1"))
    host.ask("#E\r")
    sers.settle()
    assert sers.read("axis.position") == pytest.approx(after_next_e)  # (W in whole increments)


@pytest.mark.manual("§4.6.6", "W may be overwritten only while standing (POS=1) or in the constant phase")
def test_w_update_during_acceleration_is_refused(sers: Plant) -> None:
    host = sers.host
    host.ask("#ON V=1000 A=10 WR=36000 E\r")
    sers.advance(0.2)
    reply = host.ask("#W=100\r")
    assert reply == b"#W=100\r\n*Antrieb muss konstant fahren oder stehen\n\r"


@pytest.mark.manual("§4.8.4.1", "P1014=2 absolute: E moves to position W")
def test_absolute_mode(sers: Plant) -> None:
    host = sers.host
    host.ask("#ON WA=90 E\r")
    sers.settle()
    assert sers.read("param.P1014") == 2
    assert sers.read("param.P51") == 90
    assert host.ask("#WA=90 E\r") == b"#WA=90 E\r\nok1\n\r"  # already there: no motion
    sers.settle()
    assert sers.read("param.P51") == 90


@pytest.mark.manual("§4.8.4.1", "P1014=1 relative with clearing: P51 is set to 0 before the start")
def test_relative_clear_mode(plant_factory) -> None:
    plant = plant_factory({"params": {"P1014": 1}})
    host = plant.host
    host.ask("#ON W=360 E\r")
    plant.settle()
    host.ask("#E\r")
    plant.settle()
    assert plant.read("param.P51") == 360
    assert plant.read("axis.position") == pytest.approx(720 * DEG)


@pytest.mark.manual("§4.8.4.1", "P1014=3 relative with overflow counter C1 (P100) counting P103 overflows")
def test_overflow_counter_mode(plant_factory) -> None:
    plant = plant_factory({"params": {"P1014": 3, "P103": 360}})
    plant.host.ask("#ON W=270 E\r")
    plant.settle()
    plant.host.ask("#E\r")
    plant.settle()
    assert plant.read("param.P51") == pytest.approx(180)
    assert plant.read("param.C1") == 1


def test_e_while_moving_is_refused(sers: Plant) -> None:
    sers.host.ask("#ON W=3600 E\r")
    assert sers.host.ask("#E\r") == b"#E\r\n*Antrieb muss stehen\n\r"


def test_stop_decelerates_with_a(sers: Plant) -> None:
    host = sers.host
    host.ask("#ON V=600 A=100 W=36000 E\r")
    sers.advance(3.0)  # cruising at 600 rpm = 20π rad/s
    at_stop = sers.read("axis.position")
    assert host.ask("#S\r") == b"#S\r\nok0\n\r"
    sers.settle()
    braking = (20 * math.pi) ** 2 / (2 * 100)  # rad
    assert sers.read("axis.position") - at_stop == pytest.approx(math.degrees(braking) * DEG, rel=1e-6)
    assert host.ask("#POS?\r") == b"#POS?\rPOS=1\n\r\nok1\n\r"


def test_off_while_moving_stops_at_once(sers: Plant) -> None:
    sers.host.ask("#ON W=3600 E\r")
    sers.advance(0.5)
    here = sers.read("axis.position")
    assert sers.host.ask("#OFF\r") == b"#OFF\r\nok1\n\r"
    assert sers.read("axis.position") == pytest.approx(here)
    assert sers.read("display") == {"char": "4", "blinking": False}
    assert sers.read("output.READY") is False


@pytest.mark.manual("§4.8.3.1", "a drive error brakes the drive with P1030, then switches the motor current off and then opens the ready relay")
def test_limit_switch_hit_mid_move(plant_factory) -> None:
    plant = plant_factory({"axis": {"limit_right": 1000 * DEG}, "params": {"P1030": 1000}})
    host = plant.host
    host.ask("#ON V=300 W=3600 E\r")
    dev = plant.runtime.device("sers")
    assert plant.runtime.run_until(lambda: dev.read("P11") != 0, 10)
    assert plant.read("axis.position") == pytest.approx(1000 * DEG)
    plant.settle()
    # braked with P1030 = 1000 rad/s² from 300 rpm = 10π rad/s
    overrun = math.degrees((10 * math.pi) ** 2 / 2000)
    assert plant.read("axis.position") == pytest.approx((1000 + overrun) * DEG, rel=1e-6)
    assert plant.read("P11") == 8192
    assert plant.read("output.READY") is False
    assert plant.read("energized") is True  # phases go off 50 ms after the relay opens
    plant.advance(0.05)
    assert plant.read("energized") is False
    assert plant.read("display") == {"char": "c", "blinking": False}
    assert host.ask("#\r") == b"#\r\nok4\n\r"
    host.send("#ON\r")
    # ON is carried out at its last character, so the refusal precedes the CR's echo
    host.expect(b"#ON\n*Antrieb ist nicht freigegeben\n\r\r")


@pytest.mark.manual("§2.1.2", "without the STOP input (24 V) the drive cannot move")
def test_stop_input(sers: Plant) -> None:
    host = sers.host
    host.ask("#ON W=36000 E\r")
    sers.advance(1.0)
    sers.set("input.stop", True)
    sers.settle()
    assert sers.read("display") == {"char": "5", "blinking": True}
    assert host.ask("#P12=0\r")
    assert host.ask("#E\r") == b"#E\r\n*Stop Schalter ist offen\n\r"
    assert host.ask("#P1013?\r") == b"#P1013?\rP1013=140\n\r\nok3\n\r"  # STOP open, ref and service open
    sers.set("input.stop", False)
    assert host.ask("#P12=0 E\r") == b"#P12=0 E\r\nok0\n\r"


@pytest.mark.manual("§4.8.6.12", "below P1040 / above P1041 the drive stops, P12 'Grenzwert' is set, P1042=1 and the display blinks 'L'")
def test_software_limits(sers: Plant) -> None:
    host = sers.host
    host.ask("#P1040=-100 P1041=100\r")
    host.ask("#ON V=60 A=1000 W=360 E\r")
    sers.settle()
    p51 = sers.read("param.P51")
    assert 100 < p51 < 110
    assert sers.read("P12") & 1
    assert host.ask("#LP?\r") == b"#LP?\rLP=1\n\r\nok3\n\r"
    assert sers.read("display") == {"char": "L", "blinking": True}
    assert host.ask("#P1040=200\r") == "#P1040=200\r\n*Die negative Grenzposition ist größer als die positive\n\r".encode(
        "latin-1"
    )


@pytest.mark.manual("§4.8.6.12", "P1040: when moving in the negative direction P51 gets below it, the drive stops, "
                    "the bit 'Grenzwert' in P12 is set, P1042 becomes 1 and the display blinks 'L'")
def test_the_negative_software_limit(sers: Plant) -> None:
    host = sers.host
    host.ask("#P1040=-100 P1041=100\r")
    host.ask("#ON V=60 A=1000 W=-360 E\r")
    sers.settle()
    assert -110 < sers.read("param.P51") < -100
    assert sers.read("P12") & 1
    assert host.ask("#LP?\r") == b"#LP?\rLP=1\n\r\nok3\n\r"
    assert sers.read("display") == {"char": "L", "blinking": True}


@pytest.mark.manual("§4.8.1.2", "when P51 reaches compare position P1024 the action P1025 sets an output")
def test_compare_position_sets_output(sers: Plant) -> None:
    sers.host.ask("#P1024=90 P1025=2\r")
    sers.host.ask("#ON W=180 E\r")
    dev = sers.runtime.device("sers")
    assert sers.runtime.run_until(lambda: dev.read("output.O2") is True, 10)
    assert sers.read("param.P51") == pytest.approx(90, abs=1e-3)


def test_in_position_output(plant_factory) -> None:
    plant = plant_factory({"params": {"P1125": 1}})
    plant.host.ask("#ON\r")
    assert plant.read("output.O1") is True
    plant.host.ask("#W=90 E\r")
    assert plant.read("output.O1") is False
    plant.settle()
    assert plant.read("output.O1") is True


@pytest.mark.manual("§4.5.1", "jogging is started by signals at the inputs I1 to I4")
def test_jog_via_inputs(plant_factory) -> None:
    plant = plant_factory({"params": {"P1021": 1 | 32}})
    plant.set("input.I1", True)  # I1 = left slow; auto-energises
    plant.advance(1.0)
    assert plant.read("energized") is True
    assert plant.read("axis.velocity") == pytest.approx(-30 * 12800 / 60)
    plant.set("input.I1", False)
    plant.settle()
    assert plant.read("motion.kind") is None
    plant.set("input.I6", True)  # rising edge toggles the motor off
    assert plant.read("energized") is False


@pytest.mark.manual("§4.8.6.3", "writing P1031 runs a jog function: 1 LS, 2 RS, 4 LF, 8 RF, 16 homing")
def test_p1031_jog_command(sers: Plant) -> None:
    sers.host.ask("#ON P1035=0 P1031=8\r")
    sers.advance(5.0)
    assert sers.read("axis.velocity") == pytest.approx(300 * 12800 / 60)


def test_jog_until_condition(sers: Plant) -> None:
    sers.host.ask("#ON P1035=0\r")
    sers.host.ask("#RS:I1=1\r")
    sers.advance(2.0)
    assert sers.read("motion.kind") == "jog"
    sers.set("input.I1", True)
    sers.settle()
    assert sers.read("motion.kind") is None


def test_feed_rate_override_scales_jog(sers: Plant) -> None:
    sers.host.ask("#ON P1035=0 P108=50 LF\r")
    sers.advance(5.0)
    assert sers.read("axis.velocity") == pytest.approx(-150 * 12800 / 60)


def test_a_jog_or_homing_that_cannot_move_is_refused(sers: Plant) -> None:
    """With override P108 = 0 %, a jog or homing speed of 0 or a ramp of 0 the drive cannot
    move: the command is answered V or A too small and the drive stays at rest, and an input
    that asks for homing records the error.  (Found by fuzzing: the axis raised, and the drive
    never answered again.)"""
    host = sers.host
    host.ask("#ON P1035=0\r")
    assert host.ask("#P108=0 RS\r").endswith(b"RS\r\n*V zu klein\n\r")
    assert host.ask("#P108=100 P1018=0 RS\r").endswith(b"RS\r\n*A zu klein\n\r")
    assert host.ask("#P1018=100 P41=0 H\r").endswith(b"H\n*V zu klein\n\r\r")
    assert host.ask("#P41=60 P42=0 H\r").endswith(b"H\n*A zu klein\n\r\r")
    sers.advance(1.0)
    assert sers.read("motion.kind") is None and sers.read("axis.velocity") == 0
    host.ask("#P1021=16\r")  # I5: homing
    sers.set("input.I5", True)
    assert sers.read("motion.kind") is None and sers.read("param.P1137") == 119


def test_a_move_whose_backlash_legs_cannot_creep_is_refused(sers: Plant) -> None:
    """With backlash P1037 the final approach creeps at P1003; with P1003 = 0 the move is
    refused as V too small before anything starts (found by fuzzing: the second leg raised)."""
    host = sers.host
    host.ask("#ON P1037=5 P1003=0\r")
    assert host.ask("#W=360 E\r") == b"#W=360 E\r\n*V zu klein\n\r"
    assert sers.read("motion.kind") is None
    host.ask("#P1003=10\r")
    assert host.ask("#W=360 E\r").startswith(b"#W=360 E\r\nok")
    sers.settle()
    assert sers.read("axis.position") == pytest.approx(12800)


def test_ramp_writes_during_a_run_do_not_break_it(plant_factory) -> None:
    """A homing run creeps and brakes with P1003/P42 as they were at its start, a jog's overrun
    with the jog's own ramp: setting them to 0 meanwhile used to raise in the axis at the next
    phase (found by fuzzing).  POS0 with P41 = 0 is refused as V too small."""
    plant = plant_factory({"axis": {"reference_low": 20000}})
    host = plant.host
    host.ask("#ON H\r")
    host.ask("#P1003=0 P42=0\r")
    plant.settle()
    assert plant.read("homed") is True and plant.read("axis.position") == pytest.approx(20000)
    host.ask("#P1003=10 P42=100 P1035=0 P1039=10 RS:I1=1\r")
    plant.advance(1.0)
    host.ask("#P1018=0\r")
    plant.set("input.I1", True)
    plant.settle()
    assert plant.read("motion.kind") is None
    assert host.ask("#P41=0 POS0\r").endswith(b"POS0\r\n*V zu klein\n\r")


def test_an_overrun_from_an_event_true_at_the_start(sers: Plant) -> None:
    """RS:I1=0 with I1 already 0 ends the jog at once; the overrun P1039 is then travelled at
    the jog speed (the axis had no speed yet; found by fuzzing, the move raised)."""
    sers.host.ask("#ON P1035=0 P1039=10\r")
    assert sers.host.ask("#RS:I1=0\r") == b"#RS:I1=0\r\nok0\n\r"
    sers.settle()
    assert sers.read("axis.position") == pytest.approx(10 * 12800 / 360)


@pytest.mark.manual("§4.8.4.5", "P147 bit 0 = 1 homing negative; bit 1 = 1 the limit switch is the reference switch")
def test_homing_negative_with_limit_switch_as_reference(plant_factory) -> None:
    plant = plant_factory({"axis": {"limit_left": -50 * DEG}, "params": {"P147": 3}})
    plant.host.ask("#ON H\r")
    plant.settle()
    assert plant.read("P11") == 0
    assert plant.read("axis.position") == pytest.approx(-50 * DEG)
    assert plant.read("homed") is True


def test_speed_factor_does_not_change_simulated_timing(sers: Plant) -> None:
    """Virtual time: the T-05 move takes 1.321 simulated seconds however fast the test runs."""
    sers.host.ask("#ON V=1000 W=2500 E\r")
    assert sers.settle() == pytest.approx(1.321, abs=1e-3)


def _trapezoid_time(d: float, v: float, a: float) -> float:
    return d / v + v / a if d >= v * v / a else 2 * math.sqrt(d / a)


@pytest.mark.manual("§4.6.6", "the ramp shape: P1032 and sections P1005..P1008")
def test_ramp_sections_p1005_to_p1008(plant_factory) -> None:
    """P1032=0 with sections: 0→50 % V at 50 % A, then 50 %→100 % V at A (spec §5.2)."""
    plant = plant_factory({"params": {"P1005": 50, "P1007": 50, "P1006": 100, "P1008": 50}})
    plant.host.ask("#ON V=600 A=100 W=3600 E\r")
    took = plant.settle()
    v, a, d = 20 * math.pi, 100.0, math.radians(3600)
    ramp = (v / 2) / (a / 2) + (v / 2) / a  # per ramp: section 1 at A/2, then A
    ramp_distance = (v / 4) * (v / 2) / (a / 2) + (3 * v / 4) * (v / 2) / a
    expected = 2 * ramp + (d - 2 * ramp_distance) / v
    assert took == pytest.approx(expected, rel=1e-9)
    assert plant.read("param.P51") == pytest.approx(3600)


def test_sinusoidal_ramp_takes_as_long_as_the_linear_one(plant_factory) -> None:
    plant = plant_factory({"params": {"P1032": 1}})
    plant.host.ask("#ON V=600 A=100 W=3600 E\r")
    ramp = 20 * math.pi / 100  # s, the same duration as the linear ramp
    plant.advance(ramp / 2)
    # in the middle of the ramp the raised cosine accelerates with π/2·A
    peak = math.pi / 2 * 100 * 12800 / (2 * math.pi)
    assert plant.read("axis.acceleration") == pytest.approx(peak, rel=1e-9)
    took = plant.settle() + ramp / 2
    assert took == pytest.approx(_trapezoid_time(math.radians(3600), 20 * math.pi, 100), rel=1e-9)
