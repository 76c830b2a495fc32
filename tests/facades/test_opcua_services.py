"""The OPC UA facade against OPC UA Part 4's status codes (issue 29), through asyncua and
node-opcua: Read (5.10.2, Table 55; a dataEncoding 7.34), Write (5.10.4, Table 61), Call (5.11.2, Tables 67 and 68),
and the AccessLevel / UserAccessLevel of every point (Part 3, 5.6.2) from its declared access;
HistoryRead (5.10.3, Table 58) of a node the facade keeps no history for; Bad_NothingToDo for
a request of any service with an empty list of operations (asyncua answered Good, no results).

Expected codes are the standard's: a node the server does not have is Bad_NodeIdUnknown; an
attribute the node does not have Bad_AttributeIdInvalid; a Value whose AccessLevel has no
CurrentWrite, or another attribute whose WriteMask bit is clear, Bad_NotWritable; a write with an
IndexRange or a status code the server does not support Bad_WriteNotSupported; a call with too
few or too many arguments Bad_ArgumentsMissing / Bad_TooManyArguments, one with an argument of
another type Bad_InvalidArgument with Bad_TypeMismatch for that argument, a method that is not
the object's Bad_MethodInvalid, an object that does not exist Bad_NodeIdUnknown and a node that
is not an object Bad_NodeIdInvalid.  Nothing refused changes the device.
"""

from __future__ import annotations

import asyncio
from collections.abc import Callable, Iterator
from datetime import UTC, datetime, timedelta
from typing import Any, NamedTuple

import pytest
from asyncua import Client, ua

from devsim.facades.opcua import OpcuaFacade, start_opcua
from devsim.facades.opcua_space import NAMESPACE, variables
from devsim.runtime import Runtime
from tests.facades.opcua_clients import node_client

TEMPERATURE = "sers.quantity.heatsink_temperature"  # rw Double, 0..200 °C (the SERS table)


class Served(NamedTuple):
    runtime: Runtime
    facade: OpcuaFacade
    switched: list[tuple[str, str, bool]]  # (device, fault, active) as the devices announce it


@pytest.fixture(scope="module")
def served() -> Iterator[Served]:
    runtime = Runtime(virtual=True).start()
    try:
        devices = [runtime.add_device(kind, kind) for kind in ("sers", "gms96")]
        switched: list[tuple[str, str, bool]] = []
        for device in devices:
            runtime.call(lambda d=device: d.model.listen(
                "fault_switched", lambda kind, active, name=d.name: switched.append((name, kind, active))))
        facade = runtime.run(start_opcua(runtime, devices, "127.0.0.1:0"), timeout=60)
        yield Served(runtime, facade, switched)
    finally:
        runtime.stop()


def _other_temperature(runtime: Runtime) -> float:
    return 55.0 if runtime.read("sers", "quantity.heatsink_temperature") != 55.0 else 56.0


