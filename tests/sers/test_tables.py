"""Tests for the SERS data tables: errno texts, parameter table, weighting/units helpers."""

from __future__ import annotations

import math

import msgspec
import pytest

from devsim.devices.sers import errors, parameters, units
from devsim.devices.sers.errors import ERRNO, SersError, message
from devsim.devices.sers.parameters import (
    ALIASES,
    BIT_ADDRESSES,
    COMMAND_VALUES,
    CURRENT_MAX_MA,
    FACTORY_DEFAULTS,
    PARAMETER_MASKS,
    PARAMETER_TABLE,
    PARAMETERS,
    PROGRAM_MASKS,
    SAVED,
    SAVED_WITH_P1117,
    SUPPLY_THRESHOLDS,
    WEIGHTED,
)
from devsim.devices.sers.units import (
    ACCEL_WEIGHTINGS,
    POSITION_WEIGHTINGS,
    VELOCITY_WEIGHTINGS,
    Scaling,
    format_fixed,
    format_query,
    parse_number,
    quantize,
)

# ------------------------------------------------------------------------------------------------
# errors
# ------------------------------------------------------------------------------------------------


def test_errno_table_complete():
    assert sorted(ERRNO) == list(range(1, 126))
    for german, english in ERRNO.values():
        assert german and english
        assert german == german.strip()


@pytest.mark.parametrize(
    ("errno", "text"),
    [
        (1, "zu groß"),
        (3, "ungültig"),
        (13, "Parameter nicht vorhanden"),
        (19, "* nur bei P1 oder z erlaubt"),
        (21, "Anweisung erwartet"),
        (34, "= oder ? erwartet"),
        (44, "Programm läuft noch"),
        (74, "unbekannter Opcode, return vergessen ?"),
        (78, "Endschalter offen"),
        (94, "Die Lötbrücke ist fuer diesen Bereich falsch eingestellt."),
        (102, "Division durch 0"),
        (110, "<= 0 erwartet"),
        (111, "= 0 erwartet"),
        (114, "> erwartet"),
        (116, "= erwartet"),
        (119, "A zu klein"),
        (120, "A zu groß"),
        (122, "V zu groß"),
        (124, "RS232 Pufferüberlauf"),
        (125, "Schrittwinkelfehler"),
    ],
)
def test_errno_exact_texts(errno, text):
    assert message(errno) == text


def test_texts_110_to_117_are_ascii_and_latin1_encodable():
    assert [n for n in range(110, 118) if not message(n).isascii()] == []
    assert [german for german, _ in ERRNO.values() if any(ord(c) > 0xFF for c in german)] == []


def test_message_english_and_detail():
    assert message(122, english=True) == "V too large"
    assert message(83, detail="5") == "label bereits definiert: L5"
    with pytest.raises(KeyError):
        message(126)


def test_sers_error():
    with pytest.raises(SersError) as info:
        raise SersError(122)
    assert info.value.errno == 122
    assert info.value.text() == "V zu groß"
    assert info.value.text(english=True) == "V too large"
    assert SersError(83, "7").text() == "label bereits definiert: L7"
    with pytest.raises(ValueError):
        SersError(0)


def test_named_errnos():
    expected = {
        "TOO_LARGE": 1,
        "TOO_SMALL": 2,
        "INVALID": 3,
        "INVALID_OUTPUT": 4,
        "EEPROM_FULL": 5,
        "ACCESS_DENIED": 12,
        "NO_PARAMETER": 13,
        "TEXT_ONLY_IN_PGM": 16,
        "STATEMENT_EXPECTED": 21,
        "PGM_NOT_ACTIVE": 22,
        "EQ_OR_QUERY_EXPECTED": 34,
        "PROGRAM_RUNNING": 44,
        "PGM_NOT_ACTIVE_2": 46,
        "SERVICE_SWITCH_ON": 65,
        "DRIVE_ERROR_PRESENT": 66,
        "STOP_SWITCH_ACTIVE": 67,
        "STOP_SWITCH_OPEN": 68,
        "NO_VALID_PROGRAM": 69,
        "JUMP_TARGET_UNKNOWN": 71,
        "JUMP_TARGET_INVALID": 72,
        "STACK_OVERFLOW": 73,
        "LIMIT_OPEN": 78,
        "NOT_ENABLED": 79,
        "MUST_RUN_CONSTANT_OR_STAND": 81,
        "LABEL_ALREADY_DEFINED": 83,
        "NOT_WRITABLE_WHILE_MOVING": 93,
        "NEG_LIMIT_ABOVE_POS_LIMIT": 95,
        "RESULT_TOO_LARGE": 98,
        "RESULT_TOO_SMALL": 99,
        "DIVISION_BY_ZERO": 102,
        "READ_ONLY": 105,
        "WRITE_ONLY": 106,
        "POLY_WITH_BACKLASH": 107,
        "NO_POLY_DATA": 108,
        "A_TOO_SMALL": 119,
        "A_TOO_LARGE": 120,
        "V_TOO_SMALL": 121,
        "V_TOO_LARGE": 122,
        "BUFFER_OVERFLOW": 124,
        "STEP_ANGLE_ERROR": 125,
    }
    for name, value in expected.items():
        assert getattr(errors, name) == value, name
    for name in errors.__all__:
        value = getattr(errors, name)
        if isinstance(value, int):
            assert value in ERRNO, name


