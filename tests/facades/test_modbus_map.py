"""The Modbus map a kind's declared points give (issue 13): tables by type and access, addresses
in table order, 32-bit words high first with a scale, plant-file overrides; pure."""

from __future__ import annotations

import pytest

from devsim.core.points import Point, PointTable
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
