"""GMS96 counter input beyond the set-point mode, through a real pty under virtual time:
``m49`` synchronous run / electronic gear (spec §5.10, §3.8.9, N23, N50), ``H22`` min/max
measurement (§3.8.7), ``Q`` with P2.5 (index mark from the counter input) and P2.4 (obsolete,
§3.8.14).  Closed-form expectations: set-point = x0 + Δcount · N23, speed min(rate · N23, M)."""

from __future__ import annotations

from typing import Any

import pytest

from devsim.devices.gms96 import codec
from tests.gms96.conftest import Plant


def frame(cmd: str, *params: int) -> str:
    return codec.encode(codec.LongFrame(0x53, 3, codec.letter(cmd, *params))).hex(" ").upper()


def ok(plant: Plant, cmd: str, *params: int) -> None:
    assert plant.host.ask(frame(cmd, *params)) == "E5"


def t0(plant: Plant) -> int:
    ident, _value, raw = plant.client().read(0)
    assert ident == 0x40
    return int.from_bytes(raw, "little", signed=True)


def data24(plant: Plant, address: int) -> int:
    """``T1;6;address``: 24 bits of PLC data, signed."""
    ident, _value, raw = plant.client().read(1, 6, address)
    assert ident == 0x44
    return int.from_bytes(raw, "little", signed=True)


def reference(plant: Plant) -> None:
    ok(plant, "Q", 0)
    plant.idle()
    assert plant.read("idxoff") is False


# -- m49: synchronous run, electronic gear ------------------------------------------------------


@pytest.mark.manual("§2.3.1 m", "m49: synchronous run to the counter input (built-in, not the PLC's)")
def test_m49_setpoint_follows_pulses_times_n23(referenced: Plant) -> None:
    card = referenced
    ok(card, "N", 3, 23)  # N23 = 3 set-point increments per counted increment
    card.set("counter.pulses", 500)  # before m49: counted, not followed
    ok(card, "m", 49, 0, 0)
    card.advance(0.01)
    assert card.read("counter.sync") is True and card.read("busy") is True
    assert t0(card) == 0
    card.set("counter.pulses", 100)
    assert t0(card) == 300
    card.set("counter.pulses", -40)
    assert t0(card) == 180
    # a pulse stream: the set-point runs at rate x N23 (600 inc/s), status "motion running"
    card.set("counter.rate_hz", 200)
    card.advance(0.5)
    assert card.read("axis.setpoint") == pytest.approx(180 + 300, abs=0.01)
    assert card.read("speed") == pytest.approx(600)
    k, _ = card.client().status()
    assert k & 0x10
    card.set("counter.rate_hz", 0)
    card.advance(0.01)
    assert t0(card) == 480 and card.read("counter.count") == 500 + 60 + 100
    # other queued commands wait behind the running m49
    ok(card, "A", 0)
    card.advance(0.2)
    assert card.read("queue_length") == 1 and t0(card) == 480


def test_m49_speed_limited_to_rapid_m(referenced: Plant) -> None:
    card = referenced
    ok(card, "M", 1000)
    ok(card, "N", 4, 23)
    ok(card, "m", 49, 0, 0)
    card.set("counter.rate_hz", 500)  # 500 x 4 = 2000 inc/s > M = 1000
    card.advance(1.0)
    assert card.read("speed") == pytest.approx(1000)
    assert card.read("axis.setpoint") == pytest.approx(1000, abs=0.01)


def test_m49_ends_with_abort_and_the_queue_is_discarded(referenced: Plant) -> None:
    card = referenced
    ok(card, "B", 10)  # a = 10000 inc/s²
    ok(card, "N", 0, 24)  # linear ramp
    ok(card, "m", 49, 0, 0)
    ok(card, "A", 5000)
    card.set("counter.rate_hz", 1000)
    card.advance(1.0)
    card.client().abort()  # #0: the set-point brakes with the ramp B: 1000²/(2·10000) = 50 inc
    card.idle()
    assert card.read("counter.sync") is False and card.read("busy") is False
    assert card.read("axis.setpoint") == pytest.approx(1000 + 50, abs=1)
    x = card.read("axis.setpoint")
    card.set("counter.pulses", 100)  # no longer coupled
    card.set("counter.rate_hz", 0)
    assert card.read("axis.setpoint") == x
    assert card.read("queue_length") == 0


