"""Homing variants (P147), backlash (P1037) and standstill monitoring (P1044) through the pty."""

from __future__ import annotations

import math

import pytest

DEG = 12800 / 360


@pytest.mark.manual("§4.8.4.5", "P147 bit 2: after the switch, on to the next electrical reset position (every 7.2°)")
def test_homing_to_the_next_electrical_zero(plant_factory) -> None:
    ref = 100.0  # increments: not on a 256-increment phase zero
    plant = plant_factory({"axis": {"reference_low": ref}, "params": {"P147": 4}})
    plant.host.ask("#ON H\r")
    plant.settle()
    # creeping back (negative) from the edge at 100, the next phase zero is 0
    assert plant.read("axis.position") == pytest.approx(0.0)
    assert plant.read("param.P51") == 0


@pytest.mark.manual("§4.8.4.5", "P147 bit 3: 0 = P1040 and P1041 are ignored while homing; 1 = they are respected")
@pytest.mark.parametrize(("p147", "homed"), [(0, True), (8, False)])
def test_homing_and_the_software_limits(plant_factory, p147: int, homed: bool) -> None:
    plant = plant_factory({"axis": {"reference_low": 90 * DEG}, "params": {"P147": p147}})
    plant.host.ask("#P1041=45 ON H\r")  # the reference switch lies beyond the upper software limit
    plant.settle()
    assert plant.read("homed") is homed
    assert (plant.read("axis.position") == pytest.approx(90 * DEG)) is homed  # (else stopped after 45°)
    assert bool(plant.read("P12") & 1) is not homed


@pytest.mark.manual("§4.8.4.5", "a drive standing on the reference switch when homing starts runs at P1003 until the "
                    "falling edge of the reference input")
def test_homing_started_on_the_switch(plant_factory) -> None:
    plant = plant_factory({"axis": {"reference_low": 3200, "reference_high": 5200}, "params": {"P1003": 10}})
    plant.host.ask("#ON P1035=0 P1019=60 RS\r")
    plant.advance(0.35)
    plant.host.ask("#S\r")
    plant.settle()
    assert plant.read("input.reference") is True
    plant.host.ask("#H\r")
    plant.advance(0.05)
    assert abs(plant.read("axis.velocity")) == pytest.approx(10 * 12800 / 60)  # no fast run at P41
    plant.settle()
    assert plant.read("axis.position") == pytest.approx(3200)
    assert plant.read("homed") is True


@pytest.mark.manual("§4.8.4.5", "P147 bit 6: homing on the zero pulse instead of the reference switch")
def test_homing_on_the_encoder_zero_pulse(plant_factory) -> None:
    plant = plant_factory({"axis": {"index_offset": 5000}, "params": {"P147": 64}})
    plant.host.ask("#ON H\r")
    plant.settle()
    assert plant.read("axis.position") == pytest.approx(5000)
    assert plant.read("homed") is True


@pytest.mark.manual("§4.8.4.5", "P147 bit 7: reference switch, then zero pulse, then the next electrical reset position")
def test_homing_switch_then_zero_pulse_then_electrical_zero(plant_factory) -> None:
    plant = plant_factory({"axis": {"reference_low": 20000, "index_offset": 6000}, "params": {"P147": 128}})
    plant.host.ask("#ON H\r")
    plant.settle()
    # falling edge at 20000 creeping negative; next zero pulse below is 12800 + 6000 = 18800,
    # then the next phase zero further negative: 18688 (= 73 × 256)
    assert plant.read("axis.position") == pytest.approx(18688)


@pytest.mark.manual("§4.8.4.5", "P147 bit 5: the drive measures both edges of the reference switch and goes to its centre")
def test_homing_to_the_centre_of_the_switch(plant_factory) -> None:
    plant = plant_factory({"axis": {"reference_low": 3000, "reference_high": 5000}, "params": {"P147": 32}})
    plant.host.ask("#ON H\r")
    plant.settle()
    assert plant.read("axis.position") == pytest.approx(4000)
    assert plant.host.ask("#P51?\r") == "#P51?\rP51=0°\n\r\nok1\n\r".encode("latin-1")