# ------------------------------------------------------------------------------------------------
# parameters
# ------------------------------------------------------------------------------------------------

EXPECTED_ALIASES = {
    "A": 138,
    "B": 1096,
    "ADC": 1046,
    "C1": 100,
    "C2": 101,
    "C3": 102,
    "D": 1100,
    "D2": 1164,
    "DB": 1165,
    "M1": 1101,
    "M2": 1102,
    "M3": 1103,
    "IN": 1300,
    "POS": 336,
    "V": 91,
    "W": 47,
    "WA": 1052,
    "WR": 1051,
    "WP": 1111,
    "WRP": 1112,
    "WAP": 1113,
    "WPT": 1114,
    "WRPT": 1115,
    "WAPT": 1116,
    "X": 1047,
    "Z": 1,
    "LP": 1042,
    **{f"O{i}": 1200 + i for i in range(1, 17)},
    **{f"R{i}": 1080 + i for i in range(6)},
}


def test_aliases_exact():
    assert ALIASES == EXPECTED_ALIASES
    for alias, number in ALIASES.items():
        assert PARAMETER_TABLE.lookup(alias).key == number
        assert PARAMETER_TABLE.lookup(alias.lower()).key == number
        assert alias in PARAMETERS[number].aliases


def test_non_simple_aliases_not_in_aliases():
    for word in ("ON", "OFF", "J1", "J5", "I1", "I16", "RUN", "PSAVE", "H"):
        assert word not in ALIASES
    assert COMMAND_VALUES["ON"] == (134, 7)
    assert COMMAND_VALUES["OFF"] == (134, 0)
    assert COMMAND_VALUES["PSAVE"] == (1004, 2)
    assert COMMAND_VALUES["POSSAVE"] == (1004, 4)
    assert COMMAND_VALUES["RF"] == (1031, 8)
    assert COMMAND_VALUES["H"] == (1031, 16)
    assert BIT_ADDRESSES["I4"] == (1300, 8, False)
    assert BIT_ADDRESSES["I9"] == (1301, 1, False)
    assert BIT_ADDRESSES["J1"] == (1013, 8, True)
    assert BIT_ADDRESSES["J3"] == (1013, 1, True)
    for p, value in COMMAND_VALUES.values():
        d = PARAMETERS[p]
        assert d.choices is None or value in d.choices


def test_lookup_p_numbers_and_errors():
    assert PARAMETER_TABLE.lookup("P91").name == "Geschwindigkeit - Positionieren"
    assert PARAMETER_TABLE.lookup("p 1010").key == 1010
    assert PARAMETER_TABLE.lookup(" v ").key == 91
    for bad in ("P9999", "P1074", "Q", "", "ON", "P"):
        with pytest.raises(KeyError):
            PARAMETER_TABLE.lookup(bad)


def test_every_listed_parameter_present():
    # §4.7 overview list + P3 (§4.8.5.5)
    listed = {0, 1, 2, 3, 11, 12, 41, 42, 44, 47, 51, 76, 91, 100, 101, 102, 103, 108, 121, 122, 123}
    listed |= {134, 138, 147, 160, 265, 336, 403}
    listed |= set(range(1001, 1048)) | set(range(1050, 1069)) | set(range(1070, 1074))
    listed |= set(range(1080, 1086)) | set(range(1092, 1104)) | set(range(1110, 1128))
    listed |= {1129, 1130, 1131, 1132, 1133, 1134, 1135, 1136, 1137, 1138, 1139, 1140, 1141, 1142}
    listed |= set(range(1143, 1151)) | set(range(1152, 1166))
    listed |= set(range(1201, 1217)) | {1300, 1301}
    listed -= {1048, 1049, 1069, 1151}
    assert listed <= set(PARAMETERS)
    assert listed == set(PARAMETERS)


