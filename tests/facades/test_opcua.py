"""The OPC UA facade (issue 14) served by asyncua in a runtime's loop (virtual time), tested with
asyncua's client and with node-opcua's client run by Node.js (an implementation nobody here
wrote): browse a device object, read a variable, write a good value (``Device.read`` changes),
a refused one (Bad_OutOfRange / Bad_TypeMismatch, nothing changes) and a read-only one
(Bad_NotWritable), call the Fault and PowerCycle methods, receive fault events, see a change made
through the device in a data-change subscription; and the contract: every readable point of every
registered kind is a variable that reads back as ``Device.read`` gives it.

One server (one device per registered kind) serves the whole module: asyncua's ``init`` loads
the standard address space and takes about 1 s, the five devices' ~700 variables about 0.3 s.
"""

from __future__ import annotations

import asyncio
import json
import time
from collections.abc import Iterator
from datetime import UTC, datetime
from typing import Any

import pytest
from asyncua import Client, ua

from devsim.core.points import BadValue
from devsim.core.registry import kinds
from devsim.facades.opcua import OpcuaFacade, start_opcua
from devsim.facades.opcua_space import NAMESPACE, to_opcua, variables
from devsim.runtime import Runtime
from tests.facades.opcua_clients import node_client

PERIOD = 0.1  # seconds of device time between samples for subscriptions
TIMEOUT = 10.0  # bound on every wait for a notification


@pytest.fixture(scope="module")
def served() -> Iterator[tuple[Runtime, OpcuaFacade]]:
    runtime = Runtime(virtual=True).start()
    try:
        devices = [runtime.add_device(kind, kind) for kind in sorted(kinds())]
        started = time.perf_counter()
        facade = runtime.run(start_opcua(runtime, devices, "127.0.0.1:0", period=PERIOD), timeout=60)
        print(f"OPC UA server with {len(devices)} devices up in {time.perf_counter() - started:.2f} s")
        yield runtime, facade
    finally:
        runtime.stop()


class Collect:
    """asyncua subscription handler: data changes and events into queues."""

    def __init__(self) -> None:
        self.changes: asyncio.Queue[tuple[Any, Any]] = asyncio.Queue()
        self.events: asyncio.Queue[Any] = asyncio.Queue()

    def datachange_notification(self, node: Any, value: Any, data: Any) -> None:
        self.changes.put_nowait((node, value))

    def event_notification(self, event: Any) -> None:
        self.events.put_nowait(event)

    async def value(self, node: Any, wanted: Any) -> Any:
        """Wait (bounded) for a notification of ``node`` with ``wanted``."""
        deadline = time.monotonic() + TIMEOUT
        while True:
            got_node, value = await asyncio.wait_for(self.changes.get(), deadline - time.monotonic())
            if got_node == node and value == wanted:
                return value

    async def event(self, **fields: Any) -> Any:
        deadline = time.monotonic() + TIMEOUT
        while True:
            event = await asyncio.wait_for(self.events.get(), deadline - time.monotonic())
            if all(getattr(event, key, None) == value for key, value in fields.items()):
                return event


async def _node(client: Client, name: str) -> Any:
    ns = await client.get_namespace_index(NAMESPACE)
    return client.get_node(ua.NodeId(name, ns))


async def test_the_device_object_holds_its_points_kind_methods_and_units(served: tuple[Runtime, OpcuaFacade]) -> None:
    runtime, facade = served
    async with Client(facade.url) as client:
        ns = await client.get_namespace_index(NAMESPACE)
        sers = await client.nodes.objects.get_child(f"{ns}:sers")
        children = {(await child.read_browse_name()).Name: child for child in await sers.get_children()}
        assert await children["Kind"].read_value() == "sers"
        assert await children["FaultKinds"].read_value() == runtime.call(lambda: runtime.device("sers").faults.names())
        assert {"Fault", "PowerCycle", "axis.position", "quantity.heatsink_temperature"} <= set(children)
        position = children["axis.position"]
        assert position.nodeid == ua.NodeId("sers.axis.position", ns)
        assert await position.read_data_type_as_variant_type() == ua.VariantType.Double
        assert "actual position" in (await position.read_description()).Text
        assert await position.get_access_level() == {ua.AccessLevel.CurrentRead}
        units = await position.get_child("0:EngineeringUnits")
        assert (await units.read_value()).DisplayName.Text == "inc"
        temperature = children["quantity.heatsink_temperature"]
        assert await temperature.get_access_level() == {ua.AccessLevel.CurrentRead, ua.AccessLevel.CurrentWrite}
        celsius = await (await temperature.get_child("0:EngineeringUnits")).read_value()
        assert celsius.UnitId == 4408652 and celsius.DisplayName.Text == "°C"  # UNECE CEL
        assert await temperature.read_value() == runtime.read("sers", "quantity.heatsink_temperature")


