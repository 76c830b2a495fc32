"""The MonitoredItem service set of the OPC UA facade (OPC UA Part 4, 5.12): asyncua's, with each
item checked as Part 4 asks before asyncua creates or modifies it.

asyncua creates an item for whatever it is given and answers some cases with codes Part 4 does
not name: an event item (AttributeId EventNotifier) on a node the server does not have, or on a
Variable, is ``Bad_ServiceUnsupported``; an event item without an EventFilter, or an EventFilter
on a Value, fails the whole CreateMonitoredItems request with ``Bad_InternalError``, and so does a
ModifyMonitoredItems naming an item that does not exist; a deadband on a String or a Boolean is
taken and then raises inside asyncua at every change (the item never reports), a percent
deadband is taken and ignored, an IndexRange is taken and ignored.  :class:`ItemChecks` answers
each item as Part 4 5.12.2.4 (Table 71) and 5.12.3.4 (Table 74) do, per item:

* ``Bad_NodeIdUnknown`` for a node the server does not have, ``Bad_AttributeIdInvalid`` for an
  attribute the node does not have (the EventNotifier of a Variable);
* ``Bad_IndexRangeInvalid`` for an IndexRange of invalid syntax (7.27), ``Bad_IndexRangeNoData``
  for one on a scalar that is not a String or ByteString (its dimensions are fixed: Table 71); a
  valid range on a String or an array reports that part only (``shaped``, as Read does);
* every data change is reported with the timestamps its request's ``timestampsToReturn`` asked for
  (Source, Server, Both, Neither: 5.12.2.2);
* a data item's revisedSamplingInterval is at least the one it asked for, whatever its attribute
  (5.12.2.2; asyncua answered the publishing interval) and, for a Value, the node's
  MinimumSamplingInterval (5.12.1.2; a point's: the period the facade samples it at), and an item
  that asked for more than its subscription's publishing interval reports its values no closer
  than that on the device clock (:class:`Spacing`);
* ``Bad_DataEncodingInvalid`` for a dataEncoding on anything but the Value of a structure,
  ``Bad_DataEncodingUnsupported`` for another than ``Default Binary`` (7.34, as Read:
  :func:`devsim.facades.opcua_services.encoding_refusal`);
* an event item: ``Bad_MonitoredItemFilterInvalid`` without an EventFilter (7.22.3: the
  EventFilter selects the fields each notification carries);
* a Value item: ``Bad_FilterNotAllowed`` for an EventFilter; ``Bad_MonitoredItemFilterUnsupported``
  for a filter that is neither (an AggregateFilter); for a DataChangeFilter,
  ``Bad_DeadbandFilterInvalid`` for a deadbandType that is not None, Absolute or Percent, and for
  a percent deadband on a variable without an ``EURange`` property (Part 8, 6.2 and Table 28; no
  variable of the facade has one), ``Bad_FilterNotAllowed`` for an absolute deadband on a
  variable whose DataType is not a Number (7.22.2: it "applies only to Variables with any Number
  data type");
* any other attribute: ``Bad_FilterNotAllowed`` for a filter (5.12.1.1: those attributes are
  monitored for a change in value only, the filter is not used for them);
* ModifyMonitoredItems: ``Bad_MonitoredItemIdInvalid`` for an item the subscription does not
  have, and the filter checks above against the item's node and attribute; an item modified takes
  its new parameters as a created one does, revised by the same code (:meth:`ItemChecks._revise`:
  samplingInterval, queueSize, discardOldest, filter, clientHandle, timestampsToReturn; 5.12.3.2);
* a full queue discards as the item's discardOldest says (5.12.1.5; asyncua dropped the oldest
  whatever was asked), and a data item's queue longer than one marks where values were lost with
  the Overflow bit (:func:`discard`), an event item's with an EventQueueOverflowEventType event
  (:func:`discard_events`; asyncua generated none).

:class:`Subscriptions` is asyncua's SubscriptionService giving each new subscription an
:class:`ItemChecks` (:class:`devsim.facades.opcua_decoding.FacadeServer` installs it).
"""

from __future__ import annotations

import asyncio
import copy
import uuid
from collections.abc import Awaitable, Callable
from datetime import UTC, datetime
from typing import Any

