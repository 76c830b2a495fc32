"""The devices of a plant over MQTT (issue 14), MQTT 3.1.1 through devsim's own client
(:mod:`devsim.facades.mqtt_link`; the embedded broker needs the extra ``devsim-motion[mqtt]``).

Two conventions:

* ``devsim`` (default, topics in :mod:`devsim.facades.mqtt_topics`): each device has its own
  last will: ``devsim/<plant>/<device>/status`` is ``online`` while it is served and
  ``offline`` when it closes or its process dies (the broker sends the will).  A will belongs to
  a connection, so each device holds one idle connection for its will alone; everything else –
  births, states, commands, errors, the ``online`` – goes over the process's one shared
  connection, written once per loop turn (issue 31).  A retained ``birth`` lists its points; each readable point is
  published (retained JSON) on ``state/<name>`` when it changes; ``set/<name>``,
  ``fault/<kind>`` and ``power_cycle`` commands run the control ops of those names
  (:data:`devsim.runtime.ops.CONTROL`) and refusals are answered on ``error``.
* ``sparkplug`` (:mod:`devsim.facades.mqtt_sparkplug`): **one connection per plant process**,
  the plant being a Sparkplug edge node whose NDEATH will covers all its devices; with a
  ``primary_host`` its births wait for that Primary Host Application's online STATE
  (:mod:`devsim.facades.mqtt_sparkplug_host`).

Changes are found by :class:`devsim.core.watch.PointWatch`, which samples the points every
``rate`` seconds of device time (virtual time in tests), right after each command, and right
after each moment the model announces (a move's start and end, a fault, an input or output
switched: :mod:`devsim.facades.mqtt_events`), so that a move shorter than the rate is seen.  With no
broker URL, :func:`start_broker` runs an embedded amqtt broker in the same loop, on loopback.
Everything runs as tasks in the runtime's loop and calls device methods directly.  A lost
broker connection (the shared one or a will's) is retried every second with all of them: the
others are dropped without a goodbye, so that the broker sends their wills, and the births are
then sent again.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import os
import secrets
import socket
from collections.abc import Callable, Sequence
from typing import Any, Literal

from devsim.core.console import warn
from devsim.core.device import Device
from devsim.core.watch import PointWatch
from devsim.facades import mqtt_topics as topics
from devsim.facades.mqtt_events import SampleOnEvent
from devsim.facades.mqtt_link import LinkLost, MqttLink, open_link
from devsim.facades.mqtt_wire import Publish, Will
from devsim.runtime import Runtime
from devsim.runtime.ops import run

__all__ = ["Convention", "PlantLink", "check_options", "start_broker", "start_mqtt"]

Convention = Literal["devsim", "sparkplug"]
#: (topic, payload, qos, retain)
Message = tuple[str, bytes, int, bool]
RETRY = 1.0  # seconds between reconnection attempts (network time, not device time)
KEEPALIVE = 10  # seconds (MQTT keep alive)
SUBSCRIBER_BACKLOG = 1000  # messages waiting for a subscriber of the embedded broker: it is disconnected ([SIM-CHOICE])


class _DevsimDevice:
    """One device in the devsim convention: its will, births, watch and commands."""

    def __init__(self, runtime: Runtime, device: Device, plant: str, rate: float) -> None:
        self.runtime = runtime
        self.device = device
        self.route: str | None = device.name  # the commands it takes: devsim/<plant>/<route>/...
        self.plant = plant
        self.rate = rate
        self.base = topics.prefix(plant, device.name)
        self.send: Callable[[Message], None] = lambda message: None
        self.send_sample: Callable[[Callable[[], Message]], None] = lambda make: None  # (PlantLink's)
        self.end_session: Callable[[], None] = lambda: None  # (PlantLink's; the devsim convention never ends a session)
        self.watch: PointWatch | None = None
        self.events: SampleOnEvent | None = None

    def identifier(self) -> str:
        return f"devsim-{self.plant}-{self.device.name}-{os.getpid()}"

    def new_session(self) -> Message:
        return f"{self.base}/status", b"offline", 1, True

    def filters(self) -> list[str]:
        return topics.command_filters(self.plant, [self.device.name])

    def connected(self) -> None:
        self.send((f"{self.base}/birth", json.dumps(topics.birth(self.device, self.rate)).encode(), 1, True))
        self.stop()
        self.watch = PointWatch(self.device, self._changed, period=self.rate)
        self.watch.start()  # every readable value now, then what changes
        self.events = SampleOnEvent(self.device, self.watch.sample)
        self.events.start()
        self.send((f"{self.base}/status", b"online", 1, True))

    def _changed(self, changes: dict[str, Any]) -> None:
        for name, value in changes.items():
            self.send_sample(lambda name=name, value=value: (topics.state_topic(self.plant, self.device.name, name),
                                                             topics.encode(value), 0, True))

    def resample(self) -> None:
        """Every value again, as if none had been sent (samples were dropped: PlantLink)."""
        if self.watch is not None:
            self.watch.last = {}
            self.watch.sample()

    def handle(self, topic: str, payload: bytes) -> None:
        found = topics.parse_command(topic, self.plant)
        if found is None or found[0] != self.device.name:
            return
        _name, parse, arg = found
        try:
            run(self.runtime, parse(self.device, arg, payload))
        except Exception as exc:  # every refusal is answered, as the control API does
            self.send((f"{self.base}/error", topics.error_payload(topic, exc), 1, False))
        if self.watch is not None:  # the point just set at once (what follows from it at the next sample)
            just_set = parse is topics.COMMANDS["set"][0] and arg in self.watch.names
            self.watch.sample([arg] if just_set else None)

    def closing(self) -> list[Message]:
        return [(f"{self.base}/status", b"offline", 1, True)]

    def stop(self) -> None:
        if self.events is not None:
            self.events.stop()
            self.events = None
        if self.watch is not None:
            self.watch.stop()
            self.watch = None


class _SparkplugPlant:
    """The plant as one Sparkplug edge node with its devices.  With a Primary Host Application
    (``primary_host``, :mod:`devsim.facades.mqtt_sparkplug_host`) the node subscribes to its
    STATE and sends its births only once the host is online in this MQTT session; an offline
    STATE that counts ends the session (NDEATH, DISCONNECT) and a new one starts at once, which
    waits for the host again (Sparkplug 3.0 §5, tck-id-message-flow-edge-node-birth-publish-phid-wait,
    tck-id-message-flow-edge-node-birth-publish-phid-offline)."""

    def __init__(self, runtime: Runtime, devices: Sequence[Device], plant: str, rate: float,
                 primary_host: str | None = None) -> None:
        from devsim.facades.mqtt_sparkplug import SparkplugNode
        from devsim.facades.mqtt_sparkplug_host import PrimaryHost

        self.runtime = runtime
        self.devices = {device.name: device for device in devices}
        self.node = SparkplugNode(plant)
        self.plant = plant
        self.rate = rate
        self.route: str | None = None  # takes every message of its filters
        self.send: Callable[[Message], None] = lambda message: None
        self.send_sample: Callable[[Callable[[], Message]], None] = lambda make: None  # (PlantLink's)
        self.end_session: Callable[[], None] = lambda: None  # NDEATH, DISCONNECT, connect again (PlantLink's)
        self.watches: dict[str, PointWatch] = {}
        self.events: list[SampleOnEvent] = []
        self.host = PrimaryHost(primary_host) if primary_host is not None else None
        self.linked = False  # connected and subscribed in this MQTT session
        self.born = False  # the births of this session are out
        self.ended = 0  # the sessions it ended itself (its primary host offline)

    def identifier(self) -> str:
        """The MQTT client id; after a session the node ended itself, one of its own: the broker
        would take a new connection with the old id for the old one before it read the old one's
        DISCONNECT, and a takeover sends the will (a second NDEATH of the old bdSeq)."""
        return f"devsim-spb-{self.plant}-{os.getpid()}" + (f"-{self.ended}" if self.ended else "")

    def new_session(self) -> Message:
        self.linked = self.born = False
        if self.host is not None:
            self.host.new_session()
        topic, payload = self.node.new_session()
        return topic, payload, 1, False

    def filters(self) -> list[str]:
        return self.node.filters() + ([self.host.topic] if self.host is not None else [])

    def connected(self) -> None:
        self.stop()
        self.linked = True
        if self.host is None or self.host.online:  # (its retained STATE may have come with the subscriptions)
            self._births()

    def _births(self) -> None:
        self.born = True
        self.send((*self.node.node_birth(), 0, False))
        for device in self.devices.values():
            watch = PointWatch(device, lambda changes, d=device: self._changed(d, changes), period=self.rate)
            values = watch.values()
            self.send((*self.node.device_birth(device, values), 0, False))
            watch.last = values
            watch.start()  # nothing new yet: DDATA from the next change on
            self.watches[device.name] = watch
            events = SampleOnEvent(device, watch.sample)
            events.start()
            self.events.append(events)

    def _changed(self, device: Device, changes: dict[str, Any]) -> None:
        # (made only when sent: a DDATA takes the node's next sequence number, and a gap would be a lost message)
        self.send_sample(lambda: (*self.node.device_data(device, changes), 0, False))

    def resample(self) -> None:
        """Every metric of every device again in a DDATA (samples were dropped: PlantLink)."""
        for watch in self.watches.values():
            watch.last = {}
            watch.sample()

    def handle(self, topic: str, payload: bytes) -> None:
        """A DCMD or NCMD: a refusal (a payload that is not Sparkplug B, a metric the device
        refuses) goes to the device's ``…/error`` topic; the node's (NCMD, a device it does not
        have) to the plant's ``devsim/<plant>/error``."""
        from devsim.facades.mqtt_sparkplug import (
            REBIRTH,
            T,
            birth_datatype,
            command_request,
            command_value,
            decode_metrics,
        )

        if self.host is not None and topic == self.host.topic:
            self._host_state(payload)
            return
        try:
            name = self.node.command_target(topic)
        except ValueError:  # not a command topic of ours (amqtt hands out retained messages of others)
            return
        device = self.devices.get(name) if name is not None else None
        try:
            if not self.born:
                waits = f": it waits for primary host {self.host.host_id!r} to be online" if self.host else ""
                raise ValueError(f"node {self.plant!r} has not sent its births{waits}")
            if name is not None and device is None:
                raise KeyError(f"node {self.plant!r} has no device {name!r}")
            metrics = decode_metrics(payload)
            # an NCMD's Node Control/Rebirth is the NBIRTH's Boolean (read as one when it has no datatype)
            rebirth = device is None and any(command_value(m, T.Boolean) for m in metrics if m.name == REBIRTH)
        except (KeyError, ValueError) as exc:
            self._refused(device, topic, exc)
            return
        if device is None:
            if rebirth:
                self.stop()
                self._births()
            return
        for metric in metrics:
            try:
                value = command_value(metric, birth_datatype(device, metric.name))
                request = command_request(device, metric.name, value)
                if request is not None:
                    run(self.runtime, request)
            except Exception as exc:
                self._refused(device, f"{topic}#{metric.name}", exc)
        self.watches[device.name].sample()

    def _host_state(self, payload: bytes) -> None:
        """A STATE of the primary host: online → the births (once per session, once subscribed);
        offline → the session ends and the next one waits (an offline STATE while still waiting
        changes nothing: the node stays connected, unborn).  A payload that is not a STATE is
        answered on the plant's error topic."""
        assert self.host is not None
        try:
            online = self.host.take(payload)
        except ValueError as exc:
            self._refused(None, self.host.topic, exc)
            return
        if online and self.linked and not self.born:
            self._births()
        elif online is False and self.born:
            self.stop()
            self.born = False
            self.ended += 1
            self.end_session()

    def _refused(self, device: Device | None, topic: str, exc: BaseException) -> None:
        where = topics.prefix(self.plant, device.name) if device is not None else f"{topics.ROOT}/{self.plant}"
        self.send((f"{where}/error", topics.error_payload(topic, exc), 1, False))

    def closing(self) -> list[Message]:
        return [(*self.node.death(), 1, False)]

    def stop(self) -> None:
        for events in self.events:
            events.stop()
        self.events.clear()
        for watch in self.watches.values():
            watch.stop()
        self.watches.clear()