def test_paramdef_consistency():
    for n, d in PARAMETERS.items():
        assert d.key == n
        assert isinstance(d, msgspec.Struct)
        assert d.name and d.doc
        assert d.extra["kind"] in ("int", "position", "velocity", "acceleration", "fixed")
        if d.extra["kind"] == "fixed":
            assert d.decimals > 0
        assert d.readable or d.writable
        if d.minimum is not None and d.maximum is not None:
            assert d.minimum <= d.maximum
        if d.default is not None and d.writable:
            if d.choices is not None:
                assert d.default in d.choices, n
        if d.saved or d.extra["saved_with_p1117"]:
            assert d.writable or n == 1034
        d.name.encode("latin-1")
    with pytest.raises(AttributeError):
        PARAMETERS[91].minimum = 1  # type: ignore[misc]


@pytest.mark.parametrize(
    ("number", "minimum", "maximum", "choices"),
    [
        (76, None, None, {0, 64, 2, 66, 1, 17}),
        (44, None, None, {0, 64, 2, 66, 1, 17}),
        (160, None, None, {0, 64, 2, 66, 1, 17}),
        (1004, None, None, {2, 3, 4, 5}),
        (1031, None, None, {1, 2, 4, 8, 16}),
        (134, None, None, {0, 7}),
        (0, None, None, {0, 1, 2}),
        (1014, None, None, {0, 1, 2, 3}),
        (1300, 0, 255, None),
        (1021, 0, 255, None),
        (1036, -4, 4, None),
        (1025, -7, 7, None),
        (1160, -8, 8, None),
        (108, 0, 100, None),
        (147, 0, 511, None),
        (1028, 0, 31, None),
        (100, 0, 65535, None),
        (102, 0, 4294967295, None),
        (1053, 0, 10, None),
        (1143, 0, 5, None),
        (1059, 0, 9999, None),
        (1060, 0, 65535, None),
        (1139, 0, 327.6, None),
        (1054, -32.768, 32.767, None),
        (1164, 0, 6553.5, None),
        (1010, 0, 14500, None),  # the largest version (12 A); a drive refuses above its own (§4.8.6.1)
        (1, 0, 127, None),
        (138, 2, 100000, None),
        (91, 0, 10000, None),
        (47, -214748.3647, 214748.3647, None),
    ],
)
def test_ranges_and_choices(number, minimum, maximum, choices):
    d = PARAMETERS[number]
    assert d.minimum == minimum
    assert d.maximum == maximum
    assert (frozenset(d.choices) if d.choices is not None else None) == (
        frozenset(choices) if choices is not None else None
    )


def test_special_errnos():
    assert (PARAMETERS[91].extra["too_large_errno"], PARAMETERS[91].extra["too_small_errno"]) == (122, 121)
    assert (PARAMETERS[138].extra["too_large_errno"], PARAMETERS[138].extra["too_small_errno"]) == (120, 119)
    assert (PARAMETERS[1024].extra["too_large_errno"], PARAMETERS[1024].extra["too_small_errno"]) == (88, 89)
    assert (PARAMETERS[1026].extra["too_large_errno"], PARAMETERS[1026].extra["too_small_errno"]) == (90, 91)
    assert PARAMETERS[103].extra["too_large_errno"] == 92
    assert PARAMETERS[1014].extra["invalid_errno"] == 80
    assert PARAMETERS[0].extra["invalid_errno"] == 82
    assert PARAMETERS[1004].extra["invalid_errno"] == 82
    assert PARAMETERS[1034].extra["write_errno"] == 12
    assert PARAMETERS[1].extra["too_large_errno"] == 1
    assert PARAMETERS[91].extra["min_exclusive"]


def test_kinds_and_decimals():
    assert PARAMETERS[47].extra["kind"] == "position"
    assert PARAMETERS[91].extra["kind"] == "velocity"
    assert PARAMETERS[138].extra["kind"] == "acceleration"
    assert (PARAMETERS[1100].extra["kind"], PARAMETERS[1100].decimals) == ("fixed", 1)
    assert (PARAMETERS[1054].extra["kind"], PARAMETERS[1054].decimals) == ("fixed", 5)
    assert (PARAMETERS[1139].extra["kind"], PARAMETERS[1139].decimals) == ("fixed", 1)
    assert (PARAMETERS[1046].extra["kind"], PARAMETERS[1046].decimals) == ("fixed", 3)
    assert PARAMETERS[1010].extra["kind"] == "int"
    assert {47, 51, 103, 1024, 1026, 1037, 1039, 1040, 1041, 1044, 1051, 1052} <= WEIGHTED
    assert {91, 41, 1003, 1019, 1020, 138, 42, 1018, 1030, 1096, 1012} <= WEIGHTED
    assert 1010 not in WEIGHTED and 76 not in WEIGHTED