# -- Write and Read ------------------------------------------------------------------------------
#: (node, attribute, variant type, value, index range, status code written) -> the Part 4 answer
WRITES = [
    ("sers.nope", "Value", "Double", 1.0, None, None, "BadNodeIdUnknown"),
    ("sers.axis.position", "Value", "Double", 1.0, None, None, "BadNotWritable"),  # AccessLevel r
    ("sers#Kind", "Value", "String", "x", None, None, "BadNotWritable"),  # a read-only property
    (TEMPERATURE, "DisplayName", "LocalizedText", "x", None, None, "BadNotWritable"),  # WriteMask 0
    (TEMPERATURE, "AccessLevel", "Byte", 3, None, None, "BadNotWritable"),
    (TEMPERATURE, "EventNotifier", "Byte", 1, None, None, "BadAttributeIdInvalid"),  # not a Variable's
    ("sers", "Value", "Double", 1.0, None, None, "BadAttributeIdInvalid"),  # an Object has no Value
    (TEMPERATURE, "Value", "Double", 500.0, None, None, "BadOutOfRange"),  # above 200 °C
    ("sers.program", "Value", "String", "{not json", None, None, "BadOutOfRange"),  # a String, not JSON text
    (TEMPERATURE, "Value", "Double", 40.0, "0", None, "BadWriteNotSupported"),  # a scalar: no IndexRange
    (TEMPERATURE, "Value", "Double", 40.0, None, "BadInternalError", "BadWriteNotSupported"),  # no status
]
#: (node, attribute, data encoding) -> the Part 4 answer
READS = [
    ("sers.nope", "Value", None, "BadNodeIdUnknown"),
    ("sers", "Value", None, "BadAttributeIdInvalid"),
    ("sers.encoder.pulses", "Value", None, "BadNotReadable"),  # write-only: AccessLevel w
    ("sers.axis.position", "EventNotifier", None, "BadAttributeIdInvalid"),
    ("sers.axis.position", "Value", "Default Binary", "BadDataEncodingInvalid"),  # a Double: no Structure
    ("sers.axis.position", "DisplayName", "Default Binary", "BadDataEncodingInvalid"),  # not a Value
    ("i=2256", "Value", "Default XML", "BadDataEncodingUnsupported"),  # ServerStatus: a Structure
    ("i=2256", "Value", "Default Binary", "Good"),
]


def _write_value(ns: int, node: str, attribute: str, vtype: str, value: Any, index_range: str | None,
                 status: str | None) -> ua.WriteValue:
    if vtype == "LocalizedText":
        value = ua.LocalizedText(value)
    data_value = ua.DataValue(ua.Variant(value, ua.VariantType[vtype]))
    if status is not None:
        data_value = ua.DataValue(data_value.Value, StatusCode=ua.StatusCode(getattr(ua.StatusCodes, status)))
    return ua.WriteValue(NodeId=ua.NodeId(node, ns), AttributeId=ua.AttributeIds[attribute], Value=data_value,
                         IndexRange=index_range)


def _unchanged(served: Served, temperature: float, program: Any) -> None:
    assert served.runtime.read("sers", "quantity.heatsink_temperature") == temperature
    assert served.runtime.read("sers", "program") == program


async def test_asyncua_write_and_read_answer_with_part4_status_codes(served: Served) -> None:
    temperature = served.runtime.read("sers", "quantity.heatsink_temperature")
    program = served.runtime.read("sers", "program")
    async with Client(served.facade.url) as client:
        ns = await client.get_namespace_index(NAMESPACE)
        statuses = await client.uaclient.write(ua.WriteParameters(NodesToWrite=[
            _write_value(ns, *row[:-1]) for row in WRITES]))
        assert [status.name for status in statuses] == [row[-1] for row in WRITES]
        _unchanged(served, temperature, program)
        node = client.get_node(ua.NodeId(TEMPERATURE, ns))
        assert (await node.read_display_name()).Text == "quantity.heatsink_temperature"
        assert await client.get_node(ua.NodeId("sers#Kind", ns)).read_value() == "sers"
        results = await client.uaclient.read(ua.ReadParameters(NodesToRead=[
            ua.ReadValueId(NodeId=ua.NodeId.from_string(node) if node.startswith("i=") else ua.NodeId(node, ns),
                           AttributeId=ua.AttributeIds[attribute],
                           DataEncoding=ua.QualifiedName(encoding, 0) if encoding else ua.QualifiedName())
            for node, attribute, encoding, _ in READS]))
        assert [result.StatusCode.name for result in results] == [row[-1] for row in READS]
        new = _other_temperature(served.runtime)  # and a write that may be done still is
        await node.write_value(ua.Variant(new, ua.VariantType.Double))
        assert served.runtime.read("sers", "quantity.heatsink_temperature") == new


