"""The SERS spec's test vectors (sers.md §6), verbatim, through a real pty."""

from __future__ import annotations

import math

import pytest

from devsim.core.bus import Bus
from devsim.core.clock import VirtualClock
from devsim.core.nvram import NonVolatileMemory
from devsim.devices.sers import SersDevice
from tests.sers.conftest import Plant


@pytest.mark.manual("§4.1", "commands are taken over before the CR: #ON energises the motor before the CR arrives")
@pytest.mark.manual("§4.1", "a CR is acknowledged LF 'ok' digit LF CR; '1': the drive stands")
def test_t01_ack_of_simple_command(sers: Plant) -> None:
    sers.host.send("#ON")
    # ON is taken over before the CR arrives (§4.1): read the echo, then look at the drive
    sers.host.expect(b"#ON")
    assert sers.runtime.run_until(lambda: sers.runtime.device("sers").model.power_stage.energized, 0.0)
    sers.host.send("\r")
    sers.host.expect(b"\r\nok1\n\r")
    assert sers.read("display") == {"char": "5", "blinking": False}
    assert sers.read("output.READY") is True


@pytest.mark.manual("§4.1", "in mode Handshake_RS485 the SERS sends only the 'ok' after the CR, no character echo")
def test_t01_rs485_mode_has_no_echo(plant_factory) -> None:
    plant = plant_factory({"params": {"P1017": 2}})
    assert plant.host.ask("#ON\r") == b"\nok1\n\r"


@pytest.mark.manual("§4.1", "several commands and parameters in one line (#ON V=1000 W=2500 O=1 E) with one CR")
@pytest.mark.manual("§4.1", "ack digit '0': the drive runs (POS=0)")
def test_t02_several_statements_in_one_line(sers: Plant) -> None:
    assert sers.host.ask("#ON V=1000 W=2500 O1=1 E\r") == b"#ON V=1000 W=2500 O1=1 E\r\nok0\n\r"
    assert sers.read("output.O1") is True
    assert sers.read("motion.kind") == "position"


def test_t02_manual_O_without_number_is_refused(sers: Plant) -> None:
    sers.host.send("#O=1\r")
    # a syntax error is reported at once, while the line is still arriving (§4.1)
    sers.host.expect("#O=\n*ungültiger Ausgang\n\r1\r".encode("latin-1"))
    assert sers.read("param.P1137") == 4


@pytest.mark.manual("§4.1", "a query #2P11? is answered 'P11=0' LF CR: the parameter, '=', the value")
def test_t03_parameter_query(plant_factory) -> None:
    plant = plant_factory({"address": 2})
    assert plant.host.ask("#2P11?\r") == b"#2P11?\rP11=0\n\r\nok1\n\r"


def test_t03_query_in_rs485_mode(plant_factory) -> None:
    plant = plant_factory({"address": 3, "params": {"P1017": 2}})
    assert plant.host.ask("#3 P11?\r") == b"P11=0\n\r\nok1\n\r"


@pytest.mark.manual("§4.1", "#2 addresses drive 2; all following commands go to it, the others ignore them (the #2 ON / #3 ON example)")
def test_t04_addressing_sequence(plant_factory) -> None:
    plant = plant_factory({"address": 2}, {"address": 3})
    host = plant.host
    assert host.ask("#2 ON\r") == b"#2 ON\r\nok1\n\r"
    assert host.ask("#v=1000\r") == b"#v=1000\r\nok1\n\r"
    assert host.ask("#W=5000 E\r") == b"#W=5000 E\r\nok0\n\r"
    assert host.ask("#3 ON\r") == b"#3 ON\r\nok1\n\r"
    assert host.ask("#V=1500\r") == b"#V=1500\r\nok1\n\r"
    assert host.ask("#W=4000 E\r") == b"#W=4000 E\r\nok0\n\r"
    assert plant.read("param.V", "sers2") == 1000
    assert plant.read("param.V", "sers3") == 1500
    assert plant.read("param.W", "sers2") == 5000
    assert plant.read("param.W", "sers3") == 4000
    plant.settle("sers2")
    plant.settle("sers3")
    assert plant.read("param.P51", "sers2") == pytest.approx(5000, abs=0.01)
    assert plant.read("param.P51", "sers3") == pytest.approx(4000, abs=0.01)