def test_access():
    for n in (1300, 1301, 336, 1013, 1042, 1133, 1137, 403, 1015, 1016, 1123, 1165, 1046):
        assert not PARAMETERS[n].writable, n
        assert PARAMETERS[n].readable, n
    for n in (1004, 1031, 1043, 1051, 1052, 1111, 1116, 1097, 1099, 1100):
        assert PARAMETERS[n].writable and not PARAMETERS[n].readable, n
    for n in (47, 91, 138, 11, 12, 1047, 1080, 1201):
        assert PARAMETERS[n].readable and PARAMETERS[n].writable, n


def test_saved_sets():
    assert {76, 44, 160, 91, 138, 1010, 1017, 1021, 1117, 265, 103, 121, 122, 123} <= SAVED
    for n in (0, 1, 11, 12, 47, 51, 100, 1047, 1101, 1110, 1035, 1201, 1080):
        assert n not in SAVED, n
    assert SAVED_WITH_P1117 == {47, 1080, 1081, 1082, 1083, 1084, 1085}
    assert PARAMETERS[1080].extra["saved_with_p1117"]


def test_factory_defaults():
    d = FACTORY_DEFAULTS
    assert (d[76], d[44], d[160]) == (2, 2, 2)
    assert (d[121], d[122], d[123]) == (1, 1, 1)
    assert d[1135] == 7
    assert d[1139] == 1.0
    assert d[1002] == 255
    assert d[1110] == 1 and d[1035] == 1
    assert d[336] == 1 and d[403] == 3
    assert d[1161] == 128 and d[1163] == 3500 and d[1153] == 1000 and d[1159] == 10
    assert d[1133] == 120901
    assert d[1010] == CURRENT_MAX_MA["06"] // 2
    assert d[91] == 100 and d[138] == 100 and d[103] == 360
    assert 1004 not in d and 1031 not in d
    for n, value in d.items():
        p = PARAMETERS[n]
        if p.minimum is not None and value != 0:
            assert value >= p.minimum, n
        if p.maximum is not None:
            assert value <= p.maximum, n


def test_designations():
    assert PARAMETERS[123].name == "Vorschubkonstante"
    assert PARAMETERS[1025].name == "Vergleichsausgang 1"
    assert PARAMETERS[1060].name == "Parameter Maske [0]"
    assert PARAMETERS[1073].name == "Programm Maske [4]"
    assert PARAMETERS[1085].name == "Register 6"
    assert PARAMETERS[1216].name == "Ausgang 16"
    assert PARAMETERS[0].name == "E²PROM Modus"


def test_variant_tables():
    assert CURRENT_MAX_MA == {
        "01": 1400,
        "02": 2800,
        "03": 4200,
        "04": 4000,
        "06": 8400,
        "08": 8400,
        "12": 14500,
    }
    assert SUPPLY_THRESHOLDS["85"] == (85, 46, 43, 32)
    assert SUPPLY_THRESHOLDS["24"] == (36, 19, 18, 16)
    assert SUPPLY_THRESHOLDS["240"] == (240, 120, 100, 80)
    for u_v, u_w, u_b, u_l in SUPPLY_THRESHOLDS.values():
        assert u_v > u_w >= u_b > u_l
    assert parameters.DEFAULT_VARIANT == ("06", "85")


def test_masks():
    assert all(len(v) == 16 for v in PARAMETER_MASKS.values())
    # P1060 = 2144 (32 + 64 + 2048) -> P41, P42, P91
    mask = PARAMETER_MASKS[1060]
    assert [mask[i] for i in range(16) if 2144 >> i & 1] == [41, 42, 91]
    for masked in PARAMETER_MASKS.values():
        assert set(masked) <= set(PARAMETERS)
    # P1070 = 42 -> L2, L4, L6
    assert [PROGRAM_MASKS[1070][i] for i in range(16) if 42 >> i & 1] == [2, 4, 6]
    assert PROGRAM_MASKS[1073][-1] == 64


# ------------------------------------------------------------------------------------------------
# units
# ------------------------------------------------------------------------------------------------