def test_node_opcua_write_and_read_answer_with_part4_status_codes(served: Served) -> None:
    temperature = served.runtime.read("sers", "quantity.heatsink_temperature")
    program = served.runtime.read("sers", "program")
    plan: list[dict[str, Any]] = []
    for node, attribute, vtype, value, index_range, status, _ in WRITES:
        step = {"op": "write", "node": node, "attribute": attribute, "type": vtype, "value": value}
        if vtype == "LocalizedText":
            step["value"] = {"text": value}
        if index_range is not None:
            step["indexRange"] = index_range
        if status is not None:
            step["statusCode"] = status
        plan.append(step)
    plan += [{"op": "read", "nodeId" if node.startswith("i=") else "node": node, "attribute": attribute,
              "encoding": encoding} for node, attribute, encoding, _ in READS]
    results = node_client(served.facade.url, plan)
    assert [result["status"] for result in results] == [row[-1] for row in WRITES] + [row[-1] for row in READS]
    _unchanged(served, temperature, program)


async def test_access_levels_are_the_points_access(served: Served) -> None:
    """AccessLevel and UserAccessLevel: CurrentRead for r, CurrentWrite for w, both for rw (no
    user is refused what the access allows), for every point of both devices."""
    async with Client(served.facade.url) as client:
        ns = await client.get_namespace_index(NAMESPACE)
        for kind in ("sers", "gms96"):
            rows = variables(kind, served.runtime.device(kind).points)
            nodes = [client.get_node(ua.NodeId(row.node_id, ns)) for row in rows]
            wanted = [row.readable * ua.AccessLevel.CurrentRead.mask | row.writable * ua.AccessLevel.CurrentWrite.mask
                      for row in rows]
            for attribute in (ua.AttributeIds.AccessLevel, ua.AttributeIds.UserAccessLevel):
                levels = await client.read_attributes(nodes, attribute)
                assert [level.Value.Value for level in levels] == wanted, (kind, attribute)
    # node-opcua reads the first point of each access of the SERS table
    firsts: dict[tuple[bool, bool], str] = {}
    for row in variables("sers", served.runtime.device("sers").points):
        firsts.setdefault((row.readable, row.writable), row.node_id)
    assert len(firsts) == 3
    plan = [{"op": "read", "node": node, "attribute": attribute} for node in firsts.values()
            for attribute in ("AccessLevel", "UserAccessLevel")]
    results = iter(node_client(served.facade.url, plan))
    for readable, writable in firsts:
        for _ in range(2):
            assert next(results)["value"] == readable * 1 | writable * 2


# -- Read: index ranges, timestamps, maxAge; Browse -----------------------------------------------
LEVEL = "sers.dip.input_level"  # a String point (its choice's name)
#: (node, index range) -> the status code, and the part of the value (Part 4, 7.27: first..last)
RANGES = [
    (LEVEL, "0:1", "Good", lambda text, kinds: text[0:2]),
    (LEVEL, "1", "Good", lambda text, kinds: text[1:2]),
    ("sers#FaultKinds", "1:2", "Good", lambda text, kinds: kinds[1:3]),
    (TEMPERATURE, "0", "BadIndexRangeNoData", None),  # a scalar number has no elements
    (LEVEL, "1000:1001", "BadIndexRangeNoData", None),  # past the end
    # 7.27: "Arrays of ByteString and String values are treated as two dimensional arrays where the
    # final index specifies the substring range"
    ("sers#FaultKinds", "0,0", "Good", lambda text, kinds: [kinds[0][0:1]]),
    ("sers#FaultKinds", "0:1,1:2", "Good", lambda text, kinds: [kinds[0][1:3], kinds[1][1:3]]),
    ("sers#FaultKinds", "0,1000", "BadIndexRangeNoData", None),  # no element that long
    ("sers#FaultKinds", "0,0,0", "BadIndexRangeNoData", None),  # three dimensions
    (LEVEL, "7:5", "BadIndexRangeInvalid", None),  # first not below last: invalid syntax
    (LEVEL, "0:x", "BadIndexRangeInvalid", None),
    (LEVEL, "\u0660:\u0661", "BadIndexRangeInvalid", None),  # 7.27's digits are ASCII, not Arabic-Indic ٠:١
    (LEVEL, "\uff10", "BadIndexRangeInvalid", None),  # nor a fullwidth ０
]
#: (node, attribute other than the Value, index range) -> the status code, and the part of the value:
#: 7.27, "Bad_IndexRangeInvalid is only used for invalid syntax of the NumericRange.  All other invalid
#: requests with a valid syntax shall result in Bad_IndexRangeNoData" (a LocalizedText, a QualifiedName)
ATTRIBUTE_RANGES = [
    (TEMPERATURE, "DisplayName", "0:1", "BadIndexRangeNoData", None),
    (TEMPERATURE, "BrowseName", "0", "BadIndexRangeNoData", None),
    (TEMPERATURE, "DisplayName", "7:5", "BadIndexRangeInvalid", None),
    ("sers#FaultKinds", "ArrayDimensions", "0", "Good", [0]),  # an array: its part
    ("sers#FaultKinds", "ArrayDimensions", "1", "BadIndexRangeNoData", None),  # past its end
]
TIMESTAMPS = {"Source": (True, False), "Server": (False, True), "Both": (True, True), "Neither": (False, False)}


