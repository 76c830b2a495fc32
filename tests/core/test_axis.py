"""Tests of the closed-form axis model (design.md principle 2) on a virtual clock."""

from __future__ import annotations

import math

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from devsim.core.axis import Axis, RampProfile, RegionSwitch, Segment
from devsim.core.clock import VirtualClock

#: No deadline, no speed health check: a loaded machine (or a mutation run) must not fail these.
BOUNDARY = settings(deadline=None, suppress_health_check=[HealthCheck.too_slow])


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


# -- ramp profiles (SERS P1032/P1005-P1008, spec 5.2) --------------------------------------------
HALF = RampProfile(speed1=0.5, accel1=0.5)
HALF_SINE = RampProfile(speed1=0.5, accel1=0.5, shape="sine")
V, A = 1000.0, 500.0  # section 1: 0..500 inc/s at 250 inc/s^2 (2 s, 500 inc); 2: ..1000 at 500 (1 s, 750 inc)


def test_profile_linear_long_move_time_is_closed_form(clock: VirtualClock) -> None:
    axis = Axis(clock)
    end = axis.move_to(10000.0, V, A, profile=HALF)
    t_ramp = (0.5 * V) / (0.5 * A) + (0.5 * V) / A
    d_ramp = (0.5 * V) ** 2 / (2 * 0.5 * A) + (V**2 - (0.5 * V) ** 2) / (2 * A)
    assert (t_ramp, d_ramp) == (3.0, 1250.0)
    assert end == pytest.approx(2 * t_ramp + (10000.0 - 2 * d_ramp) / V, abs=1e-12)
    assert [s.a for s in axis.segments()] == [250.0, 500.0, 0.0, -500.0, -250.0]
    assert all(s.shape == "linear" for s in axis.segments())
    check_continuity(axis)
    assert axis.velocity(2.0) == pytest.approx(500.0)
    assert axis.position(2.0) == pytest.approx(500.0)
    assert axis.phase(1.0) == "accel" and axis.phase(5.0) == "const" and axis.phase(end - 1.0) == "decel"
    assert axis.acceleration(end - 1.0) == -250.0
    run_idle(clock, axis)
    assert axis.position() == 10000.0


@pytest.mark.parametrize("profile", [HALF, HALF_SINE])
@pytest.mark.parametrize(
    ("length", "peak", "t_end"),
    [
        # peak inside section 1 (both ramps at 250): v^2 = 250 * 800
        (800.0, math.sqrt(250.0 * 800.0), 2 * math.sqrt(250.0 * 800.0) / 250.0),
        # section 1 complete (500 inc each way), the remaining 100 inc in section 2:
        # 100 = 2 (v^2 - 500^2) / (2*500)
        (1100.0, math.sqrt(500.0**2 + 100.0 * 500.0), 2 * (2.0 + (math.sqrt(300000.0) - 500.0) / 500.0)),
    ],
)
def test_profile_triangle_solves_peak_exactly(
    clock: VirtualClock, profile: RampProfile, length: float, peak: float, t_end: float
) -> None:
    axis = Axis(clock, position=-100.0)
    target = length - 100.0
    done: list[float] = []
    end = axis.move_to(target, V, A, profile=profile, on_done=lambda: done.append(clock.now()))
    assert end == pytest.approx(t_end, rel=1e-13)
    segs = axis.segments()
    assert all(s.a != 0.0 for s in segs)  # no cruise
    assert max(abs(s.velocity(s.t1)) for s in segs) == pytest.approx(peak, rel=1e-13)
    check_continuity(axis)
    xs = [axis.position(end * i / 2000) for i in range(2001)]
    assert all(b >= a for a, b in zip(xs, xs[1:], strict=False))  # monotone: never back
    assert max(xs) <= target + 1e-9  # and never beyond the target
    run_idle(clock, axis)
    assert done == [end]
    assert axis.position() == target and axis.velocity() == 0.0


