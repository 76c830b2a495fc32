"""Tests of the closed-form axis model (design.md principle 2) on a virtual clock."""

from __future__ import annotations

import math

import pytest

from devsim.core.axis import Axis, RegionSwitch, Segment
from devsim.core.clock import VirtualClock


@pytest.fixture
def clock() -> VirtualClock:
    return VirtualClock()


def run_idle(clock: VirtualClock, axis: Axis, timeout: float = 1000.0) -> None:
    assert clock.run_until(lambda: not axis.moving and clock.next_event() is None, timeout)


def check_continuity(axis: Axis) -> None:
    segs = axis.segments()
    for a, b in zip(segs, segs[1:], strict=False):
        assert a.t1 == b.t0
        assert a.position(a.t1) == pytest.approx(b.x0, abs=1e-6)
        assert a.velocity(a.t1) == pytest.approx(b.v0, abs=1e-6)


# -- profiles -----------------------------------------------------------------------------------
def test_sers_vector_triangle(clock: VirtualClock) -> None:
    """SERS manual example: 2500 deg at 1000 rpm, 100 rad/s², 12800 inc/rev."""
    cpr = 12800
    d = 2500 / 360 * cpr
    v = 1000 * cpr / 60
    a = 100 * cpr / (2 * math.pi)
    axis = Axis(clock, counts_per_rev=cpr)
    done: list[float] = []
    end = axis.move_to(d, v, a, on_done=lambda: done.append(clock.now()))
    assert end == pytest.approx(2 * math.sqrt(d / a), abs=1e-3)
    assert end == pytest.approx(1.321, abs=1e-3)
    assert [s.a for s in axis.segments()] == [a, -a]  # triangle: no cruise
    assert max(abs(s.velocity(s.t1)) for s in axis.segments()) < v
    assert axis.phase() == "accel"
    run_idle(clock, axis)
    assert done == [end]
    assert axis.position() == d
    assert axis.velocity() == 0.0
    assert not axis.moving
    assert axis.phase() == "idle"


def test_trapezoid_timing_and_exact_positions(clock: VirtualClock) -> None:
    axis = Axis(clock, position=100.0)
    end = axis.move_to(10100.0, 1000.0, 500.0, decel=250.0)
    # accel 2 s (1000 inc), decel 4 s (2000 inc), cruise 7000 inc = 7 s
    assert end == pytest.approx(13.0)
    assert [s.a for s in axis.segments()] == [500.0, 0.0, -250.0]
    check_continuity(axis)
    assert axis.position(1.0) == pytest.approx(100.0 + 250.0)
    assert axis.velocity(1.0) == pytest.approx(500.0)
    assert axis.phase(1.0) == "accel"
    assert axis.position(5.0) == pytest.approx(100.0 + 1000.0 + 3000.0)
    assert axis.phase(5.0) == "const"
    assert axis.position(11.0) == pytest.approx(10100.0 - 0.5 * 250.0 * 4.0)
    assert axis.velocity(11.0) == pytest.approx(500.0)
    assert axis.acceleration(11.0) == -250.0
    assert axis.phase(11.0) == "decel"
    assert axis.final_position() == 10100.0
    clock.advance(5.0)
    assert axis.position() == pytest.approx(4100.0)
    clock.advance(10.0)
    assert axis.position() == 10100.0
    assert clock.next_event() is None
    # the recent past stays queryable
    assert axis.position(1.0) == pytest.approx(350.0)


def test_negative_move_and_zero_move(clock: VirtualClock) -> None:
    axis = Axis(clock)
    end = axis.move_to(-400.0, 100.0, 100.0)
    assert end == pytest.approx(1.0 + 4.0 + 1.0 - 1.0)  # 1 s ramp (50 inc) x2, 300 inc cruise
    run_idle(clock, axis)
    assert axis.position() == -400.0
    done: list[float] = []
    assert axis.move_to(-400.0, 100.0, 100.0, on_done=lambda: done.append(clock.now())) == clock.now()
    clock.advance(0.0)
    assert done == [clock.now()]
    assert clock.next_event() is None


