"""The PCA2.D14 lines DP14 writes (spec pcd4h3.md §3.4, the vectors of §6.7)."""

from __future__ import annotations

import pytest

from devsim.devices.pcd4h3.display import six_digits, ten_digits


@pytest.mark.parametrize(("value", "line"), [
    (0, "     0"), (42, "    42"), (999_999, "999999"),  # 0 … 999 999: the digits
    (1_000_000, "A00000"), (1_234_567, "A34567"),  # above: A and the five low-order digits
    (-1, "-    1"), (-99_999, "-99999"),  # −1 … −99 999: a minus sign first
    (-100_000, "U00000"), (-2_147_483_647, "U83647"),  # below: U
])
def test_two_times_six_digits(value: int, line: str) -> None:
    assert six_digits(value) == line


def test_one_times_ten_digits() -> None:
    assert ten_digits(-2_147_483_647) == (" -2147", "483647")  # b v 1 2 3 4 / 5 … 10
    assert ten_digits(2_147_483_647) == ("  2147", "483647")
    assert ten_digits(5) == ("      ", "     5")