def _expected_ranges(served: Served) -> list[tuple[str, Any]]:
    text = served.runtime.read("sers", "dip.input_level")
    kinds = served.runtime.call(lambda: served.runtime.device("sers").faults.names())
    return [(status, part(text, kinds) if part else None) for *_, status, part in RANGES]


async def test_asyncua_reads_honour_index_range_timestamps_and_max_age(served: Served) -> None:
    async with Client(served.facade.url) as client:
        ns = await client.get_namespace_index(NAMESPACE)

        async def read(node: str, index_range: str | None = None, timestamps: str = "Both",
                       max_age: float = 0) -> ua.DataValue:
            [result] = await client.uaclient.read(ua.ReadParameters(
                NodesToRead=[ua.ReadValueId(NodeId=ua.NodeId(node, ns), AttributeId=ua.AttributeIds.Value,
                                            IndexRange=index_range)],
                TimestampsToReturn=ua.TimestampsToReturn[timestamps], MaxAge=max_age))
            return result

        got = []
        for node, index_range, *_ in RANGES:
            result = await read(node, index_range)
            got.append((result.StatusCode.name, result.Value.Value if result.StatusCode.is_good() else None))
        assert got == _expected_ranges(served)
        for node in (TEMPERATURE, "sers#Kind"):  # a point, a property
            for timestamps, wanted in TIMESTAMPS.items():
                result = await read(node, timestamps=timestamps)
                assert (result.SourceTimestamp is not None, result.ServerTimestamp is not None) == wanted, (
                    node, timestamps)
        results = await client.uaclient.read(ua.ReadParameters(NodesToRead=[
            ua.ReadValueId(NodeId=ua.NodeId(node, ns), AttributeId=ua.AttributeIds[attribute], IndexRange=index_range)
            for node, attribute, index_range, *_ in ATTRIBUTE_RANGES]))
        assert [(result.StatusCode.name, result.Value.Value if result.StatusCode.is_good() else None)
                for result in results] == [(status, part) for *_, status, part in ATTRIBUTE_RANGES]
        with pytest.raises(ua.uaerrors.BadMaxAgeInvalid):
            await read(TEMPERATURE, max_age=-1)
        with pytest.raises(ua.uaerrors.BadTimestampsToReturnInvalid):
            await read(TEMPERATURE, timestamps="Invalid")
        assert await client.get_node(ua.NodeId("sers#FaultKinds", ns)).read_value_rank() == ua.ValueRank.OneDimension
        [browsed] = await client.uaclient.browse(ua.BrowseParameters(NodesToBrowse=[ua.BrowseDescription(
            NodeId=ua.NodeId("sers.nope", ns), BrowseDirection=ua.BrowseDirection.Forward)]))
        assert browsed.StatusCode.name == "BadNodeIdUnknown"