def test_weighting_tables():
    assert POSITION_WEIGHTINGS == {
        0: ("inkr", 0),
        64: ("inkr", 0),
        2: ("°", 4),
        66: ("°", 4),
        1: ("mm", 4),
        17: ("in", 6),
    }
    assert VELOCITY_WEIGHTINGS[2] == ("U/min", 4)
    assert VELOCITY_WEIGHTINGS[1] == ("mm/min", 3)
    assert VELOCITY_WEIGHTINGS[17] == ("in/min", 5)
    assert ACCEL_WEIGHTINGS[2] == ("rad/s²", 3)
    assert ACCEL_WEIGHTINGS[1] == ("mm/s²", 3)
    assert ACCEL_WEIGHTINGS[17] == ("in/s²", 5)
    assert set(POSITION_WEIGHTINGS) == set(VELOCITY_WEIGHTINGS) == set(ACCEL_WEIGHTINGS)


def test_t22_translational_scaling():
    s = Scaling(p76=1, p44=1, p160=2, p121=2, p122=1, p123=5)
    assert s.pos_to_inc(2.5) == pytest.approx(12800)
    assert s.inc_to_pos(12800) == pytest.approx(2.5)
    assert s.pos_unit == "mm" and s.pos_decimals == 4
    assert s.vel_unit == "mm/min" and s.vel_decimals == 3
    assert format_query(s.inc_to_pos(12800), s.pos_decimals, s.pos_unit) == "2.5mm"
    # P103 = 2500 mm is a whole number of increments
    assert s.pos_to_inc(2500) == pytest.approx(12_800_000)
    # velocity 1, 17: inc/s = u/60 * g * 12800 / f  -> 150 mm/min = 1 motor rev/s
    assert s.vel_to_incps(150) == pytest.approx(12800)


def test_t05_default_weighting():
    s = Scaling()
    assert (s.pos_unit, s.vel_unit, s.acc_unit) == ("°", "U/min", "rad/s²")
    assert (s.pos_decimals, s.vel_decimals, s.acc_decimals) == (4, 4, 3)
    assert s.pos_to_inc(2500) == pytest.approx(2500 / 360 * 12800)
    assert s.vel_to_incps(1000) == pytest.approx(1000 * 12800 / 60)
    assert s.acc_to_incps2(100) == pytest.approx(100 * 12800 / (2 * math.pi))
    assert s.pos_to_inc(360) == pytest.approx(12800)


@pytest.mark.parametrize(
    ("p76", "inc_per_unit"),
    [(0, 1), (64, 8), (2, 12800 / 360), (66, 8 * 12800 / 360), (1, 8 * 12800 / 5), (17, 8 * 12800 / 5)],
)
def test_position_weightings_with_gear(p76, inc_per_unit):
    s = Scaling(p76=p76, p121=8, p122=1, p123=5)
    assert s.pos_to_inc(1) == pytest.approx(inc_per_unit)


@pytest.mark.parametrize(
    ("code", "vel", "acc"),
    [
        (0, 12800 / 60, 12800 / (2 * math.pi)),
        (2, 12800 / 60, 12800 / (2 * math.pi)),
        (64, 4 * 12800 / 60, 4 * 12800 / (2 * math.pi)),
        (66, 4 * 12800 / 60, 4 * 12800 / (2 * math.pi)),
        (1, 4 * 12800 / 60 / 2, 4 * 12800 / 2),
        (17, 4 * 12800 / 60 / 2 * 25.4, 4 * 12800 / 2 * 25.4),  # inches; P123 in mm (P76=2): 1 in = 25.4 mm
    ],
)
def test_velocity_and_accel_weightings(code, vel, acc):
    s = Scaling(p44=code, p160=code, p121=4, p122=1, p123=2)
    assert s.vel_to_incps(1) == pytest.approx(vel)
    assert s.acc_to_incps2(1) == pytest.approx(acc)


@pytest.mark.parametrize(("p76", "code", "mm_per_unit"), [(1, 1, 1), (17, 17, 1), (1, 17, 25.4), (17, 1, 1 / 25.4)])
def test_speeds_in_the_other_length_unit_than_p123(p76, code, mm_per_unit):
    """P123 is in the position length unit (G-UNITS); in/min and in/s² are inches also while it is
    in mm (P76=1), and mm/min, mm/s² millimetres while it is in inches (P76=17) (§4.8.4.6)."""
    s = Scaling(p76=p76, p44=code, p160=code, p121=2, p122=1, p123=5)
    same = Scaling(p76=p76, p44=p76, p160=p76, p121=2, p122=1, p123=5)
    assert s.vel_to_incps(1) == pytest.approx(same.vel_to_incps(1) * mm_per_unit)
    assert s.acc_to_incps2(1) == pytest.approx(same.acc_to_incps2(1) * mm_per_unit)


