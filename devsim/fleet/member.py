"""A devsim process as a fleet member: its devices announced on the broker, control-API requests
taken from it (``devsim run/up --fleet URL``).

:func:`join_fleet` (awaited in the runtime's loop) connects to the broker with aiomqtt and

1. reads every retained announcement and refuses to join when a device name is already served
   by another *online* process (:class:`FleetClash`; offline marks do not count);
2. subscribes to its request topic, then publishes its announcement (retained, QoS 1): process
   id, host, pid, clock, the plant and part it serves, and its devices as the control API's
   ``devices`` op lists them (name, kind, ports).  Its last will is the same announcement with
   ``"online": false`` (retained; MQTT 5 message expiry of 24 h, so a crashed process's mark
   does not stay for ever);
3. answers each request with :func:`devsim.runtime.ops.answer` – the very code of the control
   API (its op table), so ops, validation and error types are the same; a ``watch`` request
   starts a stream published on the broker (:mod:`devsim.fleet.streams`).

A request is the control API's JSON request plus ``"reply_to"``: the topic for the answer, which
must lie under ``ROOT/client/`` (a member publishes nothing outside its own topics and the
clients' reply topics).  An MQTT 5 *response topic* property is honoured too (and its
*correlation data* echoed); the JSON field wins, and it is what devsim's own client sends,
because it survives bridges that speak MQTT 3.1.1.  The ``id`` of the request is the correlation
id: the answer carries it back.  A request without a reply topic is executed and not answered.

A clean stop clears the retained announcement (the process leaves the listing); a lost broker
connection is retried (after 0.5 s, 1 s, 2 s, then every 5 s) and the announcement renewed.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import logging
import os
import socket
import sys
import time
from typing import Any

import aiomqtt
from paho.mqtt.packettypes import PacketTypes
from paho.mqtt.properties import Properties

from devsim.core.clock import VirtualClock
from devsim.fleet.streams import StreamServer
from devsim.fleet.topics import FleetUrl, Topics, parse_fleet_url, process_id
from devsim.runtime import Runtime, ops
from devsim.runtime.control import MAX_LINE
from devsim.runtime.ops import ErrorResponse, OkResponse, WatchStart
from devsim.runtime.requests import Devices

__all__ = ["FleetClash", "FleetMember", "join_fleet"]

OFFLINE_EXPIRY = 24 * 3600  # seconds a crashed process's offline mark stays retained (MQTT 5)
RECONNECT_DELAYS = (0.5, 1.0, 2.0, 5.0)  # seconds between attempts after the broker went away (then 5 s)
SYNC_TIMEOUT = 10.0  # seconds to wait for the broker to hand over the retained announcements
# aiomqtt warns on every publish beyond ten in flight; under load that is a line per request
_LOG = logging.getLogger("devsim.fleet.mqtt")
_LOG.setLevel(logging.ERROR)


class FleetClash(RuntimeError):
    """A device name this process would serve is served by another online process."""


def mqtt_client(url: FleetUrl, identifier: str, will: aiomqtt.Will | None = None) -> aiomqtt.Client:
    """An aiomqtt client (MQTT 5) for the fleet's broker."""
    return aiomqtt.Client(
        url.host,
        url.port,
        identifier=identifier,
        username=url.username,
        password=url.password,
        protocol=aiomqtt.ProtocolVersion.V5,
        will=will,
        timeout=SYNC_TIMEOUT,
        keepalive=15,
        logger=_LOG,
        socket_options=[(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)],  # requests are small and waited for
    )


async def retained_announcements(client: aiomqtt.Client, topics: Topics, marker: str) -> dict[str, dict[str, Any]]:
    """Subscribe to every announcement and collect the retained ones: after them the broker
    delivers ``marker``, published by us once subscribed (messages on one connection keep their
    order).  Returns process → announcement."""
    await client.subscribe(topics.announcements, qos=1)
    await client.subscribe(marker, qos=0)
    await client.publish(marker, b"sync", qos=0)
    found: dict[str, dict[str, Any]] = {}

    async def collect() -> None:
        async for message in client.messages:
            topic = message.topic.value
            if topic == marker:
                return
            process = topics.process_of(topic)
            announcement = parse_announcement(message.payload)
            if process is not None and announcement is not None:
                found[process] = announcement

    await asyncio.wait_for(collect(), SYNC_TIMEOUT)
    return found


