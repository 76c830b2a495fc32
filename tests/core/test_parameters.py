"""The kit's parameter rows (devsim.core.parameters): lookup by key, alias and spelling; checks
before a value is stored; named accessors; the points and the reference derived from the rows."""

from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from devsim.core.parameters import (
    Param,
    Parameters,
    ParameterTable,
    ParameterValues,
    accessor,
    alias_hook,
    parameter_points,
)
from devsim.core.points import BadValue, PointTable, UnknownName

ROWS = (
    Param(41, "Geschwindigkeit", "§4.8.4", "velocity", aliases=("V",), type="float", minimum=0.5,
          maximum=3000, unit="U/min", default=100, attr="velocity"),
    Param(1014, "Baudrate", "§4.8.6", "baud rate code", choices=(0, 1, 2), default=1, attr="baud"),
    Param(1133, "Version", "§4.8.6", "firmware version", access="r", saved=False, default=4),
    Param(60, "Passwort", "§4.8.6", "stored only", effect="stored", default=None, saved=False),
)
TABLE = ParameterTable(ROWS, prefix="P")


class Values(Parameters):
    velocity = accessor(41)
    baud = accessor(1014)


def test_a_row_is_found_by_number_spelling_and_alias() -> None:
    assert TABLE.find("P41") is ROWS[0]
    assert TABLE.find("p 41") is ROWS[0]
    assert TABLE.find("41") is ROWS[0]
    assert TABLE.find(41) is ROWS[0]
    assert TABLE.find("v") is ROWS[0]
    assert TABLE.find("P42") is None
    assert TABLE.find("W") is None
    with pytest.raises(UnknownName):
        TABLE.lookup("P42")
    assert TABLE.by_attr("baud") is ROWS[1]


def test_an_alias_is_matched_in_ascii_case_only() -> None:
    """Upper case is a-z to A-Z: str.upper made 'poſ' (U+017F, the long s) POS and 'ın' (U+0131,
    the dotless i) IN, so ctl read sers param.poſ read P51."""
    row = Param(51, "Position", "§4.8.4", "position", aliases=("POS", "IN"))
    table = ParameterTable((row,), prefix="P")
    assert table.find("pos") is row and table.find("In") is row
    assert table.find("po\u017f") is None and table.find("\u0131n") is None


def test_a_table_refuses_a_key_or_alias_declared_twice() -> None:
    with pytest.raises(ValueError):
        ParameterTable((ROWS[0], ROWS[0]))
    with pytest.raises(ValueError):
        ParameterTable((ROWS[0], Param(42, "x", "§1", aliases=("v",))))


def test_values_start_at_the_factory_value_and_are_checked_before_they_are_stored() -> None:
    values = Values(TABLE)
    assert values.velocity == 100 and values.baud == 1 and values[1133] == 4
    assert 60 not in values.values  # no default: no value
    seen = []
    values.on_change(lambda row, value: seen.append((row.key, value)))
    assert values.set(41, "250.5") == 250.5
    assert values.velocity == 250.5
    for bad in ("nan", 3000.5, 0.4, "fast"):
        with pytest.raises(BadValue):
            values.set(41, bad)
    with pytest.raises(BadValue):
        values.set(1014, 3)
    with pytest.raises(BadValue):
        values.set(1014, 1.5)
    assert values.velocity == 250.5 and values.baud == 1
    assert seen == [(41, 250.5)]
    values.reset([41])
    assert values.velocity == 100


def test_snapshot_and_restore_keep_only_saved_rows_and_known_keys() -> None:
    values = Values(TABLE)
    values.set(41, 200)
    image = values.snapshot()
    assert image == {41: 200, 1014: 1}
    fresh = Values(TABLE)
    fresh.restore({**image, 9999: 1, 1014: float("nan")})
    assert fresh.velocity == 200 and fresh.baud == 1 and 9999 not in fresh.values


