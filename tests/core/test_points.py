"""Declared points (devsim/core/points.py): the one conversion of a control value, the range and
choice checks, the JSON limits, the table's lookup and the derived read / set / state.

Boundaries by property: hypothesis generates values at and around a point's minimum and maximum,
JSON nested around the 32-level limit, texts around the 40- and 60-character cuts, and compares
with the rule written out here (not with the code under test).
"""

from __future__ import annotations

import math
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from devsim.core.points import (
    BadValue,
    Family,
    Point,
    PointTable,
    ReadOnlyName,
    UnknownName,
    finite,
    number_text,
    parse_as,
    parse_bool,
    range_text,
)

#: No deadline, no speed health check: a loaded machine (or a mutation run) must not fail these.
BOUNDARY = settings(deadline=None, suppress_health_check=[HealthCheck.too_slow])

#: The deepest a JSON value may nest: a value at depth 32 (32 containers around it) is taken,
#: one level more is refused.
JSON_DEPTH = 32


def nested(levels: int, leaf: Any = 1, dicts: bool = False) -> Any:
    value = leaf
    for _ in range(levels):
        value = {"k": value} if dicts else [value]
    return value


# -- one conversion of a control value ----------------------------------------------------------


@pytest.mark.parametrize("text", ["true", "TRUE", " On ", "yes", "1", True, 1, 1.0])
def test_true_spellings(text: Any) -> None:
    assert parse_bool(text) is True


@pytest.mark.parametrize("text", ["false", "Off", " no", "0", False, 0, 0.0])
def test_false_spellings(text: Any) -> None:
    assert parse_bool(text) is False


@pytest.mark.parametrize("value", [2, -1, 0.5, "maybe", "", None, [1], "\u3000true", "on\u00a0", "\x1cyes\x1f"])
def test_not_a_bool(value: Any) -> None:
    with pytest.raises(BadValue) as err:
        parse_bool(value)
    assert str(err.value) == f"expects a boolean (true/false/1/0/on/off/yes/no), not {value!r}"


def test_finite_numbers_and_refusals() -> None:
    assert finite("2.5") == 2.5 and finite(3) == 3.0 and type(finite(3)) is float
    for value, message in [
        (True, "expects a number, not True"),
        ("x", "expects a number, not 'x'"),
        (None, "expects a number, not None"),
        (10**400, None),
        ("nan", "expects a finite number, not 'nan'"),
        (math.inf, "expects a finite number, not inf"),
        ("-inf", "expects a finite number, not '-inf'"),
        ("\u0663", "expects a number, not '\u0663'"),  # an Arabic-Indic three, which float() reads as 3
        ("\x1c2.5\x1f", "expects a number, not '\\x1c2.5\\x1f'"),  # FS … US, which float() skips
        ("\x0b2.5", "expects a number, not '\\x0b2.5'"),
    ]:
        with pytest.raises(BadValue) as err:
            finite(value)
        if message is not None:
            assert str(err.value) == message
        else:
            assert str(err.value).startswith("expects a number, not 1000")


def test_whole_numbers() -> None:
    assert parse_as("int", 7) == 7
    assert parse_as("int", " 0x10 ") == 16  # any base Python spells
    assert parse_as("int", "-12") == -12
    assert parse_as("int", "3.0") == 3 and type(parse_as("int", "3.0")) is int
    assert parse_as("int", 4.0) == 4 and type(parse_as("int", 4.0)) is int
    with pytest.raises(BadValue) as err:
        parse_as("int", "3.5")
    assert str(err.value) == "expects a whole number, not '3.5'"
    with pytest.raises(BadValue, match="expects a number, not True"):
        parse_as("int", True)
    with pytest.raises(BadValue, match="expects a number"):
        parse_as("int", "\u0661\u0662")  # Arabic-Indic digits, which int() reads as 12
    with pytest.raises(BadValue, match="expects a number"):
        parse_as("int", "\x1c12")  # FS, which int() skips as a blank


def test_each_kind() -> None:
    assert parse_as("bool", "on") is True
    assert parse_as("float", "1e3") == 1000.0
    assert parse_as("str", "text") == "text"
    with pytest.raises(BadValue) as err:
        parse_as("str", 5)
    assert str(err.value) == "expects text, not 5"
    assert parse_as("json", '{"a": [1, 2]}') == {"a": [1, 2]}
    assert parse_as("json", "not json") == "not json"  # text that is no JSON stays text
    assert parse_as("json", [1, "x"]) == [1, "x"]
    with pytest.raises(BadValue) as err:
        parse_as("json", {"a": [1.0, math.nan]})
    assert str(err.value) == "expects finite numbers, not nan"
    with pytest.raises(BadValue, match="finite"):
        parse_as("json", "[1, NaN]")  # JSON text parses to NaN, then is refused


