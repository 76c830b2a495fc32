"""GMS96 reference runs, backlash, end stops, H2/H7 and motion timing through a real pty.

Every command goes through the pty with the :class:`Gms96Client`; virtual time only moves when
the test advances it, so each expectation is a closed form of the spec's motion laws (§5.3:
a = 1000·B inc/s², sin² ramps take π/2 longer than linear ones, i.e. their average acceleration
is 2a/π).  Defaults after power-on: M = f = 2000 Hz, S = 100 Hz, B = 50 Hz/ms, N24 = 1 (sin²),
cam [-20000, -15000] on E2.1, an index mark every 4096 inc.

Cam, limit switches and index marks switch on the ACTUAL position (spec §5.6, §5.7, §5.11): while
cruising at v it lags the set-point by v/Kv (Kv = 0.2·N10 = 40 s⁻¹), so a switch is seen
``LAG_T`` = 1/Kv later than the set-point passes it, with the set-point v/Kv further on; a
reference run repositions onto the actual position at the detection instant.
"""

from __future__ import annotations

import math
from typing import Any

import pytest

from devsim.devices.gms96.client import Gms96Client
from devsim.devices.gms96.codec import ACK, SingleChar
from tests.gms96.conftest import Plant

A = 50000.0  # B50
A_SIN = 2.0 * A / math.pi  # average acceleration of a sin² ramp with peak a
S = 100.0
TOL = 1e-6
KV = 40.0  # 0.2 · N10 (200)
LAG_T = 1.0 / KV  # a cruising actual position passes a point 1/Kv after the set-point


def lag(v: float) -> float:
    """The following error v/Kv while cruising at ``v``."""
    return v / KV


def ramp(v: float, a: float = A_SIN) -> float:
    """Time to change the speed by ``v``."""
    return v / a


def dist(v: float, a: float = A_SIN) -> float:
    """Distance of a ramp between 0 and ``v``."""
    return v * v / (2.0 * a)


def reposition(v: float, a: float = A_SIN) -> float:
    """Brake from ``v`` past the detected point and come back onto it at the search speed S: at
    detection the set-point is already v/Kv past the (actual) point."""
    d = dist(v, a) + lag(v)
    back = d / S + S / a if d >= 2 * dist(S, a) else 2.0 * math.sqrt(d / a)
    return ramp(v, a) + back


def trapezoid(d: float, v: float, a: float = A_SIN) -> float:
    """Rest-to-rest move over ``d`` at cruise speed ``v`` (full profile)."""
    assert d >= 2 * dist(v, a)
    return d / v + v / a


def send(c: Gms96Client, command: str, *params: int) -> None:
    assert c.send_letter(command, *params) == SingleChar(ACK)


def last(dev: Any, name: str) -> float:
    return [t for t, e in dev.events if e == name][-1]


def status(c: Gms96Client) -> int:
    """T3;0: the identifier is the standard status byte I (spec §4.3.1)."""
    ident, _value, _raw = c.read(3, 0)
    return ident


MOTION, IDXOFF, BUSY = 0x02, 0x08, 0x10


def physical(plant: Plant) -> float:
    return float(plant.device().axis.position())


def velocity(plant: Plant) -> float:
    return float(plant.device().axis.velocity())


# ================================================================================================
# reference runs (spec §3.8.14, §5.6)
# ================================================================================================


@pytest.mark.manual("§2.3.1 Q", "Q1: only the search of the index mark (at the S speed)")
@pytest.mark.manual("§2.3.1 S", "S: the search speed of the index mark, default 100 Hz")
def test_q1_index_mark_only(plant_factory: Any) -> None:
    plant = plant_factory({"axis": {"index_offset": 100}})
    c = plant.client()
    t0 = plant.now()
    send(c, "Q", 1)
    assert status(c) == MOTION | IDXOFF | BUSY
    plant.advance(1.0)
    assert velocity(plant) == pytest.approx(-S)  # search speed S, negative
    plant.idle()
    dev = plant.device()
    # first mark below 0 is 100 - 4096 = -3996
    t_mark = ramp(S) + (3996 - dist(S)) / S + LAG_T  # the actual reaches the mark 1/Kv later
    assert last(dev, "reference_done") - t0 == pytest.approx(t_mark + reposition(S), abs=TOL)
    assert physical(plant) == pytest.approx(-3996)
    assert status(c) == 0
    assert c.read(0)[1] == 0
    assert plant.read("position_counter") == 0


@pytest.mark.manual("§2.3.1 Q", "Q2: only the search of the mechanical cam")
def test_q2_cam_only_at_working_speed(card: Plant) -> None:
    c = card.client()
    send(c, "f", 1000)
    card.advance(0.01)
    t0 = card.now()
    send(c, "Q", 2)
    card.advance(1.0)
    assert velocity(card) == pytest.approx(-1000)  # fast search at f
    assert card.device().executor.reference.cam_phase is True  # FB 254 (3) = 1
    card.idle()
    dev = card.device()
    t_cam = ramp(1000) + (15000 - dist(1000)) / 1000 + LAG_T
    # drive off the cam at S (positive): brake from lag(1000) past the edge, come back; the actual
    # leaves the cam at its edge -15000 with the set-point lag(S) beyond it
    t_off = t_cam + ramp(1000) + ramp(S) + (dist(1000) + lag(1000) - dist(S) + lag(S)) / S
    assert last(dev, "reference_done") - t0 == pytest.approx(t_off + reposition(S), abs=TOL)
    assert physical(card) == pytest.approx(-15000)  # the cam's inactive edge is the point
    assert card.read("position_counter") == 0 and card.read("idxoff") is False


