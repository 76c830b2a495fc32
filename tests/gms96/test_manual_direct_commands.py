"""Manual §2.4.3 (PLC direct commands ``p10;OpCode;Operand``) and §2.4.1 (the special markers they
can wait on): driven through the card's pty with the :class:`Gms96Client`.

Marker operands number the bits from M0.0: operand = 8·byte + bit."""

from __future__ import annotations

import pytest

from devsim.devices.gms96.client import Gms96Client
from devsim.devices.gms96.i2t import I_BASE
from tests.gms96.conftest import Plant
from tests.gms96.test_motion_reference import send

BUSY = 0x10  # T3;0 I.4
WOSF, WORF = 10, 11
M1_1_I2T = 8 * 1 + 1  # M1.1 I²t marker
M1_4_SPEED_REACHED = 8 * 1 + 4  # M1.4 set speed reached
N15_DEFAULT = 84


def status(c: Gms96Client) -> int:
    return c.read(3, 0)[0]


@pytest.mark.manual("§2.4.3", "WOSF (10): wait until marker Operand is set -- also a status marker the firmware sets")
@pytest.mark.manual("§2.4.1", "M1.1 [r.]: I²t marker (1 = an I²t situation is or was present)")
def test_wosf_waits_for_the_i2t_marker(card: Plant) -> None:
    c = card.client()
    send(c, "p", 10, WOSF, M1_1_I2T)
    assert status(c) & BUSY
    card.set("quantity.load_pct", (2 * N15_DEFAULT / 255.0 - I_BASE) * 100.0)  # 100 % excess: 2 s (§3.1)
    card.advance(1.9)
    assert status(c) & BUSY
    card.advance(0.2)
    assert status(c) & BUSY == 0
    assert c.read(1, 3, 0)[2][1] & 0x02  # T1;3;0: MB1 shows M1.1


@pytest.mark.manual("§2.4.3", "WORF (11): wait until marker Operand is reset -- also a status marker the firmware clears")
@pytest.mark.manual("§2.4.1", "M1.4 [r.]: set speed reached = acceleration or braking finished (e.g. for spindle functions)")
def test_worf_waits_until_the_speed_reached_marker_drops(referenced: Plant) -> None:
    c = referenced.client()
    send(c, "Q", 8, 3, 1000)  # spindle simulation, clockwise at 1000 Hz: BUSY = 0 (§2.3.1 Q)
    referenced.advance(0.5)
    assert status(c) & BUSY == 0
    assert c.read(1, 3, 0)[2][1] & 0x10  # M1.4: the speed is reached
    send(c, "p", 10, WORF, M1_4_SPEED_REACHED)
    referenced.advance(0.5)
    assert status(c) & BUSY  # waits: M1.4 is 1
    c.override(50)  # the spindle ramps down to 500 Hz: M1.4 drops
    referenced.advance(0.001)
    assert status(c) & BUSY == 0
