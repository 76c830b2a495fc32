"""The IP247's values to and from the PLC at their limits (spec ip247.md §3.3.2, §3.4.3, §3.4.6):
the sign of BCD zero, which of position and residual stayed binary, and the SYS-ID record's
fixed-width text and byte fields."""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as hs

from devsim.devices.ip247.values import NotBcd, actual_values, path_from_plc, path_to_plc, sys_id_record

BCD_LIMIT = 9_999_999


def _bcd_oracle(value: int) -> int:
    """7 decades, one nibble each, the sign nibble F for a negative value (spec §3.3.2)."""
    digits = int(f"{abs(value):07d}", 16)
    return (0xF000_0000 if value < 0 else 0) | digits


@given(hs.one_of(hs.integers(-BCD_LIMIT, BCD_LIMIT), hs.sampled_from([0, 1, -1, BCD_LIMIT, -BCD_LIMIT])))
def test_a_bcd_path_to_the_plc(value: int) -> None:
    assert path_to_plc(value, bcd=True) == (_bcd_oracle(value), False)
    assert path_from_plc(_bcd_oracle(value), bcd=True) == value


def test_zero_is_sent_without_a_sign() -> None:
    assert path_to_plc(0, bcd=True) == (0x0000_0000, False)
    assert path_from_plc(0xF000_0000, bcd=True) == 0  # a "-0" from the PLC reads as 0


@pytest.mark.parametrize("position, residual, flags", [
    (1, 2, 0), (BCD_LIMIT + 1, 2, 1), (1, -BCD_LIMIT - 1, 2), (BCD_LIMIT + 1, -BCD_LIMIT - 1, 3)])
def test_the_flags_say_which_value_stayed_binary(position: int, residual: int, flags: int) -> None:
    words, got = actual_values(position, residual, bcd=True)
    assert got == flags
    assert words[2:4] == [0, 0]


def test_the_sys_id_record_has_fixed_fields() -> None:
    record = sys_id_record(0x10B, 0x101, 0x1FF, firmware="B1", module_type="IP2471X")  # too long, too short
    assert bytes(b for word in record[:6] for b in word.to_bytes(2, "big")) == b"IP2471B1    "
    assert record[6:] == [0x0B, 0x01, 0xFF]  # each a byte
    assert sys_id_record(1, 2, 3, module_type="IP")[:3] == [0x4950, 0x2020, 0x2020]  # "IP    "


def test_a_value_that_is_not_bcd_names_its_module_error() -> None:
    with pytest.raises(NotBcd, match="^module error 66: value not BCD-coded$"):
        path_from_plc(0x0000_000A, bcd=True)