@pytest.mark.manual("§4.6.12", "the serial example: #1, #ON, #V=1000, #W=2500 E, #POS? answers 0 or 1, #P1300? answers 0..255")
@pytest.mark.manual("§4.8.3.2", "P336 (POS) = 0 while the drive moves, 1 when it stands")
def test_t05_serial_mode_session(sers: Plant) -> None:
    host = sers.host
    assert host.ask("#1\r") == b"#1\r\nok1\n\r"
    assert host.ask("#ON\r") == b"#ON\r\nok1\n\r"
    assert host.ask("#V=1000\r") == b"#V=1000\r\nok1\n\r"
    t0 = sers.runtime.now()
    assert host.ask("#W=2500 E\r") == b"#W=2500 E\r\nok0\n\r"
    assert host.ask("#POS?\r") == b"#POS?\rPOS=0\n\r\nok0\n\r"
    sers.settle()
    # triangular profile: d = 2500° = 43.63 rad, a = 100 rad/s² → t = 2·√(d/a) = 1.321 s
    d = math.radians(2500)
    assert sers.runtime.now() - t0 == pytest.approx(2 * math.sqrt(d / 100), abs=2e-3)
    assert sers.runtime.now() - t0 == pytest.approx(1.321, abs=1e-3)
    assert host.ask("#POS?\r") == b"#POS?\rPOS=1\n\r\nok1\n\r"
    assert host.ask("#P1300?\r") == b"#P1300?\rP1300=0\n\r\nok1\n\r"


@pytest.mark.manual("§4.8.1.1", "P1300 holds I1..I8 binary: P1300 = 11 means I1, I2 and I4 are set")
def test_t06_input_byte(sers: Plant) -> None:
    for name in ("I1", "I2", "I4"):
        sers.set(f"input.{name}", True)
    assert sers.host.ask("#P1300?\r") == b"#P1300?\rP1300=11\n\r\nok1\n\r"
    assert sers.host.ask("#IN?\r") == b"#IN?\rIN=11\n\r\nok1\n\r"


@pytest.mark.manual("§4.1", "an error message starts with '*', e.g. the limit switch message when E is sent with a limit switch reached")
@pytest.mark.manual("§4.8.3.1", "P11 8192: a limit switch is reached; after P11=0 the motor can be energised again")
@pytest.mark.manual("§4.1", "ack digit '4': the drive has an error (P11 > 0)")
def test_t07_motion_refused_at_open_limit_switch(sers: Plant) -> None:
    host = sers.host
    host.ask("#ON\r")
    sers.set("input.limit_right", True)
    assert sers.read("P11") == 8192
    sers.advance(0.1)
    assert sers.read("display") == {"char": "c", "blinking": False}
    assert host.ask("#\r") == b"#\r\nok4\n\r"
    assert host.ask("#P11=0\r") == b"#P11=0\r\nok1\n\r"
    assert host.ask("#ON\r") == b"#ON\r\nok1\n\r"
    assert host.ask("#W=100 E\r") == "#W=100 E\r\n*Endschalter offen\n\r".encode("latin-1")
    assert sers.read("param.P1137") == 78
    assert sers.read("P12") & 16
    assert host.ask("#\r") == b"#\r\nok3\n\r"
    assert host.ask("#P12=0\r") == b"#P12=0\r\nok1\n\r"
    # away from the open limit is allowed (G-LIMIT)
    assert host.ask("#W=-100 E\r") == b"#W=-100 E\r\nok0\n\r"


@pytest.mark.manual("§4.1", "ack digit '3': the drive stands and a warning (P12 > 0) was generated")
@pytest.mark.manual("§4.8.3.1", "P12 16: an error message was generated, e.g. a parameter value too large")
def test_t08_value_error_and_warning_digit(sers: Plant) -> None:
    assert sers.host.ask("#V=20000\r") == "#V=20000\r\n*V zu groß\n\r".encode("latin-1")
    assert sers.read("param.P1137") == 122
    assert sers.read("P12") == 16
    assert sers.host.ask("#\r") == b"#\r\nok3\n\r"


@pytest.mark.manual("§4.8.3.1", "P11 = 514 means overtemperature (2) and undervoltage (512)")
def test_t09_error_combination(sers: Plant) -> None:
    sers.set("quantity.heatsink_temperature", 90.0)
    sers.set("quantity.supply_voltage", 40.0)  # between U_L 32 and U_B 43 of the .85 class
    assert sers.host.ask("#P11?\r") == b"#P11?\rP11=514\n\r\nok4\n\r"


@pytest.mark.manual("§4.8.3.2", "P1121=1: at the end of a positioning '@nPOS=1' is sent (drive 2: '@2POS=1')")
def test_t19_spontaneous_in_position(plant_factory) -> None:
    plant = plant_factory({"address": 2, "params": {"P1121": 1}})
    host = plant.host
    assert host.ask("#2 ON\r") == b"#2 ON\r\nok1\n\r"
    assert host.ask("#2W=360 E\r") == b"#2W=360 E\r\nok0\n\r"
    plant.settle()
    host.expect(b"@2POS=1\n\r")