# -- replanning ---------------------------------------------------------------------------------
def test_replan_longer_target(clock: VirtualClock) -> None:
    axis = Axis(clock)
    axis.move_to(1000.0, 100.0, 100.0)
    clock.advance(3.0)
    x, v = axis.position(), axis.velocity()
    assert (x, v) == (pytest.approx(250.0), pytest.approx(100.0))
    end = axis.move_to(2000.0, 100.0, 100.0)
    assert axis.segments()[0].x0 == x and axis.segments()[0].v0 == v
    assert end == pytest.approx(3.0 + 17.0 + 1.0)  # cruise 1750-50 inc, then 1 s ramp
    run_idle(clock, axis)
    assert axis.position() == 2000.0


def test_replan_faster_and_slower(clock: VirtualClock) -> None:
    axis = Axis(clock)
    axis.move_to(10000.0, 100.0, 100.0)
    clock.advance(2.0)
    axis.move_to(10000.0, 300.0, 100.0)  # speed up again from 100 inc/s
    assert axis.phase() == "accel"
    clock.advance(2.0)
    assert axis.velocity() == pytest.approx(300.0)
    axis.move_to(10000.0, 100.0, 100.0, decel=50.0)  # too fast now: slow down with decel
    assert axis.acceleration() == -50.0
    assert axis.segments()[0].t1 == pytest.approx(clock.now() + 4.0)
    check_continuity(axis)
    run_idle(clock, axis)
    assert axis.position() == 10000.0


def test_replan_shorter_target_overshoots_and_returns(clock: VirtualClock) -> None:
    axis = Axis(clock)
    axis.move_to(1000.0, 100.0, 100.0)
    clock.advance(3.0)  # x=250, v=100: needs 50 inc to stop
    end = axis.move_to(260.0, 100.0, 100.0)
    segs = axis.segments()
    assert segs[0].a == -100.0 and segs[0].t1 == pytest.approx(4.0)
    assert axis.position(4.0) == pytest.approx(300.0)  # braked to 0 past the target
    assert axis.velocity(4.0) == pytest.approx(0.0)
    # then a triangle back over 40 inc: 2*sqrt(40/100)
    assert end == pytest.approx(4.0 + 2 * math.sqrt(0.4))
    assert axis.final_position() == 260.0
    check_continuity(axis)
    run_idle(clock, axis)
    assert axis.position() == 260.0


def test_replan_reversal(clock: VirtualClock) -> None:
    axis = Axis(clock)
    axis.move_to(1000.0, 100.0, 100.0)
    clock.advance(3.0)
    axis.move_to(0.0, 100.0, 100.0, decel=200.0)
    segs = axis.segments()
    assert segs[0].a == -200.0 and segs[0].t1 == pytest.approx(3.5)
    assert axis.position(3.5) == pytest.approx(275.0)
    assert axis.phase(3.25) == "decel"
    assert axis.phase(3.5) == "accel"
    assert all(s.v0 <= 0 for s in segs[1:])
    run_idle(clock, axis)
    assert axis.position() == 0.0


def test_exact_stop_on_target_without_overshoot(clock: VirtualClock) -> None:
    axis = Axis(clock)
    axis.jog(+1, 100.0, 100.0)
    clock.advance(2.0)  # x=150, v=100, stopping distance 50
    end = axis.move_to(200.0, 100.0, 100.0)
    assert len(axis.segments()) == 1
    assert end == pytest.approx(3.0)
    run_idle(clock, axis)
    assert axis.position() == 200.0


def test_superseded_on_done_never_fires(clock: VirtualClock) -> None:
    axis = Axis(clock)
    calls: list[str] = []
    axis.move_to(1000.0, 100.0, 100.0, on_done=lambda: calls.append("first"))
    clock.advance(1.0)
    axis.move_to(500.0, 100.0, 100.0, on_done=lambda: calls.append("second"))
    run_idle(clock, axis)
    assert calls == ["second"]


