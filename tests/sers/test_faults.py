"""SERS supply, temperature and short-circuit faults through a real pty
(sers.md §2.7, §4.3, §4.6, §4.7, §5.4, §5.14; variant 06.85: U_W 46 V, U_B 43 V, U_L 32 V)."""

from __future__ import annotations

import pytest

from tests.sers.conftest import Plant

NOMINAL = 68.0  # default supply of the .85 class
U_W, U_B, U_L = 46.0, 43.0, 32.0
FAST = 300 * 12800 / 60  # RF speed, inc/s (P1020 default 300 U/min)
P1030 = 1000 * 12800 / (2 * 3.141592653589793)  # error deceleration, inc/s² (1000 rad/s²)

INVALID = "\n*ungültig\n\r".encode("latin-1")
NOT_ENABLED = b"\n*Antrieb ist nicht freigegeben\n\r"


def display(char: str, blinking: bool = False) -> dict[str, object]:
    return {"char": char, "blinking": blinking}


def start_fast_jog(plant: Plant) -> None:
    """ON, jog right fast without the 500 ms timeout, up to full speed."""
    assert plant.host.ask("#ON P1035=0\r") == b"#ON P1035=0\r\nok1\n\r"
    assert plant.host.ask("#RF\r") == b"#RF\r\nok0\n\r"
    plant.advance(1.0)
    assert plant.read("motion.kind") == "jog"
    assert plant.read("axis.velocity") == pytest.approx(FAST)


def assert_on_refused(plant: Plant) -> None:
    """``#ON`` refused with errno 79.  ON may be executed at its last character (§3.1 rule 3),
    so the message may come before the echo of the CR (§3.2.4a); no acknowledgement follows."""
    answer = plant.host.ask("#ON\r")
    if answer == b"#ON" + NOT_ENABLED:
        plant.host.expect(b"\r")
    else:
        assert answer in (b"#ON\r" + NOT_ENABLED, b"#ON" + NOT_ENABLED + b"\r")
    assert plant.read("param.P1137") == 79
    assert plant.read("energized") is False


def line_bytes_out(plant: Plant) -> int:
    return plant.read("line.bytes_out")


def assert_silent(plant: Plant, line: bytes) -> None:
    """Send ``line``; the device receives it and sends nothing back."""
    before_in = plant.read("line.bytes_in")
    before_out = line_bytes_out(plant)
    plant.host.send(line)
    plant.wait_received(before_in + len(line))
    assert line_bytes_out(plant) == before_out
    port = plant.host.port
    port.timeout = 0.2
    try:
        assert port.read(64) == b""
    finally:
        port.timeout = 2.0


# ======================================================================================
# supply voltage (§2.7, §5.14)
# ======================================================================================
def test_default_supply_is_nominal(sers: Plant) -> None:
    assert sers.read("quantity.supply_voltage") == NOMINAL
    assert sers.read("P11") == 0 and sers.read("P12") == 0


@pytest.mark.manual("§2.1.4", "below U_W the undervoltage pre-warning: display '9' blinking")
@pytest.mark.manual("§4.8.3.1", "P12 values 2 and 4 reset themselves when the cause disappears")
def test_undervoltage_prewarning_auto_clears(sers: Plant) -> None:
    host = sers.host
    sers.set("quantity.supply_voltage", U_W - 1)  # 45 V: below U_W, above U_B
    assert sers.read("P12") == 4
    assert sers.read("P11") == 0
    assert sers.read("display") == display("9", blinking=True)
    assert host.ask("#\r") == b"#\r\nok3\n\r"  # standing + warning
    assert host.ask("#P12?\r") == b"#P12?\rP12=4\n\r\nok3\n\r"
    sers.set("quantity.supply_voltage", NOMINAL)
    assert sers.read("P12") == 0  # cleared without P12=0
    assert sers.read("display") == display("4")
    assert host.ask("#\r") == b"#\r\nok1\n\r"