@pytest.mark.manual("§4.8.4.6", "P76/P44 select the weighting; with gear P121/P122 and feed constant P123 positions are in mm")
def test_t22_scaling(plant_factory) -> None:
    plant = plant_factory({"params": {"P76": 1, "P44": 1, "P121": 2, "P122": 1, "P123": 5}})
    host = plant.host
    host.ask("#ON\r")
    start = plant.read("axis.position")
    host.ask("#W=2.5 E\r")
    plant.settle()
    assert plant.read("axis.position") - start == pytest.approx(12800)
    assert host.ask("#P51?\r") == b"#P51?\rP51=2.5mm\n\r\nok1\n\r"
    assert host.ask("#P103=2500\r") == b"#P103=2500\r\nok1\n\r"


def test_t23_pos0_after_possave(plant_factory, tmp_path) -> None:
    plant = plant_factory({}, state_dir=tmp_path)
    host = plant.host
    host.ask("#P51=361.8\r")
    host.ask("#POSSAVE\r")
    plant.runtime.power_cycle("sers")
    plant.advance(2.0)
    assert host.ask("#P51?\r") == b"#P51?\rP51=361.8\xb0\n\r\nok1\n\r"
    start = plant.read("axis.position")
    host.ask("#ON\r")
    host.ask("#POS0\r")
    plant.settle()
    # 361.8° → nearest phase zero 360° (1.8° back), then P51 := 0
    assert plant.read("axis.position") - start == pytest.approx(-1.8 / 360 * 12800)
    assert host.ask("#P51?\r") == b"#P51?\rP51=0\xb0\n\r\nok1\n\r"


@pytest.mark.parametrize(("target", "final"), [("3.6", 3.7), ("5.35", 5.3)])
def test_t24_leave_zero_phase(plant_factory, target: str, final: float) -> None:
    plant = plant_factory({"params": {"P1001": 1}})
    plant.host.ask("#ON\r")
    plant.host.ask(f"#WA={target} E\r")
    plant.settle()
    assert plant.read("param.P51") == pytest.approx(final, abs=0.02)


@pytest.mark.manual("§4.8.6.15", "parameter masks P1060.. and program masks P1070..P1073 are parameters (e.g. P1060 = 2144)")
def test_t25_parameter_masks_are_stored(sers: Plant) -> None:
    assert sers.host.ask("#P1060=2144\r") == b"#P1060=2144\r\nok1\n\r"
    assert sers.host.ask("#P1070=42\r") == b"#P1070=42\r\nok1\n\r"
    assert sers.host.ask("#P1060?\r") == b"#P1060?\rP1060=2144\n\r\nok1\n\r"
    assert sers.host.ask("#P1074?\r") == "#P1074?\r\n*Parameter nicht vorhanden\n\r".encode("latin-1")


@pytest.mark.manual("§4.8.6.4", "P1035=1 (after power-on): a jog started over RS232 stops unless repeated within 500 ms; P1035=0: no timeout")
def test_t27_jog_with_timeout(sers: Plant) -> None:
    host = sers.host
    host.ask("#ON\r")
    t0 = sers.runtime.now()
    assert host.ask("#RS\r") == b"#RS\r\nok0\n\r"
    assert sers.read("axis.velocity") >= 0
    sers.settle()
    # the jog was not repeated: stopped 500 ms after the command, then braked with P1018
    speed = 30 * 12800 / 60
    accel = 100 * 12800 / (2 * math.pi)
    assert sers.runtime.now() - t0 == pytest.approx(0.5 + speed / accel, abs=1e-3)
    host.ask("#P1035=0\r")
    host.ask("#RS\r")
    sers.advance(10.0)
    assert sers.read("motion.kind") == "jog"
    assert host.ask("#S\r") == b"#S\r\nok0\n\r"
    sers.settle()
    assert sers.read("motion.kind") is None


@pytest.mark.manual("§4.8.6.4", "repeating the jog command within 500 ms keeps the jog running")
def test_t27_repeating_the_jog_keeps_it_running(sers: Plant) -> None:
    host = sers.host
    host.ask("#ON\r")
    host.ask("#RF\r")
    for _ in range(5):
        sers.advance(0.4)
        host.ask("#RF\r")
    assert sers.read("motion.kind") == "jog"
    sers.advance(0.6)
    sers.settle()
    assert sers.read("motion.kind") is None


