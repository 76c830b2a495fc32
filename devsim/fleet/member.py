"""A devsim process as a fleet member: its devices announced on the broker, control-API requests
taken from it (``devsim run/up --fleet URL``).

:func:`join_fleet` (awaited in the runtime's loop) connects to the broker (one MQTT 5 connection
per process, :mod:`devsim.facades.mqtt_link`) and

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
connection is retried (after 0.5 s, 1 s, 2 s, then every 5 s) and the announcement renewed.  On
rejoining, the member checks the names again as in 1.: while it was away (frozen, asleep, cut
off) its last will marked it offline and another process may have joined serving one of its
names.  Its watch streams end then unless its announcement is still there, online: its last
will told every watcher they ended, and a watch that goes on asks again
(:meth:`~devsim.fleet.streams.StreamServer.ended_by_will`).  Such a name is *withdrawn*: left out of its announcement (and its last will) for the rest
of its run, said in one line on stderr; its ports keep serving here, outside the fleet (a
request for it that reaches the member anyway is refused, ``FleetClash``; the fast path of
:mod:`devsim.fleet.answers` is left out while a name is withdrawn).

A request costs the member its own work and little else: it is handed over in the step that read
it (no queue, no task, no record when it has no MQTT 5 properties), parsed once with msgspec, and
its answer joins the others of the same read in one write to the broker.  A read or a set of a
point resolved before is answered straight from the point (:mod:`devsim.fleet.answers`).
"""

from __future__ import annotations

import asyncio
import contextlib
import functools
import json
import os
import socket
import time
from typing import Any

import msgspec

from devsim.core.clock import VirtualClock
from devsim.core.console import warn
from devsim.facades.mqtt_link import LinkLost, MqttLink, open_link
from devsim.facades.mqtt_wire import Publish, Will, publish_head
from devsim.fleet.answers import ResolvedRequests, encode_answer
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
KEEPALIVE = 15  # seconds (MQTT keep alive)
_json_decode = msgspec.json.Decoder().decode
_json_encode = msgspec.json.Encoder().encode


class FleetClash(RuntimeError):
    """A device name this process would serve is served by another online process."""


async def connect(url: FleetUrl, identifier: str, will: Will | None = None) -> MqttLink:
    """A connection to the fleet's broker (MQTT 5); ConnectionError when it cannot be reached."""
    return await open_link(url.host, url.port, identifier, keepalive=KEEPALIVE, will=will, username=url.username,
                           password=url.password, timeout=SYNC_TIMEOUT)


async def retained_announcements(link: MqttLink, topics: Topics, marker: str) -> dict[str, dict[str, Any]]:
    """Subscribe to every announcement and collect the retained ones: after them the broker
    delivers ``marker``, published by us once subscribed (messages on one connection keep their
    order).  Returns process → announcement."""
    found: dict[str, dict[str, Any]] = {}
    synced: asyncio.Future[None] = asyncio.get_running_loop().create_future()

    def collect(message: Publish) -> None:
        if message.topic == marker:
            if not synced.done():
                synced.set_result(None)
            return
        process = topics.process_of(message.topic)
        announcement = parse_announcement(message.payload)
        if process is not None and announcement is not None:
            found[process] = announcement

    link.on_message = collect
    await link.subscribe(topics.announcements, qos=1)
    await link.subscribe(marker, qos=0)
    link.publish(marker, b"sync")
    try:
        await asyncio.wait_for(asyncio.shield(synced), SYNC_TIMEOUT)
    finally:
        link.on_message = lambda message: None
    return found


def _lenient(raw: bytes) -> Any:
    """What :mod:`json` makes of what msgspec refused (``NaN``, deep nesting), else ``raw``: the
    control API then says what is wrong with it."""
    try:
        return json.loads(raw)
    except (ValueError, RecursionError):
        return raw


