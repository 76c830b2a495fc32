"""The LM628 profile generator (spec pcd4h3.md §5.2) against the spec's reference kinematics."""

from __future__ import annotations

import math

import pytest

from devsim.devices.pcd4h3.trajectory import Profile, Trajectory
from devsim.devices.pcd4h3.units import CHIP_SAMPLE

SAMPLE_RATE = 1 / CHIP_SAMPLE


def run(profile: Profile, limit: int = 10_000_000) -> tuple[int, float]:
    """Samples until the trajectory completes, and the peak speed in counts/s."""
    peak = 0.0
    for n in range(limit):
        if profile.complete:
            return n, peak
        profile.sample()
        peak = max(peak, abs(profile.velocity) / 65536 * SAMPLE_RATE)
    raise AssertionError("the trajectory never completed")


def test_example_1_move_is_a_triangle() -> None:
    """0 → 100 mm (100 000 counts), Veloc 500 (V = 1 117 389), Accel 100 (A = 76): triangular,
    peak 31 549 counts/s, 6.34 s; it ends exactly on the target; the way back takes as long."""
    profile = Profile()
    profile.start(Trajectory(acceleration=76, velocity=1_117_389, position=100_000))
    samples, peak = run(profile)
    assert profile.desired == 100_000 and profile.velocity == 0
    assert peak == pytest.approx(31_549, rel=0.01)
    assert samples * CHIP_SAMPLE == pytest.approx(6.34, rel=0.01)
    profile.start(Trajectory(acceleration=76, velocity=1_117_389, position=0))
    back, _ = run(profile)
    assert profile.desired == 0 and back == pytest.approx(samples, rel=0.001)


def test_a_long_move_cruises_at_the_velocity() -> None:
    """Veloc 100 at k 100 (V = 223 478): 1 000 000 counts take accel + cruise + decel; the cruise
    speed is V / 65536 counts per sample."""
    profile = Profile()
    profile.start(Trajectory(acceleration=76, velocity=223_478, position=1_000_000))
    samples, peak = run(profile)
    v = 223_478 / 65536
    a = 76 / 65536
    expected = 1_000_000 / v + v / a  # distance/v + one ramp time (two half-ramps)
    assert peak == pytest.approx(v * SAMPLE_RATE, rel=1e-4)
    assert samples == pytest.approx(expected, rel=0.002)
    assert profile.desired == 1_000_000


def test_velocity_mode_and_smooth_stop() -> None:
    profile = Profile()
    profile.start(Trajectory(acceleration=76, velocity=223_478, velocity_mode=True, forward=False))
    for _ in range(5000):
        profile.sample()
    assert profile.velocity == -223_478 and not profile.complete
    before = profile.desired
    profile.stop_smoothly()
    samples, _ = run(profile)
    assert samples == math.ceil(223_478 / 76) and profile.desired < before
    profile.start(Trajectory(acceleration=76, velocity=223_478, position=profile.desired + 10))
    run(profile)


def test_a_new_target_behind_brakes_and_turns() -> None:
    """§5.2 [DECISION]: a target behind the moving axis: brake to 0, reverse, arrive exactly."""
    profile = Profile()
    profile.start(Trajectory(acceleration=76, velocity=1_117_389, position=100_000))
    for _ in range(5000):
        profile.sample()
    passed = profile.desired
    profile.start(Trajectory(acceleration=76, velocity=1_117_389, position=passed - 20_000))
    run(profile)
    assert profile.desired == passed - 20_000 and profile.velocity == 0


def test_abrupt_stop_holds_the_position() -> None:
    profile = Profile()
    profile.start(Trajectory(acceleration=76, velocity=1_117_389, position=100_000))
    for _ in range(3000):
        profile.sample()
    here = profile.desired
    profile.stop_abruptly()
    profile.sample()
    assert profile.complete and profile.desired == here and profile.velocity == 0
