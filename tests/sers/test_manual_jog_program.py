"""Manual §4.8.6.3 P1093 "Stop bei Handfahren": a jog function of an input I1..I6 while a sequence
program runs interrupts it and continues it after the input is released (0) or aborts it (1);
the jog commands of the serial line leave the program alone.  Through the pty on virtual time.
"""

from __future__ import annotations

import pytest

from tests.sers.conftest import Plant
from tests.sers.test_programs import degrees, download, finish, out, query, run, running, until

MOVE = ("ON", "WR=3600 E", "O1=1", "PE")  # one positioning, then O1


def _jog_input_enabled(plant: Plant, p1093: int) -> None:
    """I2 jogs right slow (P1021 bit 1); P1093 as given."""
    plant.host.ask("#P1021=2\r")
    plant.host.ask(f"#P1093={p1093}\r")


@pytest.mark.manual("§4.8.6.3", "P1093=0: a jog input interrupts the program; after the input is released the "
                    "program is continued")
def test_p1093_0_the_program_does_not_advance_during_the_jog(sers: Plant) -> None:
    host = sers.host
    _jog_input_enabled(sers, 0)
    download(host, "ON", "O1=1", "WAIT I3=1", "O2=1", "PE")
    run(host)
    sers.advance(0.01)
    sers.set("input.I2", True)  # jog right slow
    sers.advance(0.1)
    assert sers.read("motion.kind") == "jog"
    assert query(host, "P0") == "1"  # interrupted, not ended [SIM-CHOICE]
    sers.set("input.I3", True)  # what the WAIT waits for comes during the interruption
    sers.advance(0.2)
    assert out(sers, 2) is False  # the program does not advance
    sers.set("input.I2", False)  # the jog stops; once the drive stands the program goes on
    finish(sers, 2)
    assert out(sers, 2) is True
    assert sers.read("motion.kind") is None


@pytest.mark.manual("§4.8.6.3", "P1093=0: an interrupted positioning is continued to its setpoint after the jog "
                    "input is released (as P1033=1 continues an interrupted positioning, §4.8.6.2)")
def test_p1093_0_continues_the_interrupted_positioning(sers: Plant) -> None:
    host = sers.host
    _jog_input_enabled(sers, 0)
    download(host, *MOVE)
    run(host)
    sers.advance(0.5)
    assert sers.read("motion.kind") == "position"
    sers.set("input.I2", True)
    sers.advance(0.5)
    assert sers.read("motion.kind") == "jog"
    assert running(sers)
    sers.set("input.I2", False)
    until(sers, lambda d: d.read("motion.kind") != "stopping")  # the jog stops ...
    assert sers.read("motion.kind") == "position"  # ... and the positioning goes on
    assert out(sers, 1) is False
    finish(sers, 30)
    assert degrees(sers) == pytest.approx(3600, abs=1e-3)  # at the setpoint of WR=3600
    assert out(sers, 1) is True  # then the program went on


@pytest.mark.manual("§4.8.6.3", "P1093=1: a jog input aborts the program; after the input is released the program "
                    "is not continued")
def test_p1093_1_aborts_the_program(sers: Plant) -> None:
    host = sers.host
    _jog_input_enabled(sers, 1)
    host.ask("#P1033=1\r")  # (a stop's continuation does not apply: the next start begins at line 1)
    download(host, *MOVE)
    run(host)
    sers.advance(0.5)
    sers.set("input.I2", True)
    sers.advance(0.1)
    assert sers.read("motion.kind") == "jog"
    assert query(host, "P0") == "0"
    sers.set("input.I2", False)
    sers.settle()
    sers.advance(0.1)
    assert not running(sers)
    assert out(sers, 1) is False
    at = degrees(sers)
    assert 0 < at < 3600
    run(host)
    finish(sers, 30)
    assert degrees(sers) == pytest.approx(at + 3600, abs=1e-3)  # WR=3600 anew from line 1


@pytest.mark.manual("§4.8.6.3", "only a jog function through a digital input (I1 to I6) interrupts the program, "
                    "not the jog commands of the serial interface (§4.5.1)")