def test_points_derive_from_the_rows() -> None:
    values = Values(TABLE)
    written = []

    def write(model: Values, row: Param, value: object) -> None:
        written.append((row.key, value))
        model.set(row.key, value)

    points = PointTable.of(
        parameter_points(TABLE, lambda m, row: m.get(row.key), write), alias=alias_hook(TABLE)
    )
    assert points.names() == ["param.P41", "param.P1014", "param.P1133", "param.P60"]
    assert points.read(values, "param.V") == 100
    points.set(values, "param.p41", 300)
    assert written == [(41, 300.0)] and values.velocity == 300
    with pytest.raises(BadValue):
        points.set(values, "param.P41", 5000)
    assert points.lookup("param.P1133").access == "r"
    assert points.lookup("param.P41").unit == "U/min"


def test_the_echo_kind_reads_its_parameter_by_name() -> None:
    """tests/support/echo.py, the README's smallest kind: P1 through the control API, the face
    reading it as ``params.repeat``."""
    from devsim.core.clock import VirtualClock
    from tests.support.echo import EchoDevice

    device = EchoDevice(clock=VirtualClock())
    sent: list[bytes] = []
    device.attach(sent.append)
    device.feed(b"ab")
    device.set("param.p1", 3)
    device.feed(b"c")
    assert sent == [b"ab", b"ccc"]
    assert device.model.params.repeat == 3 and device.read("param.P1") == 3
    with pytest.raises(BadValue):
        device.set("param.P1", 5)
    assert EchoDevice.reference().parameter_table is not None


def test_a_refusal_names_the_limit_with_every_digit() -> None:
    row = Param(7, "Weg", "§1", maximum=99999999, minimum=-214748.3647, type="float")
    with pytest.raises(BadValue, match=r"#7: 100000000 is above the maximum 99999999"):
        row.check(100000000)
    with pytest.raises(BadValue, match=r"is below the minimum -214748\.3647"):
        row.check(-300000)
    assert row.range_text() == "-214748.3647 … 99999999"


# -- the compact values (issue 31: a device's share of a plant) ------------------------------------

KEYS = st.sampled_from([41, 1014, 1133, 60, 9999, "name"])
VALUES = st.one_of(st.integers(-3, 300), st.sampled_from([100, 100.0, -0.0, 0.0, 4, True, 1, "x"]),
                   st.floats(allow_nan=True))
OPERATIONS = st.lists(st.one_of(
    st.tuples(st.just("set"), KEYS, VALUES), st.tuples(st.just("del"), KEYS, st.none()),
    st.tuples(st.just("clear"), st.none(), st.none()), st.tuples(st.just("factory"), st.none(), st.none()),
), max_size=30)


@settings(max_examples=300, deadline=None)
@given(OPERATIONS)
def test_the_compact_values_behave_as_the_dict_they_replace(operations: list) -> None:
    values, model = ParameterValues(TABLE), TABLE.defaults()
    for op, key, value in operations:
        if op == "set":
            values[key] = value
            model[key] = value
        elif op == "del":
            if key in model:
                del values[key]
                del model[key]
            else:
                with pytest.raises(KeyError):
                    del values[key]
        elif op == "clear":
            values.clear()
            model.clear()
        else:  # factory: every row's factory value, keys that are no row stay
            values.factory()
            model = {**{k: v for k, v in model.items() if k not in TABLE}, **TABLE.defaults()}
        assert list(values) == [k for k in TABLE.rows if k in model] + [k for k in model if k not in TABLE]
        assert len(values) == len(model)
        for k in (41, 1014, 1133, 60, 9999, "name"):
            assert (k in values) == (k in model)
            stored = values.get(k, "absent")
            expected = model.get(k, "absent")
            assert type(stored) is type(expected) and repr(stored) == repr(expected)  # -0.0 stays -0.0


def test_devices_share_the_factory_values_until_they_write_another() -> None:
    first, second = Values(TABLE), Values(TABLE)
    assert first.values.cells is second.values.cells is TABLE.template  # nothing copied yet
    first.values[41] = 100  # the factory value again: still shared
    assert first.values.cells is TABLE.template
    first.set(41, 250)
    assert first.values.cells is not TABLE.template and second.velocity == 100 and first.velocity == 250
    first.values[1014] = 1 + 0  # equal to the factory value: kept as its object
    assert first.values.cells[TABLE.positions[1014]] is TABLE.template[TABLE.positions[1014]]
    first.reset()
    assert first.values.cells is TABLE.template and first.velocity == 100