@pytest.mark.manual("§2.3.1 Q", "Q0: fast search negative until the cam (E2.1), free the cam slowly (S) positive, then negative onto the index mark")
def test_q0_timing_closed_form(card: Plant) -> None:
    c = card.client()
    t0 = card.now()
    send(c, "Q", 0)
    card.idle()
    t_cam = ramp(2000) + (15000 - dist(2000)) / 2000 + LAG_T  # switches on the actual position
    t_off = t_cam + ramp(2000) + ramp(S) + (dist(2000) + lag(2000) - dist(S) + lag(S)) / S
    # reversal at S from lag(S) above the edge, then down until the actual reaches the mark
    t_mark = t_off + 2 * ramp(S) + (16384 - 15000 + 2 * lag(S)) / S
    assert last(card.device(), "reference_done") - t0 == pytest.approx(t_mark + reposition(S), abs=TOL)
    assert physical(card) == pytest.approx(-16384)


@pytest.mark.manual("§2.3.1 Q", "Q P2.1: reversed direction of the reference run")
def test_q0_reversed_direction_p2_1(plant_factory: Any) -> None:
    plant = plant_factory({"axis": {"cam": [15000, 20000]}})
    c = plant.client()
    t0 = plant.now()
    send(c, "Q", 0, 0x02)
    plant.advance(1.0)
    assert velocity(plant) == pytest.approx(2000)  # "negative" is positive with P2.1
    plant.idle()
    t_cam = ramp(2000) + (15000 - dist(2000)) / 2000 + LAG_T  # switches on the actual position
    t_off = t_cam + ramp(2000) + ramp(S) + (dist(2000) + lag(2000) - dist(S) + lag(S)) / S
    t_mark = t_off + 2 * ramp(S) + (16384 - 15000 + 2 * lag(S)) / S
    assert last(plant.device(), "reference_done") - t0 == pytest.approx(t_mark + reposition(S), abs=TOL)
    assert physical(plant) == pytest.approx(16384)
    assert plant.read("position_counter") == 0 and plant.read("idxoff") is False


@pytest.mark.manual("§2.3.1 Q", "Q P2.3: the cam on E2.0 instead of E2.1")
def test_q0_cam_on_e2_0_p2_3(plant_factory: Any) -> None:
    plant = plant_factory({"axis": {"cam_input": "E2.0"}})
    c = plant.client()
    send(c, "Q", 0, 0x08)
    plant.idle()
    assert plant.read("idxoff") is False
    assert physical(plant) == pytest.approx(-16384)
    # without P2.3 the card watches E2.1, which never comes: the P3 limit ends the run
    t0 = plant.now()
    start = physical(plant)
    send(c, "Q", 0, 0, 30000)
    plant.idle()
    dev = plant.device()
    t_limit = ramp(2000) + (30000 - dist(2000)) / 2000
    assert last(dev, "reference_failed") - t0 == pytest.approx(t_limit + ramp(2000), abs=TOL)
    assert physical(plant) == pytest.approx(start - 30000 - dist(2000))
    assert plant.read("idxoff") is True


@pytest.mark.manual("§2.3.1 Q", "Q P2.2 = 1: the position counter is not zeroed, it keeps counting")
def test_q1_counter_keeps_counting_p2_2(referenced: Plant) -> None:
    c = referenced.client()
    send(c, "A", 10000)  # physical -6384
    referenced.idle()
    send(c, "Q", 1, 0x04)
    referenced.idle()
    assert physical(referenced) == pytest.approx(-8192)  # the next mark below
    assert referenced.read("idxoff") is False
    assert referenced.read("position_counter") == 8192  # counted on, not zeroed
    assert c.read(0)[1] == 8192
    send(c, "+", 10)  # off the mark (a run started on a mark finds that mark at once)
    send(c, "Q", 1)
    referenced.idle()
    assert physical(referenced) == pytest.approx(-8192)
    assert referenced.read("position_counter") == 0


@pytest.mark.manual("§2.3.1 Q", "Q P2.6 with P3 = 0: the absolute resolver position [-2048..2047] goes into the position counter")
def test_q2_resolver_position_p2_6_p3_0(card: Plant) -> None:
    c = card.client()
    send(c, "Q", 2, 0x40)
    card.idle()
    assert physical(card) == pytest.approx(-15000)
    # -15000 = -4·4096 + 1384: the absolute position within the pole pass
    assert card.read("position_counter") == 1384
    assert card.read("idxoff") is False


