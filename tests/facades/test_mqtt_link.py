"""devsim's own MQTT client (devsim.facades.mqtt_link) against a real mosquitto: a round trip in
MQTT 5 and 3.1.1, everything published in one loop turn in one write, a will sent when the
connection is dropped, and the end of the link when the broker goes away."""

from __future__ import annotations

import asyncio
from collections.abc import Iterator

import pytest

from devsim.facades.mqtt_link import LinkLost, open_link
from devsim.facades.mqtt_wire import PacketReader, Publish, Will
from tests.support.broker import Broker


@pytest.fixture
def broker() -> Iterator[Broker]:
    server = Broker().start()
    yield server
    server.stop()


@pytest.mark.parametrize("v5", [True, False], ids=["mqtt5", "mqtt311"])
def test_a_round_trip_and_one_write_per_loop_turn(broker: Broker, v5: bool) -> None:
    async def run() -> None:
        link = await open_link("127.0.0.1", broker.port, "t-round-trip", v5=v5)
        got: list[Publish] = []
        fifty = asyncio.Event()
        link.on_message = lambda message: (got.append(message), len(got) == 50 and fifty.set())
        await link.subscribe("t/+", qos=1)
        writes: list[bytes] = []
        transport = link._transport
        assert transport is not None
        real_write = transport.write
        transport.write = lambda data: (writes.append(bytes(data)), real_write(data))  # type: ignore[method-assign]
        for i in range(49):
            link.publish(f"t/{i}", str(i).encode(), correlation=b"c" if v5 else None)
        await link.publish_acked("t/last", b"end", qos=1)
        assert [kind for kind, _f, _b in PacketReader().feed(writes[0])] == [3] * 50  # fifty PUBLISH, one write
        await asyncio.wait_for(fifty.wait(), 10)
        assert [m.payload for m in got] == [str(i).encode() for i in range(49)] + [b"end"]
        assert got[0].correlation == (b"c" if v5 else None)
        await link.disconnect()
        with pytest.raises(LinkLost):
            link.publish("t/x", b"")

    asyncio.run(run())


def test_a_dropped_link_leaves_its_will_and_a_stopped_broker_ends_the_link(broker: Broker) -> None:
    async def run() -> None:
        watcher = await open_link("127.0.0.1", broker.port, "t-watcher")
        wills: asyncio.Queue[bytes] = asyncio.Queue()
        watcher.on_message = lambda message: wills.put_nowait(message.payload)
        await watcher.subscribe("t/status", qos=1)
        holder = await open_link("127.0.0.1", broker.port, "t-holder",
                                 will=Will("t/status", b"offline", qos=1, retain=False, expiry=60))
        holder.abort()  # no DISCONNECT: the broker sends the will
        assert await asyncio.wait_for(wills.get(), 10) == b"offline"
        broker.stop()
        with pytest.raises(LinkLost):
            await asyncio.wait_for(watcher.closed, 10)

    asyncio.run(run())


def test_an_idle_link_keeps_alive(broker: Broker) -> None:
    async def run() -> None:
        link = await open_link("127.0.0.1", broker.port, "t-idle", keepalive=1, v5=False)
        # mosquitto drops a client silent for 1.5 keep-alive intervals; the link's pings prevent it
        with pytest.raises(TimeoutError):
            await asyncio.wait_for(asyncio.shield(link.closed), 4)  # idle for four intervals
        await link.publish_acked("t/still", b"here", qos=1)
        await link.disconnect()

    asyncio.run(run())


def test_a_routed_topic_hands_plain_payloads_to_its_handler_and_the_rest_to_on_message(broker: Broker) -> None:
    async def run() -> None:
        sender = await open_link("127.0.0.1", broker.port, "t-sender")
        await sender.publish_acked("t/req", b"kept", qos=1, retain=True)
        taker = await open_link("127.0.0.1", broker.port, "t-taker")
        routed: list[bytes] = []
        messages: list[Publish] = []
        done = asyncio.Event()
        taker.route("t/req", routed.append)
        taker.on_message = lambda message: (messages.append(message), message.topic == "t/end" and done.set())
        await taker.subscribe("t/#", qos=1)
        sender.publish("t/req", b"plain")
        sender.publish("t/req", b"with correlation", correlation=b"c1")
        sender.publish("t/req", b"at qos 1", qos=1)
        sender.publish("t/reqs", b"another topic")
        sender.publish("t/req", b"")
        sender.publish("t/end", b"")
        await asyncio.wait_for(done.wait(), 10)
        assert routed == [b"plain", b""]
        assert [(m.topic, m.payload, m.retain, m.qos, m.correlation) for m in messages] == [
            ("t/req", b"kept", True, 1, None), ("t/req", b"with correlation", False, 0, b"c1"),
            ("t/req", b"at qos 1", False, 1, None), ("t/reqs", b"another topic", False, 0, None),
            ("t/end", b"", False, 0, None)]
        taker.publish_headed(taker.head("t/end"), b"headed")  # a PUBLISH on a head arrives as the plain one
        done.clear()
        await asyncio.wait_for(done.wait(), 10)
        assert (messages[-1].topic, messages[-1].payload) == ("t/end", b"headed")
        await sender.publish_acked("t/req", b"", qos=1, retain=True)
        await taker.disconnect()
        await sender.disconnect()

    asyncio.run(run())
