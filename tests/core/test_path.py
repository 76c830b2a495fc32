"""Coordinated path motion (devsim.core.path) on the closed-form axes: an arc's speed profile,
its pieces, and crossings on curve segments."""

from __future__ import annotations

import math

import pytest

from devsim.core.axis import Axis
from devsim.core.clock import VirtualClock
from devsim.core.path import Arc, Line, SpeedProfile, path_pieces


def test_speed_profile_trapezoid_triangle_and_slowing_down() -> None:
    trapezoid = SpeedProfile.plan(100.0, 0.0, 50.0, 500.0)  # 0.1 s ramps of 2.5, cruise 95 at 50
    assert trapezoid.end == pytest.approx(0.1 + 95 / 50 + 0.1)
    assert trapezoid.state(1.0) == pytest.approx((2.5 + 50 * 0.9, 50.0, 0.0))
    assert trapezoid.state(trapezoid.end) == (100.0, 0.0, 0.0)
    triangle = SpeedProfile.plan(1.0, 0.0, 50.0, 500.0)  # peak sqrt(500) < 50
    assert triangle.end == pytest.approx(2 * math.sqrt(1.0 / 500.0))
    faster = SpeedProfile.plan(100.0, 80.0, 50.0, 500.0)
    assert faster.state(0.0)[1:] == (80.0, -500.0) and faster.state(0.06)[1] == pytest.approx(50.0)
    for profile in (trapezoid, triangle, faster):
        for s in (0.0, 0.3, 0.5 * profile.length, profile.length):
            assert profile.state(profile.time_at(s))[0] == pytest.approx(s, abs=1e-9)


def test_an_arc_is_followed_exactly_on_two_axes() -> None:
    """A quarter circle clockwise, radius 20 around (0, -43.144) from (-20, -43.144) to (0,
    -23.144) (the manual's N3, spec §6.6), at 50 mm/s; increments of 0.001 mm."""
    clock = VirtualClock()
    x = Axis(clock, position=-20_000, name="x")
    y = Axis(clock, position=-43_144, name="y")
    arc = Arc(0.0, -43.144, 20.0, math.pi, -1, math.pi / 2)
    profile = SpeedProfile.plan(arc.length, 0.0, 50.0, 500.0)
    pieces = path_pieces(arc, profile, (1000.0, 1000.0))
    done = []
    end = x.follow([(d, px) for d, (px, _) in pieces], on_done=lambda: done.append(clock.now()))
    y.follow([(d, py) for d, (_, py) in pieces])
    crossed = []
    x.watch(-20_000 * math.cos(math.pi / 4), lambda *args: crossed.append(clock.now()))
    assert end == pytest.approx(profile.end)
    for t in (0.05, 0.3, 0.5, profile.end - 0.01):
        clock.advance_to(t)
        radius = math.hypot(x.position() / 1000, y.position() / 1000 + 43.144)
        assert radius == pytest.approx(20.0, abs=1e-9)
        if t == 0.3:
            assert math.hypot(x.velocity(), y.velocity()) == pytest.approx(50_000)  # the path speed
    clock.advance(1.0)
    assert (x.position(), y.position()) == pytest.approx((0.0, -23_144), abs=1e-6)
    assert done == [pytest.approx(profile.end)] and not x.moving
    assert crossed and crossed[0] == pytest.approx(profile.time_at(20.0 * math.pi / 4), abs=1e-9)


def test_a_profile_may_end_at_speed_and_the_next_go_on_from_it() -> None:
    """A continuous path: the first piece ends at its cruise speed, the next starts there."""
    first = SpeedProfile.plan(10.0, 0.0, 50.0, 500.0, v_end=50.0)
    assert first.final == 50.0 and first.state(first.end)[1] == 50.0
    assert first.end == pytest.approx(0.1 + (10.0 - 2.5) / 50)
    second = SpeedProfile.plan(10.0, first.final, 50.0, 500.0)
    assert second.state(0.0)[1] == 50.0 and second.end == pytest.approx((10.0 - 2.5) / 50 + 0.1)


def test_a_line_is_followed_on_three_axes() -> None:
    clock = VirtualClock()
    axes = [Axis(clock, name=n) for n in "xyz"]
    line = Line((0.0, 0.0, 0.0), (3.0, 4.0, 12.0))  # 13 long
    profile = SpeedProfile.plan(line.length, 0.0, 13.0, 130.0)
    pieces = path_pieces(line, profile, (1.0, 1.0, 1.0))
    for i, axis in enumerate(axes):
        axis.follow([(d, parts[i]) for d, parts in pieces])
    clock.advance_to(0.5)
    assert [a.velocity() for a in axes] == pytest.approx([3.0, 4.0, 12.0])
    clock.advance(2.0)
    assert [a.position() for a in axes] == pytest.approx([3.0, 4.0, 12.0])