def _move_time(distance_deg: float, rpm: float, accel: float = 100.0) -> float:
    """Closed-form time of a trapezoid/triangle move (rad, rad/s, rad/s²)."""
    d = math.radians(distance_deg)
    v = rpm * 2 * math.pi / 60
    if d >= v * v / accel:
        return d / v + v / accel
    return 2 * math.sqrt(d / accel)


@pytest.mark.manual("§4.8.4.7", "backlash P1037 positioning in the backlash direction: W minus backlash at V, then the backlash at P1003 the same way")
def test_backlash_in_the_approach_direction(plant_factory) -> None:
    # P147 bit 0 = 1: homing negative, so every target is approached in the positive direction:
    # W - b at V, then b at the backlash speed P1003 (diagram "1A/1B")
    plant = plant_factory({"params": {"P147": 1, "P1037": 1.8, "P1003": 10}})
    plant.host.ask("#ON V=600 W=90 E\r")
    took = plant.settle()
    assert plant.read("param.P51") == pytest.approx(90)
    assert took == pytest.approx(_move_time(88.2, 600) + _move_time(1.8, 10), abs=1e-6)


@pytest.mark.manual("§4.8.4.7", "backlash positioning the other way: past the target by the backlash, then the backlash back at P1003")
def test_backlash_against_the_approach_direction(plant_factory) -> None:
    plant = plant_factory({"params": {"P147": 1, "P1037": 1.8, "P1003": 10}})
    host = plant.host
    host.ask("#ON V=600 W=-90 E\r")
    dev = plant.runtime.device("sers")
    lowest = []

    def track() -> bool:
        lowest.append(dev.model.axis.position())
        return dev.read("motion.kind") is None

    assert plant.runtime.run_until(track, 60)
    # overshoots by the backlash (1.8°) and comes back positive: net displacement = W
    assert min(lowest) == pytest.approx((-90 - 1.8) * DEG)
    assert plant.read("param.P51") == pytest.approx(-90)


@pytest.mark.manual("§4.8.6.8", "P1044/P1045: without an edge on the input P1045 at least every P1044 of travel the drive stops with P11 'Stillstandsüberwachung' and display 'A'")
@pytest.mark.manual("§4.8.3.1", "P11 2048 standstill monitoring (P1044)")
@pytest.mark.manual("§3.5", "display 'A': standstill monitoring error")
def test_standstill_monitoring(plant_factory) -> None:
    plant = plant_factory({"params": {"P1044": 10, "P1045": 2}})
    host = plant.host
    host.ask("#ON V=60 W=360 E\r")
    # an edge on I2 at least every 7.2° (0.02 s at 360°/s): the drive keeps going
    for _ in range(5):
        plant.advance(0.02)
        plant.set("input.I2", True)
        plant.set("input.I2", False)
    assert plant.read("P11") == 0
    # no more edges: after 10° the drive stops with error 2048, display 'A'
    plant.settle()
    assert plant.read("P11") == 2048
    assert plant.read("display") == {"char": "A", "blinking": False}
    assert plant.read("param.P51") < 360


@pytest.mark.manual("§4.8.6.6", "P1029=1: a load angle beyond P1002 is a drive error; P11=0 replaces P51 by the motor's real position (encoder)")
@pytest.mark.manual("§4.8.3.1", "P11 32 step monitoring error (P1029)")
@pytest.mark.manual("§3.5", "display 'F': load-angle monitoring error")
@pytest.mark.manual("§4.8.6.6", "P1029=3: reported as a drive error (P11), but the motor stays energised")
@pytest.mark.parametrize(("p1029", "energized"), [(1, False), (3, True)])
def test_step_loss_drive_error_and_resync(plant_factory, p1029: int, energized: bool) -> None:
    plant = plant_factory({"options": ["E50"], "params": {"P1053": 8, "P1029": p1029}})
    host = plant.host
    host.ask("#ON V=60 W=360 E\r")
    plant.advance(0.2)
    plant.set("quantity.stall", True)  # the load blocks the rotor
    stalled_at = plant.read("encoder.position")
    dev = plant.runtime.device("sers")
    assert plant.runtime.run_until(lambda: dev.read("P11") != 0, 5)
    # the error comes when the load angle reaches P1002 = 255 increments
    assert plant.read("axis.position") - stalled_at == pytest.approx(255)
    assert plant.read("P11") == 32
    plant.settle()
    assert plant.read("display") == {"char": "F", "blinking": False}
    plant.advance(0.1)  # (the phases go off 50 ms after the relay opens)
    assert plant.read("energized") is energized
    plant.set("quantity.stall", False)
    # P11=0 takes the encoder position as P51 (§4.8.6.6)
    host.ask("#P11=0\r")
    assert plant.read("axis.position") == pytest.approx(stalled_at)
    assert plant.read("param.P51") == pytest.approx(round(stalled_at) / DEG, abs=1e-4)