async def test_the_server_names_itself_devsim_and_its_version(served: tuple[Runtime, OpcuaFacade]) -> None:
    """Part 5 6.3.1 (ServerArray[0] and NamespaceArray[1] are the server's ApplicationUri) and 12.4
    (BuildInfo): a client's server list shows the simulator, not asyncua's default identity."""
    import devsim

    _, facade = served
    async with Client(facade.url) as client:
        build = await client.get_node(ua.ObjectIds.Server_ServerStatus_BuildInfo).read_value()
        assert (build.ProductName, build.ManufacturerName, build.SoftwareVersion, build.ProductUri) == (
            "devsim devsim", "devsim", devsim.__version__, NAMESPACE)
        uri = "urn:devsim:server:devsim"
        assert await client.get_node(ua.ObjectIds.Server_ServerArray).read_value() == [uri]
        assert (await client.get_node(ua.ObjectIds.Server_NamespaceArray).read_value())[1:3] == [uri, NAMESPACE]
        servers = await client.find_servers()
        assert [(s.ApplicationUri, s.ProductUri, s.ApplicationName.Text) for s in servers] == [
            (uri, NAMESPACE, "devsim devsim")]


async def test_writes_go_through_the_device_with_its_validation(served: tuple[Runtime, OpcuaFacade]) -> None:
    runtime, facade = served
    async with Client(facade.url) as client:
        temperature = await _node(client, "sers.quantity.heatsink_temperature")
        await temperature.write_value(ua.Variant(61.5, ua.VariantType.Double))
        assert runtime.read("sers", "quantity.heatsink_temperature") == 61.5
        assert await temperature.read_value() == 61.5
        with pytest.raises(ua.uaerrors.BadOutOfRange):  # above the declared maximum of 200 °C
            await temperature.write_value(ua.Variant(500.0, ua.VariantType.Double))
        with pytest.raises(ua.uaerrors.BadTypeMismatch):
            await temperature.write_value(ua.Variant("hot", ua.VariantType.String))
        assert runtime.read("sers", "quantity.heatsink_temperature") == 61.5
        with pytest.raises(ua.uaerrors.BadNotWritable):
            await (await _node(client, "sers.axis.position")).write_value(ua.Variant(5.0, ua.VariantType.Double))
        pulses = await _node(client, "sers.encoder.pulses")  # write-only: counted, never read
        assert await pulses.get_access_level() == {ua.AccessLevel.CurrentWrite}
        with pytest.raises(ua.uaerrors.BadNotReadable):
            await pulses.read_value()
        await pulses.write_value(ua.Variant(100, ua.VariantType.Int64))  # taken (Good)
        with pytest.raises(ua.uaerrors.BadTypeMismatch):
            await pulses.write_value(ua.Variant(1.5, ua.VariantType.Double))
        switch = await _node(client, "sers.input.I1")
        wanted = not runtime.read("sers", "input.I1")
        await switch.write_value(ua.Variant(wanted, ua.VariantType.Boolean))
        assert runtime.read("sers", "input.I1") is wanted


async def test_a_value_written_with_timestamps_is_read_back_with_them(served: tuple[Runtime, OpcuaFacade]) -> None:
    """OPC UA Part 4, 5.10.4.2 Table 59: "If the SourceTimestamp or the ServerTimestamp is
    specified, the Server shall use these values": the value written is read back (and reported
    to a subscription) with the written timestamps until the device's value changes; then with
    the time it is read again.  asyncua's write_value of a plain value sends a SourceTimestamp."""
    runtime, facade = served
    source, server = datetime(2020, 1, 2, 3, 4, 5, tzinfo=UTC), datetime(2021, 6, 7, 8, 9, 10, tzinfo=UTC)
    async with Client(facade.url) as client:
        volts = await _node(client, "sers.quantity.supply_voltage")
        await volts.write_value(ua.DataValue(ua.Variant(47.0, ua.VariantType.Double), SourceTimestamp=source,
                                             ServerTimestamp=server))
        params = ua.ReadParameters()
        params.TimestampsToReturn = ua.TimestampsToReturn.Both
        params.NodesToRead = [ua.ReadValueId(NodeId=volts.nodeid, AttributeId=ua.AttributeIds.Value)]
        [read] = await client.uaclient.read(params)
        assert (read.Value.Value, read.SourceTimestamp, read.ServerTimestamp) == (47.0, source, server)
        subscription = await client.create_subscription(50, handler := Collect())
        try:
            await subscription.subscribe_data_change(volts)
            node, _value = await asyncio.wait_for(handler.changes.get(), TIMEOUT)
            first = (await volts.read_data_value()).SourceTimestamp
            assert first == source  # (the subscription's sample did not stamp it anew)
        finally:
            await subscription.delete()
        await volts.write_value(ua.Variant(48.0, ua.VariantType.Double))  # asyncua stamps it now
        stamped = await volts.read_data_value()
        assert stamped.Value.Value == 48.0 and stamped.SourceTimestamp.year >= 2026
        runtime.set("sers", "quantity.supply_voltage", 49.0)  # the device's own change: its time
        again = await volts.read_data_value()
        assert again.Value.Value == 49.0 and again.SourceTimestamp > stamped.SourceTimestamp


