"""The OPC UA facade's monitored items against OPC UA Part 4 (5.12.2.4 Table 71, 5.12.3.4 Table 74,
7.22 filters; Part 8, 6.2 percent deadband), through asyncua's client and node-opcua's.

Each item is refused on its own with the code Part 4 names, the rest of the request and the
session serve on: a node the server does not have Bad_NodeIdUnknown (an event item too), the
EventNotifier of a Variable Bad_AttributeIdInvalid, an event item without an EventFilter
Bad_MonitoredItemFilterInvalid, an EventFilter on a Value or a filter on another attribute
Bad_FilterNotAllowed, an absolute deadband on a String or a Boolean Bad_FilterNotAllowed, a percent
deadband without an EURange Bad_DeadbandFilterInvalid, an IndexRange of invalid syntax
Bad_IndexRangeInvalid and one on a scalar number Bad_IndexRangeNoData, a dataEncoding on a Double
Bad_DataEncodingInvalid, a ModifyMonitoredItems of an item that does not exist
Bad_MonitoredItemIdInvalid.  asyncua's server answered most of these Good (and then ignored the
filter or range), Bad_ServiceUnsupported, or failed the whole request with Bad_InternalError.

An item reports the part of a String its IndexRange selects, and the timestamps its request's
timestampsToReturn asks for (5.12.2.2; asyncua sent a SourceTimestamp only, whatever was asked).
A ModifyMonitoredItems revises and applies an item's parameters as a CreateMonitoredItems does
(5.12.3.2): samplingInterval, queueSize (a longer queue cut at once), filter with its whereClause,
clientHandle and timestampsToReturn.  A full queue discards as the item's discardOldest asks, and
marks where values were lost with the Overflow bit, where events were lost with an
EventQueueOverflowEventType event (5.12.1.5; asyncua dropped the oldest whatever was asked, set no
bit and queued no overflow event).
"""

from __future__ import annotations

import asyncio
from collections.abc import Iterator
from typing import Any

import pytest
from asyncua import Client, ua
from asyncua.common.subscription import SubscriptionItemData

from devsim.core.clock import VirtualClock
from devsim.facades.opcua import OpcuaFacade, start_opcua
from devsim.facades.opcua_monitoring import Spacing
from devsim.facades.opcua_space import NAMESPACE
from devsim.runtime import Runtime
from tests.facades.opcua_clients import node_client

EVENT = {"type": "event"}
ABSOLUTE = {"type": "datachange", "deadband": "Absolute", "value": 0.5}
PERCENT = {"type": "datachange", "deadband": "Percent", "value": 10.0}
SERVER_STATUS = "i=2256"  # ServerStatus, a ServerStatusDataType: a structure

#: (node, attribute, filter, index range, data encoding) -> the Part 4 answer
ITEMS = [
    ("sers.nope", "Value", None, None, None, "BadNodeIdUnknown"),
    ("sers.nope", "EventNotifier", EVENT, None, None, "BadNodeIdUnknown"),
    ("sers.axis.position", "EventNotifier", EVENT, None, None, "BadAttributeIdInvalid"),  # a Variable's
    ("sers", "EventNotifier", None, None, None, "BadMonitoredItemFilterInvalid"),  # events need an EventFilter
    ("sers", "EventNotifier", ABSOLUTE, None, None, "BadMonitoredItemFilterInvalid"),
    ("sers.axis.position", "Value", EVENT, None, None, "BadFilterNotAllowed"),
    ("sers.axis.position", "DisplayName", ABSOLUTE, None, None, "BadFilterNotAllowed"),  # 5.12.1.1
    ("sers.axis.phase", "Value", ABSOLUTE, None, None, "BadFilterNotAllowed"),  # a String: no Number
    ("sers.axis.moving", "Value", ABSOLUTE, None, None, "BadFilterNotAllowed"),  # a Boolean
    ("sers.axis.position", "Value", PERCENT, None, None, "BadDeadbandFilterInvalid"),  # no EURange
    ("sers.axis.phase", "Value", None, "7:5", None, "BadIndexRangeInvalid"),
    ("sers.axis.position", "Value", None, "0:1", None, "BadIndexRangeNoData"),  # a scalar Double
    ("sers.axis.position", "Value", None, None, "Default Binary", "BadDataEncodingInvalid"),
    (SERVER_STATUS, "Value", None, None, "Default XML", "BadDataEncodingUnsupported"),  # binary only
    # and what is taken
    ("sers.axis.position", "Value", ABSOLUTE, None, None, "Good"),
    ("sers.P11", "Value", ABSOLUTE, None, None, "Good"),  # an integer is a Number too
    ("sers.axis.phase", "Value", None, "0:2", None, "Good"),
    ("sers", "EventNotifier", EVENT, None, None, "Good"),
    (SERVER_STATUS, "Value", None, None, "Default Binary", "Good"),
]
WANTED = [status for *_, status in ITEMS]


@pytest.fixture(scope="module")
def served() -> Iterator[tuple[Runtime, OpcuaFacade]]:
    runtime = Runtime(virtual=True).start()
    try:
        devices = [runtime.add_device("sers", "sers")]
        facade = runtime.run(start_opcua(runtime, devices, "127.0.0.1:0"), timeout=60)
        yield runtime, facade
    finally:
        runtime.stop()


def _node_id(ns: int, node: str) -> ua.NodeId:
    return ua.NodeId.from_string(node) if node.startswith("i=") else ua.NodeId(node, ns)


def _filter(spec: dict[str, Any] | None) -> Any:
    if spec is None:
        return None
    if spec["type"] == "event":
        return ua.EventFilter(SelectClauses=[ua.SimpleAttributeOperand(
            TypeDefinitionId=ua.NodeId(ua.ObjectIds.BaseEventType), BrowsePath=[ua.QualifiedName("Message", 0)],
            AttributeId=ua.AttributeIds.Value)])
    return ua.DataChangeFilter(Trigger=ua.DataChangeTrigger.StatusValue, DeadbandType=ua.DeadbandType[spec["deadband"]],
                               DeadbandValue=spec["value"])


def _request(ns: int, handle: int, node: str, attribute: str, spec: dict[str, Any] | None, index_range: str | None,
             encoding: str | None) -> ua.MonitoredItemCreateRequest:
    item = ua.ReadValueId(NodeId=_node_id(ns, node), AttributeId=ua.AttributeIds[attribute], IndexRange=index_range)
    if encoding is not None:
        item.DataEncoding = ua.QualifiedName(encoding, 0)
    parameters = ua.MonitoringParameters(ClientHandle=handle, SamplingInterval=0, QueueSize=1, DiscardOldest=True,
                                         Filter=_filter(spec))
    return ua.MonitoredItemCreateRequest(ItemToMonitor=item, MonitoringMode=ua.MonitoringMode.Reporting,
                                         RequestedParameters=parameters)