@pytest.mark.manual("§4.8.6.6", "P1029=2: a step loss is a warning; POSR travels at P41 to the original setpoint W")
@pytest.mark.manual("§3.5", "'F' blinking: load-angle monitoring warning")
def test_step_loss_warning_then_posr_reaches_the_setpoint(plant_factory) -> None:
    plant = plant_factory({"options": ["E50"], "params": {"P1053": 8, "P1029": 2}})
    host = plant.host
    host.ask("#ON V=60 W=360 E\r")
    plant.advance(0.3)
    plant.set("quantity.stall", True)
    plant.settle()
    plant.set("quantity.stall", False)
    assert plant.read("P12") & 32
    assert plant.read("display") == {"char": "F", "blinking": True}  # §3.5 'Warnung Lastwinkelüberwachung'
    assert host.ask("#\r") == b"#\r\nok3\n\r"
    assert host.ask("#POSR\r") == b"#POSR\r\nok0\n\r"
    plant.settle()
    assert plant.read("encoder.position") == pytest.approx(360 * DEG)
    assert plant.read("param.P51") == pytest.approx(360)


@pytest.mark.manual("§4.8.4.2", "POSR only applies while P11=32 or P12=32 is set")
def test_posr_without_step_loss_is_refused(sers) -> None:
    sers.host.send("#ON POSR\r")
    sers.host.expect("#ON POSR\n*ungültig\n\r\r".encode("latin-1"))


@pytest.mark.manual("§4.8.4.2", "P1138 n: after a step-angle error the SERS tries POSR up to n times, after the waiting time P1139")
def test_automatic_posr_retries(plant_factory) -> None:
    plant = plant_factory({"options": ["E50"], "params": {"P1053": 8, "P1029": 3, "P1138": 2, "P1139": 5}})
    plant.host.ask("#ON V=60 W=720 E\r")
    plant.advance(0.3)
    plant.set("quantity.stall", True)
    dev = plant.runtime.device("sers")
    assert plant.runtime.run_until(lambda: dev.read("P11") != 0, 5)
    plant.set("quantity.stall", False)
    # after P1139 × 0.1 s = 0.5 s the drive corrects itself and reaches the target
    assert plant.runtime.run_until(lambda: dev.read("motion.kind") == "posr", 2)
    plant.settle()
    assert plant.read("encoder.position") == pytest.approx(720 * DEG)
    assert plant.read("P11") == 0


@pytest.mark.manual("§4.8.6.6", "P1053=3/7 hand-wheel / electric shaft: the motor follows the encoder pulses (P1054 = 1 for an E50 encoder, 4-fold evaluation: 200 counts per revolution)")
def test_handwheel_pulses_move_the_motor(plant_factory) -> None:
    # P1053=3: quadrature encoder on I3/I4, P1054=1 → 64 increments per count (E50)
    plant = plant_factory({"params": {"P1053": 3, "P1054": 1}})
    plant.host.ask("#ON\r")
    plant.set("encoder.pulses", 200)  # one hand-wheel revolution of an E50
    plant.settle()
    assert plant.read("axis.position") == pytest.approx(12800)
    plant.set("encoder.pulses", -50)
    plant.settle()
    assert plant.read("axis.position") == pytest.approx(12800 - 50 * 64)
    assert plant.read("param.P1119") == 150