@pytest.mark.manual("§4.8.4.5", "after H the drive runs at P41 to the reference switch, brakes after the rising edge, creeps back at P1003 to the falling edge")
@pytest.mark.manual("§4.8.3.2", "P403 = 3 after power-on, 0 after a successful homing run")
def test_t28_homing(plant_factory) -> None:
    ref = 90 / 360 * 12800
    plant = plant_factory({"axis": {"reference_low": ref}, "params": {"P41": 60, "P42": 100, "P1003": 10}})
    host = plant.host
    host.ask("#ON\r")
    assert host.ask("#P403?\r") == b"#P403?\rP403=3\n\r\nok1\n\r"
    assert host.ask("#H\r") == b"#H\r\nok0\n\r"
    plant.settle()
    # stopped exactly at the falling edge of the reference cam, P51 := 0
    assert plant.read("axis.position") == pytest.approx(ref, abs=1e-6)
    assert host.ask("#P51?\r") == b"#P51?\rP51=0\xb0\n\r\nok1\n\r"
    assert host.ask("#P403?\r") == b"#P403?\rP403=0\n\r\nok1\n\r"
    assert host.ask("#POS?\r") == b"#POS?\rPOS=1\n\r\nok1\n\r"


def test_t28_homing_overshoot(plant_factory) -> None:
    """After the rising edge the drive brakes with P42: overshoot (6.283 rad/s)²/(2·100) ≈ 11.3°."""
    ref = 90 / 360 * 12800
    plant = plant_factory({"axis": {"reference_low": ref}})
    plant.host.ask("#ON\r")
    plant.host.ask("#H\r")
    dev = plant.runtime.device("sers")
    assert plant.runtime.run_until(lambda: dev.read("homing") == "creep", 10)
    overshoot = (dev.read("axis.position") - ref) / 12800 * 360
    assert overshoot == pytest.approx(math.degrees((2 * math.pi) ** 2 / (2 * 100)), abs=0.01)


@pytest.mark.manual("§4.1", "the ack digit is 0..4: runs, stands, runs with a warning, stands with a warning, drive error")
@pytest.mark.manual("§4.8.3.1", "P12 values 2 and 4 reset themselves when the cause goes")
def test_t29_ack_digits(sers: Plant) -> None:
    host = sers.host
    assert host.ask("#\r") == b"#\r\nok1\n\r"
    host.ask("#ON V=100 W=3600 E\r")
    assert host.ask("#\r") == b"#\r\nok0\n\r"
    sers.set("quantity.heatsink_temperature", 80.0)
    assert host.ask("#\r") == b"#\r\nok2\n\r"
    sers.settle()
    assert host.ask("#\r") == b"#\r\nok3\n\r"
    sers.set("quantity.heatsink_temperature", 30.0)  # warning 2 clears by itself
    assert host.ask("#\r") == b"#\r\nok1\n\r"
    sers.set("input.limit_left", True)
    assert host.ask("#\r") == b"#\r\nok4\n\r"


@pytest.mark.manual("§4.2", "Achsnummer '*' addresses all axes (broadcast), e.g. for a synchronous start")
def test_t30_broadcast_starts_both_without_reply(plant_factory) -> None:
    plant = plant_factory({"address": 1}, {"address": 2})
    host = plant.host
    for address in (1, 2):
        assert host.ask(f"#{address} ON W=360\r") == f"#{address} ON W=360\r\nok1\n\r".encode()
    host.send("#*E\r")
    # nobody answers a broadcast: the next reply on the line is drive 2's own echo
    assert host.ask("#2 POS?\r") == b"#2 POS?\rPOS=0\n\r\nok0\n\r"
    assert plant.read("motion.kind", "sers1") == "position"
    assert plant.read("motion.kind", "sers2") == "position"


@pytest.mark.manual("§4.1", "after the address every following command is for the drive it names; a bare #* names every drive")
def test_a_bare_broadcast_address_selects_every_drive_for_the_lines_after_it(plant_factory) -> None:
    plant = plant_factory({"address": 1}, {"address": 2})
    host = plant.host
    for address in (1, 2):
        assert host.ask(f"#{address} V={address}1\r") == f"#{address} V={address}1\r\nok1\n\r".encode()
    host.send("#*\r")
    host.send("#V=33\r")  # every drive takes it, none answers: the next reply is drive 1's
    assert host.ask("#1 V?\r") == b"#1 V?\rV=33U/min\n\r\nok1\n\r"
    assert plant.read("param.V", "sers2") == 33
    assert host.ask("#V?\r") == b"#V?\rV=33U/min\n\r\nok1\n\r"  # drive 1 alone from #1 on


