"""Tests for the GMS96 data tables (spec §4.3-§4.7, §4.12.4, §5.2; manual §2.3.1, §2.4.1, §2.7, §6)."""

from __future__ import annotations

import msgspec
import pytest

from devsim.core.parameters import Param
from devsim.devices.gms96 import tables as t

# Every N index of spec §4.6 / manual §2.3.1 N, with the manual's "Grundstellung" where it gives one.
MANUAL_N = {
    8: None,
    10: 200,
    11: 200,
    12: 0,
    13: 0,
    15: 84,
    16: 3,
    17: 0,
    19: None,
    20: 1000,
    21: 1,
    22: None,
    23: 1,
    24: 1,
    25: 0,
    26: 0,
    27: 0,
    28: None,
    32: None,
    33: None,
    34: 1200,
    35: 0,
    39: None,
    41: 0,
    42: None,
    43: None,
    44: None,
    45: None,
    50: 6,
    51: None,
    52: 0,
    53: 0,
    54: None,
    55: None,
    56: None,
}

MANUAL_N_RANGES = {
    10: (1, 3000),
    11: (50, 255),
    12: (0, 15),
    13: (0, 9999),
    15: (0, 255),
    16: (2, 6),
    20: (10, 15000),
    23: (1, 8),
    27: (-255, 255),
    28: (1, 255),
    39: (0, 100),
    41: (0, 255),
    42: (1, 255),
    52: (0, 6),
    53: (0, 6),
    17: (0, 1),
    21: (0, 1),
    22: (0, 1),
    24: (0, 1),
    25: (0, 1),
    26: (0, 1),
    32: (0, 1),
    51: (0, 1),
}


# ----------------------------------------------------------------------------- N parameters


def test_every_n_index_present() -> None:
    assert set(t.N_TABLE.rows) == set(MANUAL_N)


@pytest.mark.parametrize("index", sorted(MANUAL_N))
def test_n_default_within_range_and_saved(index: int) -> None:
    p = t.N_TABLE[index]
    assert p.key == index
    lo = t.INT24_MIN if p.minimum is None else p.minimum
    hi = t.INT24_MAX if p.maximum is None else p.maximum
    assert lo <= p.default <= hi
    assert t.clamp_n(index, p.default) == p.default
    assert p.saved  # s saves "all entries of the N command"
    assert p.name and p.doc  # the manual's designation and its English name


@pytest.mark.parametrize("index", sorted(MANUAL_N))
def test_n_defaults_match_manual_or_are_marked_simulator_choice(index: int) -> None:
    manual = MANUAL_N[index]
    if manual is None:
        assert index in t.N_SIMULATOR_DEFAULTS
    else:
        assert index not in t.N_SIMULATOR_DEFAULTS
        assert t.N_TABLE[index].default == manual


@pytest.mark.parametrize("index", sorted(MANUAL_N_RANGES))
def test_n_ranges_match_manual(index: int) -> None:
    p = t.N_TABLE[index]
    assert (p.minimum, p.maximum) == MANUAL_N_RANGES[index]


def test_spec_simulator_defaults() -> None:
    d = {i: t.N_TABLE[i].default for i in (8, 22, 28, 32, 33, 39, 42, 51)}
    assert d == {8: 0, 22: 0, 28: 1, 32: 0, 33: 0, 39: 100, 42: 10, 51: 0}


def test_only_n21_needs_restart() -> None:
    assert {i for i, p in t.N_TABLE.rows.items() if p.extra["needs_restart"]} == {21}


def test_n_rows_are_frozen_kit_rows_with_the_agreed_facts() -> None:
    # the kit's one parameter row type (issue 27): index -> key, name_en -> doc, needs_restart and
    # the note -> extra
    for index, p in t.N_TABLE.rows.items():
        assert isinstance(p, Param) and t.N_TABLE.find(f"N{index}") is p  # found by its spelling
        assert (p.key, p.section) == (index, f"§2.3.1 N{index}")
        assert set(p.extra) == {"needs_restart", "note"}
    with pytest.raises(AttributeError):
        t.N_TABLE[10].default = 1  # type: ignore[misc]


