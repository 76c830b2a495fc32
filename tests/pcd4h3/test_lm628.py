"""The LM628 chip of a PCD4.H3 axis (spec pcd4h3.md §3.5, §4.5, §4.8, §5.2–§5.8): commands,
status, signals, and a closed-loop move."""

from __future__ import annotations

import pytest

from devsim.devices.pcd4h3.lm628 import BREAKPOINT, COMPLETE, MOTOR_OFF, POSITION_ERROR, Lm628
from devsim.devices.pcd4h3.pid import Motor


def ready(chip: Lm628, ki: int = 0) -> None:
    chip.reset()
    chip.port(12)
    chip.load_filter(0x030F, [40, ki, 400, 500])  # ds 3, kp, ki, kd, il
    chip.update_filter()


def test_reset_state() -> None:
    chip = Lm628()
    chip.reset()
    assert chip.status == MOTOR_OFF | COMPLETE
    assert chip.signals & 0x0180 == 0x0180  # motor off, 8-bit output
    assert chip.filter.dac == 0


def test_a_closed_loop_move_reaches_the_target_and_sets_complete() -> None:
    chip = Lm628(Motor(kv=10_000.0, tau=0.020))
    ready(chip)
    chip.load_trajectory(0x002A, [76, 1_117_389, 100_000])
    chip.start()
    assert chip.status & (MOTOR_OFF | COMPLETE) == 0
    worst = 0
    for _ in range(30_000):
        chip.sample()
        worst = max(worst, abs(chip.profile.desired - chip.actual))
    assert chip.status & COMPLETE and chip.signals & 0x0400
    assert abs(chip.actual - 100_000) <= 2
    assert 0 < worst < 2000  # a following error from the loop, within PosEr


def test_the_integral_winds_up_during_a_move_and_the_axis_overshoots() -> None:
    """With ki the error sum grows while the axis lags, so it passes the target before the
    sum unwinds: an overshoot the loop makes (§5.3), limited by il."""
    chip = Lm628(Motor(kv=10_000.0, tau=0.020))
    ready(chip, ki=2)
    chip.load_trajectory(0x002A, [76, 1_117_389, 100_000])
    chip.start()
    peak = 0
    for _ in range(30_000):
        chip.sample()
        peak = max(peak, chip.actual)
    assert peak > 100_000 and abs(chip.filter.integral) <= 500


def test_blocked_motor_trips_the_position_error_and_switches_off() -> None:
    motor = Motor()
    chip = Lm628(motor)
    ready(chip)
    chip.position_error(2000, stop=True)  # LPES
    chip.load_trajectory(0x002A, [76, 1_117_389, 100_000])
    chip.start()
    motor.blocked = True
    for _ in range(20_000):
        chip.sample()
        if chip.status & POSITION_ERROR:
            break
    assert chip.status & POSITION_ERROR and chip.status & MOTOR_OFF
    chip.reset_interrupts(~POSITION_ERROR & 0xFFFF)
    assert not chip.status & POSITION_ERROR


def test_breakpoint_flag_when_the_actual_position_passes_it() -> None:
    chip = Lm628(Motor(tau=0.0))
    ready(chip)
    chip.set_breakpoint(70_000)
    chip.load_trajectory(0x002A, [76, 1_117_389, 100_000])
    chip.start()
    while not chip.status & BREAKPOINT:
        chip.sample()
    assert 69_000 < chip.actual < 71_000


def test_pd_step_response_on_a_pure_inertia_matches_the_closed_form() -> None:
    """The loop from 2000 counts off target back to it, on a motor that is a pure inertia
    (x'' = b·U: a lag of τ = 10^6 s): kp, kd give x'' + b·g·kd·T·x' + b·g·kp·x = 0 with g the
    12-bit output's volts per filter unit (10 V / 2^15), so ωn² = b·g·kp, 2ζωn = b·g·kd·T; the
    first undershoot is x0·exp(−ζπ/√(1−ζ²)) at t = π/ωd (§5.3 on the closed form of a damped
    oscillator)."""
    import math

    from devsim.devices.pcd4h3.units import CHIP_SAMPLE

    g, T = 10.0 / 32768, CHIP_SAMPLE
    omega, zeta = 2 * math.pi * 5, 0.3
    kp = 8
    b = omega**2 / (g * kp)  # counts/s² per volt
    kd = round(2 * zeta * omega / (b * g * T))
    tau = 1e6
    chip = Lm628(Motor(kv=b * tau, tau=tau))
    chip.reset()
    chip.port(12)
    chip.load_filter(0x000F, [kp, 0, kd, 0])
    chip.update_filter()
    chip.load_trajectory(0x0000, [])
    chip.start()  # the control on, the target where the axis is: 0
    chip.motor.position = 2000.0  # then the axis is pushed 2000 counts away
    low, when = math.inf, 0.0
    for n in range(1, int(0.3 / T)):
        chip.sample()
        if chip.actual < low:
            low, when = chip.actual, n * T
    z = zeta * (kd * b * g * T) / (2 * zeta * omega)  # ζ with kd as rounded
    damped = omega * math.sqrt(1 - z * z)
    assert when == pytest.approx(math.pi / damped, rel=0.03)
    assert low == pytest.approx(-2000 * math.exp(-z * math.pi / math.sqrt(1 - z * z)), rel=0.05)