@pytest.mark.parametrize("code", sorted(units.WEIGHTING_CODES))
def test_round_trips(code):
    s = Scaling(p76=code, p44=code, p160=code, p121=3, p122=2, p123=7.5)
    for u in (0.0, 1.0, -12.3456, 1234.5):
        assert s.inc_to_pos(s.pos_to_inc(u)) == pytest.approx(u)
        assert s.incps_to_vel(s.vel_to_incps(u)) == pytest.approx(u)
        assert s.incps2_to_acc(s.acc_to_incps2(u)) == pytest.approx(u)
        for kind in ("position", "velocity", "acceleration"):
            assert s.from_internal(kind, s.to_internal(kind, u)) == pytest.approx(u)


def test_scaling_rejects_invalid():
    with pytest.raises(ValueError):
        Scaling(p76=3)
    with pytest.raises(ValueError):
        Scaling(p44=65)
    with pytest.raises(ValueError):
        Scaling(p122=0)


def test_pos_range_matches_manual():
    assert Scaling(p76=2).pos_range() == (-214748.3647, 214748.3647)
    assert Scaling(p76=1).pos_range() == (-167772.1599, 167772.1599)
    assert Scaling(p76=0).pos_range() == (-2147483639, 2147483639)  # §4.8.4.2


@pytest.mark.parametrize(
    ("value", "decimals", "unit", "text"),
    [
        (2.5, 4, "mm", "2.5mm"),
        (150, 4, "mm", "150mm"),
        (0, 4, "°", "0°"),
        (-0.0, 4, "°", "0°"),
        (1000, 4, "U/min", "1000U/min"),
        (25.5, 4, "°", "25.5°"),
        (100, 3, "rad/s²", "100rad/s²"),
        (-12.34, 4, "°", "-12.34°"),
        (0.00004, 4, "°", "0°"),
        (0.00005, 4, "°", "0.0001°"),
        (12800, 0, "inkr", "12800inkr"),
        (11, 0, "", "11"),
    ],
)
def test_format_query(value, decimals, unit, text):
    assert format_query(value, decimals, unit) == text


def test_format_fixed():
    assert format_fixed(500, 4) == "500.0000"
    assert format_fixed(2000, 3) == "2000.000"
    assert format_fixed(-0.0, 4) == "0.0000"
    assert format_fixed(-1.25, 1) == "-1.3"
    assert format_fixed(7, 0) == "7"
    assert format_fixed(0.1 + 0.2, 4) == "0.3000"


@pytest.mark.parametrize(
    ("text", "value"),
    [
        ("10", 10.0),
        ("10.75", 10.75),
        (".5", 0.5),
        ("-.5", -0.5),
        ("-2500", -2500.0),
        ("10.", 10.0),
        ("007", 7.0),
    ],
)
def test_parse_number_valid(text, value):
    assert parse_number(text) == value


@pytest.mark.parametrize(
    "text", ["", "-", ".", "1,5", "1e3", "+5", " 5", "5 ", "1.2.3", "--1", "abc", "0x10"]
)
def test_parse_number_invalid(text):
    with pytest.raises(ValueError):
        parse_number(text)


def test_quantize():
    assert quantize(2.675, 2) == 2.68
    assert quantize(-2.675, 2) == -2.68
    assert quantize(1.23456789, 4) == 1.2346
    assert quantize(0.00004, 4) == 0.0
    assert quantize(12800.4, 0) == 12800.0
    assert quantize(-0.0, 3) == 0.0
    assert math.copysign(1, quantize(-0.00001, 3)) == 1.0
    with pytest.raises(ValueError):
        quantize(math.inf, 2)


def test_each_accessor_reads_the_row_that_names_it() -> None:
    """(Checked here rather than at every import of the parameters: issue 31.)"""
    from devsim.devices.sers.params import SersParameters

    probe = SersParameters()
    named = [row for row in parameters.PARAMETER_TABLE if row.attr]
    assert len(named) > 50
    for row in named:
        mark = object()
        probe.values[row.key] = mark
        assert getattr(probe, row.attr, None) is mark, f"P{row.key}: the accessor {row.attr!r} does not read it"
