"""Binary and BCD values and the small records of the IP247 (spec ip247.md §3.3.2, §3.4.3–§3.4.7)."""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as hs

from devsim.devices.ip247.values import (
    NotBcd,
    actual_values,
    md_directory,
    md_overview,
    path_from_plc,
    path_to_plc,
    program_directory,
    sys_id_record,
    velocity_from_plc,
)


def test_the_worked_example_of_section_3_3_2() -> None:
    """BA6 to ±120 000 µm; 1000 and 10 000 mm/min, binary and BCD."""
    assert path_from_plc(0x0001D4C0, bcd=False) == 120_000 and path_from_plc(0x00120000, bcd=True) == 120_000
    assert path_from_plc(0xFFFE2B40, bcd=False) == -120_000 and path_from_plc(0xF0120000, bcd=True) == -120_000
    assert velocity_from_plc(0x03E8, 0x55, bcd=False) == 1000 and velocity_from_plc(0x1000, 0, bcd=True) == 1000
    assert velocity_from_plc(0x2710, 0, bcd=False) == 10_000 and velocity_from_plc(0x1000, 1, bcd=True) == 10_000
    assert path_to_plc(-120_000, bcd=True) == (0xF0120000, False)
    assert path_to_plc(12_345_678, bcd=True) == (12_345_678, True)  # not representable: binary, flagged


def test_non_bcd_values_give_errors_66_and_67() -> None:
    with pytest.raises(NotBcd) as path:
        path_from_plc(0x0012A000, bcd=True)
    with pytest.raises(NotBcd) as sign:
        path_from_plc(0x50120000, bcd=True)
    with pytest.raises(NotBcd) as velocity:
        velocity_from_plc(0x10F0, 0, bcd=True)
    assert (path.value.error, sign.value.error, velocity.value.error) == (66, 66, 67)


@given(hs.integers(min_value=-9_999_999, max_value=9_999_999))
def test_bcd_paths_round_trip(value: int) -> None:
    raw, binary = path_to_plc(value, bcd=True)
    assert not binary and path_from_plc(raw, bcd=True) == value


def test_the_records_of_sections_3_4_3_to_3_4_7() -> None:
    """SYS-ID as in vector (a) of §3.6.7 (module 11, slot 1, page 0, A02.1); the directories and
    the overview of the manual's examples; actual values as in vector (c)."""
    assert sys_id_record(11, 1, 0) == [0x4950, 0x3234, 0x3720, 0x4130, 0x322E, 0x3120, 0x000B, 0x0001, 0x0000]
    assert md_directory([(1, 70), (5, 70), None]) == [1, 70, 5, 70, 0, 0]
    assert program_directory([(1, 25), (78, 44)]) == [1, 25, 78, 44]
    assert md_overview([(1, 0, 1, 70, 0), None, (3, 0, 3, 70, 0)]) == [1, 0, 1, 70, 0, 0, 0, 0, 0, 0, 3, 0, 3, 70, 0]
    assert actual_values(47_287, 12_602) == ([0x0000, 0xB8B7, 0, 0, 0x0000, 0x313A], 0)
    assert actual_values(47_287, 12_602, bcd=True) == ([0x0004, 0x7287, 0, 0, 0x0001, 0x2602], 0)
