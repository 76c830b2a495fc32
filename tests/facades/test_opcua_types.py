"""The OPC UA facade's one type policy (issue 29), checked with asyncua and with node-opcua.

OPC UA Part 4, 5.10.4.1 (Write): "A Server shall return a Bad_TypeMismatch error if the data type
of the written value is not the same type or subtype of the Attribute's DataType."  The built-in
types a point variable has (Boolean, Int32, Int64, Double, String) have no subtype a client can
send, so a Double variable takes only Double, an Int32 only Int32, and so on.

The matrix comes from the kinds' point tables: every writable point variable of every registered
kind, written with every other built-in type, answers Bad_TypeMismatch and the device keeps its
value; written with its own type (a value next to the one it has), it answers Good and the device
has the new value, or Bad_OutOfRange exactly where the control API refuses that value too.  The
device is read through the control API's socket (what ``devsim ctl read`` uses), not through OPC UA.

Values of the right type outside what a point declares (below its minimum, above its maximum, not
one of its choices; NaN and infinity for every Double) are Bad_OutOfRange (Part 4, Table 61:
"the value was out of range"), and the device keeps its value.
"""

from __future__ import annotations

import json
import math
from collections.abc import Iterator
from typing import Any, NamedTuple

import pytest
from asyncua import Client, ua

from devsim.core.points import Point
from devsim.core.registry import kinds
from devsim.facades.opcua import OpcuaFacade, start_opcua
from devsim.facades.opcua_space import NAMESPACE, Variable, variables
from devsim.runtime import Runtime
from devsim.runtime.client import ControlClient, ControlError
from devsim.runtime.control import ControlServer
from tests.facades.opcua_clients import node_client

#: A value of each built-in type a client may send (the types of the issue, and two more).
SENT = {"Boolean": True, "Int16": 1, "Int32": 1, "UInt32": 1, "Int64": 1, "Float": 1.0, "Double": 1.0,
        "String": "1"}
DATA_TYPES = {"Boolean", "Int32", "Int64", "Double", "String"}  # the ones point variables have


class Served(NamedTuple):
    runtime: Runtime
    facade: OpcuaFacade
    control: ControlClient  # the control API over its socket, as `devsim ctl` talks to it


@pytest.fixture(scope="module")
def served() -> Iterator[Served]:
    runtime = Runtime(virtual=True).start()
    server: ControlServer | None = None
    try:
        devices = [runtime.add_device(kind, kind) for kind in sorted(kinds())]
        facade = runtime.run(start_opcua(runtime, devices, "127.0.0.1:0"), timeout=60)
        server = ControlServer(runtime, "127.0.0.1:0")
        with ControlClient(str(server.start_sync())) as control:
            yield Served(runtime, facade, control)
    finally:
        if server is not None:
            server.close_sync()
        runtime.stop()


class Write(NamedTuple):
    kind: str
    row: Variable
    vtype: str  # the variant type sent
    value: Any


def _points(runtime: Runtime, kind: str) -> tuple[list[Variable], dict[str, Point]]:
    points = list(runtime.device(kind).points)
    return variables(kind, points), {point.name: point for point in points}


def mismatches(runtime: Runtime) -> list[Write]:
    """Every writable variable of every kind with every built-in type but its own."""
    return [Write(kind, row, vtype, value)
            for kind in sorted(kinds()) for row in _points(runtime, kind)[0] if row.writable
            for vtype, value in SENT.items() if vtype != row.data_type]


def _another(row: Variable, point: Point, current: Any) -> Any:
    """A value of the variable's own type next to ``current`` (None: the table offers none)."""
    if row.data_type == "Boolean":
        return not current
    if point.choices:
        return next((choice for choice in point.choices if choice != current), None)
    if row.data_type in ("Int32", "Int64", "Double"):
        for value in (current + 1, current - 1):
            if (point.minimum is None or value >= point.minimum) and (point.maximum is None or value <= point.maximum):
                return float(value) if row.data_type == "Double" else int(value)
    return None  # free text, JSON