class PlantLink:
    """A process's MQTT connections for its convention objects (devices, or one Sparkplug
    plant): one shared connection carries every side's commands and messages in order, written
    once per loop turn; each side's will rides on a connection of its own (``own_wills``, the
    devsim convention: a will per device) or on the shared one (a single side, Sparkplug's
    NDEATH).  Reconnects all of them when any is lost."""

    def __init__(self, host: str, port: int, sides: Sequence[Any], identifier: str, *, own_wills: bool) -> None:
        self.host, self.port, self.sides, self.identifier = host, port, list(sides), identifier
        self.own_wills = own_wills
        self.shared: MqttLink | None = None
        self.holders: list[MqttLink] = []  # the wills' connections
        self._routes = {side.route: side for side in self.sides if side.route is not None}
        self._everything = [side for side in self.sides if side.route is None]
        for side in self.sides:
            side.send, side.send_sample, side.end_session = self._send, self._send_sample, self._end_session
        self.dropped = 0  # samples dropped since the shared connection fell behind (PAUSED_LIMIT)
        self._catching_up: asyncio.Task[None] | None = None
        self._task: asyncio.Task[None] | None = None
        self._closing = False
        self._again = False  # a side ended its session: connect again at once
        self._ending: asyncio.Task[None] | None = None  # that session's DISCONNECT

    async def start(self) -> None:
        """Connect (a refused or unreachable broker raises here) and serve in the background."""
        await self._connect()
        self._task = asyncio.get_running_loop().create_task(self._run())

    async def _open(self, identifier: str, will: Message | None) -> MqttLink:
        return await open_link(self.host, self.port, identifier, keepalive=KEEPALIVE, v5=False,
                               will=Will(will[0], will[1], will[2], will[3]) if will is not None else None)

    async def _connect(self) -> None:
        try:
            if self.own_wills:  # the wills first: a device is announced online only once its will holds
                opened = await asyncio.gather(*(self._open(side.identifier(), side.new_session()) for side in self.sides),
                                              return_exceptions=True)
                self.holders = [link for link in opened if isinstance(link, MqttLink)]
                for failed in opened:
                    if isinstance(failed, BaseException):
                        raise failed
                self.shared = await self._open(self.identifier, None)
            else:
                [side] = self.sides
                self.shared = await self._open(side.identifier(), side.new_session())
            self.shared.on_message = self._route
            patterns = list(dict.fromkeys(p for side in self.sides for p in side.filters()))
            await asyncio.gather(*(self.shared.subscribe(pattern, qos=1) for pattern in patterns))
        except BaseException:
            self._drop()
            raise
        for side in self.sides:
            side.connected()

    def _send(self, message: Message) -> None:
        if self.shared is not None:
            with contextlib.suppress(LinkLost):  # the serving loop reconnects; the births follow
                self.shared.publish(*message)

    def _send_sample(self, make: Callable[[], Message]) -> None:
        """[SIM-CHOICE] A sample (a state that changed, a DDATA) while the shared connection is
        behind (more than ``PAUSED_LIMIT`` bytes wait unsent, beyond what the socket holds: a
        broker that stopped reading) is dropped, so what waits stays bounded in bytes; once they
        are down to a quarter, every side sends every value again (:meth:`_catch_up`), so that
        the retained states are the device's.  Births, status, deaths and errors always wait
        their turn (:meth:`_send`).  Dropping the newest keeps the bytes already queued whole;
        the oldest samples of all sit in the kernel's socket buffers, beyond reach.  ``make``
        makes the message, only if it is sent."""
        shared = self.shared
        if shared is None:
            return
        if shared.behind:
            self.dropped += 1
            if self._catching_up is None:
                self._catching_up = asyncio.get_running_loop().create_task(self._catch_up(shared))
            return
        with contextlib.suppress(LinkLost):  # the serving loop reconnects; the births follow
            shared.publish(*make())

    async def _catch_up(self, shared: MqttLink) -> None:
        """Once ``shared`` has caught up, every value again (a lost link: the new one's births)."""
        try:
            await shared.drain()
        except LinkLost:
            return
        finally:
            self._catching_up = None
        if shared is self.shared and not self._closing:
            warn(f"devsim: mqtt: the broker mqtt://{self.host}:{self.port} fell behind: {self.dropped} samples"
                 " were dropped; every value is sent again")
            self.dropped = 0
            for side in self.sides:
                side.resample()

    def _end_session(self) -> None:
        """A side ends its session on purpose (Sparkplug: its primary host went offline): its
        goodbye (:meth:`closing`, the NDEATH) and a clean DISCONNECT on the shared connection,
        then the serving loop connects again at once (a new session, new births)."""
        shared, self.shared = self.shared, None
        if shared is None or self._closing:
            self.shared = shared
            return
        self._again = True
        with contextlib.suppress(LinkLost):
            for side in self.sides:
                for message in side.closing():
                    shared.publish(*message)
        self._ending = asyncio.get_running_loop().create_task(shared.disconnect())  # (the loop sees it closed)

    def _route(self, message: Publish) -> None:
        parts = message.topic.split("/", 3)
        side = self._routes.get(parts[2]) if len(parts) > 2 else None
        for target in [side] if side is not None else self._everything:
            target.handle(message.topic, message.payload)

    async def _run(self) -> None:
        while not self._closing:
            links = [link for link in (self.shared, *self.holders) if link is not None]
            await asyncio.wait([link.closed for link in links], return_when=asyncio.FIRST_COMPLETED)
            if self._closing:
                return
            for side in self.sides:
                side.stop()
            self._drop()
            delay, self._again = (0.0 if self._again else RETRY), False
            while not self._closing:
                await asyncio.sleep(delay)
                delay = RETRY
                try:
                    await self._connect()
                    break
                except (LinkLost, OSError):
                    pass

    def _drop(self) -> None:
        """Close every connection without a DISCONNECT: the broker sends the wills."""
        for link in (self.shared, *self.holders):
            if link is not None:
                link.abort()
        self.shared, self.holders = None, []

    async def close(self) -> None:
        """Say offline on the shared connection (the wills are not sent on a clean disconnect),
        wait for the broker to have it, leave."""
        self._closing = True
        for side in self.sides:
            side.stop()
        if self._catching_up is not None:
            self._catching_up.cancel()
        if self._task is not None:
            self._task.cancel()
            with contextlib.suppress(asyncio.CancelledError, Exception):
                await self._task
        shared, holders = self.shared, self.holders
        self.shared, self.holders = None, []
        if shared is not None:
            with contextlib.suppress(LinkLost, asyncio.CancelledError, TimeoutError):
                last = None
                for side in self.sides:
                    for topic, payload, qos, retain in side.closing():
                        last = shared.publish(topic, payload, qos, retain)
                if last is not None:
                    await asyncio.wait_for(last, 5)
        for link in (*holders, *([shared] if shared is not None else [])):
            await link.disconnect()