def test_m49_ends_with_plc_abort_marker(referenced: Plant) -> None:
    card = referenced
    ok(card, "m", 49, 0, 0)
    card.set("counter.pulses", 10)
    card.set("marker.M0.1", True)
    card.idle()
    assert card.read("counter.sync") is False
    card.set("counter.pulses", 10)
    assert t0(card) == 10


def test_m49_ends_with_emergency_stop(referenced: Plant) -> None:
    card = referenced
    ok(card, "m", 49, 0, 0)
    card.set("counter.rate_hz", 100)
    card.advance(0.1)
    card.set("input.emergency_stop", True)
    card.advance(0.1)
    assert card.read("counter.sync") is False and card.read("busy") is False


def test_m49_stops_at_the_position_range(referenced: Plant) -> None:
    card = referenced
    ok(card, "O", 8388000)
    ok(card, "m", 49, 0, 0)
    card.set("counter.pulses", 1000)
    assert t0(card) == 8388607
    card.set("counter.pulses", -7)
    assert t0(card) == 8388600


@pytest.mark.parametrize("setup", ["no_reference", "n50_counter_actual_value"])
def test_m49_is_skipped_like_a_move(card: Plant, setup: str) -> None:
    if setup == "n50_counter_actual_value":
        reference(card)
        ok(card, "N", 7, 50)  # bit 0: the counter input is the actual-value source
    ok(card, "m", 49, 0, 0)
    card.advance(0.05)
    assert card.read("busy") is False and card.read("counter.sync") is False
    assert card.read("rejected_moves") == 1
    card.set("counter.pulses", 100)
    assert t0(card) == 0


# -- H22: min/max measurement of the counter input -----------------------------------------------


@pytest.mark.manual("§2.3.1 H", "H22;1 starts a min/max memory of the counter input with axis positions; H22;0 ends it")
def test_h22_min_max_with_positions_copied_to_data_area(plant_factory: Any) -> None:
    card = plant_factory({"h22_data_address": 160})
    reference(card)
    ok(card, "H", 22, 1)
    card.advance(0.01)
    card.set("counter.pulses", -30)  # min -30 at position 0
    ok(card, "A", 1000)
    card.idle()
    card.set("counter.pulses", 80)  # count 50 at 1000
    ok(card, "A", 2000)
    card.idle()
    card.set("counter.pulses", 10)  # max 60 at 2000
    ok(card, "A", 0)
    card.idle()
    card.set("counter.pulses", -200)  # min -140 at 0 ...
    card.set("counter.pulses", 150)  # ... then back to 10
    ok(card, "H", 22, 0)
    card.advance(0.01)
    card.set("counter.pulses", 1000)  # after H22;0: not recorded
    expect = {"min": -140, "min_position": 0, "max": 60, "max_position": 2000}
    assert card.read("counter.h22") == expect
    assert [data24(card, 160 + 4 * k) for k in range(4)] == [-140, 0, 60, 2000]


def test_h22_with_a_pulse_stream_and_fb254_from_a_plc_hook(plant_factory: Any) -> None:
    card = plant_factory({"plc": {"cycle_ms": 20, "hook": "tests.gms96.test_gearing:hook_fb254"}})
    reference(card)
    ok(card, "H", 22, 1)
    card.advance(0.01)
    card.set("counter.rate_hz", -100)
    card.advance(1.0)  # count -100
    card.set("counter.rate_hz", 300)
    card.advance(1.0)  # count +200
    card.set("counter.rate_hz", 0)
    ok(card, "H", 22, 0)
    card.advance(0.01)
    assert [data24(card, 100 + 4 * k) for k in range(4)] == [0, 0, 0, 0]  # not yet fetched
    card.set("marker.M30.0", True)  # the PLC program calls FB 254 with Accu1 = 22, Accu2 = 100
    card.advance(0.1)
    assert [data24(card, 100 + 4 * k) for k in range(4)] == [-100, 0, 200, 0]


