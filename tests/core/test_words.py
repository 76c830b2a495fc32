"""The kit's machine words (devsim.core.words): the low 32 bits read as two's complement, at and
around each limit, against the rule written as an oracle."""

from __future__ import annotations

import hypothesis.strategies as hs
from hypothesis import example, given

from devsim.core.words import signed32


def _oracle(value: int) -> int:
    low = value % 2**32
    return low if low < 2**31 else low - 2**32


@given(hs.one_of(hs.integers(), hs.sampled_from([b + d for b in (0, 2**31, 2**32, -(2**31), 2**33) for d in (-1, 0, 1)])))
@example(0x7FFF_FFFF)
@example(0x8000_0000)
@example(0xFFFF_FFFF)
def test_the_low_32_bits_as_twos_complement(value: int) -> None:
    assert signed32(value) == _oracle(value)


def test_examples() -> None:
    assert [signed32(v) for v in (0, 1, 0x7FFF_FFFF, 0x8000_0000, 0xFFFF_FFFF, 2**32, -1, -(2**31) - 1)] == [
        0, 1, 2**31 - 1, -(2**31), -1, 0, -1, 2**31 - 1]
