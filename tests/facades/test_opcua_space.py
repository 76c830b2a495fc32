"""The OPC UA address space a kind's points give (devsim.facades.opcua_space, pure): data types,
access, engineering units, and the conversions a client's writes go through."""

from __future__ import annotations

import pytest

from devsim.core.points import BadValue, Point
from devsim.core.registry import device_class, kinds
from devsim.facades.opcua_space import (
    DEFAULT_ENDPOINT,
    RESERVED,
    TypeMismatch,
    Variable,
    data_type,
    endpoint_url,
    eu_information,
    from_opcua,
    to_opcua,
    variables,
)


def _get(model: object) -> int:
    return 0


def _put(model: object, value: object) -> None:
    return None


@pytest.mark.parametrize(("point", "expected"), [
    (Point("a", "bool", "", get=_get), "Boolean"),
    (Point("a", "int", "", get=_get), "Int64"),
    (Point("a", "int", "", get=_get, minimum=0, maximum=99), "Int32"),
    (Point("a", "int", "", get=_get, minimum=0, maximum=2**32), "Int64"),
    (Point("a", "float", "", get=_get), "Double"),
    (Point("a", "str", "", get=_get), "String"),
    (Point("a", "json", "", get=_get), "String"),
])
def test_the_data_type_comes_from_the_point_type(point: Point, expected: str) -> None:
    assert data_type(point) == expected


def test_a_variable_per_readable_or_settable_point_with_access_and_description() -> None:
    points = [Point("axis.position", "float", "actual position", "§5.1", "inc", get=_get),
              Point("param.V", "float", "velocity", "§4", put=_put),
              Point("input.I1", "bool", "input 1", get=_get, put=_put)]
    rows = {row.point: row for row in variables("x", points)}
    assert rows["axis.position"] == Variable("axis.position", "x.axis.position", "Double", True, False, "float", "inc",
                                             "actual position (§5.1)")
    assert (rows["param.V"].readable, rows["param.V"].writable) == (False, True)
    assert (rows["input.I1"].readable, rows["input.I1"].writable) == (True, True)


@pytest.mark.parametrize("kind", sorted(kinds()))
def test_no_kind_has_a_point_named_like_the_device_objects_own_nodes(kind: str) -> None:
    names = [row.point for row in variables(kind, device_class(kind).points)]
    assert not RESERVED & set(names) and len(names) == len(set(names))


def test_units_get_their_unece_code_or_minus_one() -> None:
    assert eu_information("V")[1:3] == (ord("V") << 16 | ord("L") << 8 | ord("T"), "V")
    assert eu_information("1/min")[1] == 4405556  # C94, reciprocal minute
    assert eu_information("inc")[1:] == (-1, "inc", "inc")


def test_values_to_and_from_opcua() -> None:
    number = Variable("q", "x.q", "Double", True, True, "float", "", "")
    assert to_opcua(number, 3) == 3.0 and to_opcua(number, None) is None
    assert from_opcua(number, "Double", 5.5) == 5.5
    for other in ("Int32", "Int64", "Float", "Boolean", "Byte"):  # no other numeric type: Part 4, 5.10.4.1
        with pytest.raises(TypeMismatch):
            from_opcua(number, other, 5)
    count = Variable("n", "x.n", "Int32", True, True, "int", "", "")
    with pytest.raises(TypeMismatch):
        from_opcua(count, "Int64", 5)
    with pytest.raises(TypeMismatch):
        from_opcua(number, "String", "5")
    with pytest.raises(TypeMismatch):
        from_opcua(number, "Double", [1.0, 2.0])
    switch = Variable("b", "x.b", "Boolean", True, True, "bool", "", "")
    with pytest.raises(TypeMismatch):
        from_opcua(switch, "Int32", 1)
    blob = Variable("j", "x.j", "String", True, True, "json", "", "")
    assert to_opcua(blob, {"a": [1, 2]}) == '{"a":[1,2]}'
    assert to_opcua(blob, None) == "null"  # the JSON point's value: null
    text = Variable("t", "x.t", "String", True, False, "str", "", "")
    assert to_opcua(text, None) is None and to_opcua(text, "idle") == "idle"  # a null String
    assert from_opcua(blob, "String", '{"a": [1, 2]}') == {"a": [1, 2]}
    with pytest.raises(BadValue):  # a String: the right type, a value the point refuses
        from_opcua(blob, "String", "{not json")