from asyncua import ua
from asyncua.common.event_objects import EventQueueOverflowEvent
from asyncua.server.address_space import AddressSpace
from asyncua.server.monitored_item_service import MonitoredItemService, WhereClauseEvaluator
from asyncua.server.subscription_service import SubscriptionService
from asyncua.ua import uaprotocol_auto

from devsim.core.clock import Clock
from devsim.facades.opcua_services import derives, encoding_refusal, index_range, shaped

__all__ = ["OVERFLOW", "QUEUE_SIZE", "ItemChecks", "Spacing", "Subscriptions", "discard", "discard_events", "overflow_event",
           "refusal"]

#: [SIM-CHOICE] The most notifications a monitored item queues for a client that does not take
#: them (Part 4 5.12.1.5: the server revises the queue size it is asked for; a queue size of 0 asks
#: for the server's largest).  asyncua's own cap, 10,000, was not applied to a ModifyMonitoredItems:
#: an item modified to QueueSize 0 queued every change for as long as its subscription lived.
QUEUE_SIZE = 1000

#: The InfoBits of a DataValue whose queue lost values before it: InfoType DataValue (bits 10:11 =
#: 01) and Overflow (bit 7; Part 4 v1.05 7.39.1 Table 177, v1.04 7.34.1).
OVERFLOW = 0x0400 | 0x0080

_BAD = ua.StatusCodes
_VALUE, _EVENTS = ua.AttributeIds.Value, ua.AttributeIds.EventNotifier
_SLICEABLE = (ua.NodeId(ua.ObjectIds.String), ua.NodeId(ua.ObjectIds.ByteString))
_NUMBER = ua.NodeId(ua.ObjectIds.Number)
_HAS_PROPERTY = ua.NodeId(ua.ObjectIds.HasProperty)
#: (a DataChangeFilter as asyncua decodes it; ``ua.DataChangeFilter`` is a subclass of it)
_DATA_CHANGE = uaprotocol_auto.DataChangeFilter
_DEADBANDS = {int(ua.DeadbandType.None_), int(ua.DeadbandType.Absolute), int(ua.DeadbandType.Percent)}


def _attribute(aspace: AddressSpace, node_id: ua.NodeId, attribute: ua.AttributeIds) -> Any:
    value = aspace.read_attribute_value(node_id, attribute)
    return value.Value.Value if value.StatusCode.is_good() and value.Value is not None else None


def _has_property(aspace: AddressSpace, node_id: ua.NodeId, name: str) -> bool:
    return any(ref.IsForward and ref.ReferenceTypeId == _HAS_PROPERTY and ref.BrowseName.Name == name
               for ref in aspace[node_id].references)


def _filter_refusal(aspace: AddressSpace, item: ua.ReadValueId, flt: Any) -> int | None:
    """The status a monitored item's filter is refused with (None: none)."""
    if isinstance(flt, ua.ExtensionObject) and flt.Body is None:
        flt = None  # no filter: a null ExtensionObject on the wire
    if item.AttributeId == _EVENTS:
        return None if isinstance(flt, ua.EventFilter) else _BAD.BadMonitoredItemFilterInvalid
    if flt is None:
        return None
    if item.AttributeId != _VALUE or isinstance(flt, ua.EventFilter):
        return _BAD.BadFilterNotAllowed
    if not isinstance(flt, _DATA_CHANGE):
        return _BAD.BadMonitoredItemFilterUnsupported
    deadband = int(flt.DeadbandType)
    if deadband not in _DEADBANDS:
        return _BAD.BadDeadbandFilterInvalid
    if deadband == ua.DeadbandType.Percent:
        return (_BAD.BadMonitoredItemFilterUnsupported if _has_property(aspace, item.NodeId, "EURange")
                else _BAD.BadDeadbandFilterInvalid)
    data_type = _attribute(aspace, item.NodeId, ua.AttributeIds.DataType)
    if deadband == ua.DeadbandType.Absolute and not derives(aspace, data_type, _NUMBER):
        return _BAD.BadFilterNotAllowed
    return None