# -- the embedded broker --------------------------------------------------------------------
def _free(host: str, port: int) -> bool:
    with socket.socket() as sock:
        try:
            sock.bind((host, port))
        except OSError:
            return False
    return True


async def start_broker(host: str = "127.0.0.1", port: int | None = None) -> tuple[Any, int]:
    """An amqtt broker in this loop on ``host`` (loopback unless named): on ``port``, or on 1883
    when that is free, else on a free port.  Returns the broker (``await broker.shutdown()``) and
    its port."""
    from amqtt.broker import Broker
    from amqtt.errors import ProtocolHandlerError

    class OwnRetained(Broker):
        """amqtt 0.12.1 sends a client, at every connect, the retained messages of every topic
        filter any client holds (``Broker.client_connected``); with a ``devsim/#`` watcher that
        is the whole retained state, and a ``mosquitto_pub`` at QoS 0, busy taking it, lost its
        message.  Here a client gets the retained messages of the filters it holds itself."""

        async def _publish_retained_messages_for_subscription(self, subscription: tuple[str, int],
                                                              session: Any) -> None:
            holders = self._subscriptions.get(subscription[0], ())
            if any(held.client_id == session.client_id for held, _qos in holders):
                await super()._publish_retained_messages_for_subscription(subscription, session)

        def _get_handler(self, session: Any) -> Any:
            handler = super()._get_handler(session)
            return None if handler is None else _BoundedHandler(handler, ProtocolHandlerError)

    if port is None:
        port = topics.DEFAULT_PORT
        if not _free(host, port):
            with socket.socket() as sock:
                sock.bind((host, 0))
                port = int(sock.getsockname()[1])
    config = {
        "listeners": {"default": {"type": "tcp", "bind": f"{host}:{port}"}},
        "plugins": {"amqtt.plugins.authentication.AnonymousAuthPlugin": {"allow_anonymous": True}},
    }
    broker = OwnRetained(config)
    await broker.start()
    return broker, port