@pytest.mark.manual("§4.8.6.6", "P1053=2 / P1143=2: pulses at I3 change the position, with the direction at the "
                    "digital input I4 (aktiv = negativ)")
@pytest.mark.parametrize(("params", "counter"), [({"P1053": 2, "P1054": 1}, "P1119"),
                                                 ({"P1143": 2, "P1144": 1}, "P1120")])
def test_pulse_and_direction_input(plant_factory, params: dict, counter: str) -> None:
    plant = plant_factory({"params": params})
    plant.host.ask("#ON\r")
    plant.set("encoder.pulses", 100)  # I4 inactive: positive
    plant.settle()
    assert plant.read("axis.position") == pytest.approx(100 * 64)
    plant.set("input.I4", True)
    plant.set("encoder.pulses", 150)  # I4 active: negative
    plant.settle()
    assert plant.read("axis.position") == pytest.approx(-50 * 64)
    assert plant.read(f"param.{counter}") == -50


@pytest.mark.manual("§4.8.6.6", "P1053=9: pulses at I3 are measured as a frequency in P1124 per window P1055")
@pytest.mark.manual("§4.8.6.6", "P1143=5: pulses at input 3 are measured as a frequency in P1146 per window P1145")
@pytest.mark.parametrize(("params", "result"), [({"P1053": 9, "P1055": 50}, "P1124"),
                                                ({"P1143": 5, "P1145": 50}, "P1146")])
def test_frequency_measurement(plant_factory, params: dict, result: str) -> None:
    plant = plant_factory({"params": params})
    plant.set("quantity.pulse_frequency", 1000.0)
    answer = f"#{result}?\r{result}=100\n\r\nok1\n\r".encode()  # 1 kHz × 100 ms
    assert plant.host.ask(f"#{result}?\r") == answer


@pytest.mark.manual("§4.8.6.1", "P1011 bit 1: while accelerating above the limit P1012 the phase current is raised by "
                    "20 %; bit 2: at standstill it is raised by 20 %")
@pytest.mark.parametrize(("p1011", "line", "after", "current"), [
    (2, "#ON A=100 V=600 W=3600 E\r", 0.05, 6000),  # A=100 > P1012=50: boost while accelerating
    (2, "#ON A=20 V=600 W=3600 E\r", 0.05, 5000),  # A below P1012: no boost
    (2, "#ON A=100 V=600 W=36000 E\r", 1.0, 5000),  # constant speed: no boost
    (4, "#ON\r", 0.1, 6000),  # standstill boost
    (4, "#ON W=3600 E\r", 0.05, 5000),  # (not while moving)
])
def test_phase_current_boost(plant_factory, p1011: int, line: str, after: float, current: int) -> None:
    plant = plant_factory({"params": {"P1010": 5000, "P1011": p1011, "P1012": 50}})
    plant.host.ask(line)
    plant.advance(after)
    assert plant.read("phase_current") == current


@pytest.mark.manual("§4.8.6.1", "P1011 bit 5: after power-on the motor phase current is switched on automatically (ON)")
@pytest.mark.parametrize(("p1011", "p134"), [(32, "7"), (0, "0")])
def test_automatic_on_after_power_on(plant_factory, p1011: int, p134: str) -> None:
    plant = plant_factory({"params": {"P1011": p1011}})
    assert plant.host.ask("#P134?\r") == f"#P134?\rP134={p134}\n\r\nok1\n\r".encode()


@pytest.mark.manual("§4.8.6.1", "P1011 bit 0: at standstill the phase current falls to 50 % of P1010, 20 ms after the last motion")
def test_phase_current_reduction_at_standstill(plant_factory) -> None:
    plant = plant_factory({"params": {"P1010": 6000, "P1011": 1}})
    plant.host.ask("#ON W=90 E\r")
    assert plant.read("phase_current") == 6000
    plant.settle()
    plant.advance(0.02)
    assert plant.read("phase_current") == 3000