def test_clamp_n() -> None:
    assert t.clamp_n(10, 0) == 1
    assert t.clamp_n(10, 5000) == 3000
    assert t.clamp_n(10, 300) == 300
    assert t.clamp_n(20, 5) == 10
    assert t.clamp_n(20, 20000) == 15000
    assert t.clamp_n(27, -5) == -5
    assert t.clamp_n(27, -300) == -255
    assert t.clamp_n(21, 7) == 1
    assert t.clamp_n(8, -100) == -100
    assert t.clamp_n(45, 10**9) == t.INT24_MAX
    assert t.clamp_n(10, 5, stepper=True) == 10
    assert t.clamp_n(10, 2000, stepper=True) == 500
    with pytest.raises(KeyError):
        t.clamp_n(9, 1)


def test_current_controller_coupling() -> None:
    # N34 >= 1.5 * N35
    assert t.current_gain_limits(34, 1200, 100) == (150, 32000)
    assert t.current_gain_limits(35, 1200, 0) == (0, 800)
    assert t.clamp_n(34, 100, {34: 1200, 35: 100}) == 150
    assert t.clamp_n(35, 1000, {34: 1200, 35: 0}) == 800
    assert t.clamp_n(35, 1000) == 1000  # without context only the static range applies


def test_reference_type_decoding() -> None:
    assert t.decode_reference_type(0x0301) == (1, 3)  # spec §3.11 N0x0301;19 = Q1 with P2=3
    assert t.decode_reference_type(0x4000) == (0, 0x40)


# ----------------------------------------------------------------------------- status bytes


def test_status_bits_exact() -> None:
    assert t.STATUS_BITS == {
        "ESTOP": 0x01,
        "MOTION": 0x02,
        "MONITORING": 0x04,
        "IDXOFF": 0x08,
        "BUSY": 0x10,
        "I2T_ACTIVE": 0x20,
        "I2T_LATCHED": 0x40,
        "MESSAGE": 0x80,
    }
    assert t.MEMORY_STATUS_BITS == {
        "PLC_STORAGE_ERROR": 0x01,
        "PLC_NOT_RUNNING": 0x02,
        "FLASH_ERROR": 0x04,
        "CNC_STORAGE_ERROR": 0x10,
        "NV_ERROR": 0x20,
        "EEPROM_DEFECTIVE": 0x40,
    }
    assert t.K_BITS == {
        "I2T": 0x01,
        "AE": 0x02,
        "ESTOP": 0x08,
        "MOTION": 0x10,
        "MONITORING": 0x20,
        "IDXOFF": 0x40,
        "BUSY": 0x80,
    }


@pytest.mark.parametrize(
    ("byte", "names"),
    [(0x08, {"IDXOFF"}), (0x12, {"MOTION", "BUSY"}), (0x80, {"MESSAGE"})],
)
def test_t30_examples(byte: int, names: set[str]) -> None:
    # spec §3.11: 08h after power-on, 12h motion running + BUSY, 80h message in MB4
    assert t.decode_bits(byte, t.STATUS_BITS) == names


def test_t34_example_ok() -> None:
    assert t.decode_bits(0x00, t.MEMORY_STATUS_BITS) == set()


@pytest.mark.parametrize(
    ("byte", "names"),
    [
        (0x40, {"IDXOFF"}),
        (0x00, set()),
        (0x90, {"BUSY", "MOTION"}),
        (0x42, {"IDXOFF", "AE"}),
        (0x48, {"ESTOP", "IDXOFF"}),
        (0x61, {"MONITORING", "IDXOFF", "I2T"}),
    ],
)
def test_k_examples(byte: int, names: set[str]) -> None:
    assert t.decode_bits(byte, t.K_BITS) == names