def parse_announcement(payload: Any) -> dict[str, Any] | None:
    """An announcement's JSON object, or None (an empty payload: the process left)."""
    if not isinstance(payload, bytes | bytearray) or not payload:
        return None
    try:
        data = _json_decode(payload)
    except (msgspec.DecodeError, RecursionError):
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
        self._link: MqttLink | None = None
        self._task: asyncio.Task[None] | None = None
        self._closing = False
        self._replies: dict[str, bytes] = {}  # reply topics found allowed -> the head of a PUBLISH on each
        self.streams = StreamServer(runtime, self.topics, self.process)
        self._request_topic = self.topics.request(self.process)  # compared with every message's topic
        self.resolved = ResolvedRequests(runtime)  #: the fast path of reads and sets
        self.withdrawn: dict[str, str] = {}  #: names served by another process when we rejoined -> by whom

    @property
    def request_topic(self) -> str:
        return self._request_topic

    def devices(self) -> list[dict[str, Any]]:
        """The ``devices`` rows this process announces: every device but the withdrawn ones."""
        return [row for row in ops.run(self.runtime, Devices()) if row["name"] not in self.withdrawn]

    def announcement(self, online: bool = True) -> dict[str, Any]:
        devices = self.devices()
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

    def _will(self) -> Will:
        return Will(self.topics.announcement(self.process), _json_encode(self.announcement(False)),
                    qos=1, retain=True, expiry=OFFLINE_EXPIRY)

    async def start(self) -> None:
        """Connect, check the names, subscribe, announce; then serve in a task."""
        try:
            link = await connect(self.url, f"devsim-{self.process}", self._will())
        except LinkLost as exc:
            raise ConnectionError(f"cannot reach the fleet broker {self.url}: {exc}") from None
        try:
            taken = self._taken(await self._others(link))
            if taken:
                name, served = next(iter(taken.items()))
                raise FleetClash(f"device {name!r} is already in the fleet {self.url}, served by {served};"
                                 " device names are unique across a fleet")
            await self._announce(link)
        except BaseException:
            with contextlib.suppress(Exception):
                await link.disconnect()
            raise
        self._link = link
        self._task = asyncio.ensure_future(self._run(link))

    async def _others(self, link: MqttLink) -> dict[str, dict[str, Any]]:
        """The retained announcements (process -> announcement; ours among them, if any)."""
        others = await retained_announcements(link, self.topics, self.topics.sync(f"member-{self.process}"))
        await link.unsubscribe(self.topics.announcements)
        return others

    def _taken(self, others: dict[str, dict[str, Any]]) -> dict[str, str]:
        """Which of the names we announce another *online* process serves (by the retained
        announcements ``others``; offline marks do not count): name -> ``PROCESS (host H, pid P)``,
        sorted."""
        mine = {row["name"] for row in self.devices()}
        taken: dict[str, str] = {}
        for process, announcement in sorted(others.items()):
            if process == self.process or not announcement.get("online"):
                continue
            for name in sorted(mine & {str(row.get("name")) for row in announcement["devices"]}):
                taken.setdefault(name, f"{process} (host {announcement.get('host')}, pid {announcement.get('pid')})")
        return dict(sorted(taken.items()))

    async def _announce(self, link: MqttLink) -> None:
        link.on_message = functools.partial(self._received, link)
        link.route(self.request_topic, functools.partial(self._requested, link))
        await link.subscribe(self.request_topic, qos=0)
        await self.streams.subscribe(link)
        await link.publish_acked(self.topics.announcement(self.process), _json_encode(self.announcement(True)),
                                 qos=1, retain=True)

    async def _run(self, link: MqttLink) -> None:
        while not self._closing:
            pump = asyncio.ensure_future(self.streams.pump(link))
            try:
                await asyncio.wait([link.closed])  # not `await link.closed`: cancelling us would cancel it
            finally:
                pump.cancel()
            if self._closing:
                return
            why = link.closed.exception() if not link.closed.cancelled() else None
            warn(f"devsim: fleet broker {self.url} lost ({why}); reconnecting")
            self._link = None
            link = await self._reconnect()
            self._link = link

    async def _reconnect(self) -> MqttLink:
        attempt = 0
        while True:
            await asyncio.sleep(RECONNECT_DELAYS[min(attempt, len(RECONNECT_DELAYS) - 1)])  # retry pacing
            attempt += 1
            try:
                link = await connect(self.url, f"devsim-{self.process}", self._will())
            except LinkLost:
                continue
            try:
                others = await self._others(link)
                taken = self._taken(others)  # the name check of joining, again
                self.withdrawn.update(taken)
                if not others.get(self.process, {}).get("online"):  # our will went out (or the broker is new)
                    self.streams.ended_by_will()
                await self._announce(link)
            except (LinkLost, TimeoutError):
                await link.disconnect()
                continue
            warn(f"devsim: fleet broker {self.url} back; announced again" + (_withdrawal(taken) if taken else ""))
            return link

    def _received(self, link: MqttLink, message: Publish) -> None:
        """A message from the broker, in the step that read it: a request is answered into the
        link's write of this loop turn."""
        if message.topic != self._request_topic:
            self.streams.handle(message.topic, message.payload)
            return
        self._answer_into(link, message.payload, message.response_topic, message.correlation)

    def _requested(self, link: MqttLink, payload: bytes) -> None:
        """A request without MQTT 5 properties, which the link hands over straight from its read
        (the common case): a read or a set resolved before is answered here in as few steps as
        it takes, as :meth:`answer` answers it; anything else goes the way of :meth:`answer`
        (which tries the resolved requests again: a request they declined costs more anyway)."""
        fast = self.resolved.answer(payload) if len(payload) <= MAX_LINE and not self.withdrawn else None
        if fast is None:
            self._answer_into(link, payload, None, None)
            return
        self.served += 1
        reply_to, body = fast
        head = self._replies.get(reply_to) if type(reply_to) is str else None
        if head is None:
            if not self._reply_allowed(reply_to):  # (no reply topic, or one not allowed: no answer)
                return
            head = self._replies[reply_to]
        try:
            link.publish_headed(head, body)
        except LinkLost:  # a lost connection shows in the serving loop
            pass

    def _answer_into(self, link: MqttLink, payload: bytes, reply_to: str | None,
                     correlation: bytes | None) -> None:
        """A request answered by :meth:`answer` into the link's write of this loop turn."""
        answer = self.answer(payload, reply_to, correlation)
        if answer is not None:
            topic, body, correlation = answer
            try:
                if correlation is None:
                    link.publish_headed(self._replies[topic], body)
                else:
                    link.publish(topic, body, 0, False, correlation)
            except LinkLost:  # a lost connection shows in the serving loop
                pass

    def answer(self, payload: Any, reply_to: str | None = None,
               correlation: bytes | None = None) -> tuple[str, bytes, bytes | None] | None:
        """Execute one request; returns (reply topic, answer, MQTT 5 correlation data) or None
        when the request names no usable reply topic (``reply_to``, ``correlation``: the MQTT 5
        response topic and correlation data it came with; a ``"reply_to"`` in the JSON wins)."""
        self.served += 1
        raw = payload if type(payload) is bytes else (
            bytes(payload) if isinstance(payload, (bytes, bytearray)) else str(payload or "").encode())
        response: OkResponse | ErrorResponse
        stream_to = None
        if len(raw) > MAX_LINE:
            response = ErrorResponse(error="request too long", type="BadRequest")
        elif not self.withdrawn and (fast := self.resolved.answer(raw)) is not None:  # resolved before
            asked_reply, body = fast
            if asked_reply is not msgspec.UNSET:
                reply_to = asked_reply
            if self._reply_allowed(reply_to):
                return reply_to, body, correlation
            return None
        else:
            try:
                data: Any = _json_decode(raw)
            except (msgspec.DecodeError, RecursionError):
                data = _lenient(raw)
            if isinstance(data, dict):
                reply_to = data.pop("reply_to", reply_to)
                stream_to = data.pop("stream_to", None)
            if isinstance(data, dict) and isinstance(data.get("device"), str) and data["device"] in self.withdrawn:
                response = self._withdrawn(data)
            else:
                response = (ops.answer_parsed(self.runtime, data) if isinstance(data, dict)
                            else ops.answer(self.runtime, raw))
            if isinstance(response, OkResponse) and isinstance(response.result, WatchStart):
                response = self.streams.start(response.result, response.id, stream_to)
        if not self._reply_allowed(reply_to):
            return None
        return str(reply_to), encode_answer(response), correlation

    def _withdrawn(self, request: dict[str, Any]) -> ErrorResponse:
        """The answer to a request over the broker for a device this process withdrew."""
        name, req_id = request["device"], request.get("id")
        return ErrorResponse(id=req_id if isinstance(req_id, int | str) else None, type="FleetClash", error=(
            f"device {name!r} of {self.process} is out of the fleet: {self.withdrawn[name]} served it"
            " when this process rejoined (its ports serve on, outside the fleet)"))

    def _reply_allowed(self, topic: Any) -> bool:
        if type(topic) is not str:  # (a list or an object from the JSON: no topic, and no set member)
            return False
        if topic in self._replies:  # one reply topic per client, asked again and again
            return True
        allowed = (topic.startswith(f"{self.topics.root}/client/")
                   and not any(c in topic for c in "+#\x00") and len(topic) < 1024)
        if allowed:
            if len(self._replies) >= 1024:
                self._replies.clear()
            self._replies[topic] = publish_head(topic)  # (the member speaks MQTT 5)
        return allowed

    async def close(self) -> None:
        """Leave: clear the retained announcement, disconnect (no last will on a clean stop)."""
        self._closing = True
        self.streams.close()
        if self._task is not None:
            self._task.cancel()
            with contextlib.suppress(BaseException):
                await self._task
        link, self._link = self._link, None
        if link is not None:
            with contextlib.suppress(Exception):
                await link.publish_acked(self.topics.announcement(self.process), b"", qos=1, retain=True, timeout=5)
            with contextlib.suppress(Exception):
                await link.disconnect()


def _withdrawal(taken: dict[str, str]) -> str:
    """The rest of the rejoining line when names were withdrawn."""
    names = ", ".join(repr(name) for name in taken)
    whom = (next(iter(taken.values())) if len(taken) == 1
            else "other processes (" + "; ".join(f"{name!r} by {served}" for name, served in taken.items()) + ")")
    return (f" without {names}: served meanwhile by {whom} (device names are unique across a fleet; the ports"
            " keep serving here, outside the fleet)")


async def join_fleet(runtime: Runtime, url: str | FleetUrl, *, about: dict[str, Any] | None = None) -> FleetMember:
    """Join the fleet at ``url`` with every device of ``runtime`` (in the runtime's loop); the
    membership ends when the runtime closes.  Raises :class:`FleetClash` or ConnectionError."""
    member = FleetMember(runtime, parse_fleet_url(url) if isinstance(url, str) else url, about=about)
    await member.start()
    runtime.add_closer(member.close)
    return member
