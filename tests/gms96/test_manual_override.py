"""Manual §2.3.1 ``o`` (override on/off, ``o2;P2`` override-inactive value), §1.3 (override 0..125 %),
§2.3.2 #9 (external override): driven through the card's pty with the :class:`Gms96Client`.

Speeds are the manual's: after power-on M = f = 2000 Hz (M command default), so at an override of
P % the axis cruises at 2000·P/100 Hz.
"""

from __future__ import annotations

import pytest

from tests.gms96.conftest import Plant
from tests.gms96.test_motion_reference import send, velocity

M_DEFAULT = 2000.0  # manual §2.3.1 M: (2000)


@pytest.mark.manual("§2.3.1 o", "o2;P2: on receipt the potentiometer override is switched off and P2 becomes the "
                    "override value, also while o0 (override function off) is in force")
def test_o2_after_o0_sets_the_override_value(referenced: Plant) -> None:
    c = referenced.client()
    send(c, "o", 0)  # override function off (queued; the queue is empty, so it is in force now)
    referenced.idle()
    assert referenced.read("override") == 100
    send(c, "o", 2, 50)  # o2;50: override-inactive value 50 %
    send(c, "A", 20000)
    referenced.advance(2.0)  # well past the ramp (2000 Hz at B50 takes 63 ms)
    assert velocity(referenced) == pytest.approx(M_DEFAULT * 50 / 100)


@pytest.mark.manual("§2.3.1 o", "o2;P2 while a move runs: the P2 value acts as the override at once (immediate command)")
def test_o2_acts_during_a_move(referenced: Plant) -> None:
    c = referenced.client()
    send(c, "A", 20000)
    referenced.advance(1.0)
    assert velocity(referenced) == pytest.approx(M_DEFAULT)
    send(c, "o", 2, 25)
    referenced.advance(1.0)
    assert velocity(referenced) == pytest.approx(M_DEFAULT * 25 / 100)


@pytest.mark.manual("§2.3.1 o", "o0: override function switched off, the programmed speed runs unchanged")
@pytest.mark.manual("§2.3.1 o", "o1: override function active (potentiometer)")
def test_o0_ignores_and_o1_follows_the_potentiometer(referenced: Plant) -> None:
    c = referenced.client()
    referenced.set("quantity.override_pot", 50)
    send(c, "A", 20000)
    referenced.advance(1.0)
    assert velocity(referenced) == pytest.approx(M_DEFAULT * 50 / 100)  # o1 is the default (s saves it)
    c.abort()
    referenced.idle()
    send(c, "o", 0)
    send(c, "A", -20000)
    referenced.advance(1.0)
    assert velocity(referenced) == pytest.approx(-M_DEFAULT)


@pytest.mark.manual("§1.3", "the override potentiometer gives 0 to 125 % of the programmed speed")
@pytest.mark.manual("§2.3.1 f", "with override the f speed can be raised by 25 %, but not above the M value")
def test_potentiometer_raises_f_by_25_percent_but_not_above_m(referenced: Plant) -> None:
    c = referenced.client()
    send(c, "f", 1000)
    referenced.set("quantity.override_pot", 125)
    send(c, "A", 20000)
    referenced.advance(1.0)
    assert velocity(referenced) == pytest.approx(1250)
    c.abort()
    referenced.idle()
    send(c, "f", 1800)  # 1800·125 % = 2250 > M
    send(c, "A", -20000)
    referenced.advance(1.0)
    assert velocity(referenced) == pytest.approx(-M_DEFAULT)


@pytest.mark.manual("§2.3.2 #9", "from the first #9 on the potentiometer has no effect; values come from the host")
@pytest.mark.manual("§2.3.2 #9", "after #9 the override activity stays switchable with o0/o1")
def test_external_override_replaces_the_potentiometer(referenced: Plant) -> None:
    c = referenced.client()
    c.override(40)
    referenced.set("quantity.override_pot", 120)
    send(c, "A", 20000)
    referenced.advance(1.0)
    assert velocity(referenced) == pytest.approx(M_DEFAULT * 40 / 100)
    c.abort()
    referenced.idle()
    send(c, "o", 0)
    send(c, "A", -20000)
    referenced.advance(1.0)
    assert velocity(referenced) == pytest.approx(-M_DEFAULT)
    c.abort()
    referenced.idle()
    send(c, "o", 1)
    send(c, "A", 20000)
    referenced.advance(1.0)
    assert velocity(referenced) == pytest.approx(M_DEFAULT * 40 / 100)  # still the host's 40 %, not the pot
