"""The LM628 filter and the motor model (spec pcd4h3.md §5.3, §5.4): the loop's step response
against the closed form, and the chip's arithmetic limits."""

from __future__ import annotations

import pytest

from devsim.devices.pcd4h3.pid import Coefficients, Filter, Motor, sat
from devsim.devices.pcd4h3.units import CHIP_SAMPLE


def test_proportional_step_on_a_pure_velocity_source_decays_geometrically() -> None:
    """P control of a motor without lag: each sample the error shrinks by the factor
    1 − Ts·Kv·kp·10/32768 (the output word's top 12 bits at ±10 V), so after n samples
    e(n) = e0 · (1 − g)^n, within the DAC's quantisation."""
    filt, motor = Filter(), Motor(kv=10_000.0, tau=0.0)
    filt.buffer = Coefficients(kp=30)
    filt.update()
    target, g = 1000, CHIP_SAMPLE * 10_000.0 * 30 * 10.0 / 32768
    errors = []
    for _ in range(40):
        filt.sample(target, motor.counts)
        errors.append(target - motor.position)
        motor.step(filt.volts, CHIP_SAMPLE)
    for n, error in enumerate(errors[:12]):
        assert error == pytest.approx(target * (1 - g) ** n, abs=n * 2 + 1)


def test_a_lag_makes_the_position_loop_overshoot() -> None:
    """With τm = 20 ms and a stiff P gain the loop rings: the position passes the target
    before settling (an underdamped second-order loop), which a formula for the following
    error would not show."""
    filt, motor = Filter(), Motor(kv=10_000.0, tau=0.020)
    filt.buffer = Coefficients(kp=200, kd=400, ds=0)
    filt.update()
    peak = 0.0
    for _ in range(3000):
        filt.sample(1000, motor.counts)
        motor.step(filt.volts, CHIP_SAMPLE)
        peak = max(peak, motor.position)
    assert peak > 1000
    assert motor.position == pytest.approx(1000, abs=2)


def test_coefficients_act_after_udf_and_limits_hold() -> None:
    filt = Filter()
    filt.buffer = Coefficients(kp=100, ki=50, il=300, ds=3)
    assert filt.sample(10, 0) == 0  # not updated yet
    filt.update()
    for _ in range(1000):
        filt.sample(20, 0)
    assert filt.integral == 300  # limited to il
    assert filt.output == sat(100 * 20 + 300, 16)
    assert Filter().sample(10**6, 0) == 0 and sat(10**6, 16) == 32767


def test_derivative_every_ds_plus_one_samples() -> None:
    filt = Filter()
    filt.buffer = Coefficients(kd=1, ds=2)
    filt.update()
    outputs = [filt.sample(e, 0) for e in (3, 6, 9, 12, 15, 18)]
    assert outputs == [3, 3, 3, 9, 9, 9]  # d taken at samples 0 and 3, held in between


def test_dac_codes() -> None:
    filt = Filter()
    filt.output = 0
    assert filt.dac == 0x800 and filt.volts == 0
    filt.output = 32767
    assert filt.dac == 0xFFF and filt.volts == pytest.approx(2047 / 2048 * 10)
    pwm = Filter(dac_bits=8)
    pwm.output = -32768
    assert pwm.dac == -128 and pwm.volts == -1.0
