"""The Modbus map a kind's declared points give (issue 13): tables by type and access, addresses
in table order, 32-bit words high first with a scale, plant-file overrides; pure."""

from __future__ import annotations

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from devsim.core.points import Family, Point, PointTable
from devsim.core.registry import device_class, kinds
from devsim.facades.modbus_map import ModbusMap, from_words, to_words

POINTS = PointTable.of([
    Point("input.a", "bool", "a switch", put=lambda m, v: None, get=lambda m: True),
    Point("output.b", "bool", "a lamp", get=lambda m: False),
    Point("param.n", "int", "a number", put=lambda m, v: None, get=lambda m: 7),
    Point("axis.position", "float", "a position", get=lambda m: 1.5),
    Point("name", "str", "text", get=lambda m: "x"),
    Point("param.x", "float", "a setting", put=lambda m, v: None, get=lambda m: 0.25),
])


def test_tables_by_type_and_access() -> None:
    m = ModbusMap.generate(POINTS)
    assert [(e.name, e.table, e.address, e.width, e.scale) for e in m.entries] == [
        ("input.a", "coil", 0, 1, 1.0),
        ("output.b", "discrete", 0, 1, 1.0),
        ("param.n", "holding", 0, 2, 1.0),
        ("param.x", "holding", 2, 2, 1000.0),
        ("axis.position", "input", 0, 2, 1000.0),
    ]
    assert "name" not in m.by_name  # text has no Modbus form
    assert m.find("holding", 3) == (m.by_name["param.x"], 1)
    assert m.find("holding", 4) is None


def test_words_are_a_scaled_int32_high_word_first() -> None:
    assert to_words(1.5, 1000) == (0, 1500)
    assert to_words(-1, 1) == (0xFFFF, 0xFFFF)
    assert to_words(70000, 1) == (1, 4464)
    assert to_words(1e12, 1) == (0x7FFF, 0xFFFF)  # saturated
    assert from_words(0xFFFF, 0xFFFF, 1, "int") == -1
    assert from_words(0, 1500, 1000, "float") == 1.5


def test_overrides_move_rescale_or_drop() -> None:
    m = ModbusMap.generate(POINTS, {"param.x": {"address": 100, "scale": 10}, "input.a": None})
    assert "input.a" not in m.by_name
    assert (m.by_name["param.x"].address, m.by_name["param.x"].scale) == (100, 10.0)
    with pytest.raises(ValueError, match="read-only"):
        ModbusMap.generate(POINTS, {"axis.position": {"table": "holding"}})
    with pytest.raises(ValueError, match="no point"):
        ModbusMap.generate(POINTS, {"nothing": None})
    with pytest.raises(ValueError, match="overlaps"):
        ModbusMap.generate(POINTS, {"param.x": {"address": 1}})
    with pytest.raises(ValueError, match="does not fit"):
        ModbusMap.generate(POINTS, {"param.n": {"table": "coil"}})


@pytest.mark.parametrize("kind", sorted(kinds()))
def test_every_kind_has_a_map_without_overlaps(kind: str) -> None:
    m = ModbusMap.generate(device_class(kind).points)
    assert m.entries
    numeric = [p for p in device_class(kind).points if p.type in ("int", "float", "bool")]
    assert len(m.entries) == len(numeric)


# -- boundaries (issue 35): the standard's address space, the int32 range, the scale --------------
#
# Modbus Application Protocol V1.1b3 §4.3/§4.4: each table addresses 0 … 65535; an entry of two
# registers occupies address and address + 1, so it may start at 65534 at the most.

#: No deadline, no speed health check: a loaded machine (or a mutation run) must not fail these.
BOUNDARY = settings(deadline=None, suppress_health_check=[HealthCheck.too_slow])
LAST = 65535
I32_MIN, I32_MAX = -(1 << 31), (1 << 31) - 1


def _near(*edges: int) -> st.SearchStrategy[int]:
    return st.sampled_from(edges).flatmap(lambda e: st.integers(e - 2, e + 2))