# -- stop, quick stop, jog ----------------------------------------------------------------------
def test_stop_with_ramp(clock: VirtualClock) -> None:
    axis = Axis(clock)
    axis.move_to(1000.0, 100.0, 100.0)
    clock.advance(3.0)
    assert axis.stopping_distance(50.0) == pytest.approx(100.0)
    done: list[float] = []
    end = axis.stop(50.0, on_done=lambda: done.append(clock.now()))
    assert end == pytest.approx(5.0)
    assert axis.final_position() == pytest.approx(350.0)
    assert axis.phase() == "decel"
    run_idle(clock, axis)
    assert done == [pytest.approx(5.0)]
    assert axis.position() == pytest.approx(350.0)
    assert axis.stopping_distance(50.0) == 0.0


def test_quick_stop(clock: VirtualClock) -> None:
    axis = Axis(clock)
    calls: list[str] = []
    axis.move_to(1000.0, 100.0, 100.0, on_done=lambda: calls.append("done"))
    clock.advance(2.0)
    axis.quick_stop()
    assert axis.velocity() == 0.0
    assert axis.position() == pytest.approx(150.0)
    assert not axis.moving
    assert clock.next_event() is None
    clock.advance(100.0)
    assert calls == []
    assert axis.position() == pytest.approx(150.0)


def test_jog_then_stop_and_jog_reversal(clock: VirtualClock) -> None:
    axis = Axis(clock)
    reached: list[float] = []
    axis.jog(+1, 200.0, 100.0, on_done=lambda: reached.append(clock.now()))
    assert axis.final_position() == math.inf
    clock.advance(10.0)
    assert reached == [2.0]
    assert axis.moving and axis.phase() == "const"
    assert axis.position() == pytest.approx(200.0 + 8 * 200.0)
    axis.jog(-1, 100.0, 100.0)  # through zero to -100
    assert axis.final_position() == -math.inf
    assert [s.a for s in axis.segments()] == [-100.0, -100.0, 0.0]
    assert axis.segments()[1].v0 == 0.0
    clock.advance(3.0)
    assert axis.velocity() == pytest.approx(-100.0)
    x_top = 1800.0 + 200.0
    assert axis.position() == pytest.approx(x_top - 50.0)
    end = axis.stop(100.0)
    assert end == pytest.approx(14.0)
    run_idle(clock, axis)
    assert axis.position() == pytest.approx(x_top - 100.0)
    assert clock.next_event() is None


def test_set_position(clock: VirtualClock) -> None:
    axis = Axis(clock)
    axis.set_position(1234.0)
    assert axis.position() == 1234.0
    axis.jog(1, 10.0, 10.0)
    with pytest.raises(RuntimeError):
        axis.set_position(0.0)


def test_invalid_arguments(clock: VirtualClock) -> None:
    axis = Axis(clock)
    with pytest.raises(ValueError):
        axis.move_to(10.0, 0.0, 1.0)
    with pytest.raises(ValueError):
        axis.move_to(math.nan, 1.0, 1.0)
    with pytest.raises(ValueError):
        axis.stop(0.0)


# -- events -------------------------------------------------------------------------------------
def test_watch_constant_velocity_and_accel_phase(clock: VirtualClock) -> None:
    axis = Axis(clock)
    events: list[tuple[str, float, int]] = []
    axis.watch(12.5, lambda d: events.append(("accel", clock.now(), d)))
    axis.watch(700.0, lambda d: events.append(("const", clock.now(), d)))
    axis.move_to(1000.0, 100.0, 100.0)  # accel 0..1 s to 50 inc, cruise to 950 at 10 s
    clock.advance(20.0)
    assert [e[0] for e in events] == ["accel", "const"]
    assert events[0][1] == pytest.approx(0.5, abs=1e-12)  # 0.5*100*t² = 12.5
    assert events[1][1] == pytest.approx(1.0 + 6.5, abs=1e-12)
    assert [e[2] for e in events] == [1, 1]
    axis.move_to(0.0, 100.0, 100.0)
    clock.advance(20.0)
    assert [(e[0], e[2]) for e in events[2:]] == [("const", -1), ("accel", -1)]
    assert events[3][1] == pytest.approx(20.0 + 11.0 - 0.5, abs=1e-9)


