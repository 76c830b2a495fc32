"""The LM628 on the device clock (spec pcd4h3.md §5.1): batches of samples while it moves,
nothing once it settles."""

from __future__ import annotations

from devsim.core.clock import VirtualClock
from devsim.devices.pcd4h3.lm628 import COMPLETE, Lm628
from devsim.devices.pcd4h3.pid import Motor
from devsim.devices.pcd4h3.stepper import ChipStepper
from devsim.devices.pcd4h3.units import CHIP_SAMPLE


def _chip() -> Lm628:
    chip = Lm628(Motor(kv=10_000.0, tau=0.020))
    chip.reset()
    chip.port(12)
    chip.load_filter(0x030F, [40, 0, 400, 500])
    chip.update_filter()
    return chip


def test_a_move_runs_on_the_clock_and_the_chip_then_rests() -> None:
    clock = VirtualClock()
    chip = _chip()
    stepper = ChipStepper(chip, clock)
    chip.load_trajectory(0x002A, [76, 1_117_389, 100_000])
    chip.start()
    stepper.poke()
    clock.advance(3.17)
    stepper.catch_up()
    assert 30_000 < chip.actual < 70_000 and stepper.active  # half-way, on the way
    clock.advance(10)
    assert chip.status & COMPLETE and abs(chip.actual - 100_000) <= 2
    assert not stepper.active and clock.next_event() is None  # settled: no timer, no CPU


def test_batches_give_the_same_loop_as_single_samples() -> None:
    """However the looks fall, every sample is computed in order."""
    clock = VirtualClock()
    batched, single = _chip(), _chip()
    stepper = ChipStepper(batched, clock)
    for chip in (batched, single):
        chip.load_trajectory(0x002A, [76, 1_117_389, 100_000])  # (still moving at the end)
        chip.start()
    stepper.poke()
    for _ in range(400):
        clock.advance(0.0137)
        stepper.catch_up()
    for _ in range(int(400 * 0.0137 / CHIP_SAMPLE + 1e-9)):
        single.sample()
    assert batched.actual == single.actual and batched.motor.position == single.motor.position
