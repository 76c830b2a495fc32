"""Numbers of the PCD4.H3 library (spec pcd4h3.md §4.6, §5.1, §6.1): the machine factor in
Motorola Fast Floating Point, and the conversions of user units into the LM628's counts,
velocity and acceleration registers.

FFP (the PCD's floating-point format): bits 31…8 a normalised 24-bit mantissa m (MSB set), bit 7
the sign, bits 6…0 the exponent e excess 64; value = m / 2^24 · 2^(e − 64), 0 when m = 0.  The
function blocks convert with the sample time they assume, 341 µs (the chip really samples every
2048 / 6 MHz = 341.333 µs, so speeds come out 0.1 % low): V = v·k·65536·T, A = a·k·65536·T²,
rounded half away from zero.  Pure functions.
"""

from __future__ import annotations

import math

__all__ = [
    "CHIP_SAMPLE", "CHIP_SAMPLE_US", "FB_SAMPLE", "FFP_MAX", "acceleration_register", "counts", "ffp_decode", "ffp_encode",
    "round_half_away", "velocity_register",
]

FB_SAMPLE = 341e-6  # seconds: what the function blocks' constants 22348e-6 and 76206e-9 assume
CHIP_SAMPLE = 2048 / 6e6  # seconds: the LM628's sample period at 6 MHz
CHIP_SAMPLE_US = 2048 / 6  # the same in µs (the configuration's chip_sample_time_us)
FFP_MAX = 0xFFFFFF7F  # 9.2233715e18


def round_half_away(value: float) -> int:
    return int(math.copysign(math.floor(abs(value) + 0.5), value))


def ffp_decode(pattern: int) -> float:
    """The value of a 32-bit FFP pattern (an integer such as 00000064h decodes to 0.0)."""
    pattern &= 0xFFFF_FFFF
    mantissa, sign, exponent = pattern >> 8, pattern >> 7 & 1, pattern & 0x7F
    if mantissa == 0:
        return 0.0
    value = mantissa / (1 << 24) * 2.0 ** (exponent - 64)
    return -value if sign else value


def ffp_encode(value: float) -> int:
    """The FFP pattern nearest ``value`` (beyond the range: the largest magnitude; tiny: 0)."""
    if value == 0 or math.isnan(value):
        return 0
    sign = 0x80 if value < 0 else 0
    magnitude = abs(value)
    if math.isinf(magnitude):
        return FFP_MAX | sign
    fraction, exponent = math.frexp(magnitude)  # magnitude = fraction · 2^exponent, 0.5 ≤ fraction < 1
    mantissa = round(fraction * (1 << 24))
    if mantissa == 1 << 24:
        mantissa, exponent = 1 << 23, exponent + 1
    biased = exponent + 64
    if biased > 0x7F:
        return FFP_MAX | sign
    if biased < 0:
        return 0
    return mantissa << 8 | sign | biased


def counts(value: float, k: float) -> int:
    """A position or distance in user units as encoder counts (k = 4 · lines / unit)."""
    return round_half_away(value * k)


def velocity_register(velocity: float, k: float, sample: float = FB_SAMPLE) -> int:
    """The LM628 velocity word: counts per sample · 2^16 (16.16 fixed point)."""
    return round_half_away(velocity * k * 65536 * sample)


def acceleration_register(acceleration: float, k: float, sample: float = FB_SAMPLE) -> int:
    """The LM628 acceleration word: counts per sample² · 2^16."""
    return round_half_away(acceleration * k * 65536 * sample * sample)
