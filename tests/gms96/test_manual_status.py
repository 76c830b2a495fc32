"""Manual §2.3.1 T (read-backs, T3;0 status byte I), q, c; §2.3.2 #0, #1 (K byte), #8, #9: driven
through the card's pty with the :class:`Gms96Client`; the machine side (Notaus, monitoring, inputs)
through the card's points."""

from __future__ import annotations

import pytest

from devsim.devices.gms96.client import Gms96Client
from tests.gms96.conftest import Plant
from tests.gms96.test_motion_reference import send

# T3;0 identifier I (manual §2.3.1 T, P1=3 P2=0)
I_ESTOP, I_MOTION, I_MONITORING, I_IDXOFF, I_BUSY, I_MESSAGE = 0x01, 0x02, 0x04, 0x08, 0x10, 0x80
# #1 K byte (manual §2.3.2)
K_AE, K_ESTOP, K_MOTION, K_MONITORING, K_IDXOFF, K_BUSY = 0x02, 0x08, 0x10, 0x20, 0x40, 0x80


def status(c: Gms96Client) -> int:
    return c.read(3, 0)[0]


def k(c: Gms96Client) -> int:
    return c.status()[0]


@pytest.mark.manual("§2.3.1 T", "T3;0 I.0 = 1 while Notaus is active")
@pytest.mark.manual("§2.3.2 #1", "K.3: Notaus status, 1 = Notaus active")
def test_notaus_status(card: Plant) -> None:
    c = card.client()
    assert status(c) & I_ESTOP == 0 and k(c) & K_ESTOP == 0
    card.set("input.emergency_stop", True)
    card.advance(0.01)
    assert status(c) & I_ESTOP and k(c) & K_ESTOP


@pytest.mark.manual("§2.3.1 T", "T3;0 I.1 = 1 while a move runs (indexer or reference run) or block commands (M1.5)")
@pytest.mark.manual("§2.3.2 #1", "K.4: a move runs (indexer or reference run) or block commands (M1.5)")
def test_motion_bit_for_moves_reference_runs_and_the_block_marker(card: Plant) -> None:
    c = card.client()
    assert status(c) & I_MOTION == 0
    send(c, "Q", 0)  # reference run (cam, then index mark)
    card.advance(0.5)
    assert status(c) & I_MOTION and k(c) & K_MOTION
    card.idle()
    assert status(c) & I_MOTION == 0
    send(c, "A", 5000)
    card.advance(0.5)
    assert status(c) & I_MOTION and k(c) & K_MOTION
    card.idle()
    send(c, "p", 11, 1, 0x20)  # M1.5 block marker
    card.advance(0.01)
    assert status(c) & I_MOTION and k(c) & K_MOTION


@pytest.mark.manual("§2.3.1 T", "T3;0 I.2 = 1: monitoring tripped")
@pytest.mark.manual("§2.3.2 #1", "K.5: monitoring")
def test_monitoring_bit(card: Plant) -> None:
    c = card.client()
    assert status(c) & I_MONITORING == 0
    card.runtime.fault(card.name, "monitoring", True)
    card.advance(0.01)
    assert status(c) & I_MONITORING and k(c) & K_MONITORING


@pytest.mark.manual("§2.3.1 T", "T3;0 I.3 IDXOFF = 1 after power-on (indexer not ready), 0 when moves can run")
@pytest.mark.manual("§2.3.2 #1", "K.6: IDXOFF, 1 after power-on")
@pytest.mark.manual("§2.3.1 Q", "after a successful reference run the IDXOFF bit is cleared")
def test_idxoff_after_power_on_until_a_reference_run(card: Plant) -> None:
    c = card.client()
    assert status(c) & I_IDXOFF and k(c) & K_IDXOFF
    send(c, "Q", 0)
    card.idle()
    assert status(c) & I_IDXOFF == 0 and k(c) & K_IDXOFF == 0