def test_node_opcua_reads_honour_index_range_timestamps_and_max_age(served: Served) -> None:
    plan: list[dict[str, Any]] = [{"op": "read", "node": node, "indexRange": index_range}
                                  for node, index_range, *_ in RANGES]
    plan += [{"op": "read", "node": TEMPERATURE}, {"op": "read", "node": "sers#Kind"},  # both timestamps
             {"op": "read", "node": TEMPERATURE, "maxAge": -1},
             {"op": "read", "node": "sers#FaultKinds", "attribute": "ValueRank"},
             {"op": "browse", "node": "sers.nope"}]
    plan += [{"op": "read", "node": node, "attribute": attribute, "indexRange": index_range}
             for node, attribute, index_range, *_ in ATTRIBUTE_RANGES]
    results = node_client(served.facade.url, plan)
    ranges, (point, prop, aged, rank, browsed), attributes = (
        results[:len(RANGES)], results[len(RANGES):len(RANGES) + 5], results[len(RANGES) + 5:])
    assert [(r["status"], r["value"] if r["status"] == "Good" else None) for r in attributes] == [
        (status, part) for *_, status, part in ATTRIBUTE_RANGES]
    assert [(r["status"], r["value"] if r["status"] == "Good" else None) for r in ranges] == _expected_ranges(served)
    assert point["timestamps"] == prop["timestamps"] == [True, True]
    assert aged == {"fault": "BadMaxAgeInvalid"}
    assert rank["value"] == 1  # OneDimension
    assert browsed["status"] == "BadNodeIdUnknown"


# -- Subscriptions ---------------------------------------------------------------------------------
def _monitored(served: Served) -> tuple[list[str], list[str]]:
    """Every point variable of the SERS and the status its first data change has: Good for a
    readable one (null text where the point has no value now), Bad_NotReadable for a write-only
    one (Part 4, 5.12.2: the monitored item is created, and the Publish response says the value
    cannot be read)."""
    rows = variables("sers", served.runtime.device("sers").points)
    wanted = []
    for row in rows:
        if not row.readable:
            wanted.append("BadNotReadable")
        elif served.runtime.read("sers", row.point) is None and row.data_type != "String":
            wanted.append("BadNoData")  # a number with no value now
        else:
            wanted.append("Good")
    return [row.node_id for row in rows], wanted


class _FirstChanges:
    """asyncua subscription handler: the status of each node's first data change."""

    def __init__(self, count: int) -> None:
        self.statuses: dict[str, str] = {}
        self.count = count
        self.done = asyncio.Event()

    def datachange_notification(self, node: Any, value: Any, data: Any) -> None:
        self.statuses.setdefault(node.nodeid.Identifier, data.monitored_item.Value.StatusCode.name)
        if len(self.statuses) == self.count:
            self.done.set()


async def test_asyncua_a_write_only_point_is_monitored_as_not_readable(served: Served) -> None:
    names, wanted = _monitored(served)
    assert "BadNotReadable" in wanted and "Good" in wanted
    changes = _FirstChanges(len(names))
    async with Client(served.facade.url) as client:
        ns = await client.get_namespace_index(NAMESPACE)
        subscription = await client.create_subscription(20, changes)
        await subscription.subscribe_data_change([client.get_node(ua.NodeId(name, ns)) for name in names])
        await asyncio.wait_for(changes.done.wait(), 10)
        await subscription.delete()
    assert [changes.statuses[name] for name in names] == wanted


def test_node_opcua_a_write_only_point_is_monitored_as_not_readable(served: Served) -> None:
    names, wanted = _monitored(served)
    [result] = node_client(served.facade.url, [{"op": "monitor", "nodes": names}])
    assert result["statuses"] == wanted