def own_type_writes(served: Served) -> list[Write]:
    """Every readable and writable variable with a value of its own type it does not have now."""
    writes = []
    for kind in sorted(kinds()):
        rows, points = _points(served.runtime, kind)
        for row in rows:
            if row.readable and row.writable and row.type != "json":
                current = served.control.read(kind, row.point)
                value = None if current is None else _another(row, points[row.point], current)
                if value is not None:
                    writes.append(Write(kind, row, row.data_type, value))
    return writes


_LIMITS = {"Int32": 2**31 - 1, "Int64": 2**63 - 1, "Double": math.inf}


def out_of_range(runtime: Runtime) -> list[Write]:
    """Every writable variable with a declared range or choices, written just outside them;
    every writable Double with NaN and infinity."""
    writes = []
    for kind in sorted(kinds()):
        rows, points = _points(runtime, kind)
        for row in rows:
            point = points[row.point]
            if not row.writable or row.type in ("bool", "json"):
                continue
            outside: list[Any] = []
            if point.choices and row.data_type == "String":
                outside.append("|".join(map(str, point.choices)))  # none of them
            elif point.choices:
                outside.append(max(point.choices) + 1)
            step = 1.0 if row.data_type == "Double" else 1
            if point.minimum is not None:
                outside.append(type(step)(point.minimum) - step)
            if point.maximum is not None:
                outside.append(type(step)(point.maximum) + step)
            if row.data_type == "Double":
                outside += [math.nan, math.inf, -math.inf]
            writes += [Write(kind, row, row.data_type, value) for value in outside
                       if isinstance(value, str) or abs(value) <= _LIMITS[row.data_type]]
    return writes


def device_values(control: ControlClient, writes: list[Write]) -> dict[str, Any]:
    """What the devices give for the readable variables written (or the error they answer)."""
    values: dict[str, Any] = {}
    for write in writes:
        if write.row.readable and write.row.node_id not in values:
            try:
                values[write.row.node_id] = control.read(write.kind, write.row.point)
            except ControlError as error:
                values[write.row.node_id] = error.type
    return values


def check_own_type_write(control: ControlClient, write: Write, status: str, before: Any) -> bool:
    """Good: the device has what the control API makes of the same value (``devsim ctl set``:
    the value itself, or the device's own rounding, or nothing where the device ignores it in
    its state); Bad_OutOfRange: the control API refuses the value too and nothing changed.
    True when the device has exactly the value written."""
    where = (write.kind, write.row.point, write.value, status)
    got = control.read(write.kind, write.row.point)
    if status == "Good":
        control.set(write.kind, write.row.point, write.value)
        assert control.read(write.kind, write.row.point) == got, where
        return bool(got == write.value and got != before)
    assert status == "BadOutOfRange", where
    assert got == before, where
    with pytest.raises(ControlError):
        control.set(write.kind, write.row.point, write.value)
    return False


def _node_ids(ns: int, writes: list[Write]) -> list[ua.NodeId]:
    return [ua.NodeId(write.row.node_id, ns) for write in writes]


def _data_values(writes: list[Write]) -> list[ua.DataValue]:
    return [ua.DataValue(ua.Variant(write.value, ua.VariantType[write.vtype])) for write in writes]


async def test_asyncua_every_other_type_is_a_type_mismatch_and_changes_nothing(served: Served) -> None:
    writes = mismatches(served.runtime)
    assert {write.row.data_type for write in writes} == DATA_TYPES
    before = device_values(served.control, writes)
    async with Client(served.facade.url) as client:
        ns = await client.get_namespace_index(NAMESPACE)
        nodes = [client.get_node(node_id) for node_id in _node_ids(ns, writes)]
        statuses = await client.write_values(nodes, _data_values(writes), raise_on_partial_error=False)
    wrong = [(w.kind, w.row.point, w.vtype, s.name) for w, s in zip(writes, statuses, strict=True)
             if s.value != ua.StatusCodes.BadTypeMismatch]
    assert wrong == []
    assert device_values(served.control, writes) == before