def test_undervoltage_prewarning_while_moving_gives_ok2(sers: Plant) -> None:
    start_fast_jog(sers)
    sers.set("quantity.supply_voltage", U_W - 0.5)
    assert sers.host.ask("#\r") == b"#\r\nok2\n\r"
    assert sers.read("motion.kind") == "jog"  # a warning does not stop the drive
    assert sers.read("display") == display("9", blinking=True)


def test_just_above_u_w_no_warning(sers: Plant) -> None:
    sers.set("quantity.supply_voltage", U_W + 0.5)
    assert sers.read("P12") == 0
    assert sers.host.ask("#\r") == b"#\r\nok1\n\r"


def test_faults_send_no_unsolicited_text(sers: Plant) -> None:
    """G-FAULTMSG default: hosts see faults through the ack digit and P11/P12 only."""
    before = line_bytes_out(sers)
    sers.set("quantity.supply_voltage", U_W - 1)
    sers.set("quantity.supply_voltage", U_B - 1)
    sers.set("quantity.heatsink_temperature", 90.0)
    sers.advance(0.5)
    assert sers.read("P11") == 514
    assert line_bytes_out(sers) == before


@pytest.mark.manual("§2.1.4", "below U_B the drive is braked to standstill, then the relay opens and 50 ms later the phases go off; P11 512, display '9'")
@pytest.mark.manual("§2.1.3", "on a drive error the drive is braked under control; after that the ready signal is reset and the relay opened; last the phase currents go off")
def test_undervoltage_error_while_moving(sers: Plant) -> None:
    host = sers.host
    start_fast_jog(sers)
    x0 = sers.read("axis.position")
    t0 = sers.runtime.now()
    sers.set("quantity.supply_voltage", 40.0)  # below U_B 43, above U_L 32
    assert sers.read("P11") == 512
    assert sers.read("display") == display("9")
    # decelerated with P1030, not switched off at once; the relay opens only at standstill
    assert sers.read("output.READY") is True
    assert sers.read("energized") is True
    assert sers.read("axis.velocity") == pytest.approx(FAST)
    assert sers.settle() == pytest.approx(FAST / P1030, abs=1e-3)
    assert sers.read("output.READY") is False
    assert sers.read("axis.position") - x0 == pytest.approx(FAST**2 / (2 * P1030), abs=1.0)
    assert sers.runtime.now() - t0 == pytest.approx(FAST / P1030, abs=1e-3)
    # relay open at standstill, phases off 50 ms later (§2.1.4)
    assert sers.read("energized") is True
    sers.advance(0.045)
    assert sers.read("energized") is True
    sers.advance(0.01)
    assert sers.read("energized") is False
    assert host.ask("#\r") == b"#\r\nok4\n\r"
    # the error stays while the voltage is low: P11=0 refused with errno 3
    assert host.ask("#P11=0\r") == b"#P11=0\r" + INVALID
    assert host.ask("#P1137?\r") == b"#P1137?\rP1137=3\n\r\nok4\n\r"
    assert sers.read("P11") == 512
    sers.set("quantity.supply_voltage", NOMINAL)
    assert sers.read("P11") == 512  # the error does not clear by itself (§5.14)
    assert host.ask("#P11=0\r") == b"#P11=0\r\nok3\n\r"  # 3: P12 value 16 of the refusal
    assert sers.read("P11") == 0
    # the motor stays off until ON
    assert sers.read("energized") is False
    assert sers.read("display") == display("4")
    assert host.ask("#W=90 E\r") == b"#W=90 E\r" + NOT_ENABLED
    assert host.ask("#P12=0 ON\r") == b"#P12=0 ON\r\nok1\n\r"
    assert sers.read("energized") is True
    assert host.ask("#W=90 E\r") == b"#W=90 E\r\nok0\n\r"