class _Quiet:
    def datachange_notification(self, node: Any, value: Any, data: Any) -> None: ...

    def event_notification(self, event: Any) -> None: ...


async def test_asyncua_monitored_items_answer_with_part4_status_codes(served: tuple[Runtime, OpcuaFacade]) -> None:
    _, facade = served
    async with Client(facade.url) as client:
        ns = await client.get_namespace_index(NAMESPACE)
        subscription = await client.create_subscription(20, _Quiet())
        requests = [_request(ns, 1000 + index, *row[:-1]) for index, row in enumerate(ITEMS)]
        params = ua.CreateMonitoredItemsParameters(SubscriptionId=subscription.subscription_id,
                                                   TimestampsToReturn=ua.TimestampsToReturn.Both,
                                                   ItemsToCreate=requests)
        results = await client.uaclient.create_monitored_items(params)  # all in one request
        assert [result.StatusCode.name for result in results] == WANTED
        created = [result.MonitoredItemId for result in results if result.StatusCode.is_good()]
        position = created[0]  # the absolute deadband on axis.position
        modify = ua.ModifyMonitoredItemsParameters(
            SubscriptionId=subscription.subscription_id, TimestampsToReturn=ua.TimestampsToReturn.Both,
            ItemsToModify=[ua.MonitoredItemModifyRequest(MonitoredItemId=item, RequestedParameters=ua.MonitoringParameters(
                ClientHandle=7, SamplingInterval=0, QueueSize=1, Filter=flt))
                for item, flt in [(9999, None), (position, _filter(EVENT)), (position, _filter(PERCENT)),
                                  (position, None)]])
        modified = await client.uaclient.modify_monitored_items(modify)
        assert [result.StatusCode.name for result in modified] == [
            "BadMonitoredItemIdInvalid", "BadFilterNotAllowed", "BadDeadbandFilterInvalid", "Good"]
        await subscription.delete()
        assert await client.get_node(ua.NodeId("sers.quantity.supply_voltage", ns)).read_value() == 68.0  # serves on


def test_node_opcua_monitored_items_answer_with_part4_status_codes(served: tuple[Runtime, OpcuaFacade]) -> None:
    _, facade = served
    items = [{"node" if not node.startswith("i=") else "nodeId": node, "attribute": attribute, "filter": spec,
              "indexRange": index_range, "encoding": encoding}
             for node, attribute, spec, index_range, encoding, _ in ITEMS]
    [result, read] = node_client(facade.url, [{"op": "items", "items": items, "modify": [9999]},
                                              {"op": "read", "node": "sers.quantity.supply_voltage"}])
    assert result == {"statuses": WANTED, "modified": ["BadMonitoredItemIdInvalid"]}
    assert read["status"] == "Good"


async def test_asyncua_an_index_range_selects_what_an_item_reports(served: tuple[Runtime, OpcuaFacade]) -> None:
    runtime, facade = served
    phase = runtime.read("sers", "axis.phase")
    assert isinstance(phase, str) and len(phase) > 2
    seen: asyncio.Queue[Any] = asyncio.Queue()

    class Changes:
        def datachange_notification(self, node: Any, value: Any, data: Any) -> None:
            seen.put_nowait(value)

    async with Client(facade.url) as client:
        ns = await client.get_namespace_index(NAMESPACE)
        subscription = await client.create_subscription(20, Changes())
        [handle] = await subscription.create_monitored_items(  # asyncua's own call for an IndexRange
            [_request(ns, 1, "sers.axis.phase", "Value", None, "0:1", None)])
        assert isinstance(handle, int), handle
        assert await asyncio.wait_for(seen.get(), 10) == phase[:2]
        await subscription.delete()


def test_node_opcua_an_index_range_selects_what_an_item_reports(served: tuple[Runtime, OpcuaFacade]) -> None:
    runtime, facade = served
    phase = runtime.read("sers", "axis.phase")
    [result] = node_client(facade.url, [{"op": "monitor", "nodes": ["sers.axis.phase"], "indexRange": "0:1"}])
    assert (result["statuses"], result["values"]) == (["Good"], [phase[:2]])


async def _unpublished(client: Client, facade: Any, handler: Any = None) -> Any:
    """A subscription at the facade's period with publishing disabled: its items' notifications
    stay queued (Part 4 5.13.2, publishingEnabled)."""
    return await client.create_subscription(ua.CreateSubscriptionParameters(
        RequestedPublishingInterval=facade.period * 1000, RequestedLifetimeCount=10_000,
        RequestedMaxKeepAliveCount=10, PublishingEnabled=False), handler or _Quiet())


async def _create(client: Client, subscription: Any, request: ua.MonitoredItemCreateRequest,
                  timestamps: ua.TimestampsToReturn = ua.TimestampsToReturn.Both) -> ua.MonitoredItemCreateResult:
    """One monitored item created as ``request`` says (asyncua's Subscription asks for Both
    timestamps and hides the revised sampling interval: its handler is told of the item by hand)."""
    known = SubscriptionItemData()
    known.client_handle = request.RequestedParameters.ClientHandle
    known.node, known.attribute = client.get_node(request.ItemToMonitor.NodeId), request.ItemToMonitor.AttributeId
    subscription._monitored_items[known.client_handle] = known
    [result] = await client.uaclient.create_monitored_items(ua.CreateMonitoredItemsParameters(
        SubscriptionId=subscription.subscription_id, TimestampsToReturn=timestamps, ItemsToCreate=[request]))
    return result


#: timestampsToReturn -> (a SourceTimestamp, a ServerTimestamp) in each notification
STAMPS = {"Source": [True, False], "Server": [False, True], "Both": [True, True], "Neither": [False, False]}


async def test_asyncua_an_item_reports_the_timestamps_it_asked_for(served: tuple[Runtime, OpcuaFacade]) -> None:
    _, facade = served
    seen: asyncio.Queue[ua.DataValue] = asyncio.Queue()

    class Changes:
        def datachange_notification(self, node: Any, value: Any, data: Any) -> None:
            seen.put_nowait(data.monitored_item.Value)

    async with Client(facade.url) as client:
        ns = await client.get_namespace_index(NAMESPACE)
        for name, wanted in STAMPS.items():
            subscription = await client.create_subscription(20, Changes())
            request = _request(ns, 1, "sers.quantity.supply_voltage", "Value", None, None, None)
            result = await _create(client, subscription, request, ua.TimestampsToReturn[name])
            assert result.StatusCode.is_good()
            value = await asyncio.wait_for(seen.get(), 10)
            assert value.Value.Value == 68.0
            assert [value.SourceTimestamp is not None, value.ServerTimestamp is not None] == wanted, name
            await subscription.delete()