def test_k_from_status() -> None:
    s = t.STATUS_BITS
    assert t.k_from_status(s["IDXOFF"], False) == 0x40
    assert t.k_from_status(s["MOTION"] | s["BUSY"], False) == 0x90
    assert t.k_from_status(s["IDXOFF"] | s["MESSAGE"], True) == 0x42
    assert t.k_from_status(s["ESTOP"] | s["IDXOFF"], False) == 0x48
    assert t.k_from_status(s["MONITORING"] | s["IDXOFF"] | s["I2T_LATCHED"] | s["I2T_ACTIVE"], False) == 0x61
    # every named I bit maps onto the K bit of the same name
    for name in ("ESTOP", "MOTION", "MONITORING", "IDXOFF", "BUSY"):
        assert t.k_from_status(s[name], False) == t.K_BITS[name]
    assert t.k_from_status(s["I2T_LATCHED"], False) == t.K_BITS["I2T"]


# ----------------------------------------------------------------------------- markers


def test_markers() -> None:
    m = t.MARKERS
    assert m["STOP"] == (0, 0)
    assert m["ABORT"] == (0, 1)
    assert m["ESTOP_OK"] == (0, 4)
    assert m["POSITION_CONTROL"] == (0, 5)
    assert m["MONITORING_FAULT"] == (0, 6)
    assert m["IDXOFF"] == (0, 7)
    assert m["I2T"] == (1, 1)
    assert m["RDY"] == (1, 2)
    assert m["BLOCK_MARK"] == (1, 5)
    assert m["MESSAGE_QUERY"] == (3, 1)
    assert m["MOTION_SUPPRESSED"] == (3, 4)
    assert m["WAIT_IN_POSITION"] == (3, 5)
    assert m["MESSAGE_ACK"] == (13, 6)
    assert m["S_FUNCTION"] == (15, 7)
    assert m["T_FUNCTION"] == (18, 7)
    assert len(set(m.values())) == len(m)
    assert all(b < 30 and 0 <= i < 8 for b, i in m.values())
    assert set(t.MARKER_INFO) == set(m)
    assert t.MARKER_ADDRESSES["M0.1"] == "ABORT"
    assert t.MARKER_BYTES["MESSAGE"] == 4 and t.MARKER_BYTES["ERROR_REGISTER"] == 5
    assert t.MARKER_BYTES["TOOL_NUMBER"] == 18


@pytest.mark.parametrize(("n", "addr"), [(50, (6, 0)), (51, (6, 1)), (58, (7, 0)), (89, (10, 7))])
def test_m_function_markers(n: int, addr: tuple[int, int]) -> None:
    assert t.m_function_marker(n) == addr


def test_m_function_marker_range() -> None:
    with pytest.raises(ValueError):
        t.m_function_marker(90)


# ----------------------------------------------------------------------------- messages, faults


def test_message_23() -> None:
    assert 23 in t.MESSAGES
    assert t.MESSAGE_REFERENCE_DISTANCE_LIMIT == 23
    assert "distance limit" in t.MESSAGES[23]
    assert t.ERROR_BITS == {}  # MB5 bits are not defined by manual or spec


def test_faults_reference_known_bits() -> None:
    expected = {
        "ESTOP",
        "FOLLOWING_ERROR",
        "MONITORING",
        "I2T",
        "RESOLVER_FAILURE",
        "OUTPUT_SHORT_CIRCUIT",
        "NV_PARAMETER_ERROR",
        "EEPROM_DEFECTIVE",
        "PLC_PROGRAM_ERROR",
        "FLASH_ERROR",
        "CNC_STORAGE_ERROR",
        "REFERENCE_DISTANCE_LIMIT",
    }
    assert set(t.FAULTS) == expected
    for name, f in t.FAULTS.items():
        assert f.name == name
        assert f.status <= set(t.STATUS_BITS)
        assert f.k <= set(t.K_BITS)
        assert f.memory <= set(t.MEMORY_STATUS_BITS)
        assert all(m in t.MARKERS for m, _ in f.markers)
        assert f.message is None or f.message in t.MESSAGES
        assert f.sets and f.clears
    assert t.FAULTS["ESTOP"].markers == (("ESTOP_OK", 0),)
    assert t.FAULTS["RESOLVER_FAILURE"].inputs == ("E2.3",)
    assert t.FAULTS["OUTPUT_SHORT_CIRCUIT"].inputs == ("E2.2",)
    assert t.FAULTS["REFERENCE_DISTANCE_LIMIT"].message == 23


