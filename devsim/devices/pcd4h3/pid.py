"""The LM628's PID filter and the motor it drives, one sample at a time (spec pcd4h3.md §3.5.5,
§5.3, §5.4 ``pid`` mode, §5.5, §5.11; LM628 datasheet).

Filter arithmetic as the spec fixes it: the error e = desired − actual saturates to 16 bits; the
error sum is kept to 24 bits and its term I = ki · (Σe / 256) is limited to ±il (the sum stops
growing where the term reaches il, so it does not wind up beyond the limit: a decision, §5.3); the derivative
d = e(n') − e(n'−1) is taken every ds + 1 samples and kd · d held in between; the output word
u = sat16(kp·e + I + kd·d) goes out as the top 12 bits (offset binary around 800h, ±10 V) or the
top 8 bits (PWM, −128 … +127).  New coefficients act only after UDF.

The motor is a velocity source with a time constant (§5.4): dv/dt = (Kv · U − v) / τm, solved
exactly over each sample, so following error and overshoot come from the loop.  Pure: the caller
steps it.
"""

from __future__ import annotations

import math

import msgspec

__all__ = ["Coefficients", "Filter", "Motor", "sat"]


def sat(value: int, bits: int) -> int:
    """Saturate to a signed ``bits``-bit integer."""
    top = (1 << (bits - 1)) - 1
    return max(-top - 1, min(top, value))


class Coefficients(msgspec.Struct, frozen=True):
    """LFIL's words (§3.5.5): kp, ki, kd, il 0 … 7FFFh, and the derivative interval ds."""

    kp: int = 0
    ki: int = 0
    kd: int = 0
    il: int = 0
    ds: int = 0


class Filter:
    """The PID filter of one axis."""

    def __init__(self, dac_bits: int = 12) -> None:
        self.buffer = Coefficients()  # LFIL writes here
        self.working = Coefficients()  # UDF copies it here
        self.dac_bits = dac_bits
        self.error_sum = 0
        self.derivative = 0
        self._previous = 0  # e at the last derivative sample
        self._countdown = 0
        self.output = 0  # the last output word (u16)
        self.integral = 0  # the last integration term (RDSUM)

    def update(self) -> None:
        """UDF: the buffered coefficients take effect."""
        self.working = self.buffer

    def reset(self) -> None:
        self.error_sum = self.derivative = self._previous = self._countdown = self.output = self.integral = 0

    def sample(self, desired: int, actual: int) -> int:
        """One sample: the output word for error ``desired − actual``."""
        c = self.working
        e = sat(desired - actual, 16)
        limit = (c.il * 256 + c.ki - 1) // c.ki if c.ki else 1 << 23  # the sum stops where the term reaches il
        self.error_sum = max(-limit, min(limit, sat(self.error_sum + e, 24)))
        self.integral = max(-c.il, min(c.il, c.ki * (int(self.error_sum / 256))))
        if self._countdown == 0:
            self.derivative = e - self._previous
            self._previous = e
            self._countdown = c.ds
        else:
            self._countdown -= 1
        self.output = sat(c.kp * e + self.integral + c.kd * self.derivative, 16)
        return self.output

    @property
    def dac(self) -> int:
        """The output code: 12 bits offset binary (800h = 0 V) or 8 bits signed (PWM)."""
        if self.dac_bits == 12:
            return (self.output >> 4) + 0x800
        return self.output >> 8

    @property
    def volts(self) -> float:
        """The analog output: ±10 V for the 12-bit DAC (the PWM duty as −1 … +1 otherwise)."""
        if self.dac_bits == 12:
            return (self.output >> 4) / 2048 * 10.0
        return (self.output >> 8) / 128


def _lag_terms(t: float, tau: float) -> tuple[float, float, float]:
    """e^(−t/τ), 1 − e^(−t/τ) and t − τ·(1 − e^(−t/τ)), without cancellation when t ≪ τ (a
    motor that is nearly a pure inertia)."""
    x = t / tau
    gained = -math.expm1(-x)
    if x < 1e-3:
        travelled = tau * x * x * (0.5 - x / 6 + x * x / 24)
    else:
        travelled = t - tau * gained
    return 1.0 - gained, gained, travelled


class Motor:
    """Amplifier and motor as a velocity source with a lag: dv/dt = (Kv · U − v) / τm."""

    def __init__(self, kv: float = 10_000.0, tau: float = 0.020, *, low: float = -math.inf,
                 high: float = math.inf) -> None:
        self.kv, self.tau = kv, tau  # counts/s per volt; seconds
        self.position = 0.0  # counts
        self.velocity = 0.0  # counts/s
        self.blocked = False
        self.load = 0.0  # a load torque, as the volts that would hold it (S21)
        self.low, self.high = low, high  # mechanical end stops (S12)
        self._decay: tuple[float, float, float, float] = (0.0, 1.0, 0.0, 0.0)  # the last step's terms

    def step(self, volts: float, seconds: float) -> None:
        """Hold ``volts`` for ``seconds``: the exact solution of the first-order lag."""
        if self.blocked:
            self.velocity = 0.0
            return
        goal = self.kv * (volts - self.load)
        if self.tau <= 0:
            self.position += goal * seconds
            self.velocity = goal
        else:
            if self._decay[0] != seconds:
                self._decay = (seconds, *_lag_terms(seconds, self.tau))
            _, kept, gained, travelled = self._decay
            # v(t) = v0·e^(−t/τ) + goal·(1 − e^(−t/τ)); x(t) = x0 + v0·τ·(1 − e^(−t/τ)) + goal·(t − τ·(1 − e^(−t/τ)))
            self.position += self.velocity * self.tau * gained + goal * travelled
            self.velocity = self.velocity * kept + goal * gained
        if not self.low <= self.position <= self.high:
            self.position = min(self.high, max(self.low, self.position))
            self.velocity = 0.0

    @property
    def counts(self) -> int:
        """What the encoder reports: whole counts."""
        return math.floor(self.position)