def test_node_opcua_an_item_reports_the_timestamps_it_asked_for(served: tuple[Runtime, OpcuaFacade]) -> None:
    _, facade = served
    results = node_client(facade.url, [{"op": "monitor", "nodes": ["sers.quantity.supply_voltage"], "timestamps": name}
                                       for name in STAMPS])
    assert [result["timestamps"] for result in results] == [[wanted] for wanted in STAMPS.values()]
    assert all(result["values"] == [68.0] for result in results)


#: samplingInterval asked (ms) on a subscription publishing every 20 ms -> the revisedSamplingInterval of
#: a point's Value: what it asked for (5.12.2.2: "equal or higher than the requested samplingInterval"),
#: and never below the point's MinimumSamplingInterval, the facade's sampling period (100 ms: Part 3,
#: 5.6.2, it "specifies how fast the Server can reasonably sample the value for changes"; Part 4,
#: 5.12.1.2: "it shall always return a revisedSamplingInterval that is equal or higher than the
#: MinimumSamplingInterval if the Client subscribes to the Value Attribute")
SAMPLING = [(500.0, 500.0), (0.0, 100.0), (-1.0, 100.0), (50.0, 100.0), (150.0, 150.0)]


async def test_asyncua_an_item_keeps_the_sampling_interval_it_asked_for(served: tuple[Runtime, OpcuaFacade]) -> None:
    """500 ms asked on a subscription publishing every 20 ms: revised 500 (asyncua: 20), and the
    values sampled 0.15 and 0.3 s after the first one are held until 0.5 s have passed (device
    time), then the latest is reported; an item that asked for 0 is revised to the 100 ms the
    points are sampled at, their MinimumSamplingInterval (asyncua: 20, and the attribute said 0,
    "continuously"), and sees every sample."""
    runtime, facade = served
    seen: asyncio.Queue[tuple[int, Any]] = asyncio.Queue()

    class Changes:
        def datachange_notification(self, node: Any, value: Any, data: Any) -> None:
            seen.put_nowait((data.monitored_item.ClientHandle, value))

    name = "quantity.adc_volts"
    old = runtime.read("sers", name)
    async with Client(facade.url) as client:
        ns = await client.get_namespace_index(NAMESPACE)
        subscription = await client.create_subscription(20, Changes())
        slow = _request(ns, 1, f"sers.{name}", "Value", None, None, None)
        slow.RequestedParameters.SamplingInterval = 500.0
        fast = _request(ns, 2, f"sers.{name}", "Value", None, None, None)
        assert (await _create(client, subscription, slow)).RevisedSamplingInterval == 500.0
        assert (await _create(client, subscription, fast)).RevisedSamplingInterval == 100.0
        firsts = {await asyncio.wait_for(seen.get(), 10) for _ in range(2)}
        assert firsts == {(1, old), (2, old)}
        for value in (1.25, 1.5):  # two samples (every 0.1 s) within 0.5 s of the first value
            runtime.set("sers", name, value)
            runtime.advance(0.15)
            assert await asyncio.wait_for(seen.get(), 10) == (2, value)  # the item that asked for 0
        runtime.advance(0.25)  # 0.55 s after the first value
        assert await asyncio.wait_for(seen.get(), 10) == (1, 1.5)  # the latest; 1.25 never
        await subscription.delete()


async def test_asyncua_values_written_in_a_row_are_reported_a_sampling_interval_apart(
        served: tuple[Runtime, OpcuaFacade]) -> None:
    """Three writes at one moment of device time to a point whose item is revised to 100 ms: the
    first is reported at once (a write is sampled at once), the last when 100 ms have passed, the
    one between never (5.12.1.2: "the time between values returned to the Client shall be greater
    or equal to the sampling interval"; each write was reported at once, 0 ms apart)."""
    runtime, facade = served
    seen: asyncio.Queue[Any] = asyncio.Queue()

    class Changes:
        def datachange_notification(self, node: Any, value: Any, data: Any) -> None:
            seen.put_nowait(value)

    name = "quantity.supply_voltage"  # (a value nothing but a write changes)
    old = runtime.read("sers", name)
    async with Client(facade.url) as client:
        ns = await client.get_namespace_index(NAMESPACE)
        subscription = await client.create_subscription(20, Changes())
        item = _request(ns, 1, f"sers.{name}", "Value", None, None, None)
        assert (await _create(client, subscription, item)).RevisedSamplingInterval == 100.0
        assert await asyncio.wait_for(seen.get(), 10) == old
        runtime.advance(0.2)  # the first value is long reported
        node = client.get_node(ua.NodeId(f"sers.{name}", ns))
        for value in (45.0, 46.0, 47.0):
            await node.write_value(ua.DataValue(ua.Variant(value, ua.VariantType.Double)))
        assert await asyncio.wait_for(seen.get(), 10) == 45.0
        runtime.advance(0.1)
        assert await asyncio.wait_for(seen.get(), 10) == 47.0  # the latest; 46 never
        await subscription.delete()
    runtime.set("sers", name, old)


async def test_asyncua_no_item_samples_a_point_faster_than_its_minimum_sampling_interval(
        served: tuple[Runtime, OpcuaFacade]) -> None:
    """SAMPLING, created and modified; the MinimumSamplingInterval of a point is the period its
    device is sampled at (asyncua: 0, "continuously"), that of a property 0 (it changes only when
    written, and a notification goes out at once)."""
    _, facade = served
    name = "sers.quantity.adc_volts"
    async with Client(facade.url) as client:
        ns = await client.get_namespace_index(NAMESPACE)
        point, prop = client.get_node(ua.NodeId(name, ns)), client.get_node(ua.NodeId("sers#Kind", ns))
        minimum = ua.AttributeIds.MinimumSamplingInterval
        assert [(await node.read_attribute(minimum)).Value.Value for node in (point, prop)] == [1000 * facade.period, 0]
        subscription = await client.create_subscription(20, _Quiet())
        revised, created = [], []
        for handle, (asked, _) in enumerate(SAMPLING, 1):
            item = _request(ns, handle, name, "Value", None, None, None)
            item.RequestedParameters.SamplingInterval = asked
            result = await _create(client, subscription, item)
            revised.append(result.RevisedSamplingInterval)
            created.append(result.MonitoredItemId)
        assert revised == [wanted for _, wanted in SAMPLING]
        modified = await client.uaclient.modify_monitored_items(ua.ModifyMonitoredItemsParameters(
            SubscriptionId=subscription.subscription_id, TimestampsToReturn=ua.TimestampsToReturn.Both,
            ItemsToModify=[ua.MonitoredItemModifyRequest(MonitoredItemId=item, RequestedParameters=ua.MonitoringParameters(
                ClientHandle=handle, SamplingInterval=asked, QueueSize=1))
                for item, (handle, (asked, _)) in zip(created, enumerate(reversed(SAMPLING), 1), strict=True)]))
        assert [result.RevisedSamplingInterval for result in modified] == [wanted for _, wanted in reversed(SAMPLING)]
        await subscription.delete()