@pytest.mark.manual("§4.8.6.7", "P1152=1 SERVO mode: no step loss; the motor may run at its torque limit and catches up")
@pytest.mark.manual("§4.8.1.2", "P1160 5..8: the output is set temporarily while the SERVO overload lasts")
def test_servo_mode_loses_no_steps_and_catches_up(plant_factory) -> None:
    plant = plant_factory({"options": ["E50", "SERVO"], "params": {"P1152": 1, "P1162": 1, "P1163": 600, "P1160": 5}})
    host = plant.host
    host.ask("#ON\r")
    plant.advance(0.1)  # load-angle zero taken 100 ms after ON
    host.ask("#V=60 W=360 E\r")
    plant.advance(0.3)
    plant.set("quantity.stall", True)
    assert plant.read("output.O1") is True  # P1160=5: O1 while overloaded
    held = plant.read("axis.position")
    plant.advance(1.0)
    assert plant.read("axis.position") == pytest.approx(held)  # waits, no step loss
    plant.set("quantity.stall", False)
    assert plant.read("output.O1") is False
    plant.settle()
    assert plant.read("param.P51") == pytest.approx(360)
    assert plant.read("P11") == 0 and plant.read("P12") == 0


@pytest.mark.manual("§4.8.6.7", "P1156: the actual acceleration in SERVO mode, measured and averaged over the whole "
                    "acceleration ramp (only in SERVO mode)")
def test_servo_p1156_is_the_mean_acceleration_of_the_last_ramp(plant_factory) -> None:
    # ramp sections (P1005..P1008): 0 → V/2 at A/2, then V/2 → V at A: 1.5 V/A long, mean A/1.5
    params = {"P1152": 1, "P1005": 50, "P1007": 50, "P1006": 100, "P1008": 50}
    plant = plant_factory({"options": ["E50", "SERVO"], "params": params})
    host = plant.host
    host.ask("#ON\r")
    plant.advance(0.1)  # load-angle zero taken 100 ms after ON
    host.ask("#V=600 A=100 W=3600 E\r")
    ramp = 1.5 * 20 * math.pi / 100  # s
    plant.advance(ramp * 0.9)
    assert plant.read("param.P1156") == 0  # the ramp is not over: nothing measured yet
    plant.advance(ramp * 0.2)
    assert plant.read("param.P1156") == pytest.approx(100 / 1.5, abs=1e-3)
    plant.settle()  # (the deceleration is no acceleration ramp)
    assert plant.read("param.P1156") == pytest.approx(100 / 1.5, abs=1e-3)
    host.ask("#A=200 W=-3600 E\r")  # back, ramping with twice the acceleration
    plant.settle()
    assert plant.read("param.P1156") == pytest.approx(200 / 1.5, abs=1e-3)
    assert host.ask("#P1156?\r").startswith(b"#P1156?\rP1156=133.333")
    host.ask("#P1152=0\r")
    assert plant.read("param.P1156") == 0  # only in SERVO mode
    host.ask("#P1152=1\r")
    assert plant.read("param.P1156") == pytest.approx(200 / 1.5, abs=1e-3)
    plant.runtime.power_cycle(plant.name)
    plant.advance(2.0)
    assert plant.read("param.P1152") == 1
    assert plant.read("param.P1156") == 0  # nothing measured since power-on


@pytest.mark.manual("§4.8.3.1", "P12 2048: SERVO not active - the load angle is not yet calibrated, but a positioning or jog was made")
def test_servo_positioning_before_calibration_warns(plant_factory) -> None:
    plant = plant_factory({"options": ["E50", "SERVO"], "params": {"P1152": 1}})
    plant.host.ask("#ON W=90 E\r")
    assert plant.read("P12") & 2048


@pytest.mark.manual("§4.8.6.6", "P1054 'Intern werden nur 16 Bit abgespeichert. Bei Zahlen außerhalb -0.32768 bis "
                    "0.32767 wird die Auflösung vermindert indem die letzten beiden Nachkommastellen 0 werden'")