def test_profile_sine_same_duration_and_peak_acceleration(clock: VirtualClock) -> None:
    lin = Axis(clock)
    sine = Axis(clock)
    end_lin = lin.move_to(10000.0, V, A, profile=HALF)
    end = sine.move_to(10000.0, V, A, profile=HALF_SINE)
    assert end == end_lin  # durations and distances of the sections are the same
    assert [s.shape for s in sine.segments()] == ["sine", "sine", "linear", "sine", "sine"]
    assert [s.t1 for s in sine.segments()] == [s.t1 for s in lin.segments()]
    check_continuity(sine)
    # peak acceleration pi/2 of the section's, in the middle of each section
    assert sine.acceleration(1.0) == pytest.approx(math.pi / 2 * 250.0, rel=1e-12)
    assert sine.acceleration(2.5) == pytest.approx(math.pi / 2 * 500.0, rel=1e-12)
    assert sine.acceleration(end - 1.0) == pytest.approx(-math.pi / 2 * 250.0, rel=1e-12)
    # smooth: zero acceleration at the section ends, the section end speeds as in the linear ramp
    assert sine.acceleration(0.0) == 0.0
    assert abs(sine.acceleration(2.0)) < 1e-9
    assert sine.velocity(2.0) == pytest.approx(500.0, rel=1e-12)
    assert sine.position(2.0) == pytest.approx(500.0, rel=1e-12)
    assert sine.position(3.0) == pytest.approx(1250.0, rel=1e-12)
    assert sine.velocity(1.0) == pytest.approx(250.0, rel=1e-12)  # raised cosine: half way at mid-time
    assert sine.position(1.0) == pytest.approx(0.5 * 250.0 * 2.0 * (1.0 - 2.0 / math.pi), rel=1e-12)
    assert sine.phase(0.0) == "accel" and sine.phase(5.0) == "const"
    assert sine.phase(end - 1e-9) == "decel"
    run_idle(clock, sine)
    assert sine.position() == 10000.0 and sine.velocity() == 0.0


def test_watch_crossing_inside_sine_segments(clock: VirtualClock) -> None:
    axis = Axis(clock)
    hits: list[tuple[float, float, int]] = []
    for p in (1e-3, 100.0, 499.9, 900.0, 9900.0, 9999.9):
        axis.watch(p, lambda d, p=p: hits.append((p, clock.now(), d)))
    end = axis.move_to(10000.0, V, A, profile=HALF_SINE)
    clock.advance(end + 1.0)
    assert [h[0] for h in hits] == [1e-3, 100.0, 499.9, 900.0, 9900.0, 9999.9]
    assert all(d == 1 for _, _, d in hits)
    for p, t, _ in hits:
        assert 0.0 < t < end
        assert axis.position(t) == pytest.approx(p, abs=1e-6)
    # fired at the solved instant, not sampled: 100 inc is reached in the first section
    t100 = hits[1][1]
    assert 0.0 < t100 < 2.0
    assert axis.position(t100 - 1e-6) < 100.0 <= axis.position(t100 + 1e-9)
    # and back down through a braking sine segment
    hits.clear()
    axis.move_to(450.0, V, A, profile=HALF_SINE)
    clock.advance(20.0)
    assert [(p, d) for p, _, d in hits] == [(9999.9, -1), (9900.0, -1), (900.0, -1), (499.9, -1)]
    for p, t, _ in hits:
        assert axis.position(t) == pytest.approx(p, abs=1e-6)


@pytest.mark.parametrize("profile", [HALF, HALF_SINE])
def test_stop_with_profile_from_cruise(clock: VirtualClock, profile: RampProfile) -> None:
    axis = Axis(clock)
    axis.jog(+1, V, A, profile=profile)
    clock.advance(10.0)
    assert axis.phase() == "const"
    x = axis.position()
    assert x == pytest.approx(1250.0 + 7.0 * V)
    # mirrored sections: 1000 -> 500 with 500 (1 s, 750 inc), 500 -> 0 with 250 (2 s, 500 inc)
    assert axis.stopping_distance(A, profile) == pytest.approx(1250.0)
    assert axis.stopping_distance(A) == pytest.approx(1000.0)  # plain: v^2/(2 decel)
    done: list[float] = []
    end = axis.stop(A, on_done=lambda: done.append(clock.now()), profile=profile)
    assert end == pytest.approx(13.0)
    assert [s.a for s in axis.segments()] == [-500.0, -250.0]
    assert axis.final_position() == pytest.approx(x + 1250.0)
    assert axis.phase(10.5) == "decel" and axis.phase(12.5) == "decel"
    run_idle(clock, axis)
    assert done == [end]
    assert axis.position() == pytest.approx(x + 1250.0)


def test_jog_with_profile_and_reversal(clock: VirtualClock) -> None:
    axis = Axis(clock)
    reached: list[float] = []
    axis.jog(+1, V, A, on_done=lambda: reached.append(clock.now()), profile=HALF_SINE)
    clock.advance(5.0)
    assert reached == [3.0]
    axis.jog(-1, V, A, profile=HALF_SINE)  # brake through both sections, then the ramp back
    assert [s.a for s in axis.segments()] == [-500.0, -250.0, -250.0, -500.0, 0.0]
    assert axis.segments()[2].v0 == 0.0
    check_continuity(axis)
    clock.advance(6.0)
    assert axis.velocity() == pytest.approx(-V)