async def test_a_subscription_sees_a_change_made_through_the_device(served: tuple[Runtime, OpcuaFacade]) -> None:
    runtime, facade = served
    async with Client(facade.url) as client:
        collect = Collect()
        subscription = await client.create_subscription(20, collect)
        node = await _node(client, "sers.quantity.adc_volts")
        device, name = "sers", "quantity.adc_volts"
        await subscription.subscribe_data_change(node)
        await collect.value(node, runtime.read(device, name))  # the initial value
        new = 3.25 if runtime.read(device, name) != 3.25 else 3.5
        runtime.set(device, name, new)
        runtime.advance(PERIOD)  # the next sample on the device clock
        assert await collect.value(node, new) == new
        await subscription.delete()


async def test_fault_and_power_cycle_methods_and_fault_events(served: tuple[Runtime, OpcuaFacade]) -> None:
    runtime, facade = served
    async with Client(facade.url) as client:
        ns = await client.get_namespace_index(NAMESPACE)
        sers = await client.nodes.objects.get_child(f"{ns}:sers")
        event_type = await client.nodes.base_event_type.get_child(f"{ns}:DeviceFaultEventType")
        collect = Collect()
        subscription = await client.create_subscription(20, collect)
        await subscription.subscribe_events(sers, event_type)
        server_events = Collect()
        server_subscription = await client.create_subscription(20, server_events)
        await server_subscription.subscribe_events(client.nodes.server, event_type)

        await sers.call_method(f"{ns}:Fault", ua.Variant("emergency_stop", ua.VariantType.String),
                               ua.Variant(True, ua.VariantType.Boolean))
        event = await collect.event(FaultKind="emergency_stop", Active=True)
        assert event.SourceName == "sers" and "emergency_stop on" in event.Message.Text
        assert (await server_events.event(FaultKind="emergency_stop", Active=True)).SourceNode == sers.nodeid
        runtime.fault("sers", "emergency_stop", False)  # through the control API
        await collect.event(FaultKind="emergency_stop", Active=False)
        device = runtime.device("sers")
        runtime.call(lambda: (device.fault("emergency_stop", True), device.fault("emergency_stop", False)))
        first, second = [await asyncio.wait_for(collect.events.get(), TIMEOUT) for _ in range(2)]
        assert (first.FaultKind, first.Active, second.FaultKind, second.Active) == (
            "emergency_stop", True, "emergency_stop", False)  # both, in order, each with its own fields
        with pytest.raises(ua.uaerrors.BadInvalidArgument):
            await sers.call_method(f"{ns}:Fault", ua.Variant("no_such_fault", ua.VariantType.String),
                                   ua.Variant(True, ua.VariantType.Boolean))

        # a fault the model announces (as CANopen's EMCY): the supply below U_L is a drive error
        runtime.set("sers", "quantity.supply_voltage", 40.0)
        runtime.advance(0.5)
        event = await collect.event(Code=0x3220)
        assert event.Active is True and event.Axis == 1 and event.FaultKind == ""
        runtime.set("sers", "quantity.supply_voltage", 68.0)

        runtime.call(lambda: runtime.device("sers").events.clear())
        await sers.call_method(f"{ns}:PowerCycle", ua.Variant(False, ua.VariantType.Boolean))
        assert runtime.call(lambda: [name for _, name in runtime.device("sers").events]) == ["power_on"]
        assert runtime.read("sers", "booting") is True  # switched on again: it boots
        await subscription.delete()
        await server_subscription.delete()