def test_with_broadcast_reply_lowest_address_the_lowest_drive_answers_a_broadcast(plant_factory) -> None:
    """G-ADDR ⚙ ``broadcast_reply: lowest_address``: one answer to a broadcast, whatever the
    order of the drives on the line; the lines after a bare ``#*`` are answered the same way."""
    config = {"broadcast_reply": "lowest_address"}
    plant = plant_factory({"address": 3, **config}, {"address": 2, **config})
    host = plant.host
    assert host.ask("#*V=44\r") == b"#*V=44\r\nok1\n\r"  # drive 2's echo and answer, and no other
    assert host.ask("#*\r") == b"#*\r\nok1\n\r"  # (a line with only an address: its answering drive acknowledges)
    assert host.ask("#W=5\r") == b"#W=5\r\nok1\n\r"
    assert host.ask("#3 V?\r") == b"#3 V?\rV=44U/min\n\r\nok1\n\r"
    assert [plant.read("param.W", name) for name in ("sers3", "sers2")] == [5, 5]


@pytest.mark.manual("§4.2", "Achsnummer '*' addresses all axes: each drive carries out a broadcast line once")
def test_a_broadcast_line_echoed_by_the_answering_drive_runs_once_in_the_others(plant_factory) -> None:
    """With ``broadcast_reply: lowest_address`` drive 1 echoes a broadcast line onto the line
    (G-ADDR); drives 2 and 3 hear that echo, but what a slave sends is no command for the others
    (only a master's statements are, §3.6.2): ``+1`` adds 1 to every accumulator, not 2."""
    config = {"broadcast_reply": "lowest_address"}
    plant = plant_factory({"address": 1, **config}, {"address": 2, **config}, {"address": 3, **config})
    host = plant.host
    assert host.ask("#*X=0\r") == b"#*X=0\r\nok1\n\r"
    assert host.ask("#*+1\r") == b"#*+1\r\nok1\n\r"
    assert [plant.read("param.P1047", f"sers{n}") for n in (1, 2, 3)] == [1, 1, 1]
    assert host.ask("#*\r") == b"#*\r\nok1\n\r"  # a bare #*: the lines after it go to every drive
    assert host.ask("#+1\r") == b"#+1\r\nok1\n\r"
    assert [plant.read("param.P1047", f"sers{n}") for n in (1, 2, 3)] == [2, 2, 2]


@pytest.mark.manual("§3.6.1", "127 different addresses (1 - 127) can be set: two drives given the same one both answer")
def test_two_drives_with_the_same_address_answer_once_each(plant_factory) -> None:
    """A plant with two drives at address 2 (a wiring mistake the manual does not describe):
    both take ``#2`` and both answer, once; neither takes the other's echo of ``#2`` for a
    command of its own, which answered again and again and held the whole simulator."""
    clock = VirtualClock()
    drives = [SersDevice(clock=clock, config={"address": a, "boot_time": 0}, nvram=NonVolatileMemory(None))
              for a in (1, 2, 2)]
    bus = Bus(drives)
    line = bytearray()

    def write(data: bytes) -> None:
        line.extend(data)
        assert len(line) < 4096, f"the drives keep answering each other: {bytes(line[:80])!r}..."

    bus.attach(write)
    clock.advance(0.1)
    bus.feed(b"#2\r")
    assert bytes(line) == b"#2\r\nok1\n\r" * 2
    line.clear()
    bus.feed(b"#1 V?\r")
    assert bytes(line) == b"#1 V?\rV=100U/min\n\r\nok1\n\r"


@pytest.mark.manual("§4.8.6.16", "P1099 executes an opcode: 63235 (0xF703) is E, 62213 (0xF305) is RUN 5")
def test_t26_opcode_e_over_p1099(sers: Plant) -> None:
    sers.host.ask("#ON W=90\r")
    assert sers.host.ask("#P1099=63235\r") == b"#P1099=63235\r\nok0\n\r"  # ≙ E
    sers.settle()
    assert sers.read("param.P51") == 90
    # ≙ RUN 5: refused like RUN without a stored program
    assert sers.host.ask("#P1099=62213\r") == "#P1099=62213\r\n*kein gültiges Programm vorhanden\n\r".encode("latin-1")
    assert sers.host.ask("#P1099=63236\r") == b"#P1099=63236\r\n*unbekannter f7xx Opcode\n\r"
    assert sers.host.ask("#P1099=63000\r") == b"#P1099=63000\r\n*unbekannter fxxx Opcode\n\r"