class _BoundedHandler:
    """[SIM-CHOICE] A subscriber of the embedded broker as its broadcasts see it: one that lets
    :data:`SUBSCRIBER_BACKLOG` messages wait for it (it does not read: ``mosquitto_sub`` stopped)
    is disconnected, as the web page disconnects a browser that lets its events pile up (a client
    that reconnects gets the retained state anew).  amqtt 0.12.1 starts a task per message and
    subscriber, each waiting for the subscriber's write lock, and keeps every task, done or not,
    behind the oldest one waiting: for such a subscriber they piled up without end, and a SIGTERM
    then cancelled each one and logged its traceback, the simulator taking more than 20 s to
    stop.  A publish cancelled at the broker's shutdown ends quietly here."""

    def __init__(self, handler: Any, cancelled: type[Exception]) -> None:
        self._handler, self._cancelled = handler, cancelled

    def __getattr__(self, name: str) -> Any:
        return getattr(self._handler, name)

    async def mqtt_publish(self, topic: str, data: bytes, qos: int | None, retain: bool,
                           ack_timeout: int | None = None) -> Any:
        handler = self._handler
        waiting = getattr(handler, "devsim_waiting", 0)
        if waiting >= SUBSCRIBER_BACKLOG:
            transport = getattr(getattr(handler.writer, "_writer", None), "transport", None)
            if transport is not None and not transport.is_closing():
                transport.abort()  # (its waiting publishes end with the connection)
            return None
        handler.devsim_waiting = waiting + 1
        try:
            return await handler.mqtt_publish(topic, data, qos, retain, ack_timeout)
        except self._cancelled:  # (amqtt's word for a publish cancelled at its shutdown)
            return None
        finally:
            handler.devsim_waiting -= 1