# -- boundaries (issue 35: mutation run) ----------------------------------------------------------


@pytest.mark.parametrize(("spec", "url"), [
    (None, DEFAULT_ENDPOINT),
    ("", DEFAULT_ENDPOINT),
    ("4841", "opc.tcp://127.0.0.1:4841/devsim/"),
    (":4841", "opc.tcp://127.0.0.1:4841/devsim/"),
    ("0", "opc.tcp://127.0.0.1:0/devsim/"),
    ("65535", "opc.tcp://127.0.0.1:65535/devsim/"),
    ("0.0.0.0:4840", "opc.tcp://0.0.0.0:4840/devsim/"),
    ("XBOX:4840", "opc.tcp://XBOX:4840/devsim/"),  # only the brackets of an IPv6 address come off
    ("[::1]:4840", "opc.tcp://[::1]:4840/devsim/"),
    ("::1:4840", "opc.tcp://[::1]:4840/devsim/"),
    ("opc.tcp://h:1/x/", "opc.tcp://h:1/x/"),
])
def test_endpoint_urls(spec: str | None, url: str) -> None:
    """Loopback unless a host is named; the port 0 … 65535; a whole URL as it is."""
    assert endpoint_url(spec) == url
    assert DEFAULT_ENDPOINT == "opc.tcp://127.0.0.1:4840/devsim/"


@pytest.mark.parametrize("spec", ["65536", "-1", "h:", "h:x", "h:1.5",
                                  "48\u00b2", "\u0664\u0668\u0664\u0660"])  # (int(): refused ², read ٤٨٤٠)
def test_bad_endpoints(spec: str) -> None:
    with pytest.raises(ValueError) as err:
        endpoint_url(spec)
    assert str(err.value) == f"--opcua: expected [HOST:]PORT, not {spec!r}"


@pytest.mark.parametrize(("low", "high", "shown"), [
    (-(2**31), 2**31 - 1, "Int32"), (-(2**31) - 1, 0, "Int64"), (0, 2**31, "Int64"), (None, 5, "Int64"),
])
def test_int32_only_when_the_whole_range_fits(low: int | None, high: int, shown: str) -> None:
    point = Point("n", "int", "n", get=_get, minimum=low, maximum=high)
    assert data_type(point) == shown


def test_values_out_have_the_variables_type() -> None:
    rows = {v.point: v for v in variables("d", [
        Point("b", "bool", "b", get=_get), Point("n", "int", "n", get=_get), Point("x", "float", "x", get=_get),
        Point("s", "str", "s", get=_get)])}
    for name, value, out in [("b", 1, True), ("n", 3.0, 3), ("x", 2, 2.0), ("s", 5, "5")]:
        got = to_opcua(rows[name], value)
        assert got == out and type(got) is type(out)


def test_variables_skip_hidden_points_anywhere_and_cite_sections() -> None:
    hidden = Point("hidden", "int", "no get, no put")
    rows = variables("d", [hidden, Point("a", "int", "a doc", "§1.2", get=_get), Point("b", "int", "b doc", get=_get)])
    assert [(v.point, v.description) for v in rows] == [("a", "a doc (§1.2)"), ("b", "b doc")]
    with pytest.raises(ValueError) as err:
        variables("d", [Point("Kind", "int", "k", get=_get)])
    assert str(err.value) == "point 'Kind' has a name the OPC UA device object uses itself"


def test_messages_of_refused_writes() -> None:
    json_var, = variables("d", [Point("j", "json", "j", get=_get, put=lambda m, v: None)])
    with pytest.raises(TypeMismatch) as err:
        from_opcua(json_var, "Double", 1.0)
    assert str(err.value) == "j takes String, not Double"
    with pytest.raises(BadValue) as err2:
        from_opcua(json_var, "String", "{")
    assert str(err2.value) == "j takes JSON text"