@pytest.mark.manual("§2.3.1 Q", "Q P3: distance limit of the reference run; beyond it the run ends, the indexer stays inactive (P2.6 = 0)")
def test_p3_limit_single_leg_closed_form(plant_factory: Any) -> None:
    plant = plant_factory({"axis": {"index_period": 1_000_000, "index_offset": 500_000}})
    c = plant.client()
    t0 = plant.now()
    send(c, "Q", 1, 0, 5000)
    plant.idle()
    dev = plant.device()
    t_limit = ramp(S) + (5000 - dist(S)) / S
    assert last(dev, "reference_failed") - t0 == pytest.approx(t_limit + ramp(S), abs=TOL)
    assert physical(plant) == pytest.approx(-5000 - dist(S))
    assert status(c) == IDXOFF  # failed: IDXOFF, no message
    assert c.status() == (0x40, None)


def test_p3_limit_counts_the_path_of_every_leg(card: Plant) -> None:
    """Q0 with P3: travel to the cam, the braking overshoot and its way back both count."""
    c = card.client()
    # the cam edges are seen lag(v) late, so the set-point overshoots them by lag(v) and comes back
    used = 15000 + 2 * dist(2000) + 2 * lag(2000) + 2 * dist(S) + 2 * lag(S)
    p3 = round(used + 500)
    excess = p3 - used
    send(c, "Q", 0, 0, p3)
    card.idle()
    assert card.read("idxoff") is True
    # the limit hits in the index-mark search below the cam edge -15000
    assert physical(card) == pytest.approx(-15000 - excess - dist(S), abs=1e-6)


def test_p3_limit_with_p2_6_not_referenced_raises_message_23(plant_factory: Any) -> None:
    plant = plant_factory({"axis": {"index_period": 1_000_000, "index_offset": 500_000}})
    c = plant.client()
    send(c, "Q", 1, 0x40, 2000)
    plant.idle()
    assert status(c) == IDXOFF | 0x80  # was not active before: stays inactive; message waits
    assert c.status() == ((IDXOFF << 3) | 0x02, 23)


@pytest.mark.manual("§2.3.1 Q", "Q P2.6 with P3 > 0: beyond the limit message 23 and the indexer stays active")
def test_p3_limit_with_p2_6_keeps_the_indexer_active(referenced: Plant) -> None:
    dev = referenced.device()
    dev.cfg.axis.index_period = 1_000_000
    dev.axis.counts_per_rev = 1_000_000
    dev.axis.index_offset = 500_000
    c = referenced.client()
    counter = referenced.read("position_counter")
    send(c, "Q", 1, 0x40, 3000)
    referenced.idle()
    assert referenced.read("idxoff") is False
    assert referenced.read("position_counter") == pytest.approx(counter - 3000 - dist(S), abs=1)
    assert c.status() == (0x02, 23)
    send(c, "A", 0)  # still referenced: moves run
    referenced.idle()
    assert referenced.read("position_counter") == 0


@pytest.mark.manual("§2.3.1 Q", "Q6: search run onto the 24 V cam input")
def test_q6_input_search(card: Plant) -> None:
    c = card.client()
    t0 = card.now()
    send(c, "Q", 6, 0x08)  # E2.0, 24 V active
    card.advance(2.0)
    assert velocity(card) == pytest.approx(-2000)  # working speed
    card.set("input.E2.0", True)
    x_detect = -(dist(2000) + 2000 * (2.0 - ramp(2000))) + lag(2000)  # the actual at detection
    card.idle()
    assert last(card.device(), "reference_done") - t0 == pytest.approx(2.0 + reposition(2000), abs=TOL)
    assert physical(card) == pytest.approx(x_detect)
    assert card.read("position_counter") == 0 and card.read("idxoff") is False


def test_q6_active_at_start_ends_at_once(card: Plant) -> None:
    c = card.client()
    card.set("input.E2.0", True)
    t0 = card.now()
    send(c, "Q", 6, 0x08)
    card.idle()
    assert last(card.device(), "reference_done") == pytest.approx(t0)
    assert physical(card) == 0.0 and card.read("idxoff") is False


@pytest.mark.manual("§2.3.1 Q", "Q P2.7: edge criterion; a level present at the start ends the run only at the second change")
def test_q6_edge_criterion_p2_7(card: Plant) -> None:
    c = card.client()
    card.set("input.E2.0", True)
    t0 = card.now()
    send(c, "Q", 6, 0x88)  # level already active: first the change away, then back
    card.advance(1.0)
    card.set("input.E2.0", False)
    card.advance(1.0)
    assert card.device().axis.moving
    card.set("input.E2.0", True)
    card.idle()
    assert last(card.device(), "reference_done") - t0 == pytest.approx(2.0 + reposition(2000), abs=TOL)
    assert physical(card) == pytest.approx(-(dist(2000) + 2000 * (2.0 - ramp(2000))) + lag(2000))


@pytest.mark.manual("§2.3.1 Q", "Q P2.0 = 1: normally-closed cam switch (active at 0 V)")
def test_q6_normally_closed_p2_0_drives_the_switch_free(card: Plant) -> None:
    c = card.client()
    card.set("input.E2.0", True)  # at 24 V: with P2.0 the active level is 0 V
    send(c, "Q", 6, 0x09)
    card.advance(1.0)
    card.set("input.E2.0", False)
    card.idle()
    assert card.read("idxoff") is False
    assert physical(card) == pytest.approx(-(dist(2000) + 2000 * (1.0 - ramp(2000))) + lag(2000))