def check_options(plant: str, convention: str, rate: float, primary_host: str | None) -> None:
    """ValueError for a plant name or primary host id that is not one topic level, a rate that is
    not positive, or a primary host without the Sparkplug convention."""
    topics.check_name("plant", plant)
    if not rate > 0:
        raise ValueError(f"the MQTT rate is a positive number of seconds, not {rate!r}")
    if primary_host is not None:
        topics.check_name("primary host", primary_host)
        if convention != "sparkplug":
            raise ValueError("a primary host is a Sparkplug host application: only with the sparkplug convention")


async def start_mqtt(runtime: Runtime, devices: Sequence[Device], url: str | None, *, plant: str,
                     convention: Convention = "devsim", rate: float = 1.0,
                     primary_host: str | None = None) -> list[str]:
    """Serve ``devices`` over MQTT in ``runtime`` (in its loop): on the broker at ``url``
    (``mqtt://HOST[:PORT]``), or on an embedded broker when ``url`` is None.  ``primary_host``:
    the Sparkplug node's Primary Host Application id, whose STATE its births wait for (Sparkplug
    only).  Returns the lines ``devsim run``/``up`` print (where the broker is, and the topic root)."""
    check_options(plant, convention, rate, primary_host)
    for device in devices:
        topics.check_name("device", device.name)
    lines = []
    if url is None:
        broker, port = await start_broker()
        runtime.add_closer(broker.shutdown)
        host = "127.0.0.1"
        lines.append(f"mqtt: broker mqtt://{host}:{port} (embedded)")
    else:
        host, port = topics.parse_url(url)
        lines.append(f"mqtt: broker mqtt://{host}:{port}")
    if convention == "sparkplug":
        from devsim.facades.mqtt_sparkplug import GROUP, NAMESPACE

        sides: list[Any] = [_SparkplugPlant(runtime, devices, plant, rate, primary_host)]
        lines.append(f"mqtt: sparkplug {NAMESPACE}/{GROUP}/+/{plant}")
        if primary_host is not None:
            lines.append(f"mqtt: primary host {NAMESPACE}/STATE/{primary_host} (the births wait for it online)")
    elif convention == "devsim":
        sides = [_DevsimDevice(runtime, device, plant, rate) for device in devices]
        lines.append(f"mqtt: topics {topics.ROOT}/{plant}/")
    else:
        raise ValueError(f"an MQTT convention is devsim or sparkplug, not {convention!r}")
    shared = f"devsim-{plant}-{os.getpid()}-{secrets.token_hex(2)}"  # unique even for two plants of one name here
    link = PlantLink(host, port, sides, shared, own_wills=convention == "devsim")
    try:
        await link.start()
    except LinkLost as exc:
        raise ConnectionError(f"cannot reach the MQTT broker mqtt://{host}:{port}: {exc}") from None
    runtime.add_closer(link.close)
    return lines