def test_watch_crossing_during_decel(clock: VirtualClock) -> None:
    axis = Axis(clock)
    times: list[float] = []
    axis.watch(987.5, lambda d: times.append(clock.now()))
    end = axis.move_to(1000.0, 100.0, 100.0)
    clock.advance(20.0)
    assert times == [pytest.approx(end - 0.5, abs=1e-12)]


def test_move_ending_exactly_on_watch_fires_once(clock: VirtualClock) -> None:
    cpr = 12800
    axis = Axis(clock)
    target = 2500 / 360 * cpr
    hits: list[tuple[float, int]] = []
    axis.watch(target, lambda d: hits.append((clock.now(), d)))
    end = axis.move_to(target, 1000 * cpr / 60, 100 * cpr / (2 * math.pi))
    clock.advance(5.0)
    assert hits == [(pytest.approx(end, abs=1e-9), 1)]
    # a new move away from it reports leaving at once, exactly once
    axis.move_to(0.0, 1000.0, 1000.0)
    clock.advance(0.0)
    assert hits[1:] == [(5.0, -1)]
    run_idle(clock, axis)
    assert len(hits) == 2
    # arriving from above onto the position: still ">= position", no event
    axis.move_to(target, 1e5, 1e5)
    run_idle(clock, axis)
    axis.move_to(target + 100.0, 1e3, 1e3)
    run_idle(clock, axis)
    axis.move_to(target, 1e3, 1e3)
    run_idle(clock, axis)
    assert [d for _, d in hits] == [1, -1, 1]


def test_replan_at_crossing_instant_does_not_fire_twice(clock: VirtualClock) -> None:
    axis = Axis(clock)
    hits: list[int] = []
    axis.move_to(1000.0, 100.0, 100.0)
    t_cross = 1.0 + 5.0 - 0.5  # x = 500
    # a timer at the same instant as the crossing replans before the crossing timer runs
    clock.call_at(t_cross, lambda: axis.move_to(800.0, 50.0, 100.0))
    axis.watch(500.0, hits.append)
    clock.advance(t_cross)
    assert hits == [1]
    # and the other order: replan from inside the crossing callback
    hits2: list[int] = []
    axis.watch(700.0, lambda d: (hits2.append(d), axis.move_to(750.0, 50.0, 100.0)))
    run_idle(clock, axis)
    assert hits2 == [1]
    assert axis.position() == 750.0


def test_watch_index_fires_once_per_revolution(clock: VirtualClock) -> None:
    axis = Axis(clock, counts_per_rev=1000, index_offset=250.0)
    marks: list[tuple[float, int]] = []
    axis.watch_index(lambda d: marks.append((axis.position(), d)))
    axis.move_to(5000.0, 2000.0, 4000.0)
    run_idle(clock, axis)
    assert [round(x) for x, _ in marks] == [250, 1250, 2250, 3250, 4250]
    assert all(d == 1 for _, d in marks)
    for x, _ in marks:
        assert x == pytest.approx(round(x), abs=1e-6)
    marks.clear()
    axis.move_to(-1000.0, 2000.0, 4000.0)
    run_idle(clock, axis)
    assert [round(x) for x, _ in marks] == [4250, 3250, 2250, 1250, 250, -750]
    assert all(d == -1 for _, d in marks)
    # ending exactly on a mark moving up counts it once
    marks.clear()
    axis.move_to(-750.0 + 1000.0, 500.0, 500.0)
    run_idle(clock, axis)
    assert marks == [(-750.0, 1), (250.0, 1)]