def test_undervoltage_error_while_standing(sers: Plant) -> None:
    assert sers.host.ask("#ON\r") == b"#ON\r\nok1\n\r"
    sers.set("quantity.supply_voltage", U_B - 0.5)
    assert sers.read("P11") == 512
    assert sers.read("output.READY") is False
    sers.advance(0.06)
    assert sers.read("energized") is False
    assert sers.read("display") == display("9")
    assert sers.host.ask("#P11?\r") == b"#P11?\rP11=512\n\r\nok4\n\r"


@pytest.mark.manual("§2.1.4", "below U_L the torque goes off at once without braking")
def test_below_u_l_torque_off_immediately(sers: Plant) -> None:
    start_fast_jog(sers)
    sers.set("quantity.supply_voltage", 20.0)  # below U_L 32 (logic still supplied)
    frozen = sers.read("axis.position")
    assert sers.read("energized") is False  # no braking ramp
    assert sers.read("output.READY") is False
    assert sers.read("motion.kind") is None
    assert sers.read("P11") == 512
    assert sers.read("display") == display("9")
    sers.advance(1.0)
    assert sers.read("axis.position") == frozen
    assert sers.read("axis.velocity") == 0
    assert sers.host.ask("#P11?\r") == b"#P11?\rP11=512\n\r\nok4\n\r"


def test_supply_off_without_option_u_silences_the_drive(sers: Plant) -> None:
    host = sers.host
    assert host.ask("#P1019=45\r") == b"#P1019=45\r\nok1\n\r"  # RAM only, lost with the supply
    sers.set("quantity.supply_voltage", 0.0)
    assert sers.read("powered") is False
    assert_silent(sers, b"#P11?\r")
    sers.set("quantity.supply_voltage", NOMINAL)
    assert sers.read("powered") is True
    assert sers.read("display") == display("-")  # booting again: input discarded
    assert_silent(sers, b"#P11?\r")
    sers.advance(2.0)
    assert sers.read("display") == display("4")
    assert host.ask("#P11?\r") == b"#P11?\rP11=0\n\r\nok1\n\r"
    assert host.ask("#P1019?\r") == b"#P1019?\rP1019=30U/min\n\r\nok1\n\r"


def test_supply_loss_ends_programming_mode(sers: Plant) -> None:
    """After a power-on the drive is not in programming mode (P0 not stored, §4.8.2)."""
    host = sers.host
    assert host.ask("#NEW\r") == b"#NEW\r\npgm\n\r"
    assert host.ask("#ON\r") == b"#ON\r\npgm\n\r"
    sers.set("quantity.supply_voltage", 0.0)
    sers.set("quantity.supply_voltage", NOMINAL)
    sers.advance(2.0)
    assert host.ask("#P0?\r") == b"#P0?\rP0=0\n\r\nok1\n\r"


@pytest.mark.manual("§2.1.5", "with option U the logic stays powered when the main supply goes off, and the interfaces keep communicating")
def test_option_u_keeps_the_logic_alive_at_0_v(plant_factory) -> None:
    plant = plant_factory({"options": ["U"]})
    host = plant.host
    assert host.ask("#ON\r") == b"#ON\r\nok1\n\r"
    plant.set("quantity.supply_voltage", 0.0)
    assert plant.read("powered") is True
    assert plant.read("energized") is False
    assert plant.read("display") == display("9")
    assert host.ask("#P11?\r") == b"#P11?\rP11=512\n\r\nok4\n\r"
    assert_on_refused(plant)
    plant.set("quantity.supply_voltage", NOMINAL)
    assert plant.read("display") == display("9")  # no reboot: still the error
    assert host.ask("#P11=0\r") == b"#P11=0\r\nok3\n\r"
    assert host.ask("#ON\r") == b"#ON\r\nok3\n\r"
    assert plant.read("energized") is True