@pytest.mark.parametrize("profile", [HALF, HALF_SINE])
def test_replan_mid_section_keeps_continuity(clock: VirtualClock, profile: RampProfile) -> None:
    axis = Axis(clock)
    axis.move_to(10000.0, V, A, profile=profile)
    for t_replan, target in ((1.3, 20000.0), (2.6, 3000.0), (4.0, 1500.0)):
        clock.advance(t_replan - clock.now())  # in section 1, in section 2, at speed (overshoot)
        x, v, t = axis.position(), axis.velocity(), clock.now()
        axis.move_to(target, V, A, profile=profile)
        assert axis.position() == pytest.approx(x, abs=1e-9)
        assert axis.velocity() == pytest.approx(v, abs=1e-9)
        seg = axis.segments()[0]
        assert (seg.t0, seg.x0, seg.v0) == (t, x, v)
        check_continuity(axis)
        assert all(s.shape == profile.shape for s in axis.segments() if s.a != 0.0)
    # the last re-plan brakes through both sections past 1500, then comes back
    assert axis.final_position() == 1500.0
    run_idle(clock, axis)
    assert axis.position() == 1500.0


def test_profile_section_rules(clock: VirtualClock) -> None:
    axis = Axis(clock)
    # accel fraction 0: section 1 absent, section 2 starts at 0
    axis.move_to(1e6, V, A, profile=RampProfile(speed1=0.5, accel1=0.0, speed2=0.8, accel2=0.5))
    assert [s.a for s in axis.segments()] == [250.0, 500.0, 0.0, -500.0, -250.0]
    assert axis.segments()[0].t1 == pytest.approx(800.0 / 250.0)
    # speed2 below speed1: section 2 empty; equal linear sections merge into one segment
    axis = Axis(clock, position=1e6)
    axis.move_to(0.0, V, A, profile=RampProfile(speed1=0.4, accel1=0.5, speed2=0.2, accel2=0.1))
    assert [s.a for s in axis.segments()] == [-250.0, -500.0, 0.0, 500.0, 250.0]
    axis = Axis(clock)
    axis.move_to(1e6, V, A, profile=RampProfile(speed1=0.3, speed2=0.6))
    assert [s.a for s in axis.segments()] == [500.0, 0.0, -500.0]
    # ... but three sine sections stay three raised cosines
    axis = Axis(clock)
    axis.move_to(1e6, V, A, profile=RampProfile(speed1=0.3, speed2=0.6, shape="sine"))
    assert [s.a for s in axis.segments()] == [500.0] * 3 + [0.0] + [-500.0] * 3
    with pytest.raises(ValueError):
        RampProfile(speed1=1.5)
    with pytest.raises(ValueError):
        RampProfile(accel2=-0.1)
    with pytest.raises(ValueError):
        RampProfile(shape="cubic")  # type: ignore[arg-type]


def test_plain_profile_is_bit_identical_to_no_profile(clock: VirtualClock) -> None:
    plain, profiled = Axis(clock), Axis(clock)
    for target, speed, accel, decel in ((5000.0, 700.0, 300.0, 200.0), (-50.0, 900.0, 2000.0, None)):
        e1 = plain.move_to(target, speed, accel, decel)
        e2 = profiled.move_to(target, speed, accel, decel, profile=RampProfile())
        assert e1 == e2 and plain.segments() == profiled.segments()
        clock.advance(1.7)
    assert plain.stop(100.0) == profiled.stop(100.0, profile=RampProfile())
    assert plain.segments() == profiled.segments()


def test_segment_sine_closed_form() -> None:
    s = Segment(1.0, 3.0, 10.0, 5.0, 4.0, "sine", 2.0)
    assert s.velocity(3.0) == pytest.approx(13.0)
    assert s.velocity(2.0) == pytest.approx(9.0)
    assert s.position(3.0) == pytest.approx(10.0 + (5.0 + 13.0) / 2 * 2.0)
    assert s.acceleration(2.0) == pytest.approx(math.pi / 2 * 4.0)
    for t in (1.0 + 1e-7, 1.3, 2.0, 2.9999):
        assert s.solve(s.position(t)) == pytest.approx(t, abs=1e-12)