@pytest.mark.manual("§2.3.1 T", "T3;0 I.4 BUSY = 1 while a CNC command executes, 0 = ready")
@pytest.mark.manual("§2.3.2 #1", "K.7: BUSY, 1 = CNC command executing, 0 = ready")
def test_busy_while_a_command_executes(card: Plant) -> None:
    c = card.client()
    assert status(c) & I_BUSY == 0 and k(c) & K_BUSY == 0
    send(c, "p", 10, 14, 20)  # WAIT 2 s
    card.advance(1.0)
    assert status(c) & I_BUSY and k(c) & K_BUSY
    card.advance(1.1)
    assert status(c) & I_BUSY == 0


@pytest.mark.manual("§2.3.1 T", "T3;0 I.7 = 1: a message code in MB4; T1;3;4 test-reads it")
@pytest.mark.manual("§2.3.2 #1", "K.1: a second character with the MB4 message follows, only when MB4 is not 0; "
                    "MB4 is set to 0 by the transmission")
@pytest.mark.manual("§2.4.3", "SNDM (29): Operand buffered into MB4")
def test_message_in_mb4(card: Plant) -> None:
    c = card.client()
    assert status(c) & I_MESSAGE == 0
    assert c.status() == (K_IDXOFF, None)
    send(c, "p", 10, 29, 42)  # SNDM 42
    card.advance(0.01)
    assert status(c) & I_MESSAGE
    assert c.read(1, 3, 4)[2][0] == 42  # T1;3;4 test-reads MB4 ...
    assert status(c) & I_MESSAGE  # ... without clearing it
    kk, message = c.status()
    assert kk & K_AE and message == 42
    assert c.status() == (K_IDXOFF, None)  # sent once: MB4 = 0
    assert status(c) & I_MESSAGE == 0


@pytest.mark.manual("§2.4.3", "SNDF (28): Operand buffered into MB5 (the error byte)")
def test_sndf_is_buffered_in_mb5(card: Plant) -> None:
    c = card.client()
    send(c, "p", 10, 28, 7)  # SNDF 7
    send(c, "p", 10, 28, 9)  # SNDF 9: buffered while MB5 still holds 7
    card.advance(0.01)
    assert c.read(1, 3, 5)[2][0] == 7
    send(c, "p", 11, 5, 0)  # the error byte is taken (cleared) ...
    card.advance(0.01)
    assert c.read(1, 3, 5)[2][0] == 9  # ... and the buffered one follows
    send(c, "p", 11, 5, 0)
    card.advance(0.01)
    assert c.read(1, 3, 5)[2][0] == 0


@pytest.mark.manual("§2.3.1 T", "T0: the momentary set-point position, 3 bytes, identifier '@'")
@pytest.mark.manual("§2.3.1 T", "T1;0: identifier 'V', the software version times 100 (v4.04)")
@pytest.mark.manual("§2.3.1 T", "T5;P2: identifier 'N', the stored N parameter P2 (e.g. T5;10 the P gain)")
def test_read_backs_position_version_n(card: Plant) -> None:
    c = card.client()
    assert c.read(1, 0) == (ord("V"), 404, (404).to_bytes(2, "little"))
    send(c, "Q", 3)
    send(c, "A", -300)
    card.idle()
    ident, _value, raw = c.read(0)
    assert ident == ord("@") and int.from_bytes(raw, "little", signed=True) == -300
    send(c, "N", 321, 10)
    assert c.read(5, 10)[:2] == (ord("N"), 321)


@pytest.mark.manual("§2.3.1 T", "T1;1;P3: identifier 'I', 16 bits of the input image PAE from byte P3 (P3=4: EB4, EB5)")
@pytest.mark.manual("§2.3.1 T", "T1;2;P3: 16 bits of the output image PAA from byte P3")
@pytest.mark.manual("§2.3.1 T", "T1;3;P3: 16 bits of markers from byte P3")
def test_read_backs_of_the_images(card: Plant) -> None:
    c = card.client()
    card.set("input.E1.2", True)
    card.set("input.E2.1", False)
    card.advance(0.01)
    ident, _v, raw = c.read(1, 1, 1)
    assert ident == ord("I") and raw[0] == 0x04  # EB1: E1.2
    send(c, "p", 10, 16, 9)  # SETO 9 = A1.1
    card.advance(0.01)
    assert c.read(1, 2, 1)[2][0] == 0x02  # AB1: A1.1
    send(c, "p", 11, 40, 0x5A)
    send(c, "p", 11, 41, 0xA5)
    card.advance(0.01)
    assert c.read(1, 3, 40)[2] == bytes([0x5A, 0xA5])