def refusal(aspace: AddressSpace, item: ua.ReadValueId, flt: Any) -> int | None:
    """The status code a monitored item of ``item`` with filter ``flt`` is refused with (Part 4,
    5.12.2.4 Table 71), None when asyncua may create it."""
    node_id, attribute = item.NodeId, item.AttributeId
    if node_id not in aspace:
        return _BAD.BadNodeIdUnknown
    if attribute not in aspace[node_id].attributes:
        return _BAD.BadAttributeIdInvalid
    if item.IndexRange:
        if index_range(item.IndexRange) is None:
            return _BAD.BadIndexRangeInvalid
        rank = _attribute(aspace, node_id, ua.AttributeIds.ValueRank)
        if attribute == _VALUE and rank == ua.ValueRank.Scalar \
                and _attribute(aspace, node_id, ua.AttributeIds.DataType) not in _SLICEABLE:
            return _BAD.BadIndexRangeNoData  # a scalar number: fixed dimensions, nothing to select
    refused = encoding_refusal(aspace, item)
    return refused if refused is not None else _filter_refusal(aspace, item, flt)


def _overflowed(value: ua.DataValue) -> ua.DataValue:
    flagged = copy.copy(value)  # (values may be shared)
    flagged.StatusCode = ua.StatusCode((value.StatusCode.value if value.StatusCode is not None else 0) | OVERFLOW)
    return flagged


def discard(queue: list[Any], size: int, oldest: bool) -> None:
    """Cut an item's ``queue`` of notifications (oldest first) to ``size`` as Part 4 5.12.1.5
    (v1.05 5.13.1.5) says a full queue takes a new one: ``oldest`` (discardOldest TRUE) the oldest
    are deleted and "the next value in the queue gets the flag set"; else "the last value added to
    the queue gets replaced with the new value. The new value gets the flag set" (the first
    ``size - 1`` stay, then the newest).  The flag is the Overflow bit of a DataValue, set only
    where the queue is larger than one ("the discard policy is ignored if the queue size is one":
    the newest stays).  An event item's queue: :func:`discard_events`."""
    if len(queue) <= size:
        return
    if oldest or size == 1:
        del queue[:-size]
    else:
        queue[size - 1:] = queue[-1:]
    flagged = queue[0] if oldest else queue[-1]
    if size > 1 and isinstance(flagged, ua.MonitoredItemNotification):
        flagged.Value = _overflowed(flagged.Value)


def discard_events(queue: list[Any], size: int, oldest: bool, queued: Any, overflow: Callable[[], Any]) -> Any:
    """Cut an event item's ``queue`` of notifications (oldest first) to ``size`` events as
    :func:`discard` does, and mark where events were lost with an EventQueueOverflowEventType event
    (Part 4 v1.05 5.13.1.5, v1.04 5.12.1.5: "If Events are lost, an Event of the type
    EventQueueOverflowEventType is placed in the queue"; 7.21): ``queued``, the one already in the
    queue, or a new one from ``overflow()`` at the first event discarded.  It is queued "in addition
    to the size of the Queue" and, with ``oldest`` (discardOldest TRUE), "put at the beginning of the
    queue and is never discarded", else "at the end": where the replaced events were, before the
    newest (a queue of one: before the newest either way).  One stays one until the queue is
    published (its overflow period): a queue that loses more events keeps it, a queue published
    and full again gets a new one.  Returns the overflow event in the queue (None: none)."""
    events = [notification for notification in queue if notification is not queued]
    if len(events) == len(queue):
        queued = None  # (one from a queue already published)
    if len(events) <= size:
        return queued
    if queued is None:
        queued = overflow()
    queue[:] = [queued, *events[-size:]] if oldest else [*events[:size - 1], queued, events[-1]]
    return queued


def overflow_event(select: list[ua.SimpleAttributeOperand], handle: int) -> ua.EventFieldList:
    """The EventQueueOverflowEventType event (i=3035) of an item with ``select`` clauses and client
    ``handle``: the Server object its SourceNode and "Internal/EventQueueOverflow" its SourceName
    (Part 5 v1.05 6.4.34), a new EventId, Time and ReceiveTime now (as the facade's own events), a
    field the type does not have null.  It is no node of the address space (the type is abstract)
    and bypasses the whereClause (Part 4 7.22.3).  [SIM-CHOICE] Its Message says events were lost,
    its Severity is BaseEventType's lowest, 1 (Part 5 gives neither)."""
    event = EventQueueOverflowEvent(ua.NodeId(ua.ObjectIds.Server), "Events were lost: the event queue overflowed")
    event.EventId, event.SourceName = uuid.uuid4().bytes, "Internal/EventQueueOverflow"
    event.Time = event.ReceiveTime = datetime.now(UTC)
    return ua.EventFieldList(ClientHandle=handle, EventFields=event.to_event_fields(select))


