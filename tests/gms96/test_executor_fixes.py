"""Regression tests for executor/device fixes: H7 current level on the ramp and at an end stop,
blockage after a torque abort, in-position (A0.1, H2) timing, blending junction speeds, Q-1 with
P2.6 from N19, ``Q3;64`` with the configured pole pass, and the H2 wait flag on abort."""

from __future__ import annotations

import math
from typing import Any

import pytest

from devsim.devices.gms96.executor import Cmd
from tests.gms96.conftest import Plant
from tests.gms96.test_motion_reference import (
    A_SIN,
    END,
    IDXOFF,
    KV,
    dist,
    last,
    physical,
    ramp,
    referenced_plant,
    send,
    status,
    trapezoid,
)

TOL = 1e-6


# -- H7 (spec §5.5, §5.7) ---------------------------------------------------------------------


def test_h7_acceleration_current_reaches_the_level_on_the_ramp(referenced: Plant) -> None:
    """i = 0.05 + 0.3·|a|/50000; a sin² ramp peaks at a = 50000: H7;30 trips where
    0.3·sin(π t/T) = 0.25, solved in closed form."""
    c = referenced.client()
    send(c, "H", 7, 30)
    t0 = referenced.now()
    send(c, "A", 30000)
    referenced.idle()
    dev = referenced.device()
    t_ramp = ramp(2000)
    expected = t_ramp / math.pi * math.asin(0.25 / 0.3)
    assert last(dev, "torque_abort") - t0 == pytest.approx(expected, abs=TOL)
    assert referenced.read("idxoff") is False
    assert not any(e == "following_error" for _t, e in dev.events)


def test_h7_level_above_the_peak_current_never_trips(referenced: Plant) -> None:
    c = referenced.client()
    send(c, "N", 50, 39)  # i_lim = 50 %
    send(c, "H", 7, 60)
    send(c, "A", 5000)
    referenced.idle()
    assert not any(e == "torque_abort" for _t, e in referenced.device().events)
    assert c.read(0)[1] == 5000


def test_h7_at_the_end_stop_trips_on_contact(plant_factory: Any) -> None:
    plant, c = referenced_plant(plant_factory, END)
    send(c, "H", 7, 80)
    t0 = plant.now()
    send(c, "A", 30000)
    plant.idle()
    dev = plant.device()
    # the actual position (set-point - v/Kv) reaches the stop at counter 16384
    t_contact = ramp(2000) + (16384 + 2000 / KV - dist(2000)) / 2000
    assert last(dev, "torque_abort") - t0 == pytest.approx(t_contact, abs=1e-6)
    assert not any(e == "following_error" for _t, e in dev.events)
    assert c.read(0)[1] == 16384 and plant.read("following_error") == 0.0


def test_blockage_after_a_torque_abort_stops_the_next_move(referenced: Plant) -> None:
    c = referenced.client()
    dev = referenced.device()
    send(c, "H", 7, 50)
    send(c, "A", 30000)
    referenced.advance(3.0)
    referenced.set("quantity.blocked", True)  # stays blocked
    referenced.advance(0.01)
    assert [e for _t, e in dev.events].count("torque_abort") == 1
    held = dev.indexer.actual()
    assert dev.indexer.blocked_at == pytest.approx(held)
    send(c, "A", 0)  # H7 is used up: the blockage gives a following error
    referenced.run_until(lambda d: d.stage.idxoff, 5)
    assert last(dev, "following_error") > last(dev, "torque_abort")
    assert [e for _t, e in dev.events].count("torque_abort") == 1
    assert dev.indexer.actual() == pytest.approx(held)


# -- in-position: A0.1 and H2 (spec §5.5) -------------------------------------------------------


def test_a0_1_turns_on_exactly_n28_after_the_set_point_stops(referenced: Plant) -> None:
    c = referenced.client()
    dev = referenced.device()
    send(c, "N", 10, 27)
    send(c, "N", 50, 28)
    seen: list[tuple[float, Any]] = []
    dev.signals.subscribe("A0.1", lambda _n, _o, new: seen.append((referenced.now(), new)))
    t0 = referenced.now()
    send(c, "A", 1000)
    referenced.advance(1.0)
    end = last(dev, "move_end")
    assert end - t0 == pytest.approx(trapezoid(1000, 2000), abs=TOL)
    assert seen[-1][1] is True and seen[-1][0] - end == pytest.approx(0.050, abs=1e-9)
    assert referenced.read("output.A0.1") is True


@pytest.mark.manual("§2.3.1 N", "P2=27, positive Angabe: Ausgang A 0.1 repräsentiert In-Position")
def test_a0_1_goes_off_when_a_move_starts(referenced: Plant) -> None:
    """The output the machine sees, as the card's own T1;2 shows it: off while the axis moves
    (it stayed on from the last standstill to the end of the move)."""
    c = referenced.client()
    send(c, "N", 5, 27)
    send(c, "N", 50, 28)
    referenced.advance(0.2)
    assert referenced.read("output.A0.1") is True  # standing in the window
    send(c, "A", 4000)
    referenced.advance(0.3)
    assert referenced.read("motion") is True and referenced.read("output.A0.1") is False
    referenced.advance(5.0)
    assert referenced.read("motion") is False and referenced.read("output.A0.1") is True


