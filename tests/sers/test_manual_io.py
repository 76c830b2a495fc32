"""Manual §2.1.3 (ready relay), §3.5 (7-segment display) and §4.8.1 (inputs and outputs) through the
pty on virtual time; expected values from the manual's tables."""

from __future__ import annotations

import pytest

from tests.sers.conftest import Plant
from tests.sers.test_programs import download, query, refused, run


def out(plant: Plant, n: int) -> bool:
    return bool(plant.read(f"output.O{n}"))


# -- §2.1.3 the ready relay ------------------------------------------------------------------------
@pytest.mark.manual("§2.1.3", "after power-on the motor current is off: the relay contact is open")
@pytest.mark.manual("§2.1.3", "energising the motor (ON) makes the ready signal active (contacts closed); OFF "
                    "opens them")
def test_ready_relay_follows_on_and_off(sers: Plant) -> None:
    assert sers.read("output.READY") is False
    sers.host.ask("#ON\r")
    assert sers.read("output.READY") is True
    sers.host.ask("#OFF\r")
    assert sers.read("output.READY") is False


@pytest.mark.manual("§2.1.3", "energising the motor through the jog inputs I1..I6 makes the ready signal active")
def test_ready_relay_closes_for_a_jog_input(plant_factory) -> None:
    plant = plant_factory({"params": {"P1021": 2}})
    plant.set("input.I2", True)
    assert plant.read("output.READY") is True


# -- §3.5 the display ------------------------------------------------------------------------------
@pytest.mark.manual("§3.5", "'-' for 2 seconds after a power-on reset (initialisation)")
@pytest.mark.manual("§3.5", "'4': drive ready to be energised; '5': motor current on")
def test_display_after_power_on_and_on(plant_factory) -> None:
    plant = plant_factory({}, boot=False)
    assert plant.read("display") == {"char": "-", "blinking": False}
    plant.advance(1.9)
    assert plant.read("display")["char"] == "-"
    plant.advance(0.2)
    assert plant.read("display") == {"char": "4", "blinking": False}
    plant.host.ask("#ON\r")
    assert plant.read("display") == {"char": "5", "blinking": False}


@pytest.mark.manual("§3.5", "'5' blinking: the motor is energised but the STOP input is open")
def test_display_5_blinks_with_stop_open(sers: Plant) -> None:
    sers.host.ask("#ON\r")
    sers.set("input.stop", True)
    assert sers.read("display") == {"char": "5", "blinking": True}


@pytest.mark.manual("§3.5", "'c': a limit switch is reached")
def test_display_c_at_a_limit_switch(sers: Plant) -> None:
    sers.set("input.limit_left", True)
    sers.advance(0.1)
    assert sers.read("display") == {"char": "c", "blinking": False}


@pytest.mark.manual("§3.5", "'9' blinking: undervoltage pre-warning; '9': undervoltage error")
def test_display_9(sers: Plant) -> None:
    sers.set("quantity.supply_voltage", 45.0)  # below U_W 46 of the .85 class (§2.1.4)
    assert sers.read("display") == {"char": "9", "blinking": True}
    sers.set("quantity.supply_voltage", 40.0)  # below U_B 43
    sers.advance(0.1)
    assert sers.read("display") == {"char": "9", "blinking": False}


@pytest.mark.manual("§3.5", "'H' blinking: program error, the sequence program was stopped by an error")
def test_display_h_blinks_after_a_program_error(sers: Plant) -> None:
    download(sers.host, "GT 99")
    run(sers.host)
    sers.advance(0.1)
    assert sers.read("display") == {"char": "H", "blinking": True}


@pytest.mark.manual("§3.5", "'L' blinking: the position reached the software limit P1040 or P1041")
def test_display_l_blinks_at_a_software_limit(sers: Plant) -> None:
    sers.host.ask("#P1041=90 ON W=180 E\r")
    sers.settle()
    assert sers.read("display") == {"char": "L", "blinking": True}


