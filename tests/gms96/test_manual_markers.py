"""Manual §2.4.1 (special markers MB0..MB29), §1.4 (coupling of CNC and PLC), §2.3.1 m (M functions),
p11: driven through the card's pty with the :class:`Gms96Client` (markers written with ``p11``,
read with ``T1;3``), the PLC side through the card's marker points."""

from __future__ import annotations

import pytest

from devsim.devices.gms96.client import Gms96Client
from tests.gms96.conftest import Plant
from tests.gms96.test_motion_reference import send, velocity

BUSY, MOTION = 0x10, 0x02
FLASH_ERASE = 5.0


def mb(c: Gms96Client, byte: int) -> int:
    """MB(byte) as ``T1;3;byte`` shows it (manual §2.3.1 T)."""
    return c.read(1, 3, byte)[2][0]


def status(c: Gms96Client) -> int:
    return c.read(3, 0)[0]


@pytest.mark.manual("§2.4.1", "M0.0 STOP: set, the running move is braked (not aborted) and stays stopped; "
                    "cleared, the move goes on")
def test_m0_0_stop_holds_and_resumes(referenced: Plant) -> None:
    c = referenced.client()
    send(c, "A", 20000)
    referenced.advance(1.0)
    send(c, "p", 11, 0, 0x01)
    referenced.advance(0.5)
    assert velocity(referenced) == 0.0 and status(c) & BUSY
    send(c, "p", 11, 0, 0x00)
    referenced.advance(0.5)
    assert velocity(referenced) == pytest.approx(2000)
    referenced.idle()
    assert c.read(0)[1] == 20000


@pytest.mark.manual("§2.4.1", "M0.0 STOP in a CNC program: the move is braked, not aborted, and goes on when "
                    "STOP is cleared; M0.2 r: the CNC program runs all the while")
def test_stop_holds_a_running_program_which_still_runs(referenced: Plant) -> None:
    c = referenced.client()
    send(c, "p", 3, 100, 0)
    referenced.advance(FLASH_ERASE)
    send(c, "A", 20000)
    send(c, "p", 10, 16, 3)  # SETO A0.3 once the move is done
    send(c, "p", 3, 101)
    send(c, "p", 3, 1, 0)
    referenced.advance(1.0)
    send(c, "p", 11, 0, 0x01)  # MB0 := STOP (the host writes the whole byte)
    referenced.advance(5.0)
    held = c.read(0)[1]
    assert velocity(referenced) == 0.0 and 0 < held < 20000
    assert mb(c, 0) & 0x05 == 0x05 and mb(c, 1) & 0x01 == 0  # stopped, the program interrupted, not ended
    send(c, "p", 11, 0, 0x00)  # STOP cleared: the interrupted move and the program go on
    referenced.advance(0.5)
    assert mb(c, 0) & 0x04 and c.read(0)[1] > held
    referenced.idle()
    assert c.read(0)[1] == 20000 and c.read(1, 2, 0)[2][0] & 0x08
    assert mb(c, 0) & 0x04 == 0 and mb(c, 1) & 0x01  # ended successfully


@pytest.mark.manual("§2.4.1", "M0.1 [.w]: aborts the CNC command (move or program)")
def test_m0_1_aborts_the_move(referenced: Plant) -> None:
    c = referenced.client()
    send(c, "A", 20000)
    referenced.advance(1.0)
    send(c, "p", 11, 0, 0x02)
    referenced.idle()
    assert status(c) & BUSY == 0
    assert 0 < c.read(0)[1] < 20000


@pytest.mark.manual("§2.4.1", "M0.2 w: start the CNC program whose number is in MB2; r: a CNC program runs")
@pytest.mark.manual("§2.4.1", "M1.0: CNC program ended successfully")
@pytest.mark.manual("§2.4.1", "MB2: number of the program to start (with M0.2), and of the program started by p3;1;x")
@pytest.mark.manual("§1.4", "the PLC can start CNC programs (through reserved markers)")
def test_m0_2_starts_the_program_in_mb2(referenced: Plant) -> None:
    c = referenced.client()
    send(c, "p", 3, 100, 4)
    referenced.advance(FLASH_ERASE)
    send(c, "A", 3000)
    send(c, "p", 3, 101)
    send(c, "p", 11, 2, 4)
    send(c, "p", 11, 0, 0x04)
    referenced.advance(0.1)
    assert mb(c, 0) & 0x04 and mb(c, 1) & 0x01 == 0
    referenced.idle()
    assert mb(c, 0) & 0x04 == 0 and mb(c, 1) & 0x01
    assert c.read(0)[1] == 3000
    send(c, "p", 11, 2, 0)
    send(c, "p", 3, 1, 4)  # p3;1;4 writes the number into MB2
    assert mb(c, 2) == 4