@BOUNDARY
@given(_near(-1, 0, LAST - 1, LAST, LAST + 1), st.sampled_from(["input.a", "param.n"]))
def test_override_address_within_the_table(address: int, name: str) -> None:
    """Oracle: an entry fits when all its addresses lie in 0 … 65535 (-1: the next free one)."""
    width = 1 if name == "input.a" else 2
    fits = address == -1 or (0 <= address and address + width - 1 <= LAST)
    if fits:
        entry = ModbusMap.generate(POINTS, {name: {"address": address}}).by_name[name]
        assert entry.address == (address if address >= 0 else entry.address)
        assert entry.end - 1 <= LAST
    else:
        with pytest.raises(ValueError) as err:
            ModbusMap.generate(POINTS, {name: {"address": address}})
        assert str(err.value) == f"modbus map: {name}: address {address} is not 0 … 65535"


def test_address_minus_one_is_the_next_free_address() -> None:
    m = ModbusMap.generate(POINTS, {"param.x": {"address": -1}})
    assert m.by_name["param.x"].address == 2


def test_override_address_zero_is_an_address() -> None:
    """Address 0 is the first register, not 'choose one': it collides with param.n there."""
    with pytest.raises(ValueError, match="param.x overlaps param.n at holding 0"):
        ModbusMap.generate(POINTS, {"param.x": {"address": 0}})
    m = ModbusMap.generate(POINTS, {"param.n": {"address": 10}, "param.x": {"address": 0}})
    assert (m.by_name["param.x"].address, m.by_name["param.n"].address) == (0, 10)


@pytest.mark.parametrize("address", ["5", 5.0, None])
def test_override_address_must_be_a_whole_number(address: object) -> None:
    with pytest.raises(ValueError) as err:
        ModbusMap.generate(POINTS, {"param.n": {"address": address}})
    assert str(err.value) == f"modbus map: param.n: address {address!r} is not 0 … 65535"


@BOUNDARY
@given(st.one_of(st.sampled_from([0, 0.0, -0.0, 1e12, True, False, "10", None]),
                 st.floats(-1.0, 1.0), st.floats(1e12 - 1e6, 1e12 + 1e6), st.integers(-3, 3)))
def test_override_scale_is_a_positive_number_below_1e12(scale: object) -> None:
    fits = (not isinstance(scale, bool) and isinstance(scale, int | float) and 0 < scale < 1e12)
    if fits:
        entry = ModbusMap.generate(POINTS, {"param.x": {"scale": scale}}).by_name["param.x"]
        assert entry.scale == float(scale) and entry.address == 2  # the address stays the default
    else:
        with pytest.raises(ValueError) as err:
            ModbusMap.generate(POINTS, {"param.x": {"scale": scale}})
        assert str(err.value) == f"modbus map: param.x: scale {scale!r} must be a positive number"


def test_override_messages() -> None:
    with pytest.raises(ValueError) as err:
        ModbusMap.generate(POINTS, {"param.n": 5})
    assert str(err.value) == "modbus map: param.n: give {address, table, scale} or null"
    with pytest.raises(ValueError) as err:
        ModbusMap.generate(POINTS, {"param.n": {"adress": 1, "Scale": 2, "table": "input"}})
    assert str(err.value) == "modbus map: param.n: unknown keys Scale, adress"
    with pytest.raises(ValueError) as err:
        ModbusMap.generate(POINTS, {"name": {"address": 1}})
    assert str(err.value) == "modbus map: name (str) has no Modbus form"
    with pytest.raises(ValueError) as err:
        ModbusMap.generate(POINTS, {"output.b": {"table": "coil"}})
    assert str(err.value) == "modbus map: output.b is read-only: it cannot be a coil"
    with pytest.raises(ValueError) as err:
        ModbusMap.generate(POINTS, {"param.n": {"table": "registers"}})
    assert str(err.value) == "modbus map: param.n: table 'registers' does not fit a int point"


def test_override_table_moves_a_settable_point_to_a_read_only_table() -> None:
    m = ModbusMap.generate(POINTS, {"param.n": {"table": "input"}, "input.a": {"table": "discrete"}})
    n, a = m.by_name["param.n"], m.by_name["input.a"]
    # addresses in declaration order: param.n is declared before axis.position, input.a before output.b
    assert (n.table, n.address, n.scale) == ("input", 0, 1.0)
    assert (a.table, a.address) == ("discrete", 0)
    assert m.find("input", 1) == (n, 1)
    assert m.find("input", 2) == (m.by_name["axis.position"], 0)
    assert m.find("discrete", 1) == (m.by_name["output.b"], 0)