@pytest.mark.manual("§3.5", "a warning is cleared with P12=0, an error with P11=0")
def test_display_clears_with_p12_and_p11(sers: Plant) -> None:
    host = sers.host
    host.ask("#P1041=90 ON W=180 E\r")
    sers.settle()
    host.ask("#P12=0\r")
    assert sers.read("display") == {"char": "5", "blinking": False}
    sers.set("input.limit_left", True)
    sers.set("input.limit_left", False)
    sers.advance(0.1)
    assert sers.read("display")["char"] == "c"
    host.ask("#P11=0\r")
    assert sers.read("display") == {"char": "4", "blinking": False}


# -- §4.8.1.2 the outputs --------------------------------------------------------------------------
@pytest.mark.manual("§4.8.1.2", "#P1201=1 or #O1=1 sets output O1, #P1201=0 or #O1=0 clears it")
def test_outputs_by_number_and_name(sers: Plant) -> None:
    host = sers.host
    host.ask("#P1201=1\r")
    assert out(sers, 1)
    host.ask("#O1=0 O4=1\r")
    assert not out(sers, 1) and out(sers, 4)
    assert query(host, "P1204") == "1"


@pytest.mark.manual("§4.8.1.2", "O5..O16 (P1205..P1216) only with option IO; without it errno 4 "
                    "'ungültiger Ausgang'")
def test_extension_outputs_need_option_io(plant_factory) -> None:
    plain = plant_factory({})
    refused(plain.host, "#O5=1\r", 4)
    extended = plant_factory({"options": ["IO"]})
    assert extended.host.ask("#O16=1\r").endswith(b"ok1\n\r")
    assert out(extended, 16)


@pytest.mark.manual("§4.8.1.2", "P1036 1..4: OFF switches output O1..O4 on (brake); -1..-4: OFF switches it off")
@pytest.mark.parametrize(("p1036", "n", "after_off"), [(2, 2, True), (-3, 3, False)])
def test_brake_output_on_off(plant_factory, p1036: int, n: int, after_off: bool) -> None:
    plant = plant_factory({"params": {"P1036": p1036}})
    plant.host.ask("#ON\r")
    assert out(plant, n) is (not after_off)
    plant.host.ask("#OFF\r")
    assert out(plant, n) is after_off


@pytest.mark.manual("§4.8.1.2", "P1036: the automatic OFF of a drive error (P11 != 0) activates the brake output")
def test_brake_output_on_a_drive_error(plant_factory) -> None:
    plant = plant_factory({"params": {"P1036": 1}})
    plant.host.ask("#ON\r")
    assert not out(plant, 1)
    plant.set("input.limit_right", True)
    plant.advance(0.1)
    assert out(plant, 1)


@pytest.mark.manual("§4.8.1.2", "P1025 5..7: at compare position P1024 marker M1..M3 is set; -5..-7 clears it")
def test_compare_position_sets_a_marker(sers: Plant) -> None:
    host = sers.host
    host.ask("#M2=0 P1024=90 P1025=6 ON W=180 E\r")
    sers.settle()
    assert query(host, "M2") == "1"
    host.ask("#P1026=270 P1027=-6 W=180 E\r")
    sers.settle()
    assert query(host, "M2") == "0"


@pytest.mark.manual("§4.8.1.2", "P1125=2: O2=0 while the motor runs (P336=0), O2=1 at standstill; -n inverted")
@pytest.mark.parametrize(("p1125", "standing", "running"), [(2, True, False), (-2, False, True)])
def test_in_position_output(plant_factory, p1125: int, standing: bool, running: bool) -> None:
    plant = plant_factory({"params": {"P1125": p1125}})
    assert out(plant, 2) is standing
    plant.host.ask("#ON W=360 E\r")
    assert out(plant, 2) is running
    plant.settle()
    assert out(plant, 2) is standing