def test_h2_without_window_completes_when_the_set_point_stops(referenced: Plant) -> None:
    c = referenced.client()
    dev = referenced.device()
    send(c, "N", 200, 28)  # N27 = 0: N28 does not apply
    t0 = referenced.now()
    send(c, "A", 4000)
    send(c, "H", 2)
    send(c, "+", 100)
    referenced.idle()
    ends = [t - t0 for t, e in dev.events if e == "move_end" and t > t0]
    assert ends[0] == pytest.approx(trapezoid(4000, 2000), abs=TOL)
    assert ends[1] - ends[0] == pytest.approx(2 * math.sqrt(100 / A_SIN), abs=TOL)


def test_abort_ends_the_h2_wait(plant_factory: Any) -> None:
    plant, c = referenced_plant(plant_factory, END)
    dev = plant.device()
    send(c, "A", 16884)  # the set-point stands 500 inc past the stop: never in position
    plant.advance(10.0)
    send(c, "N", 10, 27)
    send(c, "H", 2)
    plant.advance(0.5)
    assert dev.executor.waiting_in_position is True and plant.read("marker.M3.5") is True
    c.abort()
    plant.advance(0.01)
    assert dev.executor.waiting_in_position is False and plant.read("marker.M3.5") is False
    assert plant.read("busy") is False


# -- blending (spec §5.4) ---------------------------------------------------------------------


def test_blending_negative_slower_next_move_brakes_before_the_junction(referenced: Plant) -> None:
    c = referenced.client()
    dev = referenced.device()
    t0 = referenced.now()
    send(c, "A", -10000)
    send(c, "f", 500)
    send(c, "A", -20000)
    referenced.idle()
    ends = [t for t, e in dev.events if e == "move_end" and t > t0]
    assert dev.axis.velocity(ends[0]) == pytest.approx(-500)
    # cruise at 2000, brake to 500 just before the junction, cruise at 500, brake to 0
    d_brake = (2000**2 - 500**2) / (2 * A_SIN)
    t_junction = ramp(2000) + (10000 - dist(2000) - d_brake) / 2000 + ramp(1500)
    assert ends[0] - t0 == pytest.approx(t_junction, abs=TOL)
    assert ends[1] - ends[0] == pytest.approx((10000 - dist(500)) / 500 + ramp(500), abs=TOL)
    assert c.read(0)[1] == 0xFFFFFF & -20000


def test_blending_g0_faster_next_move_accelerates_after_the_junction(referenced: Plant) -> None:
    c = referenced.client()
    dev = referenced.device()
    send(c, "f", 1000)
    t0 = referenced.now()
    send(c, "A", 10000)
    send(c, "G", 0)  # f := M = 2000
    send(c, "A", 20000)
    referenced.idle()
    ends = [t for t, e in dev.events if e == "move_end" and t > t0]
    assert dev.axis.velocity(ends[0]) == pytest.approx(1000)
    assert ends[0] - t0 == pytest.approx(ramp(1000) + (10000 - dist(1000)) / 1000, abs=TOL)


# -- reference runs (spec §3.8.14, §5.6) ------------------------------------------------------


def test_q_minus_1_with_p2_6_in_n19_keeps_the_indexer_active(referenced: Plant) -> None:
    c = referenced.client()
    send(c, "N", 1 | (0x40 << 8), 19)  # Q1 with P2.6 (resolver position at the mark)
    send(c, "N", 1000, 33)
    send(c, "A", 2000)
    referenced.idle()
    send(c, "Q", -1)
    referenced.advance(0.5)
    assert status(c) & IDXOFF == 0  # P2.6 and active before: IDXOFF unchanged
    referenced.idle()
    assert referenced.read("idxoff") is False
    assert c.read(0)[1] == 1000


def test_q3_64_uses_the_configured_pole_pass(plant_factory: Any) -> None:
    plant = plant_factory({"axis": {"index_offset": 100, "index_period": 8192}})
    c = plant.client()
    send(c, "Q", 3, 64)
    plant.advance(0.01)
    # physical 0 lies 100 inc before the mark at 100: -100 within the pole pass
    assert plant.read("position_counter") == -100
    assert plant.read("idxoff") is False
    send(c, "A", 5000)  # physical 5100: 5000 past the mark = 5000 - 8192 in -4096..4095
    plant.idle()
    send(c, "Q", 3, 64)
    plant.advance(0.01)
    assert plant.read("position_counter") == 5000 - 8192
    assert physical(plant) == pytest.approx(5100)



def test_zero_length_move_before_a_blendable_one_completes(referenced: Plant) -> None:
    """A move onto the standing position completes at once, also with a blendable move queued
    behind it (a CNC program puts both into the queue before the first starts)."""
    dev = referenced.device()
    dev.flash.programs[5] = [["A", 0, 0, 0, 1], ["A", -1000, 0, 0, 1]]
    referenced.runtime.call(lambda: dev.executor.submit(Cmd("p", 3, 1, 5, 3)))
    referenced.idle(timeout=5)
    assert referenced.read("position") == -1000
