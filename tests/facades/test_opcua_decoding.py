"""Requests whose parameters asyncua cannot decode (devsim/facades/opcua_decoding.py), sent by
asyncua's client over TCP to the facade's server: each is a ServiceFault with the status OPC UA
Part 4 names, not Bad_InternalError, and the simulator's stderr gets no traceback for them.

asyncua's client encodes an enumeration parameter given as a plain int as it is, so it sends what
its server cannot decode: a timestampsToReturn of 5 or -1 (Part 4, 7.40: 0..3; asyncua's enum has
4, ``Invalid``, and nothing above), a monitoringMode or browseDirection of 9.  Expected codes:
Bad_TimestampsToReturnInvalid for Read (5.10.2), HistoryRead (5.10.3), CreateMonitoredItems
(5.12.2) and ModifyMonitoredItems (5.12.3); Bad_MonitoringModeInvalid for SetMonitoringMode
(5.12.4, Table 76); Bad_DecodingError (7.34.2) for an item's enumeration that does not decode.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from typing import Any

import pytest
from asyncua import Client, ua

from devsim.facades.opcua import OpcuaFacade, start_opcua
from devsim.facades.opcua_space import NAMESPACE
from devsim.runtime import Runtime
from tests.test_cli import Sim

VOLTAGE = "sers.quantity.supply_voltage"


@pytest.fixture(scope="module")
def served() -> Iterator[OpcuaFacade]:
    runtime = Runtime(virtual=True).start()
    try:
        devices = [runtime.add_device("sers", "sers")]
        yield runtime.run(start_opcua(runtime, devices, "127.0.0.1:0"), timeout=60)
    finally:
        runtime.stop()


def _item(node: ua.NodeId, mode: int = ua.MonitoringMode.Reporting) -> ua.MonitoredItemCreateRequest:
    return ua.MonitoredItemCreateRequest(
        ItemToMonitor=ua.ReadValueId(NodeId=node, AttributeId=ua.AttributeIds.Value), MonitoringMode=mode,
        RequestedParameters=ua.MonitoringParameters(ClientHandle=1, SamplingInterval=100, QueueSize=1))


def _read(node: ua.NodeId, timestamps: int) -> ua.ReadParameters:
    return ua.ReadParameters(NodesToRead=[ua.ReadValueId(NodeId=node, AttributeId=ua.AttributeIds.Value)],
                             TimestampsToReturn=timestamps)


class _Session:
    """A client's session with a subscription and one monitored item of the voltage, and the
    requests of the cases below built on them."""

    def __init__(self, client: Client, node: ua.NodeId, subscription: int, item: int) -> None:
        self.uaclient, self.node, self.subscription, self.item = client.uaclient, node, subscription, item

    def read(self, timestamps: int) -> Any:
        return self.uaclient.read(_read(self.node, timestamps))

    def history_read(self, timestamps: int) -> Any:
        return self.uaclient.history_read(ua.HistoryReadParameters(
            HistoryReadDetails=ua.ReadRawModifiedDetails(), TimestampsToReturn=timestamps,
            NodesToRead=[ua.HistoryReadValueId(NodeId=self.node)]))

    def create_items(self, timestamps: int, mode: int = ua.MonitoringMode.Reporting) -> Any:
        return self.uaclient.create_monitored_items(ua.CreateMonitoredItemsParameters(
            SubscriptionId=self.subscription, TimestampsToReturn=timestamps, ItemsToCreate=[_item(self.node, mode)]))

    def modify_items(self, timestamps: int) -> Any:
        return self.uaclient.modify_monitored_items(ua.ModifyMonitoredItemsParameters(
            SubscriptionId=self.subscription, TimestampsToReturn=timestamps,
            ItemsToModify=[ua.MonitoredItemModifyRequest(MonitoredItemId=self.item, RequestedParameters=ua.MonitoringParameters(
                ClientHandle=1, SamplingInterval=100, QueueSize=1))]))

    def set_mode(self, mode: int) -> Any:
        return self.uaclient.set_monitoring_mode(ua.SetMonitoringModeParameters(
            SubscriptionId=self.subscription, MonitoringMode=mode, MonitoredItemIds=[self.item]))

    def browse(self, direction: int) -> Any:
        return self.uaclient.browse(ua.BrowseParameters(NodesToBrowse=[ua.BrowseDescription(
            NodeId=self.node, BrowseDirection=direction)]))


#: (what is sent) -> the ServiceFault's status
CASES: list[tuple[str, Callable[[_Session], Any], str]] = [
    ("Read, timestampsToReturn 5", lambda s: s.read(5), "BadTimestampsToReturnInvalid"),
    ("Read, timestampsToReturn -1", lambda s: s.read(-1), "BadTimestampsToReturnInvalid"),
    ("HistoryRead, timestampsToReturn 5", lambda s: s.history_read(5), "BadTimestampsToReturnInvalid"),
    ("HistoryRead, timestampsToReturn 4", lambda s: s.history_read(4), "BadTimestampsToReturnInvalid"),
    ("CreateMonitoredItems, timestampsToReturn 5", lambda s: s.create_items(5), "BadTimestampsToReturnInvalid"),
    ("CreateMonitoredItems, timestampsToReturn 4", lambda s: s.create_items(4), "BadTimestampsToReturnInvalid"),
    ("ModifyMonitoredItems, timestampsToReturn 5", lambda s: s.modify_items(5), "BadTimestampsToReturnInvalid"),
    ("ModifyMonitoredItems, timestampsToReturn 4", lambda s: s.modify_items(4), "BadTimestampsToReturnInvalid"),
    ("SetMonitoringMode, monitoringMode 9", lambda s: s.set_mode(9), "BadMonitoringModeInvalid"),
    ("CreateMonitoredItems, an item's monitoringMode 9", lambda s: s.create_items(2, mode=9), "BadDecodingError"),
    ("Browse, a browseDirection 9", lambda s: s.browse(9), "BadDecodingError"),
]


async def test_undecodable_parameters_are_answered_with_part4_status_codes(
        served: OpcuaFacade, capfd: pytest.CaptureFixture[str]) -> None:
    async with Client(served.url) as client:
        ns = await client.get_namespace_index(NAMESPACE)
        node = ua.NodeId(VOLTAGE, ns)
        subscription = await client.create_subscription(100, None)
        [item] = await client.uaclient.create_monitored_items(ua.CreateMonitoredItemsParameters(
            SubscriptionId=subscription.subscription_id, TimestampsToReturn=ua.TimestampsToReturn.Both,
            ItemsToCreate=[_item(node)]))
        session = _Session(client, node, subscription.subscription_id, item.MonitoredItemId)
        got = []
        for _label, send, _status in CASES:
            try:
                await send(session)
                got.append("Good")
            except ua.UaStatusCodeError as fault:
                got.append(ua.StatusCode(fault.code).name)
        assert list(zip([label for label, *_ in CASES], got, strict=True)) == [(label, status) for label, _, status in CASES]
        [value] = await client.uaclient.read(_read(node, ua.TimestampsToReturn.Both))  # the session serves on
        assert value.StatusCode.is_good() and value.Value.Value == 68.0
    err = capfd.readouterr().err
    assert "Traceback" not in err and "Error while processing" not in err, err


async def test_bad_timestamps_to_return_leave_one_line_on_stderr() -> None:
    """30 Reads with timestampsToReturn 5 to `devsim run --opcua`: 30 Bad_TimestampsToReturnInvalid,
    and on stderr one line about them, headed devsim: opcua: (rate-limited, docs/monitor.md), no
    traceback."""
    sim = Sim("sers", "--pty", "--virtual", "--opcua", "127.0.0.1:0")
    try:
        url = sim.read_until("opcua:")["opcua"]
        async with Client(url) as client:
            node = ua.NodeId(VOLTAGE, await client.get_namespace_index(NAMESPACE))
            for _ in range(30):
                with pytest.raises(ua.uaerrors.BadTimestampsToReturnInvalid):
                    await client.uaclient.read(_read(node, 5))
    finally:
        _status, err = sim.stop()
    about = [line for line in err.splitlines() if "timestamps" in line.lower() or "error" in line.lower()]
    assert len(about) == 1 and about[0].startswith("devsim: opcua: "), err
    assert "Traceback" not in err, err