def test_fault_k_bits_consistent_with_status() -> None:
    for f in t.FAULTS.values():
        i = sum(t.STATUS_BITS[n] for n in f.status)
        k = t.k_from_status(i, f.message is not None)
        assert t.decode_bits(k, t.K_BITS) == set(f.k)


# ----------------------------------------------------------------------------- variants

# type: (rated V, under V, over V, ballast V, cap µF, rated A, peak A, braking A, height, in/out, PLC ms)
MANUAL_VARIANTS = {
    "K1": (70, 30, 95, 85, 1000, 5, 15, 15, "48 mm", (7, 6), 87),
    "KSA15": (70, 30, 95, 80, 1000, 5, 15, 15, "68 mm", (17, 11), 87),
    "KSA15-2": (160, 60, 190, 180, 100, 5, 15, 15, "68 mm", (17, 11), 87),
    "KS4": (160, 60, 190, 180, 100, 2, 4, 5, "68 mm", (17, 11), 72),
    "KS8": (160, 60, 190, 180, 100, 4, 8, 15, "80 mm", (17, 11), 72),
    "KSA20": (250, 100, 340, 320, 380, 9, 19, 20, "112 mm", (17, 11), 87),
    "KSA65": (250, 100, 340, 320, 380, 18, 65, 65, "135 mm", (17, 11), 87),
    "KD8": (310, 200, 400, 380, 200, 5, 8, 10, "112 mm", (17, 11), 88),
    "KD12": (310, 200, 400, 380, 200, 5, 12, 10, "112 mm", (17, 11), 88),
    "HD15": (560, 250, 680, 650, 330, 3, 15, 5, "6U", (17, 11), 88),
    "HD50": (560, 250, 680, 650, 330, 15, 50, 14, "112 mm", (17, 11), 88),
}


@pytest.mark.parametrize("name", sorted(MANUAL_VARIANTS))
def test_variant_table_complete(name: str) -> None:
    rated, under, over, ballast, cap, cont, peak, brake, height, io, plc = MANUAL_VARIANTS[name]
    v = t.VARIANTS[name]
    assert (v.supply_v, v.undervoltage_v, v.overvoltage_v, v.ballast_on_v) == (rated, under, over, ballast)
    assert v.dc_link_capacitor_uf == cap
    assert (v.continuous_current_a, v.peak_current_a, v.braking_current_a) == (cont, peak, brake)
    assert v.height == height
    assert (v.io_inputs, v.io_outputs) == io
    assert v.plc_ms_per_1000 == plc
    assert v.undervoltage_v < v.supply_v < v.ballast_on_v < v.overvoltage_v


def test_resolver_variants_and_feedback() -> None:
    for base in ("KSA15", "KSA15-2", "KSA20", "KSA65"):
        r = t.VARIANTS[base + "R"]
        assert r.feedback == "resolver"
        assert t.VARIANTS[base].feedback == "encoder"
        assert msgspec.structs.replace(r, name=base, feedback="encoder", doc="") == msgspec.structs.replace(
            t.VARIANTS[base], doc=""
        )
    for name in ("KD8", "KD12", "HD15", "HD50"):
        assert t.VARIANTS[name].feedback == "resolver"
        assert not t.VARIANTS[name].logic_from_dc_bus
    for name in ("KS4", "KS8"):
        v = t.VARIANTS[name]
        assert v.stepper and v.feedback == "none"
        assert v.increments_per_rev == 6400 and v.max_step_frequency_hz == 500_000
    assert sum(v.stepper for v in t.VARIANTS.values()) == 2
    assert t.VARIANTS["K1"].input_bits == 6 and t.VARIANTS["K1"].output_bits == 6
    assert t.VARIANTS["KSA15-2R"].input_bits == 18 and t.VARIANTS["KSA15-2R"].output_bits == 11