# -- boundaries (issue 35): mid-ramp profiled commands, the recent past --------------------------
# Profile sections as SERS P1005–P1008 define them (spec sers §5.2, RampProfile): with speed1 0.5
# and accel1 0.5, section 1 is 0 … V/2 with A/2, above it A; braking mirrors it with D.
MID = RampProfile(speed1=0.5, accel1=0.5)


def _mid_ramp(clock: VirtualClock) -> Axis:
    """A jog to 100 inc/s with A = 100 under MID, caught at 1.25 s: 75 inc/s, in section 2."""
    axis = Axis(clock)
    axis.jog(+1, 100.0, 100.0, profile=MID)  # 0 -> 50 in 1 s (a = 50), 50 -> 100 in 0.5 s (a = 100)
    clock.advance(1.25)
    assert axis.velocity() == pytest.approx(75.0) and axis.phase() == "accel"
    return axis


def test_profiled_stop_in_the_middle_of_a_ramp_keeps_the_jogs_speed_as_reference(clock: VirtualClock) -> None:
    """The sections of a stop are fractions of the last jog's speed (100), not of the speed the
    axis happens to have (75): 75 -> 50 with D, 50 -> 0 with D/2."""
    axis = _mid_ramp(clock)
    x = axis.position()
    assert axis.stopping_distance(100.0, MID) == pytest.approx((75**2 - 50**2) / 200 + 50**2 / 100)
    assert axis.stopping_distance(100.0, MID, speed=75.0) == pytest.approx(
        (75**2 - 37.5**2) / 200 + 37.5**2 / 100)  # a reference speed given: its sections
    done: list[float] = []
    end = axis.stop(100.0, on_done=lambda: done.append(clock.now()), profile=MID)
    assert end == pytest.approx(1.25 + 0.25 + 1.0)
    assert [s.a for s in axis.segments()] == [-100.0, -50.0]
    run_idle(clock, axis)
    assert done == [end]
    assert axis.position() == pytest.approx(x + 40.625)


def test_profiled_jog_stop_in_the_middle_of_a_ramp(clock: VirtualClock) -> None:
    """``jog(0, speed, accel)`` is that stop, with the sections of ``speed``."""
    axis = _mid_ramp(clock)
    done: list[float] = []
    axis.jog(0, 100.0, 100.0, on_done=lambda: done.append(clock.now()), profile=MID)
    assert [s.a for s in axis.segments()] == [-100.0, -50.0]
    run_idle(clock, axis)
    assert done == [pytest.approx(2.5)]


def test_profiled_jog_faster_in_the_middle_of_a_ramp(clock: VirtualClock) -> None:
    """A new jog speed of 200 moves section 1 up to 100: 75 -> 100 with A/2, 100 -> 200 with A."""
    axis = _mid_ramp(clock)
    reached: list[float] = []
    axis.jog(+1, 200.0, 100.0, on_done=lambda: reached.append(clock.now()), profile=MID)
    assert [s.a for s in axis.segments()] == [50.0, 100.0, 0.0]
    clock.advance(5.0)
    assert reached == [pytest.approx(1.25 + 0.5 + 1.0)]
    assert axis.velocity() == 200.0


def test_reference_speed_must_be_positive(clock: VirtualClock) -> None:
    axis = _mid_ramp(clock)
    for speed in (0.0, -1.0, math.nan):
        with pytest.raises(ValueError, match="^speed must be positive$"):
            axis.stop(100.0, profile=MID, speed=speed)
    with pytest.raises(ValueError, match="decel must be positive"):
        axis.stopping_distance(0.0)


def test_past_positions_after_a_quick_stop(clock: VirtualClock) -> None:
    """The recent past stays what it was: the ramp, the cruise, then standing at the stop."""
    axis = Axis(clock, position=10.0)
    clock.advance(1.0)  # idle at 10 for one second
    axis.move_to(1010.0, 100.0, 100.0)  # 1 s ramp (50 inc), then cruise
    clock.advance(2.0)
    axis.quick_stop()
    assert axis.stopped_since() == 3.0
    clock.advance(4.0)
    assert axis.position(0.5) == 10.0 and axis.velocity(0.5) == 0.0  # idle before the move
    assert axis.position(-1.0) == 10.0  # before anything: where the axis first stood
    assert axis.position(1.5) == pytest.approx(10.0 + 12.5)
    assert (axis.velocity(1.5), axis.acceleration(1.5), axis.phase(1.5)) == (pytest.approx(50.0), 100.0, "accel")
    assert axis.position(2.5) == pytest.approx(10.0 + 50.0 + 50.0)
    assert (axis.velocity(2.5), axis.acceleration(2.5), axis.phase(2.5)) == (pytest.approx(100.0), 0.0, "const")
    for t in (3.0, 5.0, 7.0):
        assert (axis.position(t), axis.velocity(t), axis.phase(t)) == (pytest.approx(160.0), 0.0, "idle")
    axis.move_to(0.0, 100.0, 100.0)  # standing since the stop becomes part of the past
    for t in (3.0, 5.0, 6.99):
        assert (axis.position(t), axis.velocity(t), axis.acceleration(t)) == (pytest.approx(160.0), 0.0, 0.0)
    assert (axis.position(0.5), axis.velocity(0.5), axis.acceleration(0.5)) == (10.0, 0.0, 0.0)