def test_entries_carry_type_unit_and_doc() -> None:
    points = PointTable.of([
        Point("input.a", "bool", "a switch", unit="", get=lambda m: True),
        Point("axis.position", "float", "a position", unit="inc", get=lambda m: 1.5),
        Point("param.v", "int", "a speed", unit="inc/s", put=lambda m, v: None, get=lambda m: 1),
    ])
    m = ModbusMap.generate(points)
    assert [(e.name, e.type, e.unit, e.doc, e.address) for e in m.entries] == [
        ("input.a", "bool", "", "a switch", 0),
        ("param.v", "int", "inc/s", "a speed", 0),
        ("axis.position", "float", "inc", "a position", 0),
    ]
    assert m.rows() == [
        ("discrete", "0", "input.a", "bool", "", "", "a switch"),
        ("holding", "0–1", "param.v", "int", "×1", "inc/s", "a speed"),
        ("input", "0–1", "axis.position", "float", "×1000", "inc", "a position"),
    ]
    assert [m.size(t) for t in ("coil", "discrete", "holding", "input")] == [0, 1, 2, 2]
    rescaled = ModbusMap.generate(points, {"param.v": {"scale": 2}, "axis.position": {"scale": 0.5}})
    assert [row[4] for row in rescaled.rows()] == ["", "×2", "×0.5"]


@BOUNDARY
@given(st.one_of(_near(I32_MIN, I32_MAX, 0, 0xFFFF, 0x10000), st.integers(-(1 << 40), 1 << 40)))
def test_int32_words_by_property(value: int) -> None:
    """Oracle: saturate at the int32 range, two's complement, high word first; back the same."""
    clamped = max(I32_MIN, min(I32_MAX, value))
    raw = clamped % (1 << 32)
    high, low = to_words(value, 1)
    assert (high, low) == (raw // 65536, raw % 65536)
    assert from_words(high, low, 1, "int") == clamped
    assert type(from_words(high, low, 1, "int")) is int


def test_words_boundaries() -> None:
    assert to_words(I32_MIN, 1) == (0x8000, 0)
    assert from_words(0x8000, 0, 1, "int") == I32_MIN
    assert from_words(0x7FFF, 0xFFFF, 1, "int") == I32_MAX
    assert from_words(0, 1, 1, "int") == 1  # only bit 31 is the sign
    assert from_words(0x1_0001, 0x1_0002, 1, "int") == 65538  # each word is 16 bits
    assert to_words(None, 1000) == (0, 0)  # a point that reads nothing is 0
    assert from_words(0, 1500, 1000, "int") == 2  # an int point rounds
    assert from_words(0, 1500, 1000, "float") == 1.5
    assert to_words(-1e12, 1) == (0x8000, 0)  # saturated below


def test_mirror_of_declared_families() -> None:
    none = Family("X.<n>", "int", "no mirror", "§1", lambda name: None)
    regs = Family("R.<n>", "int", "register n", "§9.5", lambda name: None, modbus=(("holding", "input"), 3))
    flags = Family("F.<n>", "bool", "flag n", "§9.5", lambda name: None, modbus=(("coil",), 2))
    m = ModbusMap.mirror(PointTable.of([], families=[none, regs, flags]))
    assert [(e.name, e.table, e.address, e.width, e.scale, e.type, e.unit, e.doc) for e in m.entries] == [
        ("F.0", "coil", 0, 1, 1.0, "bool", "", "flag n"),
        ("F.1", "coil", 1, 1, 1.0, "bool", "", "flag n"),
        ("R.0", "holding", 0, 2, 1.0, "int", "", "register n"),
        ("R.1", "holding", 2, 2, 1.0, "int", "", "register n"),
        ("R.2", "holding", 4, 2, 1.0, "int", "", "register n"),
        ("R.0", "input", 0, 2, 1.0, "int", "", "register n"),
        ("R.1", "input", 2, 2, 1.0, "int", "", "register n"),
        ("R.2", "input", 4, 2, 1.0, "int", "", "register n"),
    ]
    assert m.by_name["R.1"].table == "holding"  # the first table a name appears in
    assert (m.size("coil"), m.size("holding"), m.size("discrete")) == (2, 6, 0)
    with pytest.raises(ValueError) as err:
        ModbusMap.mirror(PointTable.of([], families=[none]))
    assert str(err.value) == "the kind declares no Modbus mirror"