def hook_fb254(plc: Any) -> None:
    if plc.bit("M30.0"):
        plc.fb254(22, 100)
        plc.set_marker_bit(30, 0, False)


# -- Q P2.5 (counter-input index mark) and P2.4 (obsolete immediate stop) -------------------------


@pytest.mark.manual("§2.3.1 Q", "Q P2.5: the reference mark of the counter input instead of the motor encoder")
def test_q_p2_5_uses_the_counter_input_reference_mark(plant_factory: Any) -> None:
    card = plant_factory({"axis": {"counter_marks": [-7000.0, 9000.0]}})
    ok(card, "S", 2000)  # search speed
    ok(card, "Q", 1, 0x20)  # index search on the counter input's track (motor marks every 4096)
    card.idle()
    assert card.read("idxoff") is False
    assert card.read("axis.physical") == pytest.approx(-7000, abs=1e-3)
    assert card.read("position_counter") == 0
    ok(card, "Q", 1, 0x20 | 0x02)  # reversed: the next mark in positive direction
    card.idle()
    assert card.read("axis.physical") == pytest.approx(9000, abs=1e-3)


def test_q_p2_5_without_a_mark_fails_at_the_distance_limit(plant_factory: Any) -> None:
    card = plant_factory({})
    ok(card, "S", 2000)
    ok(card, "Q", 1, 0x20, 3000)
    card.idle()
    assert card.read("idxoff") is True


@pytest.mark.manual("§2.3.1 Q", "Q P2.4 is not needed since v3.79: the brake ramp repositions onto the criterion")
def test_q_p2_4_is_obsolete_and_changes_nothing(plant_factory: Any) -> None:
    results = []
    for p2 in (0, 0x10):
        card = plant_factory({"axis": {"index_offset": 1000.0}})
        ok(card, "Q", 1, p2)
        took = card.idle()
        results.append((card.read("axis.physical"), round(took, 6), card.read("idxoff")))
    assert results[0] == results[1]
    assert results[0][0] == pytest.approx(1000 - 4096, abs=1e-3) and results[0][2] is False


# -- G92 / G96 / G97: constant cutting speed (desired spindle speed only) -------------------------


@pytest.mark.manual("§2.3.1 G", "G96: constant cutting speed, a desired speed from the distance to the zero point")
@pytest.mark.manual("§2.3.1 G", "G92: speed limit for G96; G97 deselects G96")
def test_g96_desired_speed_from_distance_to_zero_point(referenced: Plant) -> None:
    card = referenced
    assert card.read("g96_rpm") is None
    ok(card, "G", 54, 1000, 1)  # G54 zero point at machine 1000
    ok(card, "G", 54, 0, 0)
    ok(card, "G", 96, 600000, 0)  # C = 600000 inc/min/2π: n = C / r
    card.advance(0.01)
    assert card.read("position") == -1000
    assert card.read("g96_rpm") == pytest.approx(600.0)
    ok(card, "A", 2000)
    card.idle()
    assert card.read("g96_rpm") == pytest.approx(300.0)
    ok(card, "G", 92, 3000)  # speed limit 3000 rpm
    ok(card, "A", 100)
    card.idle()
    assert card.read("g96_rpm") == pytest.approx(3000.0)  # 6000 limited
    ok(card, "A", 1000)
    card.advance(0.2)  # while the axis moves the speed follows the set-point
    r = abs(card.read("position"))
    assert 100 < r < 1000 and card.read("g96_rpm") == pytest.approx(min(600000 / r, 3000))
    card.idle()
    ok(card, "G", 97)
    card.advance(0.01)
    assert card.read("g96_rpm") is None
    assert card.read("axis.setpoint") == pytest.approx(2000, abs=1e-6)  # motion unaffected