async def test_a_held_value_is_never_reported_after_a_newer_one() -> None:
    """An item that asked for 500 ms: a value 0.45 s after its last one is held (until 0.5 s);
    a newer value that comes at 0.5 s, before the timer that would release the held one (a
    sample timer due at the same moment and armed earlier), is reported, and the held one,
    older, is then dropped (5.12.1.2: the Client's value is the latest sample; Spacing reported
    the older one after it, so the item ended with a value the device no longer had)."""
    clock = VirtualClock()
    reported: list[str] = []

    async def deliver(mid: int, handle: int, value: ua.DataValue) -> None:
        reported.append(value.Value.Value)

    spacing = Spacing(clock, deliver)
    spacing.set(1, 500.0)

    def offer(value: str) -> None:
        if not spacing.hold(1, 7, ua.DataValue(ua.Variant(value))):
            reported.append(value)

    offer("first")  # at 0: reported
    clock.call_later(0.5, lambda: offer("newest"))  # a sample at 0.5 s, armed before the hold's timer
    clock.advance(0.45)
    offer("held")  # at 0.45 s: held until 0.5 s
    clock.advance(0.05)
    await asyncio.sleep(0)  # (a released value is sent in a task)
    assert reported == ["first", "newest"]


def test_node_opcua_an_item_keeps_the_sampling_interval_it_asked_for(served: tuple[Runtime, OpcuaFacade]) -> None:
    _, facade = served  # (node-opcua's subscription publishes every 20 ms)
    items = [{"node": "sers.quantity.adc_volts", "sampling": asked} for asked, _ in SAMPLING]
    result, point, prop = node_client(facade.url, [
        {"op": "items", "items": items},
        {"op": "read", "node": "sers.quantity.adc_volts", "attribute": "MinimumSamplingInterval"},
        {"op": "read", "node": "sers#Kind", "attribute": "MinimumSamplingInterval"}])
    assert result["statuses"] == ["Good"] * len(SAMPLING)
    assert result["revised"] == [wanted for _, wanted in SAMPLING]
    assert (point["value"], prop["value"]) == (100, 0)  # the points are sampled; a property changes by writes


async def test_an_item_queues_at_most_queue_size_notifications_for_a_client_that_takes_none(
        served: tuple[Runtime, OpcuaFacade]) -> None:
    """A subscription whose notifications are not taken (publishing disabled: the server's view
    of a client that sends no Publish requests, or whose socket is not read) keeps
    at most QUEUE_SIZE notifications per item, the newest ([SIM-CHOICE], docs/facades/opcua.md):
    for an item created with QueueSize 0 (the server's largest) and for one modified to it.  (asyncua
    took a modified item's QueueSize as it came: 0 queued every change for the subscription's whole
    life, QUEUE_SIZE + 20 here.)"""
    from devsim.facades.opcua_monitoring import QUEUE_SIZE
    from tests.support.process import wait_until

    runtime, facade = served
    name = "quantity.heatsink_temperature"  # (changes only when set)
    async with Client(facade.url) as client:
        ns = await client.get_namespace_index(NAMESPACE)
        subscription = await _unpublished(client, facade)
        item = ua.ReadValueId(NodeId=ua.NodeId(f"sers.{name}", ns), AttributeId=ua.AttributeIds.Value)
        created = await client.uaclient.create_monitored_items(ua.CreateMonitoredItemsParameters(
            SubscriptionId=subscription.subscription_id, TimestampsToReturn=ua.TimestampsToReturn.Both,
            ItemsToCreate=[ua.MonitoredItemCreateRequest(
                ItemToMonitor=item, MonitoringMode=ua.MonitoringMode.Reporting,
                RequestedParameters=ua.MonitoringParameters(ClientHandle=handle, SamplingInterval=0, QueueSize=size,
                                                            DiscardOldest=True))
                for handle, size in [(1, 0), (2, 1)]]))
        assert [result.RevisedQueueSize for result in created] == [QUEUE_SIZE, 1]
        modified = await client.uaclient.modify_monitored_items(ua.ModifyMonitoredItemsParameters(
            SubscriptionId=subscription.subscription_id, TimestampsToReturn=ua.TimestampsToReturn.Both,
            ItemsToModify=[ua.MonitoredItemModifyRequest(
                MonitoredItemId=created[1].MonitoredItemId,
                RequestedParameters=ua.MonitoringParameters(ClientHandle=2, SamplingInterval=0, QueueSize=0))]))
        assert [result.RevisedQueueSize for result in modified] == [QUEUE_SIZE]
        queues = facade.server.iserver.subscription_service.subscriptions[subscription.subscription_id]._triggered_datachanges
        start = runtime.read("sers", name)
        values = [round(start + 0.01 * n, 2) for n in range(1, QUEUE_SIZE + 21)]
        for value in values:
            runtime.set("sers", name, value)
            runtime.advance(facade.period)  # (the facade samples the point)
        mids = [result.MonitoredItemId for result in created]

        def newest(mid: int) -> Any:
            queue = queues.get(mid)
            return queue[-1].Value.Value.Value if queue else None

        wait_until(lambda: all(newest(mid) == values[-1] for mid in mids), "the last value in both queues", 30)
        for mid in mids:
            assert [n.Value.Value.Value for n in queues[mid]] == values[-QUEUE_SIZE:]
        await subscription.delete()


#: (node, attribute, filter, samplingInterval, queueSize asked) -> (revisedSamplingInterval, revisedQueueSize)
#: on a subscription publishing every 20 ms, the same from a CreateMonitoredItems and from a
#: ModifyMonitoredItems (5.12.3.1: "illegal request values for parameters that can be revised do not
#: generate errors. Instead the Server will choose default values and indicate them in the
#: corresponding revised parameter"; 7.21: -1 asks for the publishing interval, a queueSize of 0
#: for the server's largest, QUEUE_SIZE; 5.12.2.2: the revisedSamplingInterval "equal or higher than
#: the requested samplingInterval" for an attribute that is not the Value too: it is "only monitored
#: for a change in value", 5.12.1.1, asyncua revised it down to the publishing interval)
REVISED = [
    (("sers#Kind", "Value", None, -1.0, 0), (20.0, 1000)),  # a property: MinimumSamplingInterval 0
    (("sers#Kind", "Value", None, 0.0, 1), (20.0, 1)),
    (("sers#Kind", "Value", None, 500.0, 5), (500.0, 5)),
    (("sers.quantity.adc_volts", "DisplayName", None, -1.0, 5000), (20.0, 1000)),  # not a Value
    (("sers.quantity.adc_volts", "DisplayName", None, 500.0, 5), (500.0, 5)),
    (("sers#Kind", "BrowseName", None, 0.0, 2), (20.0, 2)),
    (("sers", "Description", None, 250.0, 2), (250.0, 2)),
    (("sers.quantity.adc_volts", "Value", None, -1.0, 2), (100.0, 2)),  # a point: sampled every 100 ms
    (("sers", "EventNotifier", EVENT, -1.0, 0), (20.0, 1000)),
]