@BOUNDARY
@given(st.integers(0, JSON_DEPTH + 3), st.booleans(), st.booleans())
def test_json_nested_up_to_the_limit(levels: int, dicts: bool, as_text: bool) -> None:
    """A value 32 containers deep is taken; one level deeper is refused (in lists, in mappings,
    and as JSON text)."""
    value = nested(levels, dicts=dicts)
    given_value = json_text(value) if as_text else value
    if levels <= JSON_DEPTH:
        assert parse_as("json", given_value) == value
    else:
        with pytest.raises(BadValue) as err:
            parse_as("json", given_value)
        assert str(err.value) == "value nested too deeply"


def test_json_empty_containers_count_as_a_level() -> None:
    assert parse_as("json", nested(JSON_DEPTH, [])) == nested(JSON_DEPTH, [])  # innermost [] at 32
    with pytest.raises(BadValue):
        parse_as("json", nested(JSON_DEPTH + 1, [1]))


def test_json_text_too_deep_for_the_parser_stays_text() -> None:
    deep = "[" * 100_000 + "]" * 100_000  # past Python's recursion limit: not JSON to it
    assert parse_as("json", deep) == deep


def json_text(value: Any) -> str:
    import json

    return json.dumps(value)


@BOUNDARY
@given(st.text(max_size=60))
def test_shown_values_are_cut_at_40_characters(text: str) -> None:
    shown = repr(text)
    expected = shown if len(shown) <= 40 else shown[:37] + "..."
    with pytest.raises(BadValue) as err:
        parse_bool(text + "?")
    shown = repr(text + "?")
    expected = shown if len(shown) <= 40 else shown[:37] + "..."
    assert str(err.value) == f"expects a boolean (true/false/1/0/on/off/yes/no), not {expected}"


# -- a point: range, choices, access ----------------------------------------------------------

LOW, HIGH = -5.0, 10.0


@BOUNDARY
@given(st.one_of(st.integers(-8, 13), st.floats(-5.5, 10.5, allow_nan=False)))
def test_minimum_and_maximum_are_inclusive(value: float) -> None:
    point = Point("param.x", "float", "x", minimum=LOW, maximum=HIGH, unit="mm", put=lambda m, v: None)
    if LOW <= value <= HIGH:
        assert point.parse(value) == value
    else:
        with pytest.raises(BadValue) as err:
            point.parse(value)
        side = "below the minimum -5" if value < LOW else "above the maximum 10"
        assert str(err.value) == f"{value!r} is {side} mm"


def test_range_message_without_a_unit() -> None:
    point = Point("param.n", "int", "n", minimum=0, maximum=3)
    with pytest.raises(BadValue) as err:
        point.parse(4)
    assert str(err.value) == "4 is above the maximum 3"
    assert point.parse(0) == 0 and point.parse(3) == 3


def test_only_one_side_limited() -> None:
    assert Point("a", "int", "a", minimum=1).parse(10**9) == 10**9
    assert Point("a", "int", "a", maximum=1).parse(-(10**9)) == -(10**9)


def test_choices() -> None:
    point = Point("mode", "int", "m", choices=(1, 2, 4))
    assert point.parse("4") == 4
    with pytest.raises(BadValue) as err:
        point.parse(3)
    assert str(err.value) == "expects one of 1, 2, 4, not 3"
    assert point.range_text() == "1 / 2 / 4"


def test_access_from_get_and_put() -> None:
    def get(m: Any) -> int:
        return 1

    def put(m: Any, v: Any) -> None:
        return None

    read_only, both, write_only = Point("r", "int", "d", get=get), Point("rw", "int", "d", get=get, put=put), \
        Point("w", "int", "d", put=put)
    assert [p.access for p in (read_only, both, write_only)] == ["r", "rw", "w"]
    assert [p.readable for p in (read_only, both, write_only)] == [True, True, False]
    assert [p.settable for p in (read_only, both, write_only)] == [False, True, True]
    assert both.describe() == {"name": "rw", "type": "int", "unit": "", "access": "rw", "doc": "d", "section": ""}
    described = Point("axis.position", "float", "pos", "§5.1", "inc").describe()
    assert described == {"name": "axis.position", "type": "float", "unit": "inc", "access": "r", "doc": "pos",
                         "section": "§5.1"}