# ======================================================================================
# temperature (§2.7, §4.6)
# ======================================================================================
@pytest.mark.manual("§4.8.3.1", "P12 2: heat-sink temperature above 75 °C")
@pytest.mark.manual("§3.5", "display '8' blinking: temperature pre-warning")
def test_overtemperature_warning_at_75(sers: Plant) -> None:
    sers.set("quantity.heatsink_temperature", 74.0)
    assert sers.read("P12") == 0
    sers.set("quantity.heatsink_temperature", 76.0)
    assert sers.read("P12") == 2
    assert sers.read("P11") == 0
    assert sers.read("display") == display("8", blinking=True)
    assert sers.host.ask("#\r") == b"#\r\nok3\n\r"
    sers.set("quantity.heatsink_temperature", 40.0)
    assert sers.read("P12") == 0  # auto-clear
    assert sers.host.ask("#\r") == b"#\r\nok1\n\r"


@pytest.mark.manual("§4.8.3.1", "P11 2: heat-sink temperature above 85 °C")
@pytest.mark.manual("§3.5", "display '8': temperature error")
def test_overtemperature_error_at_85(sers: Plant) -> None:
    host = sers.host
    assert host.ask("#ON\r") == b"#ON\r\nok1\n\r"
    sers.set("quantity.heatsink_temperature", 84.0)
    assert sers.read("P11") == 0
    sers.set("quantity.heatsink_temperature", 86.0)
    assert sers.read("P11") == 2
    assert sers.read("display") == display("8")
    assert sers.read("output.READY") is False
    sers.advance(0.06)
    assert sers.read("energized") is False
    assert host.ask("#P11?\r") == b"#P11?\rP11=2\n\r\nok4\n\r"
    assert host.ask("#P11=0\r") == b"#P11=0\r" + INVALID
    sers.set("quantity.heatsink_temperature", 80.0)  # below the error, still a warning
    assert host.ask("#P11=0\r") == b"#P11=0\r\nok3\n\r"
    assert sers.read("P11") == 0
    assert sers.read("P12") & 2
    assert sers.read("display") == display("8", blinking=True)
    assert sers.read("energized") is False


@pytest.mark.manual("§4.8.3.1", "P11 = 514: overtemperature (2) and undervoltage (512)")
def test_error_combination_514(sers: Plant) -> None:
    sers.set("quantity.heatsink_temperature", 90.0)
    sers.set("quantity.supply_voltage", 40.0)
    assert sers.read("P11") == 514
    assert sers.read("display") == display("8")  # display priority 8 before 9 (§4.7)
    assert sers.host.ask("#P11?\r") == b"#P11?\rP11=514\n\r\nok4\n\r"
    sers.set("quantity.heatsink_temperature", 30.0)
    sers.set("quantity.supply_voltage", NOMINAL)
    assert sers.read("P11") == 514  # errors are latched
    assert sers.host.ask("#P11=0\r") == b"#P11=0\r\nok1\n\r"
    assert sers.read("P11") == 0


# ======================================================================================
# short circuit (§4.3, §4.6.1, G-P11CLEAR)
# ======================================================================================
@pytest.mark.manual("§2.1.3", "on a short circuit the phase currents go off at once and the ready relay opens at the same time")
@pytest.mark.manual("§3.5", "display 'E': short circuit")
def test_short_circuit(sers: Plant) -> None:
    host = sers.host
    start_fast_jog(sers)
    sers.set("quantity.short_circuit", True)
    frozen = sers.read("axis.position")
    assert sers.read("P11") == 128
    assert sers.read("display") == display("E")
    assert sers.read("energized") is False  # current off at once
    assert sers.read("output.READY") is False
    assert sers.read("motion.kind") is None
    sers.advance(0.5)
    assert sers.read("axis.position") == frozen
    assert host.ask("#P11=0\r") == b"#P11=0\r" + INVALID  # short still present
    sers.set("quantity.short_circuit", False)
    assert host.ask("#P11=0\r") == b"#P11=0\r" + INVALID  # STOP not yet opened and closed
    assert sers.read("P11") == 128
    sers.set("input.stop", True)
    sers.set("input.stop", False)
    assert host.ask("#P11=0\r") == b"#P11=0\r\nok3\n\r"
    assert sers.read("P11") == 0
    assert sers.read("display") == display("4")
    assert host.ask("#P12=0 ON\r") == b"#P12=0 ON\r\nok1\n\r"