async def test_asyncua_a_modify_revises_each_parameter_as_a_create_does(served: tuple[Runtime, OpcuaFacade]) -> None:
    """Each REVISED item created as asked, and each created asking 1000 ms and QueueSize 3 (each
    data item revised to 1000 ms, whatever its attribute) then modified to what was asked: the same
    revised values.  (asyncua's ModifyMonitoredItems answered
    the samplingInterval as it came, -1 and 0 too, where a create answered the publishing interval.)"""
    _, facade = served
    async with Client(facade.url) as client:
        ns = await client.get_namespace_index(NAMESPACE)
        subscription = await client.create_subscription(20, _Quiet())
        wanted = [revised for _, revised in REVISED]
        asked, other = [], []
        for handle, ((node, attribute, spec, sampling, size), _) in enumerate(REVISED, 1):
            request = _request(ns, handle, node, attribute, spec, None, None)
            request.RequestedParameters.SamplingInterval, request.RequestedParameters.QueueSize = sampling, size
            asked.append(request)
            request = _request(ns, 100 + handle, node, attribute, spec, None, None)
            request.RequestedParameters.SamplingInterval, request.RequestedParameters.QueueSize = 1000.0, 3
            other.append(request)
        created = [await _create(client, subscription, request) for request in asked + other]
        assert all(result.StatusCode.is_good() for result in created)
        assert [(r.RevisedSamplingInterval, r.RevisedQueueSize) for r in created[:len(asked)]] == wanted
        assert [r.RevisedSamplingInterval for r in created[len(asked):]] == [
            20.0 if attribute == "EventNotifier" else 1000.0 for (_, attribute, *_), _ in REVISED]
        modified = await client.uaclient.modify_monitored_items(ua.ModifyMonitoredItemsParameters(
            SubscriptionId=subscription.subscription_id, TimestampsToReturn=ua.TimestampsToReturn.Both,
            ItemsToModify=[ua.MonitoredItemModifyRequest(MonitoredItemId=result.MonitoredItemId,
                                                         RequestedParameters=request.RequestedParameters)
                           for result, request in zip(created[len(asked):], asked, strict=True)]))
        assert [result.StatusCode.name for result in modified] == ["Good"] * len(asked)
        assert [(r.RevisedSamplingInterval, r.RevisedQueueSize) for r in modified] == wanted
        await subscription.delete()


def test_node_opcua_a_modify_revises_each_parameter_as_a_create_does(served: tuple[Runtime, OpcuaFacade]) -> None:
    _, facade = served  # (node-opcua's subscription publishes every 20 ms)
    items = [{"node": node, "attribute": attribute, "filter": spec, "sampling": 1000, "queueSize": 3}
             for (node, attribute, spec, *_), _ in REVISED]
    [result] = node_client(facade.url, [{"op": "items", "items": items, "modifyTo": [
        {"sampling": sampling, "queueSize": size} for (*_, sampling, size), _ in REVISED]}])
    assert result["statuses"] == ["Good"] * len(REVISED)
    assert result["revised"] == [20.0 if attribute == "EventNotifier" else 1000.0  # (events are not sampled)
                                 for (_, attribute, *_), _ in REVISED]
    assert result["modified"] == [list(revised) for _, revised in REVISED]


async def test_asyncua_a_modified_item_reports_with_its_new_client_handle_and_timestamps(
        served: tuple[Runtime, OpcuaFacade]) -> None:
    """An item created with ClientHandle 1 and timestampsToReturn Both, modified to ClientHandle 2
    and Neither: the next value comes with handle 2 and no timestamp (5.12.3.2: the
    timestampsToReturn "for each MonitoredItem to be modified", 7.21: the clientHandle "used in
    Notifications"; asyncua kept both as the create had set them)."""
    runtime, facade = served
    seen: asyncio.Queue[tuple[int, ua.DataValue]] = asyncio.Queue()

    class Changes:
        def datachange_notification(self, node: Any, value: Any, data: Any) -> None:
            seen.put_nowait((data.monitored_item.ClientHandle, data.monitored_item.Value))

    name = "quantity.supply_voltage"  # (a value nothing but a write changes)
    old = runtime.read("sers", name)
    runtime.advance(0.2)  # (sampled since another test set it)
    try:
        async with Client(facade.url) as client:
            ns = await client.get_namespace_index(NAMESPACE)
            subscription = await client.create_subscription(20, Changes())
            request = _request(ns, 1, f"sers.{name}", "Value", None, None, None)
            created = await _create(client, subscription, request)
            handle, first = await asyncio.wait_for(seen.get(), 10)
            assert (handle, first.Value.Value) == (1, old)
            assert (first.SourceTimestamp is not None, first.ServerTimestamp is not None) == (True, True)
            subscription._monitored_items[2] = subscription._monitored_items[1]  # (asyncua's client routes by handle)
            request.RequestedParameters.ClientHandle = 2
            [modified] = await client.uaclient.modify_monitored_items(ua.ModifyMonitoredItemsParameters(
                SubscriptionId=subscription.subscription_id, TimestampsToReturn=ua.TimestampsToReturn.Neither,
                ItemsToModify=[ua.MonitoredItemModifyRequest(MonitoredItemId=created.MonitoredItemId,
                                                             RequestedParameters=request.RequestedParameters)]))
            assert modified.StatusCode.is_good()
            runtime.advance(0.2)  # (the first value is a sampling interval old)
            await client.get_node(ua.NodeId(f"sers.{name}", ns)).write_value(ua.DataValue(ua.Variant(45.0, ua.VariantType.Double)))
            handle, value = await asyncio.wait_for(seen.get(), 10)
            assert (handle, value.Value.Value, value.SourceTimestamp, value.ServerTimestamp) == (2, 45.0, None, None)
            await subscription.delete()
    finally:
        runtime.set("sers", name, old)  # (for the tests after this one)