@pytest.mark.manual("§2.3.1 Q", "Q8 spindle simulation: P2 = 3/4/5 cw/ccw/stop, P3 speed up to rapid, P2 = 8 new speed only; BUSY = 0 and motion = 1")
def test_q8_spindle_simulation(card: Plant) -> None:
    c = card.client()
    dev = card.device()
    send(c, "Q", 8, 3, 1500)
    assert status(c) == MOTION | IDXOFF  # BUSY = 0, motion = 1
    card.advance(ramp(1500))
    assert velocity(card) == pytest.approx(1500)
    assert dev.axis.phase() == "const" and card.read("marker.M1.4") is True  # set speed reached
    send(c, "B", 100)  # further queued commands run while the spindle turns
    card.advance(0.001)
    assert card.read("param.B") == 100 and card.read("busy") is False
    a = 2 * 100000 / math.pi
    send(c, "Q", 8, 8, 500)  # new speed only
    card.advance(ramp(1000, a))
    assert velocity(card) == pytest.approx(500)
    send(c, "Q", 8, 4, 99999)  # counter-clockwise, limited to M = 2000
    card.advance(ramp(500, a) + ramp(2000, a))
    assert velocity(card) == pytest.approx(-2000)
    assert status(c) == MOTION | IDXOFF
    send(c, "Q", 8, 5)
    card.advance(ramp(2000, a) - 1e-4)
    assert status(c) == MOTION | IDXOFF
    card.advance(2e-4)
    assert velocity(card) == 0.0
    assert status(c) == IDXOFF


# ------------------------------------------------------------------------------------------------
# reference type N19, drive-off N33, cam search at the M value of the EEPROM
# ------------------------------------------------------------------------------------------------


@pytest.mark.manual("§2.3.1 Q", "Q-1: reference run per N19 with drive-off to N33; the cam search uses the M speed from the NV memory")
def test_q_minus_1_uses_saved_m_and_drives_off(plant_factory: Any) -> None:
    plant = plant_factory({"axis": {"index_offset": 100}})
    c = plant.client()
    send(c, "M", 3000)
    send(c, "s", 85, 170)
    send(c, "M", 1000)  # the RAM value (and f) are now 1000
    send(c, "N", 5000, 33)
    plant.idle()
    t0 = plant.now()
    send(c, "Q", -1)
    plant.advance(1.0)
    assert velocity(plant) == pytest.approx(-3000)  # NV M, not f/M in RAM
    plant.idle()
    t_cam = ramp(3000) + (15000 - dist(3000)) / 3000 + LAG_T  # switches on the actual position
    t_off = t_cam + ramp(3000) + ramp(S) + (dist(3000) + lag(3000) - dist(S) + lag(S)) / S
    t_mark = t_off + 2 * ramp(S) + (16284 - 15000 + 2 * lag(S)) / S  # mark 100 - 4·4096 = -16284
    t_end = t_mark + reposition(S) + trapezoid(5000, 3000)
    assert last(plant.device(), "reference_done") - t0 == pytest.approx(t_end, abs=TOL)
    assert physical(plant) == pytest.approx(-16284 + 5000)
    assert c.read(0)[1] == 5000
    assert status(c) == 0


@pytest.mark.manual("§2.3.1 N", "N19: reference type, LSB = P1 of Q, middle byte = P2 of Q")
def test_q_minus_1_reference_type_from_n19(plant_factory: Any) -> None:
    plant = plant_factory({"axis": {"index_offset": 100}})
    c = plant.client()
    send(c, "N", 1 | (0x02 << 8), 19)  # Q1 with P2.1: index mark search in positive direction
    send(c, "N", -2000, 33)
    t0 = plant.now()
    send(c, "Q", -1)
    plant.idle()
    t_mark = ramp(S) + (100 - dist(S)) / S + LAG_T
    t_end = t_mark + reposition(S) + trapezoid(2000, 2000)
    assert last(plant.device(), "reference_done") - t0 == pytest.approx(t_end, abs=TOL)
    assert physical(plant) == pytest.approx(100 - 2000)
    assert plant.read("position_counter") == -2000 and plant.read("idxoff") is False


# ================================================================================================
# backlash compensation N41/N42 (spec §5.8)
# ================================================================================================