# -- Call ------------------------------------------------------------------------------------------
S, B, I32 = "String", "Boolean", "Int32"
#: (object, method, arguments) -> (the call's status, the input arguments' statuses)
CALLS = [
    ("sers", "sers#Fault", [(S, "blocked_axis")], "BadArgumentsMissing", []),
    ("sers", "sers#Fault", [(S, "blocked_axis"), (B, True), (B, True)], "BadTooManyArguments", []),
    ("sers", "sers#Fault", [(S, "blocked_axis"), (I32, 1)], "BadInvalidArgument", ["Good", "BadTypeMismatch"]),
    ("sers", "sers#Fault", [(B, True), (S, "on")], "BadInvalidArgument", ["BadTypeMismatch", "BadTypeMismatch"]),
    ("sers", "sers#Fault", [(S, "no_such_fault"), (B, True)], "BadInvalidArgument", ["BadOutOfRange", "Good"]),
    ("gms96", "sers#Fault", [(S, "blocked_axis"), (B, True)], "BadMethodInvalid", []),  # not gms96's method
    ("sers", "sers#Nope", [(S, "blocked_axis"), (B, True)], "BadMethodInvalid", []),
    ("nope", "sers#Fault", [(S, "blocked_axis"), (B, True)], "BadNodeIdUnknown", []),
    ("sers.axis.position", "sers#Fault", [(S, "blocked_axis"), (B, True)], "BadNodeIdInvalid", []),  # a Variable
    ("sers", "sers#PowerCycle", [], "BadArgumentsMissing", []),
    ("sers", "sers#PowerCycle", [(S, "false")], "BadInvalidArgument", ["BadTypeMismatch"]),
    # and one that may be done, last: the only fault the devices announce
    ("sers", "sers#Fault", [(S, "blocked_axis"), (B, True)], "Good", ["Good", "Good"]),
]


def _check_calls(served: Served, got: list[tuple[str, list[str]]]) -> None:
    assert got == [(status, inputs) for *_, status, inputs in CALLS]
    assert served.switched == [("sers", "blocked_axis", True)]  # nothing refused ran
    assert served.runtime.call(lambda: [name for _, name in served.runtime.device("sers").events]) == []
    served.runtime.fault("sers", "blocked_axis", False)
    served.switched.clear()


async def test_asyncua_calls_answer_with_part4_status_codes(served: Served) -> None:
    served.switched.clear()
    served.runtime.call(lambda: served.runtime.device("sers").events.clear())
    async with Client(served.facade.url) as client:
        ns = await client.get_namespace_index(NAMESPACE)
        requests = [ua.CallMethodRequest(ObjectId=ua.NodeId(obj, ns), MethodId=ua.NodeId(method, ns),
                                         InputArguments=[ua.Variant(v, ua.VariantType[t]) for t, v in args])
                    for obj, method, args, *_ in CALLS]
        results = [(await client.uaclient.call([request]))[0] for request in requests]  # one after the other
    _check_calls(served, [(r.StatusCode.name, [s.name for s in r.InputArgumentResults]) for r in results])


def test_node_opcua_calls_answer_with_part4_status_codes(served: Served) -> None:
    served.switched.clear()
    served.runtime.call(lambda: served.runtime.device("sers").events.clear())
    plan = [{"op": "call", "object": obj, "method": method, "args": [[t, v] for t, v in args]}
            for obj, method, args, *_ in CALLS]
    results = node_client(served.facade.url, plan)
    _check_calls(served, [(result["status"], result["inputs"]) for result in results])


# -- HistoryRead -----------------------------------------------------------------------------------
#: (node, history asked for) -> the Part 4 answer (5.10.3, Table 58): the facade keeps no history
HISTORY = [
    ("sers.nope", "raw", "BadNodeIdUnknown"),
    ("sers.axis.position", "raw", "BadHistoryOperationUnsupported"),  # AccessLevel without HistoryRead
    ("sers.axis.position", "processed", "BadHistoryOperationUnsupported"),
    ("sers", "events", "BadHistoryOperationUnsupported"),  # EventNotifier without HistoryRead
]


def _history(kind: str) -> Any:
    end = datetime.now(UTC)
    start = end - timedelta(hours=1)
    if kind == "raw":
        return ua.ReadRawModifiedDetails(StartTime=start, EndTime=end, NumValuesPerNode=10)
    if kind == "processed":
        return ua.ReadProcessedDetails(StartTime=start, EndTime=end, ProcessingInterval=1000.0)
    return ua.ReadEventDetails(StartTime=start, EndTime=end, NumValuesPerNode=10, Filter=ua.EventFilter())