async def test_every_point_of_every_kind_reads_back_as_the_device_gives_it(
        served: tuple[Runtime, OpcuaFacade]) -> None:
    runtime, facade = served
    async with Client(facade.url) as client:
        ns = await client.get_namespace_index(NAMESPACE)
        for kind in sorted(kinds()):
            device = runtime.device(kind)
            rows = variables(kind, device.points)
            names = {(await child.read_browse_name()).Name
                     for child in await (await client.nodes.objects.get_child(f"{ns}:{kind}")).get_children()}
            assert {row.point for row in rows} <= names, kind
            assert {p.name for p in device.points if p.readable} <= names, kind
            readable = [row for row in rows if row.readable]
            values = await client.read_values([client.get_node(ua.NodeId(row.node_id, ns)) for row in readable])
            expected = runtime.call(lambda d=device, r=readable: [to_opcua(row, d.read(row.point)) for row in r])
            for row, got, want in zip(readable, values, expected, strict=True):
                if want is None:  # a value the device cannot give now: Bad_NoData, no value
                    assert got is None, (kind, row.point)
                elif row.type == "json":
                    assert json.loads(got) == json.loads(want), (kind, row.point)
                else:
                    assert got == want, (kind, row.point)
            nodes = [client.get_node(ua.NodeId(row.node_id, ns)) for row in rows]
            types = await client.read_attributes(nodes, ua.AttributeIds.DataType)
            access = await client.read_attributes(nodes, ua.AttributeIds.AccessLevel)
            user_access = await client.read_attributes(nodes, ua.AttributeIds.UserAccessLevel)
            for row, data_type, level, user_level in zip(rows, types, access, user_access, strict=True):
                assert data_type.Value.Value == ua.NodeId(ua.VariantType[row.data_type].value), (kind, row.point)
                assert level.Value.Value == user_level.Value.Value == row.readable * 1 | row.writable * 2, (
                    kind, row.point)
            # every settable point written with the value it has: taken, or refused exactly where
            # the control API refuses that value too
            again = [(row, value) for row, value in zip(readable, expected, strict=True)
                     if row.writable and value is not None]
            written = await client.write_values(
                [client.get_node(ua.NodeId(row.node_id, ns)) for row, _ in again],
                [ua.DataValue(ua.Variant(value, ua.VariantType[row.data_type])) for row, value in again],
                raise_on_partial_error=False)
            for (row, value), status in zip(again, written, strict=True):
                if not status.is_good():
                    assert status.value == ua.StatusCodes.BadOutOfRange, (kind, row.point, status)
                    parsed = json.loads(value) if row.type == "json" else value
                    with pytest.raises(BadValue):
                        runtime.set(kind, row.point, parsed)


# -- node-opcua ---------------------------------------------------------------------------------
def test_node_opcua_browses_reads_writes_and_calls(served: tuple[Runtime, OpcuaFacade]) -> None:
    runtime, facade = served
    before = runtime.read("sers", "quantity.heatsink_temperature")
    good = 42.25 if before != 42.25 else 43.0
    plan = [
        {"op": "browse", "node": "sers"},
        {"op": "read", "node": "sers.axis.position"},
        {"op": "write", "node": "sers.quantity.heatsink_temperature", "type": "Double", "value": good},
        {"op": "read", "node": "sers.quantity.heatsink_temperature"},
        {"op": "write", "node": "sers.quantity.heatsink_temperature", "type": "Double", "value": 1000},
        {"op": "write", "node": "sers.quantity.heatsink_temperature", "type": "String", "value": "hot"},
        {"op": "write", "node": "sers.axis.position", "type": "Double", "value": 1},
        {"op": "read", "node": "sers.P11"},
        {"op": "call", "object": "sers", "method": "sers#Fault", "args": [["String", "blocked_axis"], ["Boolean", True]]},
        {"op": "call", "object": "sers", "method": "sers#Fault", "args": [["String", "blocked_axis"], ["Boolean", False]]},
        {"op": "call", "object": "sers", "method": "sers#Fault", "args": [["String", "nope"], ["Boolean", True]]},
    ]
    results = [{key: value for key, value in result.items() if key != "timestamps"}
               for result in node_client(facade.url, plan)]
    browse, position, write, reread, too_hot, text, read_only, errors, on, off, unknown = results
    assert browse["status"] == "Good"
    assert {"Kind", "Fault", "PowerCycle", "axis.position", "quantity.heatsink_temperature"} <= set(browse["names"])
    assert position == {"status": "Good", "type": "Double", "value": runtime.read("sers", "axis.position")}
    assert write == {"status": "Good"}
    assert reread == {"status": "Good", "type": "Double", "value": good}
    assert too_hot == {"status": "BadOutOfRange"} and text == {"status": "BadTypeMismatch"}
    assert read_only == {"status": "BadNotWritable"}
    assert errors == {"status": "Good", "type": "Int64", "value": runtime.read("sers", "P11")}
    assert on == off == {"status": "Good", "inputs": ["Good", "Good"]}
    assert unknown["status"] == "BadInvalidArgument"
    assert runtime.read("sers", "quantity.heatsink_temperature") == good