def test_a_serial_jog_leaves_the_program_running(sers: Plant) -> None:
    host = sers.host
    _jog_input_enabled(sers, 0)
    host.ask("#P1035=0\r")  # (no 500 ms timeout of the serial jog)
    download(host, "ON", "WAIT I3=1", "O1=1", "WAIT I3=0", "O2=1", "PE")
    run(host)
    sers.advance(0.01)
    assert host.ask("#RS\r").startswith(b"#RS\r\nok")
    sers.set("input.I3", True)
    sers.advance(0.1)
    assert out(sers, 1) is True  # the program went on during the serial jog
    sers.set("input.I2", True)  # the same jog, now from the input: the program is interrupted
    sers.set("input.I3", False)
    sers.advance(0.1)
    assert out(sers, 2) is False
    sers.set("input.I2", False)
    finish(sers, 2)
    assert out(sers, 2) is True


def test_p1093_0_a_jog_until_condition_is_executed_again(sers: Plant) -> None:
    """A program's ``RS:I3=1`` the jog input took over jogs again after the interruption."""
    host = sers.host
    _jog_input_enabled(sers, 0)
    download(host, "ON", "LS:I3=1", "O1=1", "PE")
    run(host)
    sers.advance(0.3)
    sers.set("input.I2", True)  # right slow instead of the program's left slow
    sers.advance(0.3)
    assert sers.read("axis.velocity") > 0
    sers.set("input.I2", False)
    sers.settle()
    sers.advance(0.3)
    assert sers.read("motion.kind") == "jog"
    assert sers.read("axis.velocity") < 0  # the program's jog again, until I3
    assert out(sers, 1) is False
    sers.set("input.I3", True)
    finish(sers, 2)
    assert out(sers, 1) is True


@pytest.mark.manual("§4.8.6.3", "the manual functions of the inputs I1 to I6 interrupt the program, e.g. motor "
                    "ON/OFF on I6")
def test_p1093_0_the_on_off_input_interrupts_too(sers: Plant) -> None:
    host = sers.host
    host.ask("#P1021=32\r")  # I6: motor ON/OFF
    download(host, "O1=1", "WAIT I3=1", "O2=1", "PE")
    run(host)
    sers.advance(0.01)
    sers.set("input.I6", True)
    sers.set("input.I3", True)
    sers.advance(0.1)
    assert sers.read("energized") is True
    assert out(sers, 2) is False
    assert running(sers)
    sers.set("input.I6", False)
    finish(sers, 1)
    assert out(sers, 2) is True


def test_p1093_0_a_d2_jump_due_during_the_interruption_comes_after_it(sers: Plant) -> None:
    """The D2 timer runs on during the interruption; its jump waits until the program continues."""
    host = sers.host
    _jog_input_enabled(sers, 0)
    download(host, "ON", "D2=2 GT60", "WAIT I3=1", "O1=1", "PE", "L60", "O2=1", "PE")
    run(host)
    sers.advance(0.1)
    sers.set("input.I2", True)
    sers.advance(0.5)  # the 200 ms of D2 are over
    assert query(host, "DB") == "1"
    assert out(sers, 2) is False  # the jump did not happen during the interruption
    sers.set("input.I2", False)
    finish(sers, 2)
    assert out(sers, 2) is True  # it aborted the WAIT once the program continued
    assert out(sers, 1) is False


def test_p1093_0_a_delay_runs_on_during_the_interruption(sers: Plant) -> None:
    """[SIM-CHOICE] the time of a D runs on; a D over during the interruption is over after it."""
    host = sers.host
    _jog_input_enabled(sers, 0)
    download(host, "ON", "D=2", "O1=1", "PE")  # 0.24 s (D × 0.1 s × 1.2)
    run(host)
    sers.advance(0.05)
    sers.set("input.I2", True)
    sers.advance(0.5)
    assert out(sers, 1) is False
    sers.set("input.I2", False)
    until(sers, lambda d: d.read("motion.kind") is None, 1)
    sers.advance(0.01)  # (a few control cycles)
    assert out(sers, 1) is True