def test_the_past_of_a_plan_ended_on_its_own(clock: VirtualClock) -> None:
    axis = Axis(clock)
    axis.move_to(100.0, 100.0, 100.0)  # triangle: 1 s up, 1 s down
    clock.advance(5.0)
    axis.move_to(0.0, 100.0, 100.0)
    clock.advance(0.5)
    assert axis.position(0.5) == pytest.approx(12.5)
    assert axis.position(1.5) == pytest.approx(100.0 - 12.5)
    assert axis.position(3.0) == 100.0 and axis.velocity(3.0) == 0.0  # standing at the target
    assert axis.position(5.25) == pytest.approx(100.0 - 3.125)


def test_history_keeps_the_last_64_segments(clock: VirtualClock) -> None:
    """64 past segments are kept: a query further back answers with the oldest one kept."""
    axis = Axis(clock)
    for k in range(40):  # each step: a 1 s move of 1 inc (a triangle: two segments), back to back
        axis.move_to(float(k + 1), 2.0, 4.0)
        clock.advance(1.0)
    axis.move_to(0.0, 2.0, 4.0)  # archives 40 x 2 segments; the last 64 are kept
    kept = axis._history
    assert len(kept) == 64
    oldest = kept[0]
    assert axis.position(0.1) == oldest.x0  # further back than the history reaches
    assert axis.position(oldest.t0) == pytest.approx(oldest.x0)
    assert oldest.t0 == 8.0  # 80 segments back to back (no standstill between): moves 0 … 7 dropped
    clock.advance(0.25)
    axis.move_to(5.0, 2.0, 4.0)  # in the middle of a plan: the running segment is cut, 64 kept
    assert len(axis._history) == 64 and axis._history[0].t0 == 8.5


def test_dwell_is_a_planned_standstill(clock: VirtualClock) -> None:
    axis = Axis(clock, position=5.0)
    done: list[float] = []
    clock.advance(1.0)
    axis.dwell(2.0, on_done=lambda: done.append(clock.now()))
    assert axis.moving and axis.stopped_since() is None
    assert axis.segments()[0].t0 == 1.0 and axis.segments()[0].t1 == 3.0
    clock.advance(1.0)
    assert (axis.position(), axis.velocity(), axis.phase(), axis.moving) == (5.0, 0.0, "idle", True)
    clock.advance(1.5)
    assert done == [3.0]
    assert not axis.moving and axis.stopped_since() == 3.0 and axis.position() == 5.0


def test_track_follows_a_sampled_loop(clock: VirtualClock) -> None:
    """A servo loop reports position and velocity; the axis goes on at that velocity until the
    next report, and watches fire on that extrapolation."""
    axis = Axis(clock)
    crossings: list[tuple[float, int]] = []
    axis.watch(25.0, lambda d: crossings.append((clock.now(), d)))
    axis.track(10.0, 10.0)
    assert axis.moving and axis.final_position() == math.inf and axis.stopped_since() is None
    assert clock.next_event() == 1.5  # the crossing of 25, nothing else
    clock.advance(2.0)
    assert axis.position() == pytest.approx(30.0) and axis.velocity() == 10.0
    assert crossings == [(1.5, +1)]
    axis.track(31.0, -20.0)
    assert axis.final_position() == -math.inf
    clock.advance(0.5)
    assert axis.position() == pytest.approx(21.0) and crossings[-1] == (pytest.approx(2.3), -1)
    axis.track(20.0, 0.0)  # the loop stands still: at rest where it says, no timers
    assert not axis.moving and axis.position() == 20.0 and axis.velocity() == 0.0
    assert axis.stopped_since() == 2.5 and clock.next_event() is None
    assert axis.position(2.25) == pytest.approx(26.0)  # the past as it was extrapolated


