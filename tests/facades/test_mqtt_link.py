"""devsim's own MQTT client (devsim.facades.mqtt_link) against a real mosquitto: a round trip in
MQTT 5 and 3.1.1, everything published in one loop turn in one write, a will sent when the
connection is dropped, and the end of the link when the broker goes away."""

from __future__ import annotations

import asyncio
import contextlib
import os
import signal
from collections.abc import Iterator

import pytest

from devsim.facades.mqtt_link import PAUSED_LIMIT, READ_SIZE, LinkLost, MqttLink, open_link
from devsim.facades.mqtt_wire import PacketReader, Publish, Will
from tests.support.broker import Broker


class _Recording:
    """A socket whose sends are recorded (the link writes with ``send``)."""

    def __init__(self, sock: object, writes: list[bytes]) -> None:
        self._sock = sock
        self._writes = writes

    def send(self, data: bytes) -> int:
        self._writes.append(bytes(data))
        return self._sock.send(data)  # type: ignore[attr-defined, no-any-return]

    def __getattr__(self, name: str) -> object:
        return getattr(self._sock, name)


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
        link._sock = _Recording(link._sock, writes)  # type: ignore[assignment]
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
        assert not asyncio.get_running_loop()._scheduled  # type: ignore[attr-defined]  (its pings: no timer in the loop)
        # mosquitto drops a client silent for 1.5 keep-alive intervals; the link's pings prevent it
        with pytest.raises(TimeoutError):
            await asyncio.wait_for(asyncio.shield(link.closed), 4)  # idle for four intervals
        await link.publish_acked("t/still", b"here", qos=1)
        await link.disconnect()

    asyncio.run(run())


def test_a_silent_broker_ends_the_link_after_one_and_a_half_keep_alive_intervals(broker: Broker) -> None:
    async def run() -> None:
        link = await open_link("127.0.0.1", broker.port, "t-silent", keepalive=1)
        with _stopped(broker):  # it answers no PINGREQ
            with pytest.raises(LinkLost, match="silent for 1.5 s"):
                await asyncio.wait_for(link.closed, 10)
        assert link._sock is None

    asyncio.run(run())


def test_a_handler_that_fails_ends_the_link_and_its_error_reaches_the_loop(broker: Broker) -> None:
    async def run() -> None:
        loop = asyncio.get_running_loop()
        reported: list[BaseException | None] = []
        loop.set_exception_handler(lambda _loop, context: reported.append(context.get("exception")))
        link = await open_link("127.0.0.1", broker.port, "t-failing")
        link.route("t/req", lambda payload: 1 / 0)  # type: ignore[func-returns-value]
        await link.subscribe("t/req")
        link.publish("t/req", b"x")
        with pytest.raises(LinkLost, match="ZeroDivisionError"):
            await asyncio.wait_for(link.closed, 10)
        assert [type(exc) for exc in reported] == [ZeroDivisionError]
        assert link._sock is None

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


def _stopped(broker: Broker) -> contextlib.AbstractContextManager[None]:
    """mosquitto stopped (SIGSTOP) inside the block: it reads nothing, and the link's socket fills."""
    assert broker.process is not None
    pid = broker.process.pid

    @contextlib.contextmanager
    def stopped() -> Iterator[None]:
        os.kill(pid, signal.SIGSTOP)
        try:
            yield
        finally:
            os.kill(pid, signal.SIGCONT)

    return stopped()