async def test_asyncua_a_modified_event_item_filters_with_its_new_where_clause(
        served: tuple[Runtime, OpcuaFacade]) -> None:
    """An event item of the device created with a whereClause no fault event passes (OfType
    BaseModelChangeEventType), modified to an EventFilter without one: the next fault is reported
    (7.22.3: the EventFilter's whereClause selects the events; asyncua's modify took the new filter's
    selectClauses and kept the old whereClause, and nothing was ever reported)."""
    runtime, facade = served
    events: asyncio.Queue[Any] = asyncio.Queue()

    class Events:
        def event_notification(self, event: Any) -> None:
            events.put_nowait(event)

    async with Client(facade.url) as client:
        ns = await client.get_namespace_index(NAMESPACE)
        subscription = await client.create_subscription(20, Events())
        request = _request(ns, 1, "sers", "EventNotifier", EVENT, None, None)
        everything = request.RequestedParameters.Filter
        request.RequestedParameters.Filter = ua.EventFilter(
            SelectClauses=everything.SelectClauses, WhereClause=ua.ContentFilter(Elements=[ua.ContentFilterElement(
                FilterOperator=ua.FilterOperator.OfType, FilterOperands=[ua.LiteralOperand(
                    Value=ua.Variant(ua.NodeId(ua.ObjectIds.BaseModelChangeEventType)))])]))
        created = await _create(client, subscription, request)
        assert created.StatusCode.is_good()
        subscription._monitored_items[1].mfilter = everything  # (the fields asyncua's client maps)
        request.RequestedParameters.Filter = everything
        [modified] = await client.uaclient.modify_monitored_items(ua.ModifyMonitoredItemsParameters(
            SubscriptionId=subscription.subscription_id, TimestampsToReturn=ua.TimestampsToReturn.Both,
            ItemsToModify=[ua.MonitoredItemModifyRequest(MonitoredItemId=created.MonitoredItemId,
                                                         RequestedParameters=request.RequestedParameters)]))
        assert modified.StatusCode.is_good()
        runtime.fault("sers", "emergency_stop", True)
        try:
            event = await asyncio.wait_for(events.get(), 10)
            assert "emergency_stop on" in event.Message.Text
        finally:
            runtime.fault("sers", "emergency_stop", False)  # (for the tests after this one)
        await subscription.delete()


async def test_a_modify_to_a_smaller_queue_discards_the_oldest_notifications(
        served: tuple[Runtime, OpcuaFacade]) -> None:
    """30 values queued for an item of a subscription with publishing disabled (QueueSize 0:
    QUEUE_SIZE), then the item modified to QueueSize 5: its queue holds the newest 5 at once, and
    5 after one more value (5.12.3.2: "If the number of notifications in the queue exceeds the new
    queue size, the notifications exceeding the size shall be discarded following the configured
    discard policy", discardOldest; asyncua dropped one a new notification, and kept 30)."""
    from tests.support.process import wait_until

    runtime, facade = served
    name = "quantity.heatsink_temperature"  # (changes only when set)
    async with Client(facade.url) as client:
        ns = await client.get_namespace_index(NAMESPACE)
        subscription = await _unpublished(client, facade)
        request = _request(ns, 1, f"sers.{name}", "Value", None, None, None)
        request.RequestedParameters.QueueSize = 0
        created = await _create(client, subscription, request)
        mid = created.MonitoredItemId
        queues = facade.server.iserver.subscription_service.subscriptions[subscription.subscription_id]._triggered_datachanges
        start = runtime.read("sers", name)
        values = [round(start + 0.01 * n, 2) for n in range(1, 31)]
        for value in values:
            runtime.set("sers", name, value)
            runtime.advance(facade.period)  # (the facade samples the point)

        def queued() -> list[Any]:
            return [n.Value.Value.Value for n in queues.get(mid, [])]

        wait_until(lambda: queued()[-1:] == values[-1:], "the last value queued", 30)
        assert queued()[-30:] == values
        request.RequestedParameters.QueueSize = 5
        [modified] = await client.uaclient.modify_monitored_items(ua.ModifyMonitoredItemsParameters(
            SubscriptionId=subscription.subscription_id, TimestampsToReturn=ua.TimestampsToReturn.Both,
            ItemsToModify=[ua.MonitoredItemModifyRequest(MonitoredItemId=mid,
                                                         RequestedParameters=request.RequestedParameters)]))
        assert modified.RevisedQueueSize == 5
        assert queued() == values[-5:]
        runtime.set("sers", name, start)
        runtime.advance(facade.period)
        wait_until(lambda: queued()[-1:] == [start], "one more value queued", 30)
        assert queued() == [*values[-4:], start]
        await subscription.delete()


#: (discardOldest created, discardOldest a ModifyMonitoredItems then asks (None: none), queueSize) ->
#: what the client gets, as (value number, Overflow bit), of the value v0 queued when the item was
#: created and v1..v4 queued after it while publishing was disabled (Part 4 v1.05 5.13.1.5, v1.04
#: 5.12.1.5: discardOldest TRUE, "the oldest value gets deleted from the queue and the next value in
#: the queue gets the flag set"; FALSE, "the last value added to the queue gets replaced with the new
#: value. The new value gets the flag set"; "the discard policy is ignored if the queue size is one").
#: asyncua dropped the oldest whatever was asked and set no bit: v2, v3, v4 unflagged each time.
DISCARD = [
    (True, None, 3, [(2, True), (3, False), (4, False)]),
    (False, None, 3, [(0, False), (1, False), (4, True)]),
    (True, False, 3, [(0, False), (1, False), (4, True)]),
    (False, True, 3, [(2, True), (3, False), (4, False)]),
    (False, None, 1, [(4, False)]),
]