def test_appendix_a_variant_names_and_default() -> None:
    for name in (
        "K1",
        "KSA15",
        "KSA15-2",
        "KS4",
        "KS8",
        "KSA20",
        "KSA65",
        "KD8",
        "KD12",
        "HD15",
        "HD50",
        "GD96",
        "KSA15-2R",
    ):
        assert name in t.VARIANTS
    assert t.DEFAULT_VARIANT == "KSA15-2R"
    assert t.variant("G96-KSA15-2R") is t.VARIANTS["KSA15-2R"]
    assert t.variant("ksa15-2r") is t.VARIANTS["KSA15-2R"]
    assert t.variant("KD8R") is t.VARIANTS["KD8"]
    with pytest.raises(KeyError):
        t.variant("XYZ")


# ----------------------------------------------------------------------------- defaults, ranges


def test_defaults() -> None:
    d = t.DEFAULTS
    assert (d["M"], d["B"], d["S"]) == (2000, 50, 100)
    assert d["f"] == d["M"]
    assert d["override_active"] == 1
    assert d["coordinates"] == 90 and d["feed_mode"] == 94
    for name, value in d.items():
        if name in t.RANGES:
            lo, hi = t.RANGES[name]
            assert lo <= value <= hi, name
    assert t.SAVED_SETTINGS == {"M", "S", "B", "override_active"}
    assert t.SAVE_KEY == (85, 170)


def test_clamp_setting() -> None:
    assert t.clamp_setting("B", 0) == 1
    assert t.clamp_setting("B", 40000) == 30000
    assert t.clamp_setting("S", 10) == 20
    assert t.clamp_setting("M", 3) == 5
    assert t.clamp_setting("M", 1) == 1  # counter-input mode
    assert t.clamp_setting("M", 0) == 0
    assert t.clamp_setting("M", 3_000_000) == 2_000_000
    assert t.clamp_setting("external_override", 200) == 125
    assert t.clamp_setting("position", 9_000_000) == t.POSITION_MAX


def test_constants() -> None:
    assert t.FIRMWARE_VERSION == 404
    assert (t.POSITION_MIN, t.POSITION_MAX) == (-8388352, 8388607)
    assert t.POSITION_MIN == -0x7FFF00


# ----------------------------------------------------------------------------- V-factor


@pytest.mark.parametrize(
    ("m", "v", "vmin"),
    [
        (5, 1, 2),
        (2000, 1, 2),
        (50000, 1, 2),
        (50001, 2, 4),
        (100000, 2, 4),
        (100001, 4, 8),
        (200000, 4, 8),
        (200001, 8, 16),
        (400000, 8, 16),
        (400001, 10, 20),
        (500000, 10, 20),
        (500001, 20, 40),
        (1000000, 20, 40),
        (1000001, 25, 50),
        (1250000, 25, 50),
        (1250001, 40, 80),
        (2000000, 40, 80),
    ],
)
def test_v_factor_table(m: int, v: int, vmin: int) -> None:
    assert t.v_factor(m) == v
    assert t.min_speed(m) == vmin


def test_v_factor_edges_and_quantisation() -> None:
    assert t.v_factor(0) == 1 and t.v_factor(1) == 1  # counter-input mode values
    assert t.v_factor(5_000_000) == 40
    assert t.quantize_speed(1000, 2_000_000) == 1000
    assert t.quantize_speed(1039, 2_000_000) == 1000
    assert t.quantize_speed(39, 2_000_000) == 0  # stalls
    assert t.quantize_speed(12345, 2000) == 12345