@pytest.mark.manual("§2.4.1", "M0.3: motion active; M0.4: Notaus status (0 = Notaus); M0.5: position controller "
                    "active; M0.7 IDXOFF")
@pytest.mark.manual("§2.4.1", "M1.2 RDY = inverted BUSY; M1.4 set speed reached")
def test_status_markers_of_mb0_and_mb1(card: Plant) -> None:
    c = card.client()
    assert mb(c, 0) & 0xF8 == 0x10 | 0x20 | 0x80  # Notaus ok, controller on, IDXOFF
    assert mb(c, 1) & 0x04  # ready
    send(c, "Q", 0)
    card.idle()
    assert mb(c, 0) & 0x80 == 0
    send(c, "A", 20000)
    card.advance(1.0)
    assert mb(c, 0) & 0x08 and mb(c, 1) & 0x04 == 0 and mb(c, 1) & 0x10  # moving, busy, at speed
    card.set("input.emergency_stop", True)
    card.advance(0.01)
    assert mb(c, 0) & 0x10 == 0 and mb(c, 0) & 0x20 == 0  # Notaus: M0.4 = 0, controller off


@pytest.mark.manual("§2.4.1", "M0.6: power-stage monitoring (1 = fault, power stage inactive)")
def test_m0_6_monitoring(card: Plant) -> None:
    c = card.client()
    assert mb(c, 0) & 0x40 == 0
    card.runtime.fault(card.name, "monitoring", True)
    card.advance(0.01)
    assert mb(c, 0) & 0x40 and mb(c, 0) & 0x20 == 0


@pytest.mark.manual("§2.4.1", "M3.4: motion function suppressed (N17)")
@pytest.mark.manual("§2.3.1 N", "N17 = 1: moves run normally in time but do not move the axis")
def test_n17_suppresses_the_motion(referenced: Plant) -> None:
    c = referenced.client()
    send(c, "N", 1, 17)
    assert mb(c, 3) & 0x10
    before = referenced.read("axis.physical")
    t0 = referenced.now()
    send(c, "A", 5000)
    referenced.advance(1.0)
    assert status(c) & BUSY
    referenced.idle()
    assert referenced.now() - t0 > 2.5  # 5000 inc at 2000 Hz
    assert referenced.read("axis.physical") == before


@pytest.mark.manual("§2.4.1", "M3.5: waiting for in-position (H2)")
@pytest.mark.manual("§2.3.1 H", "H2 waits until the axis is in position (window N27 for N28 ms)")
def test_m3_5_while_h2_waits(referenced: Plant) -> None:
    c = referenced.client()
    send(c, "N", 10, 27)
    send(c, "N", 200, 28)
    send(c, "A", 1000)
    send(c, "H", 2)
    referenced.run_until(lambda d: not d.axis.moving)
    referenced.advance(0.01)
    assert mb(c, 3) & 0x20 and status(c) & BUSY
    referenced.advance(0.3)
    assert mb(c, 3) & 0x20 == 0 and status(c) & BUSY == 0


@pytest.mark.manual("§2.3.1 m", "m50..89 sets M6.0..M10.7 (M50 = M6.0, M58 = M7.0) and waits until the PLC "
                    "resets it; P2 goes to MB11")
@pytest.mark.manual("§1.4", "an M command of the CNC holds the CNC until the PLC resets the marker bit")
@pytest.mark.parametrize(("m", "byte", "bit"), [(50, 6, 0), (58, 7, 0), (89, 10, 7)])
def test_m_function_handshake(card: Plant, m: int, byte: int, bit: int) -> None:
    c = card.client()
    send(c, "m", m, 77)
    card.advance(0.5)
    assert mb(c, byte) == 1 << bit and mb(c, 11) == 77
    assert status(c) & BUSY
    card.set(f"marker.M{byte}.{bit}", False)  # the PLC resets it
    card.advance(0.01)
    assert status(c) & BUSY == 0


@pytest.mark.manual("§2.3.2 #0", "#0 aborts the running operation (... m command ...); the commands pending are not "
                    "carried out")
def test_break_aborts_a_waiting_m_command(card: Plant) -> None:
    c = card.client()
    send(c, "m", 50, 0)
    send(c, "p", 10, 16, 3)  # SETO A0.3 behind it
    card.advance(0.5)
    assert status(c) & BUSY  # waits for the PLC
    c.abort()
    card.advance(0.01)
    assert status(c) & BUSY == 0
    assert c.read(1, 2, 0)[2][0] & 0x08 == 0  # the SETO never ran


@pytest.mark.manual("§2.3.1 m", "m100;P2;P3 (S function): P2 into MB15, P3 into MW16, M15.7 set, wait for its reset")
def test_m100_spindle_function(card: Plant) -> None:
    c = card.client()
    send(c, "m", 100, 2, 1500)
    card.advance(0.1)
    assert mb(c, 15) == 0x80 | 2
    assert int.from_bytes(c.read(1, 3, 16)[2], "big") == 1500  # MW16 (Step5 word: high byte first)
    assert status(c) & BUSY
    card.set("marker.M15.7", False)
    card.advance(0.01)
    assert status(c) & BUSY == 0