@pytest.mark.manual("§1.3", "a simple backlash compensation takes up play in the mechanics")
@pytest.mark.manual("§2.3.1 N", "N41: backlash amount [0..255 inc]; N42: its speed [inc/ms]")
def test_backlash_compensation_on_reversal(referenced: Plant) -> None:
    c = referenced.client()
    dev = referenced.device()
    send(c, "N", 50, 41)
    send(c, "N", 10, 42)  # 50 inc at 10 inc/ms: 5 ms
    comp = 0.005
    t0 = referenced.now()
    send(c, "A", 10000)  # same direction as the reference run's last motion (back onto the mark)
    referenced.idle()
    assert last(dev, "move_end") - t0 == pytest.approx(trapezoid(10000, 2000), abs=TOL)
    send(c, "A", 0)  # reversal: the motor takes up the slack first
    referenced.advance(comp / 2)
    assert status(c) == MOTION | BUSY  # motion, although the set-point stands
    assert c.read(0)[1] == 10000 and velocity(referenced) == 0.0
    assert comp / 2 + referenced.idle() == pytest.approx(comp + trapezoid(10000, 2000), abs=TOL)
    assert c.read(0)[1] == 0 and referenced.read("position_counter") == 0  # invisible in the counter
    send(c, "+", -1000)  # on in the same direction: nothing to take up
    assert referenced.idle() == pytest.approx(trapezoid(1000, 2000), abs=TOL)
    t0 = referenced.now()
    send(c, "+", 1000)
    referenced.idle()
    assert last(dev, "move_end") - t0 == pytest.approx(comp + trapezoid(1000, 2000), abs=TOL)
    assert [e for _t, e in dev.events].count("backlash") == 2


def test_backlash_off_with_n41_0(referenced: Plant) -> None:
    c = referenced.client()
    send(c, "A", 10000)
    referenced.idle()
    send(c, "A", 0)
    assert referenced.idle() == pytest.approx(trapezoid(10000, 2000), abs=TOL)


def test_backlash_reversing_spindle_brakes_dwells_and_turns(card: Plant) -> None:
    c = card.client()
    send(c, "N", 255, 41)
    send(c, "N", 1, 42)  # 255 ms
    send(c, "Q", 8, 3, 1000)
    card.advance(0.5)
    t0 = card.now()
    send(c, "Q", 8, 4, 1000)
    card.advance(ramp(1000) + 0.1)
    assert velocity(card) == 0.0 and card.device().axis.moving
    x = physical(card)
    card.advance(0.1)
    assert physical(card) == x  # the set-point stands during the compensation
    card.advance(ramp(1000) + 0.055)
    assert velocity(card) == pytest.approx(-1000)
    assert card.now() - t0 == pytest.approx(2 * ramp(1000) + 0.255)


def test_backlash_abort_during_compensation(referenced: Plant) -> None:
    c = referenced.client()
    send(c, "N", 255, 41)
    send(c, "N", 1, 42)
    send(c, "A", -1000)
    referenced.idle()
    send(c, "A", 0)
    referenced.advance(0.1)
    c.abort()
    referenced.idle()
    assert referenced.device().indexer.comp_phase == ""
    assert c.read(0)[1] == 0xFFFFFF & -1000 and status(c) == 0
    send(c, "A", 0)  # starts over: compensation, then the move
    referenced.idle()
    assert c.read(0)[1] == 0


# ================================================================================================
# end stops and limit switches (spec §5.11), H2 and H7 (spec §5.5)
# ================================================================================================

END = {"axis": {"end_stops": [-40000, 0]}}  # after Q0 the upper stop is at counter 16384


def referenced_plant(plant_factory: Any, config: dict[str, Any]) -> tuple[Plant, Gms96Client]:
    plant = plant_factory(config)
    c = plant.client()
    send(c, "Q", 0)
    plant.idle()
    assert plant.read("idxoff") is False and physical(plant) == pytest.approx(-16384)
    return plant, c


def test_end_stop_following_error(plant_factory: Any) -> None:
    plant, c = referenced_plant(plant_factory, END)
    dev = plant.device()
    t0 = plant.now()
    send(c, "A", 30000)
    plant.advance(5.0)
    assert plant.read("following_error") == pytest.approx(2000 / KV)  # lag while running free
    plant.run_until(lambda d: d.stage.idxoff, 10)
    # the actual position stops at 16384; the set-point runs on until e > N20 = 1000
    t_trip = ramp(2000) + (16384 + 1000 - dist(2000)) / 2000
    assert last(dev, "following_error") - t0 == pytest.approx(t_trip, abs=1e-5)
    plant.advance(0.1)
    assert status(c) == IDXOFF
    assert plant.read("position_counter") == 16384
    assert plant.read("output.A0.0") is False  # brake
    send(c, "Q", 3)  # re-activation: set-point := actual (at the stop)
    plant.advance(0.01)
    assert c.read(0)[1] == 16384 and plant.read("following_error") == 0.0
    send(c, "A", 10000)  # away from the stop
    plant.idle()
    assert plant.read("position_counter") == 10000


def test_end_stop_inside_n20_standing_following_error(plant_factory: Any) -> None:
    plant, c = referenced_plant(plant_factory, END)
    send(c, "A", 16884)
    plant.idle()
    assert plant.read("idxoff") is False
    assert c.read(0)[1] == 16884  # T0: the set-point
    assert plant.read("position_counter") == 16384  # the mechanics
    assert c.read(1, 4)[1] == 500  # T1;4 following error
    send(c, "N", 10, 27)
    send(c, "H", 2)  # never in position against the stop
    plant.advance(1.0)
    assert status(c) == BUSY and plant.read("marker.M3.5") is True
    c.abort()
    plant.advance(0.01)
    assert status(c) == 0


