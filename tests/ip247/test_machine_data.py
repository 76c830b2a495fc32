"""The IP247's machine-data record, its checks and the ramp (spec ip247.md §3.4.1, §4.4, §5.2,
§5.3; vectors §6.1–§6.3)."""

from __future__ import annotations

import msgspec
import pytest

from devsim.devices.ip247.machine_data import Ramp, check, decode, encode
from devsim.devices.ip247.tables import MACHINE_DATA

MANUAL = """
0046 0044 4201 0001 0100 0000 1388 0000 00C8 0000
C350 001E 0040 0004 00C8 0000 07D0 0000 0BB8 0000
0BB8 0000 0BB8 0000 0BB8 0000 0020 0000 0000 FFF9
E580 0007 A120 0001 0000 08FC 0000 0000 0000 2710
0000 61A8 0000 0CB2 FFFE DB08 0000 0000 0000 0000
""" + " 0000" * 20
COM247 = """
0046 0044 427B 0B01 0100 0001 86A0 0000 2710 0001
86A0 0001 0040 000A 03E8 0000 044C 0000 03E8 0000
03E8 0000 03E8 0000 03E8 0001 0020 0000 03E8 FFFF
D8F0 0007 A120 0001 0000 0000 0000 03E8 0000 0000
0000 0000 0000 0000 0000 0000 0000 0001 0000 0000
""" + " 0000" * 20


def words(text: str) -> list[int]:
    return [int(w, 16) for w in text.split()]


def test_the_manuals_example_record_decodes_and_is_valid() -> None:
    """§6.1: valid with SYS-ID module 0 and the NC limit inputs at 24 V; r = 10 µm/pulse,
    v_max = 3000 mm/min, τ = 101.05 ms; with module ≠ 0: MD error 12."""
    md = decode(words(MANUAL))
    assert (md.db, md.module, md.axis, md.unit, md.f_max, md.f_ss, md.a) == (1, 0, 1, 1, 5000, 200, 50_000)
    assert (md.limit_begin, md.limit_end, md.zero_offsets) == (-400_000, 500_000, (10_000, 25_000, 3_250, -75_000))
    assert md.tool_length == 2300 and md.reference_direction == 0x20 and md.limit_polarity == 1
    assert encode(md) == words(MANUAL)
    assert md.resolution == 10 and md.v_max == 3000 and md.ramp.tau * 1000 == pytest.approx(101.05, abs=0.01)
    assert check(md, sys_module=0, limit_levels=(True, True)) == 0
    assert check(md, sys_module=5, limit_levels=(True, True)) == 12


def test_every_machine_data_row_names_a_value_of_the_record() -> None:
    """Each row of the machine-data table (spec §4.8) names, by its ``attr``, a value the model
    reads on the decoded record."""
    md = decode(words(COM247))
    missing = [row.key for row in MACHINE_DATA if not isinstance(getattr(md, row.attr, None), int)]
    assert missing == []


def test_the_com247_screen_example_is_valid() -> None:
    """§6.2: valid with SYS-ID module 11; r = 1.1 µm, v_max = 6600 mm/min, 1000 mm/min is
    15 151.5 Hz, τ = 947.37 ms."""
    md = decode(words(COM247))
    assert (md.db, md.module, md.bcd, md.backlash, md.reference) == (123, 11, True, 1000, 1000)
    assert md.resolution == pytest.approx(1.1) and md.v_max == pytest.approx(6600)
    assert md.frequency(1000) == pytest.approx(15_151.5, abs=0.1) and md.ramp.tau * 1000 == pytest.approx(947.37, abs=0.01)
    assert check(md, sys_module=11, limit_levels=(True, True)) == 0


#: Spec §6.3: a change to the §6.1 record, the two limit inputs (True = 24 V), the MD error.
SECTION_6_3: list[tuple[dict[str, object], tuple[bool, bool], int]] = [
    ({"pulse_us": 32}, (True, True), 2),
    ({"pulse_us": 30, "f_max": 20_000}, (True, True), 2),
    ({"f_max": 39}, (True, True), 3),
    ({"jog1": 0}, (True, True), 4),
    ({"step_velocity": 3001}, (True, True), 4),
    ({"pulses_per_rev": 11}, (True, True), 5),
    ({"a": 19}, (True, True), 6),
    ({"a": 1000}, (True, True), 6),
    ({"limit_begin": 600_000}, (True, True), 7),
    ({"reference": 600_000}, (True, True), 8),
    ({"gear": 199}, (True, True), 9),
    ({"patterns": 3}, (True, True), 10),
    ({"patterns": 7}, (True, True), 10),
    ({"unit": 4}, (True, True), 11),
    ({"module": 12}, (True, True), 12),
    ({"zero_offsets": (99_700_000, 0, 0, 0)}, (True, True), 13),
    ({"tool_length": 99_600_000}, (True, True), 14),
    ({"reference_direction": 0x10}, (True, True), 15),
    ({"reference_sync": 2}, (True, True), 15),
    ({"reference_velocity": 100}, (True, True), 17),
    ({"pulse_polarity": 0x20}, (True, True), 18),
    ({}, (True, False), 19),  # NC contacts: an input at 0 V is actuated
    ({"backlash": 65_000}, (True, True), 20),
    ({"rotary": True, "limit_begin": 600_000}, (True, True), 21),
    ({"f_ss": 0}, (True, True), 22),
    ({"f_ss": 5000}, (True, True), 22),
]


@pytest.mark.parametrize(("changes", "levels", "error"), SECTION_6_3)
def test_each_trigger_of_section_6_3(changes: dict[str, object], levels: tuple[bool, bool], error: int) -> None:
    md = msgspec.structs.replace(decode(words(MANUAL)), **changes)
    assert check(md, sys_module=0, limit_levels=levels) == error


@pytest.mark.parametrize(
    ("f_max", "f_ss", "a", "big_f", "tau_ms", "t_v_ms", "pulses"),
    [
        (5000, 200, 50, 5052.63, 101.05, 302.73, 1105.1),
        (100_000, 10_000, 100, 94_736.8, 947.37, 2838.1, 211_986.5),
        (30_000, 500, 20, 31_052.6, 1552.6, 4651.3, 100_957.1),
    ],
)
def test_the_ramp_vectors_of_section_5_3(f_max: float, f_ss: float, a: float, big_f: float, tau_ms: float,
                                         t_v_ms: float, pulses: float) -> None:
    ramp = Ramp(f_max, f_ss, a)
    assert ramp.big_f == pytest.approx(big_f, rel=1e-5)
    assert ramp.tau * 1000 == pytest.approx(tau_ms, rel=1e-4)
    assert ramp.time_to(f_max) * 1000 == pytest.approx(t_v_ms, rel=1e-4)
    assert ramp.pulses_to(f_max) == pytest.approx(pulses, rel=1e-4)
