"""FFP and the unit conversions of the PCD4.H3 library (spec pcd4h3.md §4.6, §5.1, §6.1 U1–U12)."""

from __future__ import annotations

import hypothesis.strategies as hs
import pytest
from hypothesis import given

from devsim.devices.pcd4h3.units import (
    CHIP_SAMPLE,
    FFP_MAX,
    acceleration_register,
    counts,
    ffp_decode,
    ffp_encode,
    velocity_register,
)


@pytest.mark.parametrize(("value", "pattern"), [
    (100.0, 0xC8000047), (1.0, 0x80000041), (4.0, 0x80000043), (1.33333, 0xAAAA8F41), (133.333, 0x85553F48),
    (1333.3, 0xA6A99A4B),
])
def test_ffp_vectors_of_section_4_6(value: float, pattern: int) -> None:
    assert ffp_encode(value) == pattern
    assert ffp_decode(pattern) == pytest.approx(value, rel=1e-6)


def test_ffp_edges() -> None:
    assert ffp_decode(0x00000064) == 0.0  # an integer 100 is not a factor (§4.6)
    assert ffp_decode(FFP_MAX) == pytest.approx(9.2233715e18, rel=1e-7)
    assert ffp_encode(-1.0) == 0x800000C1 and ffp_decode(0x800000C1) == -1.0
    assert ffp_encode(1e30) == FFP_MAX and ffp_encode(0.0) == 0


@given(hs.floats(min_value=1e-15, max_value=1e18))
def test_ffp_round_trip_keeps_24_bits(value: float) -> None:
    assert ffp_decode(ffp_encode(value)) == pytest.approx(value, rel=2 ** -23)


@pytest.mark.parametrize(("user", "k", "expected"), [
    (1000, 100, 100_000), (700, 100, 70_000), (1500, 100, 150_000), (300, 100, 30_000), (1100, 100, 110_000),
    (-300, 100, -30_000),  # §5.1 table
    (60_000, 4 * 1000 / 3000, 80_000), (600, 4 * 1000 / 30, 80_000), (-60_000, 4 * 1000 / 3000, -80_000),  # U1–U3
])
def test_positions_in_counts(user: float, k: float, expected: int) -> None:
    assert counts(user, k) == expected


@pytest.mark.parametrize(("velocity", "k", "register"), [
    (500, 100, 1_117_389), (200, 100, 446_956), (100, 100, 223_478), (300, 100, 670_433),  # §5.1
    (100, 1333.3, 2_979_629),  # U4
])
def test_velocity_registers(velocity: float, k: float, register: int) -> None:
    assert velocity_register(velocity, k) == register


@pytest.mark.parametrize(("acceleration", "k", "register"), [(100, 100, 76), (5, 1333.3, 51)])  # §5.1, U6, U12
def test_acceleration_registers(acceleration: float, k: float, register: int) -> None:
    assert acceleration_register(acceleration, k) == register


def test_the_chip_runs_slower_than_the_blocks_assume() -> None:
    """§5.1: Veloc 500 at k 100 gives V = 1 117 389, which the chip (341.333 µs) runs as 49 951
    counts/s; Accel 100 → A = 76 → 9 953.5 counts/s²."""
    assert 1_117_389 / 65536 / CHIP_SAMPLE == pytest.approx(49_951, abs=1)
    assert 76 / 65536 / CHIP_SAMPLE**2 == pytest.approx(9_953.5, abs=0.5)
