"""Manual §1.3 (indexer), §2.3.1 A, B, f, G0, M, S, v, w, +, §2.7 (range and accuracy of speeds):
driven through the card's pty with the :class:`Gms96Client`; times on the virtual clock."""

from __future__ import annotations

import pytest

from tests.gms96.conftest import Plant
from tests.gms96.test_motion_reference import last, send, status, velocity

M_DEFAULT = 2000  # manual §2.3.1 M: (2000)
B_DEFAULT = 50  # manual §2.3.1 B: (50) Hz/ms
BUSY = 0x10


@pytest.mark.manual("§2.3.1 f", "an f value above the M value sets the M value")
def test_f_above_m_sets_the_m_value(referenced: Plant) -> None:
    c = referenced.client()
    send(c, "f", 5000)  # M is 2000: f becomes 2000
    send(c, "o", 2, 50)  # 50 % of f
    send(c, "A", 20000)
    referenced.advance(1.0)
    assert velocity(referenced) == pytest.approx(M_DEFAULT * 50 / 100)
    c.abort()
    referenced.idle()
    send(c, "o", 0)
    send(c, "M", 10000)  # a later, higher M does not bring back the 5000
    send(c, "A", -20000)
    referenced.advance(1.0)
    assert velocity(referenced) == pytest.approx(-M_DEFAULT)


@pytest.mark.manual("§2.3.1 M", "M: maximum speed = rapid [5..2000000] Hz, default 2000")
@pytest.mark.manual("§2.3.1 G", "G0 (P2=P3=0): rapid, the speed of the M command")
def test_default_rapid_and_g0(referenced: Plant) -> None:
    c = referenced.client()
    send(c, "A", 20000)
    referenced.advance(1.0)
    assert velocity(referenced) == pytest.approx(M_DEFAULT)  # f = M after power-on
    referenced.idle()
    send(c, "M", 6000)
    send(c, "f", 1000)
    send(c, "A", 0)
    referenced.advance(1.0)
    assert velocity(referenced) == pytest.approx(-1000)
    referenced.idle()
    send(c, "G", 0)
    send(c, "A", 20000)
    referenced.advance(1.0)
    assert velocity(referenced) == pytest.approx(6000)


@pytest.mark.manual("§2.3.1 B", "B: acceleration in Hz/ms; per millisecond the speed rises by at most B (default 50)")
@pytest.mark.manual("§1.3", "the indexer makes linear ramps (N24 = 0)")
def test_linear_ramp_rises_b_per_millisecond(referenced: Plant) -> None:
    c = referenced.client()
    send(c, "N", 0, 24)  # linear ramps
    send(c, "A", 20000)
    referenced.advance(0.010)  # 10 ms: 10 · 50 Hz
    assert velocity(referenced) == pytest.approx(10 * B_DEFAULT)
    referenced.idle()
    send(c, "B", 200)
    send(c, "A", 0)
    referenced.advance(0.005)
    assert velocity(referenced) == pytest.approx(-5 * 200)


@pytest.mark.manual("§2.3.1 B", "B P1: [1..30000]")
@pytest.mark.parametrize(("b", "after_s"), [(1, 0.010), (30000, 0.00005)])
def test_linear_ramp_at_the_ends_of_the_b_range(referenced: Plant, b: int, after_s: float) -> None:
    c = referenced.client()
    send(c, "N", 0, 24)
    send(c, "B", b)
    send(c, "A", 20000)
    referenced.advance(after_s)
    assert velocity(referenced) == pytest.approx(b * after_s * 1000)


@pytest.mark.manual("§2.3.1 B", "sin² ramps take π/2 longer than linear ones to reach the end speed at the same B")
def test_sin2_ramp_takes_pi_half_longer(referenced: Plant) -> None:
    c = referenced.client()
    send(c, "N", 1, 24)
    send(c, "A", 20000)
    t_linear = M_DEFAULT / B_DEFAULT / 1000.0  # 40 ms
    referenced.advance(t_linear)
    assert velocity(referenced) < M_DEFAULT * 0.99
    referenced.advance(t_linear * (3.14159265 / 2) - t_linear + 1e-6)
    assert velocity(referenced) == pytest.approx(M_DEFAULT)


@pytest.mark.manual("§2.7", "M above 50000 Hz: the V factor (e.g. 2 for 50001..100000); f below 2·V may give no motion")
def test_v_factor_minimum_speed(referenced: Plant) -> None:
    c = referenced.client()
    send(c, "M", 100000)  # V factor 2: the minimum f is 4
    send(c, "f", 1)
    send(c, "A", 1000)
    referenced.advance(5.0)
    assert velocity(referenced) == 0.0
    assert status(c) & BUSY
    c.abort()
    referenced.idle()
    send(c, "f", 4)
    send(c, "A", 1000)
    referenced.advance(1.0)
    assert velocity(referenced) == pytest.approx(4)


@pytest.mark.manual("§2.3.1 +", "+: a relative move of length P1 (positive or negative) without G91")
@pytest.mark.manual("§2.3.1 A", "A: a move to position P1 at the speed selected by M, f or G0")
def test_relative_and_absolute_moves(referenced: Plant) -> None:
    c = referenced.client()
    send(c, "A", 3000)
    send(c, "+", -1000)
    referenced.idle()
    assert c.read(0)[1] == 2000
    send(c, "+", 500)
    referenced.idle()
    assert c.read(0)[1] == 2500


@pytest.mark.manual("§2.3.1 w", "w: O0 (position counter := 0) and a v move with P1, in one step")
def test_w_zeroes_the_counter_and_moves(referenced: Plant) -> None:
    c = referenced.client()
    send(c, "A", 3000)
    referenced.idle()
    before = referenced.read("axis.physical")
    send(c, "w", 1000)
    referenced.idle()
    assert c.read(0)[1] == 1000  # from the new zero
    assert referenced.read("axis.physical") - before == pytest.approx(1000)  # the axis moved by 1000


@pytest.mark.manual("§2.3.1 A", "A while a move runs: the running move is completed first")
@pytest.mark.manual("§1.3", "consecutive moves in the same direction are chained without braking, also with f "
                    "between them")
def test_moves_in_one_direction_chain_without_braking(referenced: Plant) -> None:
    c = referenced.client()
    send(c, "A", 10000)
    send(c, "f", 1500)
    send(c, "A", 20000)
    referenced.advance(4.0)  # past 10000 at 2000 Hz (5 s incl. ramp): still in the first move
    assert velocity(referenced) == pytest.approx(M_DEFAULT)
    referenced.advance(1.1)  # through the junction at 10000: slowed to 1500, never to 0
    assert velocity(referenced) == pytest.approx(1500)
    t0 = referenced.now()
    referenced.idle()
    assert last(referenced.device(), "move_end") > t0
    assert c.read(0)[1] == 20000