def parse_announcement(payload: Any) -> dict[str, Any] | None:
    """An announcement's JSON object, or None (an empty payload: the process left)."""
    if not isinstance(payload, bytes | bytearray) or not payload:
        return None
    try:
        data = json.loads(payload)
    except (ValueError, RecursionError):
        return None
    return data if isinstance(data, dict) and isinstance(data.get("devices"), list) else None


class FleetMember:
    """One process's membership: see the module docstring.  Runs in the runtime's loop."""

    def __init__(self, runtime: Runtime, url: FleetUrl, *, about: dict[str, Any] | None = None,
                 process: str | None = None) -> None:
        self.runtime = runtime
        self.url = url
        self.topics = Topics(url.root)
        self.process = process or process_id()
        self.about = dict(about or {})
        self.since = time.time()
        self.served = 0
        self._client: aiomqtt.Client | None = None
        self._task: asyncio.Task[None] | None = None
        self._sending: set[asyncio.Task[None]] = set()
        self._closing = False
        self.streams = StreamServer(runtime, self.topics, self.process)

    @property
    def request_topic(self) -> str:
        return self.topics.request(self.process)

    def announcement(self, online: bool = True) -> dict[str, Any]:
        devices = ops.run(self.runtime, Devices())
        return {
            "process": self.process,
            "host": socket.gethostname(),
            "pid": os.getpid(),
            "online": online,
            "since": round(self.since, 3),
            "clock": "virtual" if isinstance(self.runtime.clock, VirtualClock) else "real",
            **self.about,
            "request": self.request_topic,
            "devices": devices,
        }

    def _will(self) -> aiomqtt.Will:
        properties = Properties(PacketTypes.WILLMESSAGE)
        properties.MessageExpiryInterval = OFFLINE_EXPIRY
        return aiomqtt.Will(self.topics.announcement(self.process), json.dumps(self.announcement(False)),
                            qos=1, retain=True, properties=properties)

    async def start(self) -> None:
        """Connect, check the names, subscribe, announce; then serve in a task."""
        client = mqtt_client(self.url, f"devsim-{self.process}", self._will())
        try:
            await client.__aenter__()
        except aiomqtt.MqttError as exc:
            raise ConnectionError(f"cannot reach the fleet broker {self.url}: {exc}") from None
        try:
            others = await retained_announcements(client, self.topics, self.topics.sync(f"member-{self.process}"))
            self._refuse_clashes(others)
            await client.unsubscribe(self.topics.announcements)
            await self._announce(client)
        except BaseException:
            with contextlib.suppress(Exception):
                await client.__aexit__(None, None, None)
            raise
        self._client = client
        self._task = asyncio.ensure_future(self._run(client))

    def _refuse_clashes(self, others: dict[str, dict[str, Any]]) -> None:
        mine = {row["name"] for row in ops.run(self.runtime, Devices())}
        for process, announcement in sorted(others.items()):
            if process == self.process or not announcement.get("online"):
                continue
            taken = sorted(mine & {str(row.get("name")) for row in announcement["devices"]})
            if taken:
                raise FleetClash(
                    f"device {taken[0]!r} is already in the fleet {self.url}, served by {process}"
                    f" (host {announcement.get('host')}, pid {announcement.get('pid')}); device names"
                    " are unique across a fleet"
                )

    async def _announce(self, client: aiomqtt.Client) -> None:
        await client.subscribe(self.request_topic, qos=0)
        await self.streams.subscribe(client)
        await client.publish(self.topics.announcement(self.process), json.dumps(self.announcement(True)),
                             qos=1, retain=True)

    async def _run(self, client: aiomqtt.Client) -> None:
        while not self._closing:
            try:
                await self._serve(client)
            except aiomqtt.MqttError as exc:
                if self._closing:
                    return
                print(f"devsim: fleet broker {self.url} lost ({exc}); reconnecting", file=sys.stderr, flush=True)
            self._client = None
            with contextlib.suppress(Exception):
                await client.__aexit__(None, None, None)
            client = await self._reconnect()
            self._client = client

    async def _reconnect(self) -> aiomqtt.Client:
        attempt = 0
        while True:
            await asyncio.sleep(RECONNECT_DELAYS[min(attempt, len(RECONNECT_DELAYS) - 1)])  # retry pacing
            attempt += 1
            client = mqtt_client(self.url, f"devsim-{self.process}", self._will())
            try:
                await client.__aenter__()
                await self._announce(client)
            except aiomqtt.MqttError:
                with contextlib.suppress(Exception):
                    await client.__aexit__(None, None, None)
                continue
            print(f"devsim: fleet broker {self.url} back; announced again", file=sys.stderr, flush=True)
            return client

    async def _serve(self, client: aiomqtt.Client) -> None:
        pump = asyncio.ensure_future(self.streams.pump(client))
        try:
            async for message in client.messages:
                if message.topic.value != self.request_topic:
                    self.streams.handle(message.topic.value, message.payload)
                    continue
                answer = self.answer(message.payload, message.properties)
                if answer is not None:  # sent while the next request is handled (answers carry their id)
                    topic, payload, properties = answer
                    sending = asyncio.ensure_future(client.publish(topic, payload, qos=0, properties=properties))
                    self._sending.add(sending)
                    sending.add_done_callback(self._sent)
        finally:
            pump.cancel()

    def _sent(self, task: asyncio.Task[None]) -> None:
        self._sending.discard(task)
        if not task.cancelled():
            task.exception()  # a lost connection shows in the message loop; nothing to add here

    def answer(self, payload: Any, properties: Properties | None = None) -> tuple[str, bytes, Properties | None] | None:
        """Execute one request; returns (reply topic, answer, MQTT 5 properties) or None when
        the request names no usable reply topic."""
        self.served += 1
        raw = bytes(payload) if isinstance(payload, bytes | bytearray) else str(payload or "").encode()
        reply_to = getattr(properties, "ResponseTopic", None) if properties is not None else None
        correlation = getattr(properties, "CorrelationData", None) if properties is not None else None
        response: OkResponse | ErrorResponse
        stream_to = None
        if len(raw) > MAX_LINE:
            response = ErrorResponse(error="request too long", type="BadRequest")
        else:
            line: bytes | str = raw
            with contextlib.suppress(ValueError, RecursionError):
                data = json.loads(raw)
                if isinstance(data, dict) and ("reply_to" in data or "stream_to" in data):
                    reply_to = data.pop("reply_to", reply_to)
                    stream_to = data.pop("stream_to", None)
                    line = json.dumps(data)
            response = ops.answer(self.runtime, line)
            if isinstance(response, OkResponse) and isinstance(response.result, WatchStart):
                response = self.streams.start(response.result, response.id, stream_to)
        if not self._reply_allowed(reply_to):
            return None
        out: Properties | None = None
        if correlation is not None:
            out = Properties(PacketTypes.PUBLISH)
            out.CorrelationData = correlation
        return str(reply_to), ops.encode(response), out

    def _reply_allowed(self, topic: Any) -> bool:
        return (isinstance(topic, str) and topic.startswith(f"{self.topics.root}/client/")
                and not any(c in topic for c in "+#\x00") and len(topic) < 1024)

    async def close(self) -> None:
        """Leave: clear the retained announcement, disconnect (no last will on a clean stop)."""
        self._closing = True
        self.streams.close()
        if self._task is not None:
            self._task.cancel()
            with contextlib.suppress(BaseException):
                await self._task
        client, self._client = self._client, None
        if client is not None:
            with contextlib.suppress(Exception):
                await client.publish(self.topics.announcement(self.process), b"", qos=1, retain=True)
            with contextlib.suppress(Exception):
                await client.__aexit__(None, None, None)


async def join_fleet(runtime: Runtime, url: str | FleetUrl, *, about: dict[str, Any] | None = None) -> FleetMember:
    """Join the fleet at ``url`` with every device of ``runtime`` (in the runtime's loop); the
    membership ends when the runtime closes.  Raises :class:`FleetClash` or ConnectionError."""
    member = FleetMember(runtime, parse_fleet_url(url) if isinstance(url, str) else url, about=about)
    await member.start()
    runtime.add_closer(member.close)
    return member