class ItemChecks(MonitoredItemService):
    """asyncua's monitored items of one subscription, each checked by :func:`refusal` first; an
    item reports the part its IndexRange selects, with the timestamps its request asked for
    (timestampsToReturn, 5.12.2.2; asyncua sent the stored ones whatever was asked)."""

    def __init__(self, isub: Any, aspace: AddressSpace, clock: Clock | None = None) -> None:
        super().__init__(isub, aspace)
        self._timestamps: dict[int, ua.TimestampsToReturn] = {}  # per item id
        self._queues: dict[int, tuple[int, bool]] = {}  # per item id: (queueSize, discardOldest)
        self._overflows: dict[int, ua.EventFieldList] = {}  # per event item id: its last overflow event
        self._asked = ua.TimestampsToReturn.Both  # (of the item being created)
        self._spacing = Spacing(clock, self._deliver)

    async def create_monitored_items(self, params: ua.CreateMonitoredItemsParameters) -> list[ua.MonitoredItemCreateResult]:
        results = []
        for item in params.ItemsToCreate:
            refused = refusal(self.aspace, item.ItemToMonitor, item.RequestedParameters.Filter)
            if refused is not None:
                results.append(ua.MonitoredItemCreateResult(StatusCode=ua.StatusCode(refused)))
                continue
            one = ua.CreateMonitoredItemsParameters(SubscriptionId=params.SubscriptionId,
                                                    TimestampsToReturn=params.TimestampsToReturn, ItemsToCreate=[item])
            self._asked = params.TimestampsToReturn
            [result] = await super().create_monitored_items(one)
            results.append(result)
        return results

    def _make_monitored_item_common(self, params: ua.MonitoredItemCreateRequest) -> tuple[ua.MonitoredItemCreateResult, Any]:
        result, mdata = super()._make_monitored_item_common(params)
        self._revise(mdata, result, params.RequestedParameters, self._asked)  # (before its first notification)
        return result, mdata

    def modify_monitored_items(self, params: ua.ModifyMonitoredItemsParameters) -> list[ua.MonitoredItemModifyResult]:
        """Each item's new parameters revised and applied by :meth:`_revise`, as a create's (asyncua's
        own took the asked samplingInterval and queueSize as they came, -1 and 0 too, kept the
        item's timestampsToReturn and its event filter's whereClause)."""
        results = []
        for item in params.ItemsToModify:
            mdata = self._monitored_items.get(item.MonitoredItemId)
            refused = (_BAD.BadMonitoredItemIdInvalid if mdata is None
                       else _filter_refusal(self.aspace, mdata.read_value_id, item.RequestedParameters.Filter))
            result = ua.MonitoredItemModifyResult()
            if refused is not None:
                result.StatusCode = ua.StatusCode(refused)
            elif mdata is not None:
                self._revise(mdata, result, item.RequestedParameters, params.TimestampsToReturn)
            results.append(result)
        return results

    def _revise(self, mdata: Any, result: Any, asked: ua.MonitoringParameters, timestamps: ua.TimestampsToReturn) -> None:
        """Take the monitoring parameters ``asked`` for item ``mdata`` (7.21), revised into ``result``:
        the one code of CreateMonitoredItems (5.12.2.2) and ModifyMonitoredItems (5.12.3.2: "the
        requested values for the monitoring parameters"; "illegal request values for parameters
        that can be revised do not generate errors", they are revised).

        * its clientHandle, its filter (null: none; an event item's whereClause with it) and the
          timestamps it reports (timestampsToReturn);
        * its queueSize revised to 1..QUEUE_SIZE (0: QUEUE_SIZE) and its discardOldest, the
          policy :meth:`_bound` keeps its queue to (asyncua's queue is left unbounded: it dropped
          the oldest whatever discardOldest said), and a queue already longer cut to it at once
          (5.12.3.2: "the notifications exceeding the size shall be discarded following the
          configured discard policy": the one this request configures; asyncua's dropped one a
          notification, so its queue stayed as long as it was);
        * its samplingInterval revised by :meth:`_space`."""
        mid = mdata.monitored_item_id
        mdata.client_handle = asked.ClientHandle
        mdata.filter = asked.Filter
        if mdata.read_value_id.AttributeId == _EVENTS and isinstance(asked.Filter, ua.EventFilter):
            mdata.where_clause_evaluator = WhereClauseEvaluator(self.logger, self.aspace, asked.Filter.WhereClause)
        self._timestamps[mid] = timestamps
        result.RevisedQueueSize = self._revise_queue_size(asked.QueueSize)
        mdata.queue_size = 0  # (asyncua's bound: none)
        self._queues[mid] = (result.RevisedQueueSize, bool(asked.DiscardOldest))
        self._bound(mid)
        self._space(mid, result, mdata.read_value_id, asked.SamplingInterval)

    def _bound(self, mid: int) -> None:
        """Item ``mid``'s queues of notifications not yet published kept to its queueSize by its
        discardOldest (:func:`discard`, an event item's :func:`discard_events`); called right after
        each notification asyncua queues, with no ``await`` between, so no publish sees a queue
        longer than the size."""
        size, oldest = self._queues.get(mid, (0, True))
        if not size:
            return
        if mid in self.isub._triggered_datachanges:
            discard(self.isub._triggered_datachanges[mid], size, oldest)
        mdata = self._monitored_items.get(mid)
        if mid in self.isub._triggered_events and mdata is not None:
            queued = discard_events(self.isub._triggered_events[mid], size, oldest, self._overflows.get(mid),
                                    lambda: overflow_event(mdata.filter.SelectClauses, mdata.client_handle))
            if queued is None:
                self._overflows.pop(mid, None)
            else:
                self._overflows[mid] = queued

    def _space(self, mid: int, result: Any, item: ua.ReadValueId, requested: float) -> None:
        """An item's revisedSamplingInterval: the subscription's publishing interval (asyncua's; -1
        asks for it, 0 for the fastest practical rate, 7.21) or more: the one it asked for (5.12.2.2,
        7.21: "equal or higher than the requested samplingInterval"), for any attribute (5.12.1.1:
        an attribute other than the Value is "only monitored for a change in value", sampled at
        that interval all the same; asyncua answered the publishing interval), and for a Value the
        node's MinimumSamplingInterval too (5.12.1.2: "equal or higher than the
        MinimumSamplingInterval if the Client subscribes to the Value Attribute"; a point's is the
        period its device is sampled at).  An event item gets the publishing interval (events are
        not sampled: 5.12.1.2, "a sampling interval of 0 if it subscribes for Events").  Its values
        that far apart: a point's (sampled on the device clock: a MinimumSamplingInterval) by its
        revised interval, so that two writes in a row are not reported closer; another item's only
        when it asked for more than the publishing interval."""
        apart = 0.0
        publishing = self.isub.data.RevisedPublishingInterval
        result.RevisedSamplingInterval = publishing
        if item.AttributeId != _EVENTS:
            minimum = (_attribute(self.aspace, item.NodeId, ua.AttributeIds.MinimumSamplingInterval) or 0.0
                       if item.AttributeId == _VALUE else 0.0)
            result.RevisedSamplingInterval = max(publishing, requested, minimum)
            if minimum > 0:
                apart = result.RevisedSamplingInterval
            elif requested > publishing:
                apart = requested
        self._spacing.set(mid, apart)

    def _delete_monitored_items(self, mid: int) -> ua.StatusCode:
        self._timestamps.pop(mid, None)
        self._queues.pop(mid, None)
        self._overflows.pop(mid, None)
        self._spacing.forget(mid)
        return super()._delete_monitored_items(mid)

    async def datachange_callback(self, handle: int, value: ua.DataValue, error: ua.StatusCode | None = None) -> None:
        mid = self._monitored_datachange.get(handle, -1)
        mdata = self._monitored_items.get(mid)
        if error is None and value is not None and mdata is not None:
            value = shaped(value, self._timestamps.get(mid, ua.TimestampsToReturn.Both), mdata.read_value_id.IndexRange)
            if self._spacing.hold(mid, handle, value):
                return  # reported when its sampling interval has passed
        await super().datachange_callback(handle, value, error)
        self._bound(mid)

    async def _deliver(self, mid: int, handle: int, value: ua.DataValue) -> None:
        if mid in self._monitored_items:
            await super().datachange_callback(handle, value)
            self._bound(mid)

    async def _trigger_event(self, event: Any, mid: int) -> None:
        await super()._trigger_event(event, mid)
        self._bound(mid)