@pytest.mark.manual("§4.8.3.1", "after P11=128 the STOP input must be opened and closed again before P11=0")
def test_short_circuit_clear_refused_while_stop_still_open(sers: Plant) -> None:
    """The STOP input must be opened *and closed* before P11=0 (§4.6.1, G-P11CLEAR)."""
    host = sers.host
    sers.set("quantity.short_circuit", True)
    sers.set("quantity.short_circuit", False)
    sers.set("input.stop", True)  # opened, not yet closed again
    assert host.ask("#P11=0\r") == b"#P11=0\r" + INVALID
    assert sers.read("P11") == 128
    sers.set("input.stop", False)
    assert host.ask("#P11=0\r") == b"#P11=0\r\nok3\n\r"


def test_stop_cycle_before_the_short_does_not_count(sers: Plant) -> None:
    host = sers.host
    sers.set("input.stop", True)
    sers.set("input.stop", False)
    sers.set("quantity.short_circuit", True)
    sers.set("quantity.short_circuit", False)
    assert host.ask("#P11=0\r") == b"#P11=0\r" + INVALID
    assert sers.read("P11") == 128


# ======================================================================================
# errors and motion
# ======================================================================================
@pytest.mark.parametrize(
    ("quantity", "value", "p11"),
    [("supply_voltage", 40.0, 512), ("heatsink_temperature", 90.0, 2)],
)
def test_error_stops_a_running_jog(sers: Plant, quantity: str, value: float, p11: int) -> None:
    start_fast_jog(sers)
    sers.set(f"quantity.{quantity}", value)
    assert sers.read("P11") == p11
    sers.settle()
    assert sers.read("motion.kind") is None
    assert sers.read("axis.velocity") == 0
    stopped = sers.read("axis.position")
    sers.advance(2.0)  # the jog does not come back
    assert sers.read("axis.position") == stopped
    assert sers.host.ask("#RF\r") == b"#RF\r" + NOT_ENABLED


def test_error_stops_a_positioning(sers: Plant) -> None:
    host = sers.host
    assert host.ask("#ON W=36000 E\r") == b"#ON W=36000 E\r\nok0\n\r"
    sers.advance(1.0)
    sers.set("quantity.heatsink_temperature", 90.0)
    sers.settle()
    assert sers.read("param.P51") < 36000
    assert host.ask("#POS?\r") == b"#POS?\rPOS=1\n\r\nok4\n\r"


@pytest.mark.parametrize(
    ("quantity", "value"),
    [("supply_voltage", 40.0), ("heatsink_temperature", 90.0), ("short_circuit", True)],
)
@pytest.mark.manual("§4.8.3.1", "after an error the motor can be energised only when P11=0 has cleared it")
def test_on_refused_while_p11_set(sers: Plant, quantity: str, value: object) -> None:
    sers.set(f"quantity.{quantity}", value)
    assert sers.read("P11") != 0
    assert_on_refused(sers)
    assert sers.host.ask("#P134=7\r") == b"#P134=7\r" + NOT_ENABLED


def test_fault_does_not_disturb_an_incoming_line(sers: Plant) -> None:
    """A fault arriving while the host types a line: the line is answered normally."""
    host = sers.host
    host.send("#P1")
    sers.wait_received(3)
    sers.set("quantity.heatsink_temperature", 90.0)
    assert host.ask("1?\r") == b"#P11?\rP11=2\n\r\nok4\n\r"