def test_limit_switch_input(plant_factory: Any) -> None:
    plant, c = referenced_plant(plant_factory, {"axis": {"limit_switches": [{"input": "E0.3", "low": -6384}]}})
    dev = plant.device()
    seen: list[float] = []
    dev.signals.subscribe("E0.3", lambda *_: seen.append(plant.now()))
    t0 = plant.now()
    send(c, "A", 12000)
    plant.advance(5.5)
    assert c.read(1, 1, 0)[1] & 0x08  # T1;1;0: EB0 bit 3
    plant.idle()
    # the switch sees the actual position: 1/Kv after the set-point passes -6384
    assert seen[0] - t0 == pytest.approx(ramp(2000) + (10000 - dist(2000)) / 2000 + LAG_T, abs=1e-6)
    send(c, "A", 0)
    plant.idle()
    assert not c.read(1, 1, 0)[1] & 0x08


def test_limit_switch_follows_the_actual_position_and_n10(plant_factory: Any) -> None:
    """Spec §5.7/§5.11: the switch sees set-point - v/Kv; halving N10 halves Kv and doubles the lag."""
    plant, c = referenced_plant(plant_factory, {"axis": {"limit_switches": [{"input": "E0.3", "low": -6384}]}})
    dev = plant.device()
    seen: list[tuple[float, float, float]] = []
    dev.signals.subscribe("E0.3", lambda *_: seen.append((plant.now(), dev.indexer.actual(), dev.axis.position())))
    send(c, "N", 100, 10)  # Kv = 20 s⁻¹: 100 inc lag at 2000 Hz
    plant.idle()
    t0 = plant.now()
    send(c, "A", 12000)
    plant.idle()
    t, actual, setpoint = seen[0]
    assert t - t0 == pytest.approx(ramp(2000) + (10000 - dist(2000)) / 2000 + 1.0 / 20.0, abs=1e-6)
    assert actual == pytest.approx(-6384, abs=1e-6)
    assert setpoint == pytest.approx(-6384 + 2000 / 20.0, abs=1e-6)


def test_switch_does_not_flicker_on_the_lag_dip_at_a_move_start(plant_factory: Any) -> None:
    """Standing exactly on a switch edge, a move away from the switch region makes the static-lag
    actual (x - v/Kv) dip back across the edge at the start of the ramp; the position loop never
    drives the motor against its set-point, so the switch stays put (direction tracking)."""
    plant, c = referenced_plant(plant_factory, {"axis": {"limit_switches": [{"input": "E0.3", "high": -16384}]}})
    dev = plant.device()
    assert plant.read("input.E0.3") is True  # standing on the upper edge: active (x <= high)
    seen: list[bool] = []
    dev.signals.subscribe("E0.3", lambda *_: seen.append(bool(plant.read("input.E0.3"))))
    send(c, "A", -100)  # move down into the switch: the actual dips upwards first
    plant.idle()
    assert seen == [] and plant.read("input.E0.3") is True
    send(c, "A", 100)  # and up out of it: on the way it leaves exactly once
    plant.idle()
    assert seen == [False]


def test_h2_waits_n28_after_the_set_point(referenced: Plant) -> None:
    c = referenced.client()
    dev = referenced.device()
    send(c, "N", 10, 27)
    send(c, "N", 20, 28)
    t0 = referenced.now()
    send(c, "A", 4000)
    send(c, "H", 2)
    send(c, "+", 100)
    referenced.run_until(lambda d: any(e == "move_end" for t, e in d.events if t > t0), 10)
    end = last(dev, "move_end")
    assert end - t0 == pytest.approx(trapezoid(4000, 2000), abs=TOL)
    referenced.advance(0.010)
    assert referenced.read("marker.M3.5") is True and referenced.read("busy") is True
    assert c.read(0)[1] == 4000
    referenced.idle()
    second = last(dev, "move_end")
    # the +100 starts N28 = 20 ms after the set-point stopped (100 inc: a sin² triangle)
    assert second - end == pytest.approx(0.020 + 2 * math.sqrt(100 / A_SIN), abs=1e-6)
    assert referenced.read("marker.M3.5") is False


@pytest.mark.manual("§2.3.1 H", "H7;P2: the next move is aborted when the current reaches P2 % of the maximum")
def test_h7_torque_abort_on_blocked_axis(referenced: Plant) -> None:
    c = referenced.client()
    send(c, "H", 7, 50)
    t0 = referenced.now()
    send(c, "A", 30000)
    send(c, "+", -100)  # the queue goes on after the abort
    referenced.advance(3.0)
    referenced.set("quantity.blocked", True)
    x_actual = dist(2000) + 2000 * (3.0 - ramp(2000)) - 2000 / KV
    referenced.set("quantity.blocked", False)
    referenced.idle()
    dev = referenced.device()
    assert any(e == "torque_abort" for _t, e in dev.events)
    assert not any(e == "following_error" for _t, e in dev.events)
    assert referenced.read("idxoff") is False
    assert last(dev, "torque_abort") - t0 == pytest.approx(3.0)
    assert c.read(0)[1] == round(x_actual - 100)