def test_construction(clock: VirtualClock) -> None:
    for cpr in (0, -1):
        with pytest.raises(ValueError, match="^counts_per_rev must be positive$"):
            Axis(clock, counts_per_rev=cpr)
    clock.advance(2.0)
    axis = Axis(clock, position=7, counts_per_rev=1, name="X")
    assert axis.position() == 7.0 and type(axis.position()) is float
    assert (axis.name, axis.counts_per_rev, axis.moving, axis.stopped_since()) == ("X", 1, False, 2.0)
    assert repr(axis) == "<Axis X x=7.000 v=0.000 idle>"
    assert axis.segments() == [] and axis.final_position() == 7.0
    assert (axis.position(0.0), axis.velocity(0.0), axis.acceleration(0.0)) == (7.0, 0.0, 0.0)  # before it was made
    assert clock.next_event() is None


def test_teleport_fires_point_watches_but_not_index_marks(clock: VirtualClock) -> None:
    axis = Axis(clock, counts_per_rev=100)
    points: list[int] = []
    marks: list[int] = []
    axis.watch(50.0, points.append)
    axis.watch_index(marks.append)
    generation = axis.plan_generation
    axis.set_position(250.0)  # across the point and two index marks
    assert points == [+1] and marks == []
    assert axis.plan_generation != generation  # a watch armed under the old plan must re-arm
    axis.set_position(10.0)
    assert points == [+1, -1] and marks == []
    axis.move_to(120.0, 1000.0, 1e6)  # a real move passes the mark at 100 and the point at 50
    run_idle(clock, axis)
    assert points == [+1, -1, +1] and marks == [+1]
    axis.jog(1, 1.0, 1.0)
    with pytest.raises(RuntimeError, match="^axis: set_position while moving$"):
        axis.set_position(0.0)


def test_region_switch_bounds_and_its_own_watch(clock: VirtualClock) -> None:
    axis = Axis(clock, position=5.0)
    with pytest.raises(ValueError, match="^low must not exceed high$"):
        RegionSwitch(axis, 1.0, 0.0)
    inside = RegionSwitch(axis, 0.0, 10.0)
    assert inside.active and (inside.axis, inside.low, inside.high) == (axis, 0.0, 10.0)
    point = RegionSwitch(axis, 5.0, 5.0)  # a region of one point is allowed
    assert point.active
    # a device that watches something else than the position (GMS96: set-point − v/Kv) gives
    # its own watch; here one that watches the position shifted by 100
    shifted: list[bool] = []
    made: list[object] = []

    def make_watch(rule: object, callback: object) -> object:
        made.append(rule)
        return axis._watches.add(rule, callback, True, axis.position() + 100.0)  # type: ignore[arg-type]

    sw = RegionSwitch(axis, 100.0, 110.0, shifted.append, make_watch=make_watch)
    assert sw.active and len(made) == 1
    axis.set_position(20.0)  # its watch is told, and the switch calls back
    assert shifted == [False] and not sw.active
    assert (made[0].low, made[0].high) == (100.0, 110.0)  # type: ignore[attr-defined]


class _Line:
    """A path component at constant velocity (devsim.core.path gives real ones)."""

    def __init__(self, x0: float, v: float) -> None:
        self.x0, self.v = x0, v

    def state(self, dt: float) -> tuple[float, float, float]:
        return self.x0 + self.v * dt, self.v, 0.0


def test_follow_pieces_then_a_profiled_stop(clock: VirtualClock) -> None:
    axis = Axis(clock)
    axis.jog(1, 50.0, 100.0)  # sets a reference speed of 50 ...
    axis.quick_stop()
    done: list[float] = []
    end = axis.follow([(1.0, _Line(0.0, 10.0)), (2.0, _Line(10.0, 5.0)), (0.5, _Line(20.0, 4.0))],
                      on_done=lambda: done.append(clock.now()))
    assert end == 3.5 and axis.final_position() == 22.0
    first = axis.segments()[0]
    assert (first.t0, first.t1, first.x0, first.v0, first.a, first.shape, first.span) == (
        0.0, 1.0, 0.0, 10.0, 0.0, "curve", 1.0)
    clock.advance(2.0)
    assert (axis.position(), axis.velocity(), axis.phase()) == (15.0, 5.0, "const")
    assert axis.stopping_distance(10.0, MID) == pytest.approx((25 - 6.25) / 20 + 6.25 / 10)
    # ... which a path forgets: the stop's profile sections are fractions of the current 5 inc/s
    axis.stop(10.0, profile=MID)  # 5 -> 2.5 with 10, 2.5 -> 0 with 5: 0.25 s + 0.5 s
    assert [s.a for s in axis.segments()] == [-10.0, -5.0]
    run_idle(clock, axis)
    assert done == [] and clock.now() == pytest.approx(2.75)


