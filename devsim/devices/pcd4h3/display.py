"""The PCA2.D14 display as DP14 fills it (manual §7.4 DP14, DPB14; spec pcd4h3.md §3.4, §6.7,
G-18, G-19): two lines of six characters per axis.

* DplM = 1, two values of six digits: ``v x x x x x`` per line, where v is the most significant
  digit for 0 … 999 999, ``A`` above (overflow), ``-`` for −1 … −99 999 and ``U`` below
  (underflow); after A and U come the five low-order digits.
* DplM = 0, one value of ten digits: top line ``b v 1 2 3 4``, bottom line ``5 … 10`` (b blank,
  v blank or ``-``).

Right-aligned, leading zeros blank (the spec's decision for what the manual leaves open).  Pure.
"""

from __future__ import annotations

__all__ = ["BLANK", "six_digits", "ten_digits"]

BLANK = ("      ", "      ")  # after DPB14 or before the first DP14


def six_digits(value: int) -> str:
    """One line of the 2×6 format."""
    if value > 999_999:
        return "A" + f"{value % 100_000:05d}"
    if value < -99_999:
        return "U" + f"{-value % 100_000:05d}"
    if value < 0:
        return "-" + f"{-value:>5d}"
    return f"{value:>6d}"


def ten_digits(value: int) -> tuple[str, str]:
    """The two lines of the 1×10 format."""
    digits = f"{abs(value):010d}"[-10:]
    shown = digits.lstrip("0") or "0"
    padded = shown.rjust(10)
    sign = "-" if value < 0 else " "
    return " " + sign + padded[:4], padded[4:]