@pytest.mark.manual("§2.3.1 H", "H7 applies to the following move")
def test_h7_applies_to_the_next_move_only(referenced: Plant) -> None:
    c = referenced.client()
    send(c, "H", 7, 50)
    send(c, "A", 1000)  # the next move: completes normally, consumes the arming
    referenced.idle()
    send(c, "A", 30000)
    referenced.advance(1.0)
    referenced.set("quantity.blocked", True)
    referenced.advance(3.0)
    assert referenced.read("idxoff") is True  # a following error, no torque abort


def test_h7_aborts_when_the_current_reaches_the_level(referenced: Plant) -> None:
    c = referenced.client()
    send(c, "H", 7, 40)  # above the ramp's peak current 0.05 + 0.3 = 35 %
    t0 = referenced.now()
    send(c, "A", 30000)
    referenced.advance(2.0)
    assert not any(e == "torque_abort" for _t, e in referenced.device().events)
    referenced.set("quantity.load_pct", 40)  # i = 0.05 + 0.40 >= 40 %
    referenced.advance(0.01)
    assert last(referenced.device(), "torque_abort") - t0 == pytest.approx(2.0)


def test_h7_at_the_end_stop(plant_factory: Any) -> None:
    plant, c = referenced_plant(plant_factory, END)
    send(c, "H", 7, 80)
    send(c, "A", 30000)
    plant.idle()
    assert plant.read("idxoff") is False
    assert c.read(0)[1] == 16384


@pytest.mark.manual("§2.3.1 H", "H7: the following move is aborted when the current reaches P2 % of the maximum")
def test_h7_moving_away_from_the_end_stop_is_no_contact(plant_factory: Any) -> None:
    """Standing at an end stop, a move away from it does not press into it: its current stays low
    (the lag of the actual position behind the set-point is no contact with the stop)."""
    plant, c = referenced_plant(plant_factory, END)
    send(c, "A", 16384)  # onto the upper stop
    plant.idle()
    send(c, "H", 7, 80)
    send(c, "A", 0)
    plant.advance(0.003)
    assert c.read(1, 5)[1] < 252 * 0.8
    plant.idle()
    assert not any(e == "torque_abort" for _t, e in plant.device().events)
    assert c.read(0)[1] == 0


def test_h2_without_window_is_set_point_finished(referenced: Plant) -> None:
    c = referenced.client()
    send(c, "N", 200, 28)
    send(c, "H", 2)
    referenced.advance(0.001)
    assert referenced.read("busy") is False


@pytest.mark.manual("§2.3.1 N", "N27 > 0: A0.1 shows in-position; N28: ms the following error stays in the window")
def test_a0_1_in_position_after_n28(referenced: Plant) -> None:
    c = referenced.client()
    send(c, "N", 10, 27)
    send(c, "N", 50, 28)
    send(c, "A", 1000)
    referenced.idle()
    referenced.advance(0.010)
    assert referenced.read("output.A0.1") is False


def test_negative_move_completes_when_the_set_point_stops(referenced: Plant) -> None:
    c = referenced.client()
    send(c, "A", -10000)
    t0 = referenced.now()
    assert referenced.idle() == pytest.approx(last(referenced.device(), "move_end") - t0, abs=1e-6)



# ================================================================================================
# motion timing (spec §5.2–§5.4): ramps, speeds, override, G91, v/w, blending
# ================================================================================================


@pytest.mark.parametrize(
    ("n24", "b", "accel"),
    [(0, 50, 50000.0), (1, 50, A_SIN), (0, 200, 200000.0), (1, 200, 2 * 200000.0 / math.pi)],
)
def test_ramp_shapes_full_profile(referenced: Plant, n24: int, b: int, accel: float) -> None:
    c = referenced.client()
    send(c, "N", n24, 24)
    send(c, "B", b)
    send(c, "M", 20000)
    send(c, "f", 20000)
    referenced.advance(0.001)
    t0 = referenced.now()
    send(c, "A", 30000)
    referenced.advance(ramp(20000, accel) / 2)
    half = 20000 / 2 if n24 == 0 else 20000 * math.sin(math.pi / 4) ** 2
    assert velocity(referenced) == pytest.approx(half)  # linear / sin² halfway up the ramp
    referenced.idle()
    assert last(referenced.device(), "move_end") - t0 == pytest.approx(trapezoid(30000, 20000, accel), abs=TOL)


@pytest.mark.parametrize(("n24", "accel"), [(0, 50000.0), (1, A_SIN)])
def test_short_move_reduced_peak(referenced: Plant, n24: int, accel: float) -> None:
    """D < V²/a (linear) or (π/2)·V²/a (sin²): a triangle with V' = sqrt(a·D) resp. sqrt(2aD/π)."""
    c = referenced.client()
    send(c, "N", n24, 24)
    send(c, "M", 20000)
    send(c, "f", 20000)
    referenced.advance(0.001)
    t0 = referenced.now()
    send(c, "v", 1000)
    referenced.advance(math.sqrt(1000 / accel))
    assert velocity(referenced) == pytest.approx(math.sqrt(accel * 1000))
    referenced.idle()
    assert last(referenced.device(), "move_end") - t0 == pytest.approx(2 * math.sqrt(1000 / accel), abs=TOL)


