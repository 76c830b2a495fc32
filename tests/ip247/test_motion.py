"""An IP247 move with the exponential ramp on the shared axis (spec ip247.md §5.3)."""

from __future__ import annotations

import math
from typing import Any

import pytest

from devsim.core.axis import Axis
from devsim.core.clock import VirtualClock
from devsim.devices.ip247.machine_data import Ramp
from devsim.devices.ip247.motion import move_pieces

RAMP = Ramp(5000, 200, 50)  # the manual's machine data: F 5052.63 Hz, τ 101.05 ms
R = 10  # µm per pulse


def test_a_long_move_ramps_up_cruises_and_brakes_as_the_mirror() -> None:
    """The frequency jumps to f_ss, reaches f_max after t_v = 302.73 ms having sent 1105.1 pulses
    (11.05 mm), cruises, and brakes symmetrically to the exact target."""
    clock = VirtualClock()
    axis = Axis(clock, name="x")
    pieces = move_pieces(0.0, 100_000, 5000, RAMP, R)
    end = axis.follow(pieces)
    assert axis.velocity() == pytest.approx(200 * R)  # f_ss at once
    clock.advance(0.30273)
    assert axis.velocity() == pytest.approx(5000 * R, rel=1e-4) and axis.position() == pytest.approx(11_051, abs=1)
    cruise = (100_000 - 2 * RAMP.pulses_to(5000) * R) / (5000 * R)
    assert end == pytest.approx(2 * 0.30273 + cruise, abs=1e-4)
    clock.advance_to(end - 0.30273 + 0.1)
    assert axis.velocity() == pytest.approx(RAMP.f_ss * R + RAMP.big_f * R * (1 - 2.718281828 ** (-0.20273 / RAMP.tau)),
                                            rel=1e-3)  # the mirror: as fast as 0.2 s before the end of the ramp
    clock.advance(1.0)
    assert axis.position() == pytest.approx(100_000) and not axis.moving


def test_short_moves_meet_at_the_peak_and_slow_moves_run_without_ramps() -> None:
    clock = VirtualClock()
    axis = Axis(clock, name="x")
    short = move_pieces(0.0, -10_000, 5000, RAMP, R)  # 1000 pulses < 2 × 1105
    assert [p.kind for d, p in short if d > 1e-9] == ["accel", "decel"]
    peak = short[0][1].f_v
    assert 2 * RAMP.pulses_to(peak) == pytest.approx(1000, rel=1e-9) and peak < 5000
    axis.follow(short)
    clock.advance(short[0][0])
    assert axis.velocity() == pytest.approx(-peak * R, rel=1e-9)
    clock.advance(1.0)
    assert axis.position() == pytest.approx(-10_000, abs=1e-6)
    slow = move_pieces(0.0, 1_000, 150, RAMP, R)  # below f_ss: constant
    assert [(d, p.kind) for d, p in slow] == [(pytest.approx(100 / 150), "constant")]


def _state_from_the_ramp(piece: Any, dt: float) -> tuple[float, float, float]:
    """A piece's state with every figure taken from its ramp at each look (before issue 31)."""
    ramp = piece.ramp

    def accel(t: float) -> tuple[float, float, float]:
        decay = math.exp(-t / ramp.tau)
        pulses = ramp.big_f * (t - ramp.tau * (1 - decay)) + ramp.f_ss * t
        return pulses, ramp.f_ss + ramp.big_f * (1 - decay), ramp.big_f / ramp.tau * decay

    if piece.kind == "accel":
        n, f, df = accel(dt)
    elif piece.kind == "decel":
        n_back, f, df = accel(piece.t_v - dt)
        n, df = accel(piece.t_v)[0] - n_back, -df
    else:
        n, f, df = piece.f_v * dt, piece.f_v, 0.0
    s, r = piece.sign, piece.r
    return piece.x0 + s * r * n, s * r * f, s * r * df


@pytest.mark.parametrize("ramp", [RAMP, Ramp(10000, 500, 20), Ramp(2000, 100, 0.5)])
@pytest.mark.parametrize("distance, f_v", [(100_000, 5000), (-3_000, 9000), (250, 1800), (-77_777, 150)])
def test_a_piece_keeps_its_ramps_figures_with_the_same_states(ramp: Ramp, distance: float, f_v: float) -> None:
    """The pieces take the ramp's τ, F, f_ss and a braking piece's whole ramp once (issue 31): the
    same states, to the bit, as figures taken from the ramp at every look."""
    pieces = move_pieces(1234.5, distance, f_v, ramp, R)
    assert pieces
    for duration, piece in pieces:
        for k in range(101):
            dt = duration * k / 100
            assert piece.state(dt) == _state_from_the_ramp(piece, dt)