@pytest.mark.manual("§4.8.1.2", "P1131 1..4: the output is 1 while P11 != 0; P1132 likewise for P12 != 0")
def test_error_and_warning_outputs(plant_factory) -> None:
    plant = plant_factory({"params": {"P1131": 3, "P1132": -4}})
    host = plant.host
    assert (out(plant, 3), out(plant, 4)) == (False, True)
    refused(host, "#V=20000\r", 122)  # a refused value: P12 value 16
    assert out(plant, 4) is False
    plant.set("input.limit_left", True)
    assert out(plant, 3) is True
    plant.set("input.limit_left", False)
    host.ask("#P11=0 P12=0\r")
    assert (out(plant, 3), out(plant, 4)) == (False, True)


# -- §4.8.1.1 the inputs ---------------------------------------------------------------------------
@pytest.mark.manual("§4.8.1.1", "P1301 holds I9..I16, valid only with option IO")
def test_extension_inputs(plant_factory) -> None:
    plant = plant_factory({"options": ["IO"]})
    plant.set("input.I9", True)
    plant.set("input.I12", True)
    assert query(plant.host, "P1301") == "9"


@pytest.mark.manual("§3.1.5", "DIP switch 1 bits 4/5 OFF/ON is invalid (must not be set): the inputs I1..I8 read 0")
def test_invalid_input_level(plant_factory) -> None:
    plant = plant_factory({"input_level": "invalid"})
    plant.set("input.I1", True)
    assert query(plant.host, "P1300") == "0"


@pytest.mark.manual("§4.8.1.1", "P1021 bit 16: I5 starts homing; bit 32: I6 toggles the motor ON/OFF and clears "
                    "P11 and P12 when switching ON")
def test_homing_and_power_inputs(plant_factory) -> None:
    plant = plant_factory({"params": {"P1021": 48}, "axis": {"reference_low": 2000}})
    plant.set("input.I6", True)
    assert plant.read("energized") is True
    plant.set("input.I6", False)
    plant.set("input.I5", True)
    plant.settle()
    assert plant.read("homed") is True
    plant.set("input.I6", True)
    assert plant.read("energized") is False


@pytest.mark.manual("§4.8.1.1", "P1021 bit 64: input I7 stops the program and the motion")
def test_stop_input_i7(plant_factory) -> None:
    plant = plant_factory({"params": {"P1021": 64}})
    download(plant.host, "ON W=36000 E", "O1=1")
    run(plant.host)
    plant.advance(0.5)
    plant.set("input.I7", True)
    plant.settle()
    assert plant.read("param.P0") == 0
    assert out(plant, 1) is False


@pytest.mark.manual("§4.8.1.1", "P1135 ADC hysteresis: 0 gives P1046 its 10-bit resolution, the default 7 "
                    "(3 bits) 7 bits, 255 (8 bits) 2 bits")
@pytest.mark.manual("§4.8.1.1", "P1148 ADC offset (0..255 for 0..5 V) is subtracted from P1046 and the scale fits "
                    "the rest: 0.06 V is '3', and with P1148=3 it reads 0")
@pytest.mark.parametrize(("p1135", "p1148", "volts", "adc"), [
    (0, 0, 0.06, "0.012"), (0, 0, 0.07, "0.014"),  # 10 bits: 1/1023 of 5 V apart
    (7, 0, 0.06, "0.008"), (7, 0, 0.07, "0.008"),  # 7 bits: the same step of 8/1023
    (255, 0, 3.0, "0.5"), (255, 0, 2.4, "0.25"),  # 2 bits: quarters
    (7, 3, 0.06, "0"), (0, 3, 5.0, "1"), (0, 3, 2.53, "0.5"),  # the offset's example; the rest scaled
])
def test_adc_hysteresis_and_offset(sers: Plant, p1135: int, p1148: int, volts: float, adc: str) -> None:
    host = sers.host
    assert host.ask(f"#P1135={p1135} P1148={p1148}\r").endswith(b"ok1\n\r")
    sers.set("quantity.adc_volts", volts)
    assert query(host, "ADC") == adc