def test_follow_nothing_stands_still_and_reports_done(clock: VirtualClock) -> None:
    axis = Axis(clock, position=3.0)
    clock.advance(1.0)
    done: list[float] = []
    assert axis.follow([], on_done=lambda: done.append(clock.now())) == 1.0
    assert not axis.moving and axis.position() == 3.0
    clock.advance(0.0)
    assert done == [1.0]


def test_state_at_segment_boundaries_and_beyond_the_plan(clock: VirtualClock) -> None:
    """At the instant a segment ends, the next one holds (its acceleration); after the plan's end
    the axis stands; before its start, the past."""
    clock.advance(5.0)
    axis = Axis(clock, position=10.0)
    axis.move_to(1010.0, 100.0, 100.0)  # ramp 5 … 6, cruise 6 … 15, brake 15 … 16
    assert axis.position(1.0) == 10.0  # before the plan, no history: where it started
    assert (axis.velocity(1.0), axis.acceleration(1.0)) == (0.0, 0.0)
    assert (axis.acceleration(6.0), axis.phase(6.0)) == (0.0, "const")
    assert (axis.acceleration(15.0), axis.phase(15.0)) == (-100.0, "decel")
    assert (axis.position(20.0), axis.velocity(20.0), axis.acceleration(20.0)) == (1010.0, 0.0, 0.0)
    clock.advance(3.0)
    axis.move_to(0.0, 100.0, 100.0)  # the old plan goes to the history, from its first segment
    assert axis.position(1.0) == 10.0 and axis.acceleration(1.0) == 0.0
    assert (axis.acceleration(5.0), axis.phase(5.0)) == (100.0, "accel")  # a past segment's start
    assert (axis.acceleration(6.0), axis.phase(6.0)) == (0.0, "const")


def test_plan_generation_changes_with_every_plan(clock: VirtualClock) -> None:
    axis = Axis(clock)
    seen = [axis.plan_generation]
    axis.move_to(10.0, 10.0, 10.0)
    seen.append(axis.plan_generation)
    run_idle(clock, axis)  # the end of a plan is a change too
    seen.append(axis.plan_generation)
    axis.move_to(0.0, 10.0, 10.0)
    seen.append(axis.plan_generation)
    clock.advance(0.5)
    axis.stop(10.0)
    seen.append(axis.plan_generation)
    run_idle(clock, axis)
    seen.append(axis.plan_generation)
    axis.set_position(0.0)
    seen.append(axis.plan_generation)
    assert len(set(seen)) == len(seen)


def test_track_at_one_increment_per_second(clock: VirtualClock) -> None:
    axis = Axis(clock)
    axis.track(0.0, 1.0)
    clock.advance(2.0)
    assert axis.moving and axis.position() == 2.0


def test_sine_ramps_of_unit_acceleration(clock: VirtualClock) -> None:
    axis = Axis(clock)
    axis.move_to(100.0, 2.0, 1.0, profile=RampProfile(shape="sine"))
    shapes = [(s.shape, s.a) for s in axis.segments()]
    assert shapes == [("sine", 1.0), ("linear", 0.0), ("sine", -1.0)]
    assert axis.phase(10.0) == "const"


def test_default_encoder_index_every_12800_increments(clock: VirtualClock) -> None:
    axis = Axis(clock)
    marks: list[float] = []
    axis.watch_index(lambda d: marks.append(axis.position()))
    axis.move_to(30000.0, 12800.0, 1e6)
    run_idle(clock, axis)
    assert marks == [pytest.approx(12800.0, abs=1e-6), pytest.approx(25600.0, abs=1e-6)]


_SMALL = st.floats(0.01, 0.99)