async def test_asyncua_a_full_queue_discards_as_discard_oldest_asks_and_flags_the_overflow(
        served: tuple[Runtime, OpcuaFacade]) -> None:
    """DISCARD: an item per row on a subscription with publishing disabled, modified where the row
    says; each of v1..v4 set and sampled (a second, published subscription's item tells when: its
    notification comes after every item of the point has queued the value), then publishing
    enabled: each item's notifications and their Overflow bits (InfoType DataValue, bit 7)."""
    from devsim.facades.opcua_monitoring import OVERFLOW

    runtime, facade = served
    watched: asyncio.Queue[Any] = asyncio.Queue()
    got: asyncio.Queue[tuple[int, Any, bool]] = asyncio.Queue()

    class Watch:
        def datachange_notification(self, node: Any, value: Any, data: Any) -> None:
            watched.put_nowait(value)

    class Got:
        def datachange_notification(self, node: Any, value: Any, data: Any) -> None:
            status = data.monitored_item.Value.StatusCode.value
            got.put_nowait((data.monitored_item.ClientHandle, value, status & OVERFLOW == OVERFLOW))

    name = "quantity.heatsink_temperature"  # (changes only when set)
    async with Client(facade.url) as client:
        ns = await client.get_namespace_index(NAMESPACE)
        node = client.get_node(ua.NodeId(f"sers.{name}", ns))
        watch = await client.create_subscription(20, Watch())
        await watch.subscribe_data_change(node)
        values = [await asyncio.wait_for(watched.get(), 10)]
        queued = await _unpublished(client, facade, Got())
        modify = []
        for handle, (oldest, modified, size, _) in enumerate(DISCARD, 1):
            request = _request(ns, handle, f"sers.{name}", "Value", None, None, None)
            request.RequestedParameters.QueueSize, request.RequestedParameters.DiscardOldest = size, oldest
            created = await _create(client, queued, request)
            assert created.RevisedQueueSize == size
            if modified is not None:
                modify.append(ua.MonitoredItemModifyRequest(MonitoredItemId=created.MonitoredItemId,
                                                            RequestedParameters=ua.MonitoringParameters(
                    ClientHandle=handle, SamplingInterval=0, QueueSize=size, DiscardOldest=modified)))
        results = await client.uaclient.modify_monitored_items(ua.ModifyMonitoredItemsParameters(
            SubscriptionId=queued.subscription_id, TimestampsToReturn=ua.TimestampsToReturn.Both, ItemsToModify=modify))
        assert all(result.StatusCode.is_good() for result in results)
        for n in range(1, 5):
            values.append(round(values[0] + 0.5 * n, 2))
            runtime.set("sers", name, values[-1])
            runtime.advance(facade.period)  # (the facade samples the point)
            assert await asyncio.wait_for(watched.get(), 10) == values[-1]
        await queued.set_publishing_mode(True)
        wanted = {handle: [(values[n], flag) for n, flag in reported]
                  for handle, (*_, reported) in enumerate(DISCARD, 1)}
        seen: dict[int, list[tuple[Any, bool]]] = {handle: [] for handle in wanted}
        for _ in range(sum(len(reported) for reported in wanted.values())):
            handle, value, flag = await asyncio.wait_for(got.get(), 10)
            seen[handle].append((value, flag))
        assert seen == wanted
        await queued.delete()
        await watch.delete()
    runtime.set("sers", name, values[0])
    runtime.advance(facade.period)


def test_node_opcua_a_full_queue_discards_as_discard_oldest_asks_and_flags_the_overflow(
        served: tuple[Runtime, OpcuaFacade]) -> None:
    """DISCARD through node-opcua's client (its own item per row, its watch, its Overflow bit)."""
    runtime, facade = served
    name = "quantity.heatsink_temperature"  # (changes only when set)
    runtime.advance(facade.period)  # (sampled since another test set it)
    start = runtime.read("sers", name)
    values = [start, *(round(start + 0.5 * n, 2) for n in range(1, 5))]

    def change() -> None:
        for value in values[1:]:
            runtime.set("sers", name, value)
            runtime.advance(facade.period)  # (the facade samples the point)

    items = [{"queueSize": size, "discardOldest": oldest, **({} if modified is None else {"modifyTo": modified})}
             for oldest, modified, size, _ in DISCARD]
    try:
        [result] = node_client(facade.url, [{"op": "queue", "node": f"sers.{name}", "items": items, "last": values[-1]}],
                               paused=change)
    finally:
        runtime.set("sers", name, start)
        runtime.advance(facade.period)
    assert result["first"] == start
    assert result["got"] == [[[values[n], flag] for n, flag in reported] for *_, reported in DISCARD]


#: The fields each event item selects (BaseEventType's), as asyncua's client names them.
FIELDS = ["EventId", "EventType", "SourceNode", "SourceName", "Message"]
OVERFLOWED = "overflow"  # (an EventQueueOverflowEventType event, in EVENT_QUEUES)

#: (queueSize, discardOldest) -> what an event item reports of four fault events e0..e3 (on, off,
#: on, off) queued while publishing was disabled (Part 4 v1.05 5.13.1.5, v1.04 5.12.1.5: "If Events
#: are lost, an Event of the type EventQueueOverflowEventType is placed in the queue", "in addition
#: to the size of the Queue"; discardOldest TRUE "put at the beginning of the queue and is never
#: discarded", FALSE "at the end", where the last event queued was replaced; one for the two events
#: lost).  asyncua dropped the oldest whatever was asked and queued no overflow event.
EVENT_QUEUES = [
    (2, True, [OVERFLOWED, 2, 3]),
    (2, False, [0, OVERFLOWED, 3]),
    (1, False, [OVERFLOWED, 3]),
    (4, True, [0, 1, 2, 3]),  # (nothing lost)
]


async def test_asyncua_a_full_event_queue_discards_as_discard_oldest_asks_and_queues_an_overflow_event(
        served: tuple[Runtime, OpcuaFacade]) -> None:
    """EVENT_QUEUES: an event item of the device per row on a subscription with publishing disabled
    (a second, published subscription's item tells when all four events are queued), then publishing
    enabled: each item's events, up to a fifth event sent when all queued ones came (so an extra
    overflow event would show).  The overflow event's fields are those of Part 5 v1.05 6.4.34:
    EventType i=3035, SourceNode the Server object, SourceName "Internal/EventQueueOverflow", its
    own EventId.  An item of the first row's parameters whose whereClause passes fault events only
    (OfType DeviceFaultEventType) gets it too (7.22.3: these events "bypass the whereClause")."""
    runtime, facade = served
    watched: asyncio.Queue[Any] = asyncio.Queue()
    got: asyncio.Queue[tuple[int, Any]] = asyncio.Queue()

    class Watch:
        def event_notification(self, event: Any) -> None:
            watched.put_nowait(event)

    class Got:
        def event_notification(self, event: Any) -> None:
            got.put_nowait((event.server_handle, event))

    select = ua.EventFilter(SelectClauses=[ua.SimpleAttributeOperand(
        TypeDefinitionId=ua.NodeId(ua.ObjectIds.BaseEventType), BrowsePath=[ua.QualifiedName(name, 0)],
        AttributeId=ua.AttributeIds.Value) for name in FIELDS])

    async def item(subscription: Any, handle: int, size: int, oldest: bool,
                   where: ua.ContentFilter | None = None) -> ua.MonitoredItemCreateResult:
        request = _request(ns, handle, "sers", "EventNotifier", EVENT, None, None)
        request.RequestedParameters.Filter = select if where is None else ua.EventFilter(
            SelectClauses=select.SelectClauses, WhereClause=where)
        request.RequestedParameters.QueueSize, request.RequestedParameters.DiscardOldest = size, oldest
        created = await _create(client, subscription, request)
        known = subscription._monitored_items[handle]
        known.mfilter = select  # (the fields asyncua's client maps)
        known.server_handle = handle  # (which item an event came for)
        return created

    def seen(event: Any, ids: list[bytes]) -> Any:
        if event.EventType == ua.NodeId(ua.ObjectIds.EventQueueOverflowEventType):
            assert (event.SourceNode, event.SourceName) == (ua.NodeId(ua.ObjectIds.Server), "Internal/EventQueueOverflow")
            assert event.EventId and event.EventId not in ids
            return OVERFLOWED
        return ids.index(event.EventId)

    async with Client(facade.url) as client:
        ns = await client.get_namespace_index(NAMESPACE)
        watch = await client.create_subscription(20, Watch())
        queued = await _unpublished(client, facade, Got())
        assert (await item(watch, 0, 10, True)).StatusCode.is_good()
        for handle, (size, oldest, _) in enumerate(EVENT_QUEUES, 1):
            assert (await item(queued, handle, size, oldest)).RevisedQueueSize == size
        faults = (await client.nodes.base_event_type.get_child(f"{ns}:DeviceFaultEventType")).nodeid
        where = ua.ContentFilter(Elements=[ua.ContentFilterElement(
            FilterOperator=ua.FilterOperator.OfType, FilterOperands=[ua.LiteralOperand(Value=ua.Variant(faults))])])
        size, oldest, reported = EVENT_QUEUES[0]
        wanted = [*EVENT_QUEUES, (size, oldest, reported)]
        assert (await item(queued, len(wanted), size, oldest, where)).StatusCode.is_good()
        try:
            for active in (True, False, True, False):
                runtime.fault("sers", "emergency_stop", active)
            ids = [(await asyncio.wait_for(watched.get(), 10)).EventId for _ in range(4)]
            await queued.set_publishing_mode(True)
            events = [await asyncio.wait_for(got.get(), 10)]  # (the queues published: all in one message)
            runtime.fault("sers", "emergency_stop", True)  # e4, reported after the queued ones
            ids.append((await asyncio.wait_for(watched.get(), 10)).EventId)
            while sum(event.EventId == ids[4] for _, event in events) < len(wanted):
                events.append(await asyncio.wait_for(got.get(), 10))
        finally:
            runtime.fault("sers", "emergency_stop", False)  # (for the tests after this one)
        await queued.delete()
        await watch.delete()
    assert {handle: [seen(event, ids) for got_for, event in events if got_for == handle]
            for handle in range(1, len(wanted) + 1)} == {
        handle: [*reported, 4] for handle, (*_, reported) in enumerate(wanted, 1)}