def test_region_switch_edges(clock: VirtualClock) -> None:
    axis = Axis(clock)
    changes: list[tuple[float, bool]] = []
    sw = RegionSwitch(axis, 100.0, 200.0, lambda on: changes.append((clock.now(), on)))
    assert not sw.active
    axis.jog(+1, 100.0, 1e9)  # effectively constant 100 inc/s from t=0
    clock.advance(1.5)
    assert sw.active
    clock.advance(1.0)
    assert not sw.active
    assert [on for _, on in changes] == [True, False]
    assert changes[0][0] == pytest.approx(1.0, abs=1e-6)
    assert changes[1][0] == pytest.approx(2.0, abs=1e-6)
    axis.stop(1e9)
    run_idle(clock, axis)
    # stopping exactly on the upper bound: still active (low <= x <= high)
    axis.move_to(200.0, 100.0, 100.0)
    run_idle(clock, axis)
    assert sw.active and axis.position() == 200.0
    axis.move_to(150.0, 100.0, 100.0)
    run_idle(clock, axis)
    assert [on for _, on in changes] == [True, False, True]
    axis.set_position(1000.0)  # teleport out of the region
    assert not sw.active and changes[-1][1] is False
    axis.set_position(-1000.0)  # teleport across it: no flicker
    assert changes[-1][1] is False and len(changes) == 4
    sw.cancel()
    axis.move_to(150.0, 100.0, 100.0)
    run_idle(clock, axis)
    assert len(changes) == 4


def test_limit_watch_stops_axis_inside_callback(clock: VirtualClock) -> None:
    axis = Axis(clock)
    stopped: list[float] = []
    done: list[str] = []

    def limit(direction: int) -> None:
        if direction > 0:
            axis.stop(1000.0, on_done=lambda: stopped.append(clock.now()))

    limit_sw = RegionSwitch(axis, 5000.0, math.inf)
    axis.watch(5000.0, limit)
    axis.move_to(10000.0, 1000.0, 1000.0, on_done=lambda: done.append("target"))
    run_idle(clock, axis)
    assert done == []  # the original move was superseded
    t_hit = 1.0 + 4.5  # 500 inc ramp, then 4500 inc at 1000 inc/s
    assert stopped == [pytest.approx(t_hit + 1.0)]
    assert axis.position() == pytest.approx(5500.0)
    assert limit_sw.active
    assert clock.next_event() is None


def test_high_speed_does_not_skip_narrow_region(clock: VirtualClock) -> None:
    axis = Axis(clock)
    changes: list[tuple[float, bool]] = []
    RegionSwitch(axis, 500_000.0, 500_000.5, lambda on: changes.append((clock.now(), on)))
    RegionSwitch(axis, 600_000.0, 600_000.0, lambda on: changes.append((clock.now(), on)))
    axis.move_to(1e6, 1e7, 1e9)
    clock.advance(1.0)  # one big step: no sampling involved
    assert [on for _, on in changes] == [True, False, True, False]
    assert changes[0][0] < changes[1][0] <= changes[2][0]
    assert axis.position(changes[0][0]) == pytest.approx(500_000.0, abs=1e-6)
    assert axis.position(changes[1][0]) == pytest.approx(500_000.5, abs=1e-6)
    assert changes[1][0] - changes[0][0] == pytest.approx(0.5 / axis.velocity(changes[0][0]), rel=1e-3)


def test_idle_axis_schedules_no_timers(clock: VirtualClock) -> None:
    axis = Axis(clock)
    axis.watch(10.0, lambda d: None)
    axis.watch_index(lambda d: None)
    RegionSwitch(axis, -5.0, 5.0)
    assert clock.next_event() is None
    axis.move_to(20000.0, 1000.0, 1000.0)
    assert clock.next_event() is not None
    run_idle(clock, axis)
    assert clock.next_event() is None
    axis.jog(-1, 1000.0, 1000.0)
    clock.advance(1.0)
    axis.quick_stop()
    assert clock.next_event() is None
    axis.stop(10.0)
    assert clock.next_event() is None


def test_watch_cancel(clock: VirtualClock) -> None:
    axis = Axis(clock)
    hits: list[int] = []
    w = axis.watch(50.0, hits.append)
    axis.move_to(100.0, 100.0, 100.0)
    w.cancel()
    w.cancel()
    run_idle(clock, axis)
    assert hits == []


def test_segment_closed_form() -> None:
    s = Segment(1.0, 3.0, 10.0, 5.0, -2.0)
    assert s.position(3.0) == pytest.approx(10.0 + 5.0 * 2 - 4.0)
    assert s.velocity(3.0) == pytest.approx(1.0)
    assert s.solve(s.position(2.0)) == pytest.approx(2.0)