def test_limits_as_a_reference_prints_them() -> None:
    assert number_text(99999999.0) == "99999999"
    assert number_text(214748.3647) == "214748.3647"
    assert number_text(-3) == "-3"
    assert range_text(None, None) == ""
    assert range_text(0, None) == "0 … "
    assert range_text(None, 2.5) == " … 2.5"
    assert range_text(-1, 1) == "-1 … 1"
    assert range_text(0, 1, ("a", "b")) == "a / b"
    assert Point("p", "float", "d", minimum=0.5, maximum=2).range_text() == "0.5 … 2"


# -- the table ---------------------------------------------------------------------------------


class Model:
    def __init__(self) -> None:
        self.values: dict[str, Any] = {"axis.position": 1.5, "axis.velocity": 0.0, "motion": False, "n": 3}


def _point(name: str, type_: Any = "int", *, settable: bool = True, in_state: bool = False, **kw: Any) -> Point:
    def get(m: Model) -> Any:
        return m.values.get(name)

    def put(m: Model, v: Any) -> None:
        m.values[name] = v

    return Point(name, type_, name, get=get, put=put if settable else None, in_state=in_state, **kw)


def marker(name: str) -> Point | None:
    if name.startswith("marker.M") and name[8:].isdigit():
        return _point(name, "bool")
    return None


def table() -> PointTable:
    return PointTable.of(
        [_point("axis.position", "float", settable=False, in_state=True),
         _point("axis.velocity", "float", settable=False, in_state=True)],
        [_point("motion", "bool", settable=False, in_state=True), _point("n", minimum=0, maximum=9),
         Point("reset", "bool", "r", put=lambda m, v: m.values.__setitem__("reset", v))],
        alias=lambda name: "n" if name.lower() in ("param.n", "number") else None,
        families=[Family("marker.M<n>", "bool", "a marker", "§1", marker)],
    )


def test_table_lookup() -> None:
    t = table()
    assert t.names() == ["axis.position", "axis.velocity", "motion", "n", "reset"]
    assert len(t) == 5 and [p.name for p in t] == t.names()
    assert "n" in t and "Param.N" in t and "marker.M7" in t
    assert "nothing" not in t and 5 not in t and "marker.Mx" not in t
    assert t.find("number").name == "n"  # type: ignore[union-attr]
    assert t.find("marker.M3").name == "marker.M3"  # type: ignore[union-attr]
    assert t.find("nothing") is None
    with pytest.raises(ValueError, match="point 'n' declared twice"):
        t.add(_point("n"))


def test_alias_to_a_missing_point_still_tries_the_families() -> None:
    t = PointTable.of([], alias=lambda name: "marker.M1" if name == "m1" else None,
                      families=[Family("marker.M<n>", "bool", "a marker", "§1", marker)])
    assert t.find("m1").name == "marker.M1"  # type: ignore[union-attr]


def test_unknown_names_with_suggestions() -> None:
    t = table()
    with pytest.raises(UnknownName) as err:
        t.lookup("motoin")
    assert str(err.value) == "the device has no 'motoin' (did you mean motion?)"
    with pytest.raises(UnknownName) as err:
        t.lookup("zzz", "card 1")
    assert str(err.value) == "card 1 has no 'zzz'"
    assert str(UnknownName()) == "unknown name"
    assert t.unknown_text("axis.positio", "x") == "x has no 'axis.positio' (did you mean axis.position, axis.velocity?)"


@BOUNDARY
@given(st.integers(50, 70))
def test_long_unknown_names_are_cut_at_60(length: int) -> None:
    name = ("motion" + "x" * length)[:length]
    text = table().unknown_text(name, "d")
    shown = name if len(name) <= 60 else name[:57] + "..."
    assert text == f"d has no {shown!r}"


def test_three_suggestions_at_most() -> None:
    t = PointTable.of([_point(name) for name in ("abcdxyzwv", "abcdxy", "abcdxyzw", "abcdxyz", "xyzw")])
    assert t.unknown_text("abcdx", "d") == "d has no 'abcdx' (did you mean abcdxy, abcdxyz, abcdxyzw?)"


