"""The LM628 chip of a PCD4.H3 axis (spec pcd4h3.md §3.5, §4.5, §4.8, §5.2–§5.8): commands,
status, signals, and a closed-loop move."""

from __future__ import annotations

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