async def test_asyncua_history_reads_answer_with_part4_status_codes(served: Served) -> None:
    async with Client(served.facade.url) as client:
        ns = await client.get_namespace_index(NAMESPACE)
        got = []
        for node, kind, _ in HISTORY:
            [result] = await client.uaclient.history_read(ua.HistoryReadParameters(
                HistoryReadDetails=_history(kind), TimestampsToReturn=ua.TimestampsToReturn.Both,
                NodesToRead=[ua.HistoryReadValueId(NodeId=ua.NodeId(node, ns))]))
            got.append(result.StatusCode.name)
    assert got == [status for *_, status in HISTORY]


def test_node_opcua_history_reads_answer_with_part4_status_codes(served: Served) -> None:
    raw = [(node, status) for node, kind, status in HISTORY if kind == "raw"]
    results = node_client(served.facade.url, [{"op": "history", "node": node} for node, _ in raw])
    assert [result["status"] for result in results] == [status for _, status in raw]


# -- a request of no operations ------------------------------------------------------------------
#: service -> its request with an empty list of operations (Part 4: Bad_NothingToDo, the whole request)
EMPTY: dict[str, Callable[[Any, int], Any]] = {
    "Read": lambda u, sub: u.read(ua.ReadParameters(NodesToRead=[])),
    "Write": lambda u, sub: u.write(ua.WriteParameters(NodesToWrite=[])),
    "Browse": lambda u, sub: u.browse(ua.BrowseParameters(NodesToBrowse=[])),
    "TranslateBrowsePathsToNodeIds": lambda u, sub: u.translate_browsepaths_to_nodeids([]),
    "Call": lambda u, sub: u.call([]),
    "HistoryRead": lambda u, sub: u.history_read(ua.HistoryReadParameters(
        HistoryReadDetails=ua.ReadRawModifiedDetails(), NodesToRead=[])),
    "CreateMonitoredItems": lambda u, sub: u.create_monitored_items(ua.CreateMonitoredItemsParameters(
        SubscriptionId=sub, ItemsToCreate=[])),
    "ModifyMonitoredItems": lambda u, sub: u.modify_monitored_items(ua.ModifyMonitoredItemsParameters(
        SubscriptionId=sub, ItemsToModify=[])),
    "DeleteMonitoredItems": lambda u, sub: u.delete_monitored_items(ua.DeleteMonitoredItemsParameters(
        SubscriptionId=sub, MonitoredItemIds=[])),
    "SetMonitoringMode": lambda u, sub: u.set_monitoring_mode(ua.SetMonitoringModeParameters(
        SubscriptionId=sub, MonitoredItemIds=[])),
    "SetPublishingMode": lambda u, sub: u.set_publishing_mode(ua.SetPublishingModeParameters(SubscriptionIds=[])),
    "DeleteSubscriptions": lambda u, sub: u.delete_subscriptions([]),
    "RegisterNodes": lambda u, sub: u.register_nodes([]),
}


async def test_asyncua_a_request_of_no_operations_is_nothing_to_do(served: Served) -> None:
    async with Client(served.facade.url) as client:
        subscription = await client.create_subscription(100, None)
        got = {}
        for service, send in EMPTY.items():
            try:
                await send(client.uaclient, subscription.subscription_id)
                got[service] = "Good"
            except ua.UaStatusCodeError as fault:
                got[service] = ua.StatusCode(fault.code).name
        assert got == dict.fromkeys(EMPTY, "BadNothingToDo")
        ns = await client.get_namespace_index(NAMESPACE)
        assert await client.get_node(ua.NodeId("sers.quantity.supply_voltage", ns)).read_value() == 68.0


def test_node_opcua_a_request_of_no_operations_is_nothing_to_do(served: Served) -> None:
    services = ["read", "write", "browse", "call"]
    results = node_client(served.facade.url, [{"op": "empty", "service": service} for service in services])
    assert results == [{"fault": "BadNothingToDo"}] * len(services)