async def test_asyncua_its_own_type_is_taken_and_the_device_has_it(served: Served) -> None:
    writes = own_type_writes(served)
    seen: set[str] = set()
    async with Client(served.facade.url) as client:
        ns = await client.get_namespace_index(NAMESPACE)
        for write, node_id, data_value in zip(writes, _node_ids(ns, writes), _data_values(writes), strict=True):
            before = served.control.read(write.kind, write.row.point)
            [status] = await client.write_values([client.get_node(node_id)], [data_value],
                                                 raise_on_partial_error=False)
            if check_own_type_write(served.control, write, status.name, before):
                seen.add(write.row.data_type)
    assert seen == DATA_TYPES  # each type written and seen by the device


def test_node_opcua_every_other_type_is_a_type_mismatch_and_changes_nothing(served: Served) -> None:
    writes = mismatches(served.runtime)
    before = device_values(served.control, writes)
    [result] = node_client(served.facade.url, [
        {"op": "writes", "items": [[w.row.node_id, w.vtype, w.value] for w in writes]}])
    wrong = [(w.kind, w.row.point, w.vtype, status) for w, status in zip(writes, result["statuses"], strict=True)
             if status != "BadTypeMismatch"]
    assert wrong == []
    assert device_values(served.control, writes) == before


async def test_asyncua_a_value_outside_the_declared_range_is_out_of_range(served: Served) -> None:
    writes = out_of_range(served.runtime)
    assert {write.row.data_type for write in writes} == {"Int32", "Int64", "Double", "String"}
    before = device_values(served.control, writes)
    async with Client(served.facade.url) as client:
        ns = await client.get_namespace_index(NAMESPACE)
        nodes = [client.get_node(node_id) for node_id in _node_ids(ns, writes)]
        statuses = await client.write_values(nodes, _data_values(writes), raise_on_partial_error=False)
    wrong = [(w.kind, w.row.point, w.value, s.name) for w, s in zip(writes, statuses, strict=True)
             if s.value != ua.StatusCodes.BadOutOfRange]
    assert wrong == []
    assert device_values(served.control, writes) == before


def test_node_opcua_a_value_outside_the_declared_range_is_out_of_range(served: Served) -> None:
    writes = out_of_range(served.runtime)
    before = device_values(served.control, writes)
    items = [[w.row.node_id, w.vtype, w.value if isinstance(w.value, str) or math.isfinite(w.value)
              else json.dumps(w.value)] for w in writes]  # "NaN", "Infinity": JSON has no such number
    [result] = node_client(served.facade.url, [{"op": "writes", "items": items}])
    wrong = [(w.kind, w.row.point, w.value, status) for w, status in zip(writes, result["statuses"], strict=True)
             if status != "BadOutOfRange"]
    assert wrong == []
    assert device_values(served.control, writes) == before


def test_node_opcua_its_own_type_is_taken_and_the_device_has_it(served: Served) -> None:
    """One node-opcua run writes the first candidate of each data type of each kind (one after
    the other, then the devices are read: fewer writes, so that none undoes another's effect)."""
    firsts: dict[tuple[str, str], Write] = {}
    for write in own_type_writes(served):
        firsts.setdefault((write.kind, write.row.data_type), write)
    writes = list(firsts.values())
    befores = [served.control.read(write.kind, write.row.point) for write in writes]
    results = node_client(served.facade.url, [
        {"op": "write", "node": write.row.node_id, "type": write.vtype, "value": write.value} for write in writes])
    seen = set()
    for write, result, before in zip(writes, results, befores, strict=True):
        if check_own_type_write(served.control, write, result["status"], before):
            seen.add(write.row.data_type)
    assert seen == DATA_TYPES