def test_read_parse_set_and_state() -> None:
    t, model = table(), Model()
    assert t.read(model, "axis.position") == 1.5
    assert t.read(model, "number") == 3
    with pytest.raises(UnknownName) as err:
        t.read(model, "reset", "card")
    assert str(err.value) == "reset of card can only be set"
    with pytest.raises(ReadOnlyName) as err2:
        t.set(model, "motion", True, "card")
    assert str(err2.value) == "motion of card is read-only"
    with pytest.raises(BadValue) as err3:
        t.set(model, "n", 10)
    assert str(err3.value) == "n: 10 is above the maximum 9"
    assert model.values["n"] == 3  # nothing changed
    assert t.parse("param.n", "7") == (t.points["n"], 7)
    assert model.values["n"] == 3
    t.set(model, "param.n", "8")
    assert model.values["n"] == 8
    t.set(model, "reset", "on")
    assert model.values["reset"] is True
    assert t.state(model) == {"axis": {"position": 1.5, "velocity": 0.0}, "motion": False}


def test_state_of_a_name_under_a_value_keeps_the_value() -> None:
    """``motion`` holds a value; ``motion.x`` cannot nest under it and is left out."""
    t = PointTable.of([_point("motion", "bool", in_state=True), _point("motion.x", in_state=True),
                       Point("hidden", "int", "h", in_state=True)])
    model = Model()
    model.values["motion.x"] = 5
    assert t.state(model) == {"motion": False}


# -- boundaries found by the mutation run (issue 35) ---------------------------------------------


def test_a_value_shown_whole_up_to_exactly_40_characters() -> None:
    forty, forty_one = "x" * 38, "x" * 39  # their reprs: 40 and 41 characters
    with pytest.raises(BadValue) as err:
        parse_bool(forty)
    assert str(err.value).endswith(f", not '{forty}'")
    with pytest.raises(BadValue) as err:
        parse_bool(forty_one)
    assert str(err.value).endswith(", not '" + "x" * 36 + "...")


def test_large_whole_limits_keep_every_digit() -> None:
    assert number_text(1e12) == "1000000000000"
    assert number_text(2147483647.0) == "2147483647"
    assert number_text(0.1) == "0.1"


@pytest.mark.parametrize("value", ["nan", "abc", True, [1.0], None])
def test_float_points_take_numbers_only(value: Any) -> None:
    with pytest.raises(BadValue, match="^expects a (finite )?number, not "):
        parse_as("float", value)


def test_a_declared_name_is_never_respelt_by_the_alias() -> None:
    t = PointTable.of([_point("a"), _point("b")], alias=lambda name: "b")
    assert t.find("a").name == "a"  # type: ignore[union-attr]
    assert t.find("anything").name == "b"  # type: ignore[union-attr]


def test_every_family_is_asked_in_turn() -> None:
    def output(name: str) -> Point | None:
        return _point(name, "bool") if name.startswith("output.") else None

    t = PointTable.of([], families=[Family("marker.M<n>", "bool", "a marker", "§1", marker),
                                    Family("output.<n>", "bool", "an output", "§2", output)])
    assert t.find("output.3").name == "output.3"  # type: ignore[union-attr]
    assert t.find("marker.M3").name == "marker.M3"  # type: ignore[union-attr]
    assert t.find("input.3") is None


def test_default_and_given_owner_in_messages() -> None:
    t, model = table(), Model()
    with pytest.raises(UnknownName, match="^reset of the device can only be set$"):
        t.read(model, "reset")
    with pytest.raises(ReadOnlyName, match="^motion of the device is read-only$"):
        t.set(model, "motion", True)
    with pytest.raises(ReadOnlyName, match="^motion of the device is read-only$"):
        t.parse("motion", True)
    for call in (lambda: t.read(model, "zzz", "card 2"), lambda: t.parse("zzz", 1, "card 2"),
                 lambda: t.set(model, "zzz", 1, "card 2")):
        with pytest.raises(UnknownName) as err:
            call()
        assert str(err.value) == "card 2 has no 'zzz'"


def test_state_skips_points_outside_it_wherever_they_stand() -> None:
    t = PointTable.of([_point("n"), _point("axis.position", "float", in_state=True)])
    assert t.state(Model()) == {"axis": {"position": 1.5}}


def test_suggestions_compare_the_first_60_characters() -> None:
    """difflib's ratio 2·M/(len a + len b) with the cutoff 0.6: 26 matching characters of a
    60-character cut give 52/86 > 0.6 (suggested); a 61-character cut would give 52/87 < 0.6."""
    t = PointTable.of([_point("a" * 26)])
    name = "a" * 30 + "z" * 31
    assert t.unknown_text(name, "d").endswith(f"(did you mean {'a' * 26}?)")