@pytest.mark.manual("§2.3.1 m", "m101;P2;P3 (T function): P2 into MB18, M18.7 set, P3 into MB19; MB18 kept at "
                    "power failure")
@pytest.mark.manual("§2.4.1", "MB18: tool number from the T function (18.0..18.6, NV); MB19: current tool memory")
def test_m101_tool_function(card: Plant) -> None:
    c = card.client()
    send(c, "m", 101, 5, 9)
    card.advance(0.1)
    assert mb(c, 18) == 0x80 | 5 and mb(c, 19) == 9
    card.set("marker.M18.7", False)
    card.advance(0.01)
    assert status(c) & BUSY == 0
    card.runtime.power_cycle(card.name)
    card.advance(0.6)
    assert mb(c, 18) == 5


@pytest.mark.manual("§2.3.1 p", "p11;P2;P3: the byte P3 into marker byte P2 (e.g. p11;13;1: MB13 = 1)")
@pytest.mark.manual("§2.3.1 p", "p11 received during a CNC download is recorded into the program")
def test_p11_writes_a_marker_byte_and_is_recorded(referenced: Plant) -> None:
    c = referenced.client()
    send(c, "p", 11, 13, 1)
    assert mb(c, 13) == 1
    send(c, "p", 3, 100, 0)
    referenced.advance(FLASH_ERASE)
    send(c, "p", 11, 40, 0x33)
    send(c, "p", 3, 101)
    assert mb(c, 40) == 0
    send(c, "p", 3, 1, 0)
    referenced.idle()
    assert mb(c, 40) == 0x33


@pytest.mark.manual("§2.3.1 p", "p11;P2;P3: the byte P3 into marker byte P2 (spec §3.10: a parameter out of range is "
                    "clamped)")
def test_p11_clamps_a_value_beyond_a_byte(referenced: Plant) -> None:
    c = referenced.client()
    send(c, "p", 11, 13, 300)
    assert mb(c, 13) == 255  # not 300 mod 256 = 44
    send(c, "p", 11, 14, -1)
    assert mb(c, 14) == 0


@pytest.mark.manual("§2.4.1", "M0.1 does not end a pending STOP situation (M0.0 = 1)")
def test_m0_1_leaves_the_stop(referenced: Plant) -> None:
    c = referenced.client()
    send(c, "p", 11, 0, 0x01)  # STOP
    send(c, "A", 5000)
    referenced.advance(0.5)
    send(c, "p", 11, 0, 0x03)  # abort while STOP stays
    referenced.advance(0.1)
    assert mb(c, 0) & 0x01
    send(c, "A", 6000)
    referenced.advance(1.0)
    assert velocity(referenced) == 0.0  # still held
    send(c, "p", 11, 0, 0x00)
    referenced.idle()
    assert c.read(0)[1] == 6000


@pytest.mark.manual("§2.4.1", "M0.7 IDXOFF is set when a reference run starts")
def test_idxoff_set_when_a_reference_run_starts(referenced: Plant) -> None:
    c = referenced.client()
    assert mb(c, 0) & 0x80 == 0
    send(c, "Q", 0)
    referenced.advance(0.2)
    assert mb(c, 0) & 0x80 and c.read(3, 0)[0] & 0x08
    referenced.idle()
    assert mb(c, 0) & 0x80 == 0


@pytest.mark.manual("§2.4.1", "M0.3 [r.]: Fahrbewegung aktiv (0 = keine gesteuerte Motor-Bewegung); unlike I.1/K.4 "
                    "it does not include the block marking M1.5")
@pytest.mark.manual("§2.3.1 T", "T3;0 I.1: Fahrt läuft (Indexer- oder Referenzfahrt) oder Block-Kommandos (M 1.5)")
def test_m0_3_is_motor_motion_only(referenced: Plant) -> None:
    c = referenced.client()
    send(c, "p", 11, 1, 0x20)  # M1.5 block marking, the axis at rest
    referenced.advance(0.1)
    assert status(c) & MOTION  # I.1 includes M1.5
    assert mb(c, 0) & 0x08 == 0  # M0.3: no motor movement
    send(c, "p", 11, 1, 0)
    send(c, "Q", 0)  # a reference run held by STOP (M0.0): the run goes on, the motor stands
    referenced.advance(1.0)
    assert mb(c, 0) & 0x08
    send(c, "p", 11, 0, 0x01)
    referenced.advance(1.0)
    assert velocity(referenced) == 0.0 and status(c) & MOTION
    assert mb(c, 0) & 0x08 == 0
    send(c, "p", 11, 0, 0x00)
    referenced.advance(0.5)
    assert mb(c, 0) & 0x08