def _fill(link: MqttLink, topic: str, chunk: int = 64 * 1024) -> list[bytes]:
    """Publish distinct payloads of ``chunk`` bytes, each flushed, until more than PAUSED_LIMIT
    bytes wait unsent (the broker reads nothing); the payloads, in order."""
    sent: list[bytes] = []
    while link._paused is None:
        assert len(sent) < 4096, "the socket never filled"
        sent.append(len(sent).to_bytes(4, "big") * (chunk // 4))
        link.publish(topic, sent[-1])
        link.flush()
    return sent


def test_what_a_full_socket_does_not_take_waits_in_order_and_drain_waits_for_it(broker: Broker) -> None:
    async def run() -> None:
        receiver = await open_link("127.0.0.1", broker.port, "t-receiver")
        got: list[bytes] = []
        done = asyncio.Event()
        receiver.on_message = lambda message: (got.append(message.payload), message.topic == "t/end" and done.set())
        await receiver.subscribe("t/#")
        sender = await open_link("127.0.0.1", broker.port, "t-sender")
        with _stopped(broker):
            sent = _fill(sender, "t/bulk")
            assert len(sender._unsent) > PAUSED_LIMIT  # the socket took what it could, the rest waits
            sender.publish("t/end", b"last")  # behind what waits
            drained = asyncio.ensure_future(sender.drain())
            await asyncio.sleep(0)  # (one loop turn: drain is waiting, the broker takes nothing)
            assert not drained.done()
        await asyncio.wait_for(drained, 30)
        await asyncio.wait_for(done.wait(), 30)
        assert got == [*sent, b"last"]  # every byte, in order
        assert not sender._unsent
        await sender.disconnect()
        await receiver.disconnect()

    asyncio.run(run())


def test_a_link_lost_while_bytes_wait_ends_and_its_drain_raises(broker: Broker) -> None:
    async def run() -> None:
        sender = await open_link("127.0.0.1", broker.port, "t-sender")
        assert broker.process is not None
        os.kill(broker.process.pid, signal.SIGSTOP)  # it reads nothing: the link's socket fills
        try:
            _fill(sender, "t/bulk")
            drained = asyncio.ensure_future(sender.drain())
        finally:
            broker.process.kill()  # (a stopped process dies of SIGKILL: its connections are reset)
            broker.process.wait(10)
        with pytest.raises(LinkLost):
            await asyncio.wait_for(drained, 10)
        with pytest.raises(LinkLost):
            await asyncio.wait_for(sender.closed, 10)
        assert sender._sock is None  # closed, its reader and writer gone

    asyncio.run(run())


def test_a_packet_split_across_reads_arrives_whole_through_a_shared_read_buffer(broker: Broker) -> None:
    async def run() -> None:
        receiver = await open_link("127.0.0.1", broker.port, "t-receiver")
        routed: list[bytes] = []
        got: list[bytes] = []
        done = asyncio.Event()
        receiver.route("t/req", routed.append)
        receiver.on_message = lambda message: (got.append(message.payload), done.set())
        await receiver.subscribe("t/#")
        sender = await open_link("127.0.0.1", broker.port, "t-sender")
        big = bytes(range(256)) * (5 * READ_SIZE // 256 + 7)  # five reads and a bit
        for index in range(300):  # small ones, many per read, some cut at a read's end
            sender.publish("t/req", b"%d" % index)
        sender.publish("t/req", big)
        sender.publish("t/end", big[::-1])
        await asyncio.wait_for(done.wait(), 30)
        assert routed == [b"%d" % index for index in range(300)] + [big]
        assert got == [big[::-1]]
        assert receiver._view is sender._view  # (the links of a loop share one read buffer)
        await sender.disconnect()
        await receiver.disconnect()

    asyncio.run(run())


class _Relay:
    """A TCP relay between a link and mosquitto that can cut the connection in the middle of
    what the broker sends next (:meth:`cut_after`)."""

    def __init__(self, broker_port: int) -> None:
        self.broker_port = broker_port
        self.cut: int | None = None  # bytes from the broker still passed on before the cut
        self.tasks: list[asyncio.Task[None]] = []

    async def start(self) -> int:
        self.server = await asyncio.start_server(self._serve, "127.0.0.1", 0)
        return int(self.server.sockets[0].getsockname()[1])

    def cut_after(self, count: int) -> None:
        self.cut = count

    async def _serve(self, client_reader: asyncio.StreamReader, client_writer: asyncio.StreamWriter) -> None:
        broker_reader, broker_writer = await asyncio.open_connection("127.0.0.1", self.broker_port)

        async def up() -> None:
            while data := await client_reader.read(65536):
                broker_writer.write(data)

        async def down() -> None:
            while data := await broker_reader.read(65536):
                if self.cut is not None:
                    data = data[:self.cut]
                    self.cut -= len(data)
                client_writer.write(data)
                await client_writer.drain()
                if self.cut == 0:
                    break

        self.tasks = [asyncio.ensure_future(up()), asyncio.ensure_future(down())]
        await asyncio.wait(self.tasks, return_when=asyncio.FIRST_COMPLETED)
        for task in self.tasks:
            task.cancel()
        client_writer.close()
        broker_writer.close()

    async def close(self) -> None:
        for task in self.tasks:
            task.cancel()
        self.server.close()
        await self.server.wait_closed()


def test_a_connection_lost_in_the_middle_of_a_packet_ends_the_link_and_delivers_nothing(broker: Broker) -> None:
    async def run() -> None:
        relay = _Relay(broker.port)
        port = await relay.start()
        receiver = await open_link("127.0.0.1", port, "t-receiver")
        got: list[Publish] = []
        receiver.on_message = got.append
        await receiver.subscribe("t/#")
        sender = await open_link("127.0.0.1", broker.port, "t-sender")
        relay.cut_after(1000)  # of a PUBLISH of 200 KB: its head and a part of its payload
        sender.publish("t/big", bytes(200_000))
        with pytest.raises(LinkLost, match="lost"):
            await asyncio.wait_for(receiver.closed, 10)
        assert got == []
        assert receiver._sock is None
        with pytest.raises(LinkLost):
            receiver.publish("t/x", b"")
        await sender.disconnect()
        await relay.close()

    asyncio.run(run())