@pytest.mark.manual("§4.8.6.6", "P1144 'Definition wie P1054'")
@pytest.mark.parametrize(
    ("number", "written", "kept"),
    [
        (1054, "1.23456", "1.234"),
        (1054, "-2.50099", "-2.5"),
        (1054, "0.32769", "0.327"),
        (1144, "12.34567", "12.345"),
        (1054, "0.12345", "0.12345"),  # inside ±0.32768: all five decimals
        (1144, "-0.32768", "-0.32768"),
    ],
)
def test_pulse_weight_outside_16_bits_loses_its_last_two_decimals(sers, number, written, kept) -> None:
    host = sers.host
    assert host.ask(f"#P{number}={written}\r") == f"#P{number}={written}\r\nok1\n\r".encode()
    assert host.ask(f"#P{number}?\r") == f"#P{number}?\rP{number}={kept}\n\r\nok1\n\r".encode()


@pytest.mark.manual("§4.8.6.6", "P1054 (unit 1/200 rev) outside ±0.32768 keeps three decimals: the hand-wheel "
                    "(P1053=3) moves by the pulses times the stored weight")
def test_handwheel_follows_the_stored_pulse_weight(plant_factory) -> None:
    plant = plant_factory({"params": {"P1053": 3}})
    plant.host.ask("#P1054=1.23456\r")
    plant.host.ask("#ON\r")
    plant.set("encoder.pulses", 1000)
    plant.settle()
    assert plant.read("axis.position") == pytest.approx(1000 * 1.234 * 64)


@pytest.mark.manual("§4.8.6.8", "P1044: 'ein Signal (Flanke 0 → 1 bei High-aktiven Eingangssignalen oder Flanke "
                    "1 → 0 bei Low-aktiven Eingangssignalen)' -- the edge to the active state counts")
@pytest.mark.manual("§3.1.5", "DIP 1 bits 4 and 5 ON: the inputs I1..I8 are low-active")
@pytest.mark.parametrize("level", ["plc", "low_active"])
def test_standstill_monitoring_counts_the_edges_to_active(plant_factory, level: str) -> None:
    # input.I2 is the input's state as the drive reads it (P1300, the jog inputs): True = active
    plant = plant_factory({"input_level": level, "params": {"P1044": 90, "P1045": 2}})
    plant.host.ask("#ON A=100000 V=60 W=360 E\r")  # 360°/s, at full speed within 0.1°
    # I2 active at 60°, 140°, 220° (never 90° apart); inactive at 70°, 200°, 230° (130° apart)
    for seconds, active in ((60, True), (10, False), (70, True), (60, False), (20, True), (10, False)):
        plant.advance(seconds / 360)
        plant.set("input.I2", active)
    plant.advance(60 / 360)  # 290°
    assert plant.read("P11") == 0
    plant.settle()
    assert plant.read("P11") == 2048  # 90° after the last activation (220°)
    assert plant.read("param.P51") == pytest.approx(311, abs=1)  # from 310°, braked with P1030


@pytest.mark.manual("§4.8.4.5", "P147 bit 4: '1 = invertiert, Eingang Öffner (kein Signal = Antrieb steht auf "
                    "Referenzschalter)'")
@pytest.mark.manual("§4.8.1.1", "P1130 '1 bis 8 : digitaler Eingang I1 bis I8 = Referenzschaltereingang'")
def test_inverted_reference_input_on_a_digital_input(plant_factory) -> None:
    # the reference switch is an NC contact on I3: I3 has a signal while the drive is off the switch
    plant = plant_factory({"params": {"P1130": 3, "P147": 16}})
    plant.set("input.I3", True)
    host = plant.host
    assert host.ask("#J1?\r") == b"#J1?\rJ1=0\n\r\nok1\n\r"  # not on the reference switch
    host.ask("#ON H\r")
    plant.advance(0.5)
    assert plant.read("axis.velocity") > 0  # seeking in the positive homing direction
    plant.set("input.I3", False)  # the NC contact opens: the drive reaches the switch
    plant.advance(1.0)
    assert plant.read("axis.velocity") < 0  # braked and creeping back at P1003
    assert host.ask("#J1?\r") == b"#J1?\rJ1=1\n\r\nok0\n\r"
    plant.set("input.I3", True)  # off the switch again: the falling edge of 'on the switch'
    plant.settle()
    assert plant.read("homed") is True
    assert plant.read("param.P51") == 0