class Spacing:
    """The values of the items of the points (each at its revisedSamplingInterval: the sampling
    period, or more if asked; the facade samples a point also right after a write) and of the
    other items that asked for a sampling interval longer than their subscription's publishing
    interval, kept that far apart on the device clock ("the time between values returned to the
    Client shall be greater or equal to the sampling interval", Part 4 5.12.1.2): a value that
    comes sooner is held, replaced by a newer one, and reported when the interval has passed (the
    latest, as a sample at that moment would see it; a newer value reported first, at that very
    moment, drops it: never an older value after a newer).  Other items report every change, as
    asyncua did."""

    SLACK = 1e-6  # seconds: periodic samples one interval apart are apart (float sums of periods)

    def __init__(self, clock: Clock | None, deliver: Callable[[int, int, ua.DataValue], Awaitable[None]]) -> None:
        self.clock, self.deliver = clock, deliver
        self.apart: dict[int, float] = {}  # item id -> device seconds between its values
        self.last: dict[int, float] = {}  # item id -> when its last value was reported
        self.held: dict[int, tuple[int, ua.DataValue]] = {}
        self.timers: dict[int, Any] = {}
        self.sending: set[Any] = set()

    def set(self, mid: int, apart_ms: float) -> None:
        """Keep item ``mid``'s values ``apart_ms`` apart (0: report each at once)."""
        if self.clock is not None and apart_ms > 0:
            self.apart[mid] = apart_ms / 1000
        else:
            self.apart.pop(mid, None)

    def hold(self, mid: int, handle: int, value: ua.DataValue) -> bool:
        """Hold ``value`` for later (True) or let it be reported now (False)."""
        if self.clock is None:
            return False
        now, apart, last = self.clock.now(), self.apart.get(mid), self.last.get(mid)
        if apart is not None and last is not None and now - last < apart - self.SLACK:
            self.held[mid] = (handle, value)
            if mid not in self.timers:
                self.timers[mid] = self.clock.call_later(last + apart - now, lambda: self._release(mid))
            return True
        self.last[mid] = now
        self.held.pop(mid, None)  # older than this one: never reported after it
        timer = self.timers.pop(mid, None)
        if timer is not None:
            timer.cancel()
        return False

    def _release(self, mid: int) -> None:
        self.timers.pop(mid, None)
        held = self.held.pop(mid, None)
        if held is None or self.clock is None:
            return
        self.last[mid] = self.clock.now()
        sending = asyncio.ensure_future(self.deliver(mid, *held))  # (the clock fires in the server's loop)
        self.sending.add(sending)
        sending.add_done_callback(self.sending.discard)

    def forget(self, mid: int) -> None:
        for table in (self.apart, self.last, self.held):
            table.pop(mid, None)
        timer = self.timers.pop(mid, None)
        if timer is not None:
            timer.cancel()


class Subscriptions(SubscriptionService):
    """asyncua's subscriptions, each with :class:`ItemChecks` for its monitored items (sampling
    intervals on ``clock``, the devices' clock)."""

    def __init__(self, aspace: AddressSpace, iserver: Any, clock: Clock | None = None) -> None:
        super().__init__(aspace, iserver)
        self.clock = clock

    async def create_subscription(self, params: ua.CreateSubscriptionParameters, callback: Any, session_id: ua.NodeId,
                                  request_callback: Any = None) -> ua.CreateSubscriptionResult:
        result = await super().create_subscription(params, callback, session_id, request_callback)
        subscription = self.subscriptions[result.SubscriptionId]
        subscription.monitored_item_srv = ItemChecks(subscription, self.aspace, self.clock)  # (no items yet)
        return result