@settings(BOUNDARY, max_examples=40)
@given(st.sampled_from(["speed", "accel", "decel"]), st.one_of(st.sampled_from([0.0, -0.0, -1.0, math.nan]), _SMALL))
def test_rates_must_be_positive_and_may_be_below_one(which: str, value: float) -> None:
    """Oracle: any speed, acceleration or deceleration > 0 is taken (also below 1); 0, negative
    and NaN are refused with the message naming them, and nothing changes."""
    clock = VirtualClock()
    rates = {"speed": 2.0, "accel": 2.0, "decel": 2.0, which: value}
    taken = value > 0
    axis = Axis(clock)
    if taken:
        assert axis.move_to(1.0, rates["speed"], rates["accel"], rates["decel"]) > 0.0
        axis.quick_stop()
        assert axis.stop(rates["decel"]) == 0.0 and axis.stopping_distance(rates["decel"]) == 0.0
        if which != "decel":
            axis.jog(1, rates["speed"], rates["accel"])
            assert axis.moving
    else:
        with pytest.raises(ValueError, match="^speed, accel and decel must be positive$"):
            axis.move_to(1.0, rates["speed"], rates["accel"], rates["decel"])
        if which == "decel":
            with pytest.raises(ValueError, match="^decel must be positive$"):
                axis.stop(value)
            with pytest.raises(ValueError, match="^decel must be positive$"):
                axis.stopping_distance(value)
        else:
            with pytest.raises(ValueError, match="^speed and accel must be positive$"):
                axis.jog(1, rates["speed"], rates["accel"])
        assert not axis.moving and axis.position() == 0.0


def test_a_reference_speed_below_one_is_taken(clock: VirtualClock) -> None:
    axis = Axis(clock)
    axis.jog(1, 1.0, 10.0)
    clock.advance(1.0)
    # reference 0.5: section 1 is 0 … 0.25 with 5; from 1 down to 0.25 with 10
    assert axis.stopping_distance(10.0, MID, speed=0.5) == pytest.approx((1 - 0.0625) / 20 + 0.0625 / 10)
    # at exactly 1 inc/s a profile still applies: 1 -> 0.5 with 10, 0.5 -> 0 with 5
    assert axis.stopping_distance(10.0, MID) == pytest.approx(0.75 / 20 + 0.25 / 10)


def test_target_must_be_finite(clock: VirtualClock) -> None:
    axis = Axis(clock)
    for target in (math.inf, -math.inf, math.nan):
        with pytest.raises(ValueError, match="^target must be finite$"):
            axis.move_to(target, 1.0, 1.0)


def test_a_standing_axis_needs_no_braking_distance_with_a_profile(clock: VirtualClock) -> None:
    assert Axis(clock).stopping_distance(1.0, MID) == 0.0


def test_profiled_stop_after_a_move_in_the_middle_of_a_ramp(clock: VirtualClock) -> None:
    """The reference speed of a stop is the last move's speed too (not only a jog's)."""
    axis = Axis(clock)
    axis.move_to(10_000.0, 100.0, 100.0, profile=MID)
    clock.advance(1.25)
    assert axis.velocity() == pytest.approx(75.0)
    assert axis.stop(100.0, profile=MID) == pytest.approx(2.5)


def test_profiled_jog_stop_with_its_own_reference_speed(clock: VirtualClock) -> None:
    """``jog(0, 200, …)`` brakes with the sections of 200: 75 inc/s lies in section 1 (below 100),
    so 75 -> 0 with D/2 = 50 takes 1.5 s."""
    axis = _mid_ramp(clock)
    done: list[float] = []
    axis.jog(0, 200.0, 100.0, on_done=lambda: done.append(clock.now()), profile=MID)
    assert [s.a for s in axis.segments()] == [-50.0]
    run_idle(clock, axis)
    assert done == [pytest.approx(1.25 + 1.5)]


def test_profiled_stop_of_a_tracked_axis_uses_its_speed(clock: VirtualClock) -> None:
    """No move or jog gave a speed: the stop's sections are fractions of the current |v| (10)."""
    axis = Axis(clock)
    axis.track(0.0, 10.0)
    assert axis.stop(10.0, profile=MID) == pytest.approx(0.5 + 1.0)  # 10 -> 5 with 10, 5 -> 0 with 5


def test_many_commands_at_one_instant_keep_the_past(clock: VirtualClock) -> None:
    """Re-planning again and again at the same instant adds nothing to the history (a plan that
    starts now has no past), so the past stays answerable."""
    axis = Axis(clock)
    axis.move_to(1000.0, 100.0, 100.0)
    clock.advance(1.0)
    for k in range(70):
        axis.move_to(1000.0 + k, 100.0, 100.0)
    assert axis.position(0.5) == pytest.approx(12.5)
    assert axis.velocity(0.5) == pytest.approx(50.0)


def test_profiled_stop_from_exactly_one_increment_per_second(clock: VirtualClock) -> None:
    axis = Axis(clock)
    axis.jog(1, 1.0, 10.0)
    clock.advance(1.0)
    assert axis.stop(10.0, profile=MID) == pytest.approx(1.0 + 0.05 + 0.1)  # 1 -> 0.5 with 10, 0.5 -> 0 with 5