def test_node_opcua_a_full_event_queue_discards_as_discard_oldest_asks_and_queues_an_overflow_event(
        served: tuple[Runtime, OpcuaFacade]) -> None:
    """EVENT_QUEUES through node-opcua's client (its own items, its watch, the overflow event's
    EventType, SourceNode and SourceName as it decodes them)."""
    runtime, facade = served
    faults = iter([(True, False, True, False), (True,)])  # e0..e3 while queued, then e4

    def fault() -> None:
        for active in next(faults):
            runtime.fault("sers", "emergency_stop", active)

    items = [{"queueSize": size, "discardOldest": oldest} for size, oldest, _ in EVENT_QUEUES]
    try:
        [result] = node_client(facade.url, [{"op": "events", "node": "sers", "items": items, "count": 4}], paused=fault)
    finally:
        runtime.fault("sers", "emergency_stop", False)  # (for the tests after this one)
    ids = result["watched"]

    def seen(event_id: str, event_type: str, source: str, name: str) -> Any:
        if event_type == "ns=0;i=3035":  # (node-opcua writes the namespace 0 out)
            assert (source, name) == ("ns=0;i=2253", "Internal/EventQueueOverflow") and event_id not in ids
            return OVERFLOWED
        return ids.index(event_id)

    assert [[seen(*row) for row in got] for got in result["got"]] == [[*reported, 4] for *_, reported in EVENT_QUEUES]


def test_a_queue_cut_to_a_smaller_size_keeps_what_its_discard_policy_keeps() -> None:
    """A ModifyMonitoredItems to a smaller queueSize cuts a queue of 30 values "following the
    configured discard policy" (5.12.3.2) at once: discardOldest TRUE keeps the newest 5 and flags
    the first of them, FALSE keeps the first 4 and the newest (as if each value after the 4th had
    replaced the last one queued) and flags the newest; a queue of one keeps the newest, unflagged."""
    from devsim.facades.opcua_monitoring import OVERFLOW, discard

    def cut(size: int, oldest: bool) -> list[tuple[int, bool]]:
        queue = [ua.MonitoredItemNotification(ClientHandle=1, Value=ua.DataValue(ua.Variant(n))) for n in range(30)]
        discard(queue, size, oldest)
        return [(n.Value.Value.Value, n.Value.StatusCode.value == OVERFLOW) for n in queue]

    assert cut(5, True) == [(25, True), (26, False), (27, False), (28, False), (29, False)]
    assert cut(5, False) == [(0, False), (1, False), (2, False), (3, False), (29, True)]
    assert cut(1, False) == cut(1, True) == [(29, False)]


def test_an_event_queue_holds_one_overflow_event_until_it_is_published() -> None:
    """discard_events as events come one at a time to a queue of 3: seven events lose four, and the
    queue holds one overflow event (M) where they were lost, never discarded (discardOldest TRUE:
    first; FALSE: before the newest); a queue published (asyncua starts a new list) and full again
    gets a new one (Part 4 v1.05 5.13.1.5: generated "when the first Event is discarded"); a queue
    cut to 2 by a ModifyMonitoredItems keeps its overflow event where the discard policy asked now
    puts it."""
    from devsim.facades.opcua_monitoring import discard_events

    made: list[str] = []

    class Overflow:
        def __init__(self) -> None:
            made.append(f"M{len(made) + 1}")
            self.name = made[-1]

        def __repr__(self) -> str:
            return self.name

    def grow(queue: list[Any], events: range, size: int, oldest: bool, queued: Any = None) -> Any:
        for n in events:
            queue.append(n)
            queued = discard_events(queue, size, oldest, queued, Overflow)
        return queued

    queue: list[Any] = []
    queued = grow(queue, range(7), 3, True)
    assert (repr(queue), made) == ("[M1, 4, 5, 6]", ["M1"])
    published: list[Any] = []
    assert grow(published, range(7, 10), 3, True, queued) is None and published == [7, 8, 9]  # (nothing lost)
    grow(published, range(10, 12), 3, True, queued)
    assert (repr(published), made) == ("[M2, 9, 10, 11]", ["M1", "M2"])
    made.clear()
    queue = []
    queued = grow(queue, range(7), 3, False)
    assert (repr(queue), made) == ("[0, 1, M1, 6]", ["M1"])
    assert discard_events(queue, 2, False, queued, Overflow) is queued and repr(queue) == "[0, M1, 6]"
    assert discard_events(queue, 1, True, queued, Overflow) is queued and repr(queue) == "[M1, 6]"
    assert made == ["M1"]