@pytest.mark.manual("§2.3.1 T", "T1;4: the momentary following error in increments, identifier 'I'")
@pytest.mark.manual("§2.3.1 T", "T1;5: the momentary motor current [0..252], 252 = maximum current")
def test_following_error_and_current(referenced: Plant) -> None:
    c = referenced.client()
    assert c.read(1, 4)[:2] == (ord("I"), 0)
    send(c, "A", 20000)
    referenced.advance(1.0)
    _i, _v, raw = c.read(1, 4)
    lag = int.from_bytes(raw, "little", signed=True)
    assert lag > 0 and lag == pytest.approx(referenced.read("following_error"), abs=1)
    ident, current, _raw = c.read(1, 5)
    assert ident == ord("I") and 0 <= current <= 252
    referenced.set("quantity.load_pct", 200)  # asks for more than the maximum
    referenced.advance(0.01)
    assert c.read(1, 5)[1] == 252


@pytest.mark.manual("§2.3.1 c", "c P1;P2: register R(P2) := P1 (24-bit two's complement, P2 = 0..19), answer E5h")
@pytest.mark.manual("§2.3.1 T", "T1;6;P3: identifier 'D', 24 bits of PLC data from byte P3; T1;6;8 reads register R02")
@pytest.mark.manual("§2.3.1 c", "registers lie in the static data area, each takes 2 DWs")
def test_registers_and_data(card: Plant) -> None:
    c = card.client()
    send(c, "c", -5, 2)
    ident, _v, raw = c.read(1, 6, 8)
    assert ident == ord("D") and int.from_bytes(raw, "little", signed=True) == -5
    send(c, "c", 0x123456, 19)
    assert c.read(1, 6, 4 * 19)[1] == 0x123456
    card.runtime.power_cycle(card.name)
    card.advance(0.6)
    assert int.from_bytes(c.read(1, 6, 8)[2], "little", signed=True) == -5  # static: kept


@pytest.mark.manual("§2.3.1 q", "q sets marker bit M3.1 (message query)")
def test_q_sets_m3_1(card: Plant) -> None:
    c = card.client()
    assert c.read(1, 3, 3)[2][0] & 0x02 == 0
    send(c, "q")
    assert c.read(1, 3, 3)[2][0] & 0x02


@pytest.mark.manual("§2.3.2 #0", "#0 aborts the running operation; all commands pending up to then are not executed")
def test_abort_discards_the_pending_commands(referenced: Plant) -> None:
    c = referenced.client()
    send(c, "A", 20000)
    send(c, "p", 10, 16, 3)  # SETO A0.3 behind the move
    send(c, "A", 0)
    referenced.advance(0.5)
    c.abort()
    referenced.idle()
    assert status(c) & I_BUSY == 0
    assert c.read(1, 2, 0)[2][0] & 0x08 == 0  # the SETO never ran
    assert 0 < c.read(0)[1] < 20000  # stopped on the way


@pytest.mark.manual("§2.3.2 #8", "#8: the actual spindle speed in 2 AE bytes, acknowledged with E5h")
@pytest.mark.manual("§2.3.2 #9", "#9: an override value [0..125] in one AE byte, acknowledged with E5h")
def test_short_commands_8_and_9_are_acknowledged(card: Plant) -> None:
    c = card.client()
    c.spindle_speed(1500)  # raises unless E5h
    c.override(125)
    assert card.read("override") == 125
