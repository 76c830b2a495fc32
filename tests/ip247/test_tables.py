"""The IP247's error and mode tables (spec ip247.md §3.2, §4.3–§4.5)."""

from __future__ import annotations

from devsim.devices.ip247.tables import (
    DATA_CHANNEL,
    MD_ERRORS,
    MODES,
    MODULE_ERRORS,
    SYNTAX_ERRORS,
    error_codes,
    page_error,
    pg_code,
)


def test_the_error_tables_are_complete() -> None:
    """Module errors 0 … 67 without the free numbers; MD errors 0 … 22; syntax errors 0 … 19
    without 7, and 37; the PG shows AG + 80H (F8A = 10, FBB = 59, FC1 = 65)."""
    free = {9, 11, 16, 21, 31, 32, 50, 60, 64}
    assert set(MODULE_ERRORS) == set(range(68)) - free
    assert set(MD_ERRORS) == set(range(23)) and set(SYNTAX_ERRORS) == (set(range(20)) - {7}) | {37}
    assert (pg_code(10), pg_code(59), pg_code(65), pg_code(0)) == ("F8A", "FBB", "FC1", "F80")
    assert len(error_codes()) == len(MODULE_ERRORS)


def test_page_rules() -> None:
    """§3.2: motion modes only on axis pages (46 on the data channel), programs only on the data
    channel, MD only on axis pages; BA18/19/72 and BA3 are refused everywhere (BA3 with 46 on the
    data channel, where §6.2.4 refuses every mode 1 … 16); BA67 on the data channel only when the MD
    DB numbers differ."""
    assert page_error(1, 1) is None and page_error(1, DATA_CHANNEL) == 46
    assert page_error(22, DATA_CHANNEL) is None and page_error(22, 2) == 46
    assert page_error(20, 3) is None and page_error(20, DATA_CHANNEL) == 46
    assert page_error(17, DATA_CHANNEL) is None and page_error(70, 1) is None
    assert {page_error(m, p) for m in (3, 18, 19, 72) for p in (1, 2, 3)} == {2}
    assert {page_error(m, DATA_CHANNEL) for m in (18, 19, 72)} == {2} and page_error(3, DATA_CHANNEL) == 46
    assert page_error(67, DATA_CHANNEL) == 46 and page_error(67, DATA_CHANNEL, md_numbers_differ=True) is None
    assert sorted(MODES)[:3] == [1, 2, 4] and MODES[68].name == "Maschinendatenübersicht"