def test_working_speed_f_m_override_and_v_factor(referenced: Plant) -> None:
    c = referenced.client()
    send(c, "f", 1000)
    t0 = referenced.now()
    send(c, "A", 5000)
    referenced.idle()
    assert last(referenced.device(), "move_end") - t0 == pytest.approx(trapezoid(5000, 1000), abs=TOL)
    send(c, "f", 1800)
    c.override(125)  # #9: f·125 % = 2250, capped at M = 2000
    send(c, "A", 20000)
    referenced.advance(2.0)
    assert velocity(referenced) == pytest.approx(2000)
    c.override(50)  # during the move: ramps to 900
    referenced.advance(0.5)
    assert velocity(referenced) == pytest.approx(900)
    send(c, "o", 2, 20)  # o2;20 (immediate): 20 %
    referenced.advance(0.5)
    assert velocity(referenced) == pytest.approx(360)
    c.abort()
    referenced.idle()
    send(c, "o", 0)  # override off: 100 %
    send(c, "M", 100000)  # V-factor 2: speeds in steps of 2 Hz
    send(c, "f", 1001)
    send(c, "A", 0)
    referenced.advance(1.0)
    assert velocity(referenced) == pytest.approx(-1000)
    referenced.idle()
    assert c.read(0)[1] == 0


def test_override_zero_holds_the_move(referenced: Plant) -> None:
    c = referenced.client()
    send(c, "A", 10000)
    referenced.advance(1.0)
    c.override(0)
    referenced.advance(1.0)
    assert velocity(referenced) == 0.0 and status(c) == BUSY
    c.override(100)
    referenced.idle()
    assert c.read(0)[1] == 10000


@pytest.mark.manual("§2.3.1 G", "G90 absolute, G91 relative coordinates of the following moves")
def test_g91_relative_and_plus(referenced: Plant) -> None:
    c = referenced.client()
    send(c, "G", 91)
    send(c, "A", 1000)
    send(c, "A", 1000)
    referenced.idle()
    assert c.read(0)[1] == 2000
    send(c, "G", 90)
    send(c, "A", 500)
    send(c, "+", 250)
    referenced.idle()
    assert c.read(0)[1] == 750


def test_blending_one_plan_and_junction_on_the_fly(referenced: Plant) -> None:
    c = referenced.client()
    dev = referenced.device()
    t0 = referenced.now()
    send(c, "A", 10000)
    send(c, "A", 20000)
    referenced.idle()
    ends = [t - t0 for t, e in dev.events if e == "move_end" and t > t0]
    assert ends[0] == pytest.approx(ramp(2000) + (10000 - dist(2000)) / 2000, abs=TOL)  # passing
    assert ends[1] == pytest.approx(trapezoid(20000, 2000), abs=TOL)  # one plan to 20000
    assert abs(dev.axis.velocity(t0 + ends[0])) == pytest.approx(2000)


@pytest.mark.manual("§2.3.1 v", "v: a move with the profile computed before the start; not for chained moves")
def test_v_does_not_blend_and_reversal_stops(referenced: Plant) -> None:
    c = referenced.client()
    dev = referenced.device()
    t0 = referenced.now()
    send(c, "A", 10000)
    send(c, "v", 20000)
    referenced.idle()
    ends = [t - t0 for t, e in dev.events if e == "move_end" and t > t0]
    assert ends[0] == pytest.approx(trapezoid(10000, 2000), abs=TOL)
    assert ends[1] - ends[0] == pytest.approx(trapezoid(10000, 2000), abs=TOL)
    t0 = referenced.now()
    send(c, "A", 30000)
    send(c, "A", 25000)  # the other way: stop at 30000, then back
    referenced.idle()
    ends = [t - t0 for t, e in dev.events if e == "move_end" and t > t0]
    assert ends[0] == pytest.approx(trapezoid(10000, 2000), abs=TOL)
    assert abs(dev.axis.velocity(t0 + ends[0])) == pytest.approx(0.0, abs=1e-6)


def test_w_feed_zeroes_the_counter(referenced: Plant) -> None:
    c = referenced.client()
    send(c, "A", 3000)
    referenced.idle()
    x = physical(referenced)
    t0 = referenced.now()
    send(c, "w", 5000)
    referenced.idle()
    assert last(referenced.device(), "move_end") - t0 == pytest.approx(trapezoid(5000, 2000), abs=TOL)
    assert c.read(0)[1] == 5000
    assert physical(referenced) == pytest.approx(x + 5000)


def test_blending_slower_next_move_brakes_before_the_junction(referenced: Plant) -> None:
    c = referenced.client()
    dev = referenced.device()
    t0 = referenced.now()
    send(c, "A", 10000)
    send(c, "f", 1000)
    send(c, "A", 20000)
    referenced.idle()
    first = [t for t, e in dev.events if e == "move_end" and t > t0][0]
    assert abs(dev.axis.velocity(first)) == pytest.approx(1000)
