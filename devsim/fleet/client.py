"""The fleet's client: every device of every devsim process on a broker, reached by name.

:class:`AsyncFleetClient` (asyncio) and :class:`FleetClient` (blocking, its loop in a thread;
what ``devsim ctl --fleet URL`` uses) keep the retained announcements of all processes (see
:mod:`devsim.fleet.member`) and send a control-API request to the process that announces the
named device, on its request topic, with the client's reply topic and a unique ``id`` as the
correlation id; the answer is the control API's own (``ok``/``result`` or ``error``/``type``,
raised as :class:`devsim.runtime.client.ControlError`).  :class:`FleetClient` has the methods of
:class:`devsim.runtime.client.ControlClient`.

* ``devices()`` – one row per device: the process's ``devices`` row (name, kind, ports) with
  ``process``, ``host``, ``pid``, ``online`` (and ``plant``/``part`` when given).  A process that
  died without a clean stop shows its devices with ``"online": false`` (its last will) until a
  process serving the same name appears.  A request to an offline device fails at once
  (``Offline``); so does one in flight when its process goes offline (its last will or its
  leaving arrives): no answer can come, so it does not wait for the client's ``timeout``.
* **Clashes.** Device names are unique across a fleet: a process refuses to join when a name is
  taken.  Two processes that announce the same name anyway (they joined at the same moment, or a
  bridge joined two fleets) are both listed, each row with ``"clash": true``, and requests for
  that name are refused (``FleetClash``) until one of them leaves.
* **Time.** Virtual time belongs to each process.  ``advance(seconds, device=NAME)`` advances
  the process serving NAME; ``advance(seconds)`` advances every online process on virtual time
  and returns ``{process: new time}`` (an error of one is raised after the others advanced).
  ``now`` likewise, for every online process.
* **Watching.** ``watch(device)`` (``devsim ctl --fleet URL watch``) streams the device's changes
  and events as ``ControlClient.watch`` does, over the broker (:mod:`devsim.fleet.streams`), each
  item tagged with the ``process`` that serves it; without a device, every device online in the
  fleet.  It ends when the watched processes leave, whether they stop or go offline (their last
  will: killed, frozen, cut off; ``on_offline`` is told so, a line of ``devsim ctl``'s stderr).
  One that went offline and comes back while another is still watched (a frozen process
  continued: it rejoins, :mod:`devsim.fleet.member`) is asked again for the devices it still
  announces, as ``tail -F`` follows a file that comes back: ``on_back`` is told so in a line, and
  its items (its values first, as a new watch starts) follow that line.  One back without them
  (withdrawn), or one that left, stays gone.
  Losing the broker is neither: it raises ConnectionError, also when the broker's shutdown sends
  the members' last wills before it closes (an offline mark counts once the broker is seen alive
  after it, by a round trip of the client's marker).
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import threading
import uuid
from collections.abc import Callable, Iterable, Iterator
from typing import Any, NamedTuple

import msgspec

from devsim.facades.mqtt_link import LinkLost, MqttLink
from devsim.facades.mqtt_wire import Publish, Will
from devsim.fleet.member import connect, parse_announcement
from devsim.fleet.topics import FleetUrl, Topics, parse_fleet_url
from devsim.runtime import requests as rq
from devsim.runtime.client import ControlError, ControlOps
from devsim.runtime.ops import CONTROL, routed_by_device

__all__ = ["AsyncFleetClient", "FleetClient"]

#: Ops whose ``device`` only routes them: every process, or the one serving ``device``.
TIME_OPS = tuple(row.token for row in CONTROL if routed_by_device(row.token))
_json_decode = msgspec.json.Decoder().decode


class Watched(NamedTuple):
    """What one stream watches: the ``watch`` request's device, names and period (asked again
    as it was when its process comes back)."""

    device: str
    names: list[str] | None
    period: float | None


class StreamsEnded(msgspec.Struct, frozen=True):
    """The streams of ``devices`` ended: their ``process`` left (``offline`` False) or went offline."""

    process: str
    devices: tuple[str, ...]
    offline: bool
    where: str  # "host H, pid P" of the announcement

    def describe(self) -> str:
        names = ", ".join(self.devices)
        return (f"devsim: {self.process} ({self.where}) went offline (its last will): no more items of {names}"
                if self.offline else f"devsim: {self.process} ({self.where}) left: no more items of {names}")


class StreamsBack:
    """A process whose streams ended when it went offline is back: ``renewed`` (a task) asks it
    for ``watched`` again and gives the devices it took again and the ones it refused (why)."""

    def __init__(self, process: str, where: str, renewed: asyncio.Future[tuple[list[str], dict[str, str]]]) -> None:
        self.process = process
        self.where = where  # "host H, pid P" of its new announcement
        self.renewed = renewed

    def describe(self, devices: list[str], refused: dict[str, str]) -> list[str]:
        lines = [f"devsim: {self.process} ({self.where}) is back: items of {', '.join(devices)} follow again"] if devices else []
        return lines + [f"devsim: {self.process} ({self.where}) is back but refused the watch of {device} ({why}):"
                        f" no more items of {device}" for device, why in refused.items()]


class AsyncFleetClient:
    """An asyncio fleet client; ``async with AsyncFleetClient(url) as fleet: await fleet.request(...)``."""

    def __init__(self, url: str | FleetUrl, *, timeout: float = 10.0) -> None:
        self.url = parse_fleet_url(url) if isinstance(url, str) else url
        self.timeout = timeout
        self.topics = Topics(self.url.root)
        self.id = f"ctl-{uuid.uuid4().hex[:16]}"
        self.processes: dict[str, dict[str, Any]] = {}  # process -> its latest announcement
        self._client: MqttLink | None = None
        self._marker = self.topics.sync(self.id)
        self._reply_topic = self.topics.reply(self.id)  # compared with every message's topic
        self._pending: dict[str, asyncio.Future[dict[str, Any]]] = {}
        self._asked: dict[str, tuple[str, str]] = {}  # request id -> (the process asked, the op)
        self._changed = asyncio.Event()
        self._synced = asyncio.Event()
        self._next = 0
        self.watches: dict[str, str] = {}  # stream topic -> the process that serves it
        self._watched: dict[str, Watched] = {}  # stream topic -> what it watches
        self._away: dict[str, list[Watched]] = {}  # process gone offline -> what to ask again when it is back
        self._present = False  # our `watching` is set
        self._items: asyncio.Queue[dict[str, Any] | BaseException | StreamsEnded] = asyncio.Queue()
        #: told (one line) when a watched process goes offline; its streams end
        self.on_offline: Callable[[str], None] | None = None
        #: told (one line) when such a process is back and watched again (while others are watched)
        self.on_back: Callable[[str], None] | None = None

    @property
    def reply_topic(self) -> str:
        return self._reply_topic

    async def open(self) -> AsyncFleetClient:
        gone = Will(self.topics.watching(self.id), b"", qos=1, retain=True)  # clears a presence
        try:
            client = await connect(self.url, f"devsim-{self.id}", gone)
        except LinkLost as exc:
            raise ConnectionError(f"cannot reach the fleet broker {self.url}: {exc}") from None
        self._client = client
        client.on_message = self._received
        client.closed.add_done_callback(self._lost)
        try:
            await client.subscribe(self.reply_topic, qos=0)
            await client.subscribe(self.topics.announcements, qos=1)
            await client.subscribe(self._marker, qos=0)
            client.publish(self._marker, b"sync", qos=0)
            await asyncio.wait_for(self._synced.wait(), self.timeout)
        except (TimeoutError, LinkLost):
            await self.close()
            raise ConnectionError(f"the fleet broker {self.url} did not answer (or its ACL does not let this user"
                                  f" publish on {self.topics.root}/client/#: docs, Fleet)") from None
        return self

    async def close(self) -> None:
        client, self._client = self._client, None
        if client is not None:
            client.closed.remove_done_callback(self._lost)
            if self._present:  # the members stop our streams (a clean disconnect sends no will)
                with contextlib.suppress(Exception):
                    await client.publish_acked(self.topics.watching(self.id), b"", qos=1, retain=True, timeout=5)
            with contextlib.suppress(Exception):
                await client.disconnect()
        for future in self._pending.values():
            if not future.done():
                future.set_exception(ConnectionError("fleet client closed"))
        self._pending.clear()

    async def __aenter__(self) -> AsyncFleetClient:
        return await self.open()

    async def __aexit__(self, *exc: object) -> None:
        await self.close()

    def _received(self, message: Publish) -> None:
        topic = message.topic
        if topic == self._reply_topic:
            self._answer(message.payload)
        elif topic in self.watches:
            self._item(self.watches[topic], message.payload)
        elif topic == self._marker:
            self._synced.set()
        else:
            process = self.topics.process_of(topic)
            if process is None:
                return
            announcement = parse_announcement(message.payload)
            was = self.processes.get(process, {})
            if announcement is None:
                self.processes.pop(process, None)
            else:
                self.processes[process] = announcement
            if announcement is None or not announcement.get("online"):
                self._streams_end(process, announcement or was, offline=announcement is not None)
                self._requests_fail(process)
            elif process in self._away:
                self._come_back(process, announcement)
            self._changed.set()

    def _lost(self, closed: asyncio.Future[None]) -> None:
        why = None if closed.cancelled() else closed.exception()
        lost = f"fleet broker {self.url} lost ({why or 'the connection closed'})"
        self._items.put_nowait(ConnectionError(lost))
        for future in self._pending.values():
            if not future.done():
                future.set_exception(ConnectionError(lost))

    async def _broker_answers(self) -> None:
        """Return once the broker hands back a marker published now; ConnectionError when the
        connection ends first (or nothing comes back within the client's timeout).  A broker that
        shuts down sends the last wills of its clients and closes: after a will it answers no more."""
        client = self._client
        if client is None:
            raise ConnectionError("fleet client closed")
        self._synced.clear()
        try:
            client.publish(self._marker, b"sync", qos=0)
        except LinkLost:
            pass  # (closed: said below)
        back = asyncio.ensure_future(self._synced.wait())
        try:
            await asyncio.wait({back, client.closed}, timeout=self.timeout, return_when=asyncio.FIRST_COMPLETED)
        finally:
            back.cancel()
        if not self._synced.is_set():
            why = "the connection closed" if client.closed.done() else f"no answer within {self.timeout:g} s"
            raise ConnectionError(f"fleet broker {self.url} lost ({why})")

    def _answer(self, payload: Any) -> None:
        try:
            data = _json_decode(payload)
        except (msgspec.DecodeError, RecursionError, TypeError):
            try:  # what msgspec refuses and json takes (NaN)
                data = json.loads(payload)
            except (ValueError, RecursionError, TypeError):
                return
        if isinstance(data, dict):
            future = self._pending.pop(str(data.get("id")), None)
            if future is not None and not future.done():
                future.set_result(data)

    def _requests_fail(self, process: str) -> None:
        """Fail at once every request in flight to ``process``: it went offline (its last will,
        or it left), so no answer will come."""
        for req_id, (asked, op) in list(self._asked.items()):
            future = self._pending.get(req_id)
            if asked == process and future is not None and not future.done():
                future.set_exception(ControlError(f"{process} went offline before answering {op!r}", "Offline"))

    def in_flight(self, process: str | None = None) -> int:
        """How many requests (to ``process``, or to any) wait for their answer."""
        return sum(1 for req_id, (asked, _op) in self._asked.items()
                   if req_id in self._pending and process in (None, asked))

    # -- watching ------------------------------------------------------------------------
    async def watch(self, device: str, names: list[str] | None = None, period: float | None = None) -> Any:
        """Start watching ``device`` (see :mod:`devsim.fleet.streams`); the answer of its process
        (device, names, period, t, stream).  The items come from :meth:`next_item`."""
        return await self._watch_on(self.serving(device), Watched(device, names, period))

    async def _watch_on(self, process: str, watched: Watched) -> Any:
        """Ask ``process`` to stream what ``watched`` says (its answer)."""
        if self._client is None:
            raise ConnectionError("fleet client not open")
        if not self._present:
            await self._client.subscribe(self.topics.stream(self.id, "+"), qos=0)
            await self._client.publish_acked(self.topics.watching(self.id), b"1", qos=1, retain=True)
            self._present = True
        self._next += 1
        stream = self.topics.stream(self.id, self._next)
        self.watches[stream] = process
        self._watched[stream] = watched
        try:
            return await self.ask(process, "watch", device=watched.device, names=watched.names, period=watched.period,
                                  stream_to=stream)
        except BaseException:
            self.watches.pop(stream, None)
            self._watched.pop(stream, None)
            raise

    def _item(self, process: str, payload: Any) -> None:
        try:
            item = json.loads(payload)
        except (ValueError, RecursionError, TypeError):
            return
        if isinstance(item, dict):
            item.pop("watch", None)
            self._items.put_nowait({**item, "process": process})

    def _streams_end(self, process: str, announcement: dict[str, Any], *, offline: bool) -> None:
        """The streams of ``process`` end: it left (for good) or went offline (asked again when it
        comes back, while another watched process is still there: else the watch ends)."""
        ended = [s for s, p in self.watches.items() if p == process]
        for stream in ended:
            del self.watches[stream]
        watched = [self._watched.pop(stream) for stream in ended]
        if not offline:
            self._away.pop(process, None)
        elif watched:
            self._away.setdefault(process, []).extend(watched)
        if not self.watches:
            self._away.clear()  # nothing watched is left: the watch ends
        if ended:
            devices = tuple(sorted({w.device for w in watched}))
            self._items.put_nowait(StreamsEnded(process, devices, offline, _where(announcement)))

    def _come_back(self, process: str, announcement: dict[str, Any]) -> None:
        """``process`` went offline with streams of ours and is back: ask it again for those of
        its devices it still announces (none: it stays gone).  Told in the order of the items."""
        listed = {row.get("name") for row in announcement["devices"] if isinstance(row, dict)}
        again = [w for w in self._away.pop(process) if w.device in listed]
        if not again:
            return
        renewed = asyncio.ensure_future(self._renew(process, again))
        renewed.add_done_callback(lambda task: task.cancelled() or task.exception())  # (said by next_item, if asked)
        self._items.put_nowait(StreamsBack(process, _where(announcement), renewed))

    async def _renew(self, process: str, again: list[Watched]) -> tuple[list[str], dict[str, str]]:
        """Ask ``process`` for each of ``again``: the devices it took, and the ones it refused
        (why; one that went offline meanwhile is told as offline, and kept for its next return)."""
        answers = await asyncio.gather(*(self._watch_on(process, watched) for watched in again), return_exceptions=True)
        refused: dict[str, str] = {}
        for watched, answer in zip(again, answers, strict=True):
            if isinstance(answer, ControlError) and answer.type != "Offline":
                refused[watched.device] = f"{answer.type}: {answer}"
            elif isinstance(answer, BaseException) and not isinstance(answer, ControlError):
                raise answer  # (the broker lost, the client closed)
        took = {watched.device for watched, answer in zip(again, answers, strict=True)
                if not isinstance(answer, BaseException)}
        return sorted(took), refused

    async def next_item(self, timeout: float | None = None) -> dict[str, Any] | None:
        """The next item of any stream of this client; None once every watched process has
        left or gone offline (:attr:`on_offline` is told of each that went offline, and
        :attr:`on_back` of each that came back while others were watched: asked again, its
        items follow the line);
        TimeoutError after ``timeout`` seconds without one; ConnectionError when the broker is
        lost."""
        while True:
            if not self.watches and self._items.empty():
                return None
            try:
                item = await asyncio.wait_for(self._items.get(), timeout)
            except TimeoutError:
                raise TimeoutError(f"nothing watched changed within {timeout:g} s") from None
            if isinstance(item, BaseException):
                raise item
            if isinstance(item, StreamsBack):  # the items of its new streams follow this
                for line in item.describe(*await item.renewed):
                    if self.on_back is not None:
                        self.on_back(line)
                continue
            if not isinstance(item, StreamsEnded):
                return item
            if item.offline:  # its will – or every will, sent by a broker that shuts down
                await self._broker_answers()
                if self.on_offline is not None:
                    self.on_offline(item.describe())

    # -- the listing ---------------------------------------------------------------------
    def devices(self) -> list[dict[str, Any]]:
        """Every device of every process (see the module docstring), sorted by name."""
        rows: list[dict[str, Any]] = []
        for process, announcement in self.processes.items():
            about = {key: announcement.get(key) for key in ("host", "pid", "plant", "part") if key in announcement}
            for row in announcement.get("devices", []):
                if isinstance(row, dict) and "name" in row:
                    rows.append({**row, "process": process, **about, "online": bool(announcement.get("online"))})
        online: dict[str, int] = {}
        for row in rows:
            if row["online"]:
                online[row["name"]] = online.get(row["name"], 0) + 1
        rows = [row for row in rows if row["online"] or row["name"] not in online]
        for row in rows:
            if online.get(row["name"], 0) > 1:
                row["clash"] = True
        return sorted(rows, key=lambda row: (str(row["name"]), str(row["process"])))

    def serving(self, device: str) -> str:
        """The process that serves ``device`` (online, and the only one); else ControlError."""
        rows = [row for row in self.devices() if row["name"] == device]
        live = [row for row in rows if row["online"]]
        if len(live) == 1:
            return str(live[0]["process"])
        if len(live) > 1:
            where = ", ".join(f"{row['process']} (host {row.get('host')})" for row in live)
            raise ControlError(f"device {device!r} is served by {len(live)} processes: {where}", "FleetClash")
        if rows:
            raise ControlError(f"device {device!r} is offline (its process {rows[0]['process']} is gone)", "Offline")
        known = sorted({str(row["name"]) for row in self.devices() if row["online"]})
        raise ControlError(f"no device named {device[:60]!r} in the fleet {self.url}"
                           f" (have: {', '.join(known) or 'none'})", "UnknownDevice")

    def online_processes(self) -> list[str]:
        return sorted(p for p, a in self.processes.items() if a.get("online"))

    async def wait_for_devices(self, names: Iterable[str], timeout: float = 10.0, *,
                               online: bool = True) -> list[dict[str, Any]]:
        """Wait until every device in ``names`` is listed online (or, with ``online=False``,
        listed offline); bounded by ``timeout`` seconds.  Returns :meth:`devices`."""
        wanted = set(names)
        loop = asyncio.get_running_loop()
        deadline = loop.time() + timeout
        while True:
            have = {row["name"] for row in self.devices() if row["online"] == online}
            if wanted <= have:
                return self.devices()
            self._changed.clear()
            left = deadline - loop.time()
            if left <= 0:
                state = "online" if online else "offline"
                raise TimeoutError(f"devices not {state} in the fleet after {timeout:g} s: {sorted(wanted - have)}")
            with contextlib.suppress(TimeoutError):
                await asyncio.wait_for(self._changed.wait(), left)

    # -- requests ------------------------------------------------------------------------
    async def ask(self, process: str, op: str, **fields: Any) -> Any:
        """Send one control request to ``process``; its result, or ControlError."""
        if self._client is None:
            raise ConnectionError("fleet client not open")
        self._next += 1
        req_id = f"{self.id}-{self._next}"
        message = {"id": req_id, "op": op, **{k: v for k, v in fields.items() if v is not None},
                   "reply_to": self.reply_topic}
        future: asyncio.Future[dict[str, Any]] = asyncio.get_running_loop().create_future()
        self._pending[req_id] = future
        self._asked[req_id] = (process, op)
        try:
            acked = self._client.publish(self.topics.request(process), json.dumps(message).encode(), qos=1)
            if acked is not None:  # (a broker whose ACL refuses it says so in the PUBACK: MQTT 5)
                acked.add_done_callback(lambda done: self._refused_by_broker(done, req_id))
            if not self.processes.get(process, {}).get("online"):  # it left while we published
                self._requests_fail(process)
            reply = await asyncio.wait_for(future, self.timeout)
        except TimeoutError:
            raise ControlError(f"{process} did not answer {op!r} within {self.timeout:g} s", "Timeout") from None
        finally:
            self._pending.pop(req_id, None)
            self._asked.pop(req_id, None)
        if not reply.get("ok"):
            raise ControlError(str(reply.get("error")), str(reply.get("type", "Error")))
        return reply.get("result")

    def _refused_by_broker(self, acked: asyncio.Future[bytes], req_id: str) -> None:
        """A request's PUBACK with a reason code of 0x80 or more (MQTT 5, 3.4.2.1: mosquitto
        answers 0x87 "Not authorized" for a topic its ACL does not let this client write) fails
        the request at once: no process will hear it."""
        if acked.cancelled() or acked.exception() is not None:
            return  # (the link was lost: the request fails that way)
        body = acked.result()
        reason = body[2] if len(body) > 2 else 0
        future = self._pending.get(req_id)
        if reason < 0x80 or future is None or future.done():
            return
        process, op = self._asked[req_id]
        why = ", not authorized: see the broker's ACL" if reason == 0x87 else ""
        future.set_exception(ControlError(
            f"the broker refused the request {op!r} to {process} (PUBACK reason 0x{reason:02x}{why})", "Refused"))

    async def request(self, op: str, **fields: Any) -> Any:
        """A control request routed by its ``device``; ``devices`` from the announcements;
        ``advance``/``now`` without a device go to every online process (``{process: result}``)."""
        if op == "devices":
            return self.devices()
        device = fields.get("device")
        if device is not None:
            return await self.ask(self.serving(str(device)), op, **fields)
        if op not in TIME_OPS:
            raise ControlError(f"{op} needs 'device'", "BadRequest")
        processes = self.online_processes()
        if op == "advance":  # only clocks that wait for it; real ones would refuse
            processes = [p for p in processes if self.processes[p].get("clock") == "virtual"]
            if not processes:
                raise ControlError("no process in the fleet runs on virtual time", "BadRequest")
        results = await asyncio.gather(*(self.ask(p, op, **fields) for p in processes), return_exceptions=True)
        failed = [f"{p}: {r}" for p, r in zip(processes, results, strict=True) if isinstance(r, BaseException)]
        if failed:
            raise ControlError("; ".join(failed), "FleetError")
        return dict(zip(processes, results, strict=True))


def _where(announcement: dict[str, Any]) -> str:
    return f"host {announcement.get('host')}, pid {announcement.get('pid')}"


class FleetClient(ControlOps):
    """Blocking fleet client with :class:`~devsim.runtime.client.ControlClient`'s methods (its
    asyncio loop runs in a daemon thread).  ``with FleetClient("mqtt://broker") as fleet: ...``."""

    def __init__(self, url: str | FleetUrl, timeout: float = 10.0) -> None:
        self._loop = asyncio.new_event_loop()
        self._thread = threading.Thread(target=self._loop.run_forever, name="devsim-fleet-client", daemon=True)
        self._thread.start()
        self.fleet = AsyncFleetClient(url, timeout=timeout)
        try:
            self._run(self.fleet.open())
        except BaseException:
            self._end()
            raise

    def _run(self, coro: Any) -> Any:
        return asyncio.run_coroutine_threadsafe(coro, self._loop).result()

    def _end(self) -> None:
        self._loop.call_soon_threadsafe(self._loop.stop)
        self._thread.join(10)
        if not self._thread.is_alive():
            self._loop.close()

    def close(self) -> None:
        if self._loop.is_closed():
            return
        with contextlib.suppress(Exception):
            self._run(self.fleet.close())
        self._end()

    def __enter__(self) -> FleetClient:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def request(self, op: str, **fields: Any) -> Any:
        return self._run(self.fleet.request(op, **fields))

    def wait_for_devices(self, names: Iterable[str], timeout: float = 10.0, *,
                         online: bool = True) -> list[dict[str, Any]]:
        """Wait (bounded) until the named devices are online (or offline)."""
        return self._run(self.fleet.wait_for_devices(list(names), timeout, online=online))  # type: ignore[no-any-return]

    def watch(self, device: str | None, names: list[str] | None = None, *, period: float | None = None,
              timeout: float | None = None,
              on_offline: Callable[[str], None] | None = None,
              on_back: Callable[[str], None] | None = None) -> Iterator[dict[str, Any]]:
        """Changes and events of ``device`` (None: of every device online in the fleet) as they
        happen, as :meth:`devsim.runtime.client.ControlClient.watch` gives them plus ``process``,
        on a connection of its own; ends when the watched processes leave or go offline
        (``on_offline`` gets a line for each that goes offline; ``on_back`` one for each that
        comes back while others are watched: its devices are watched again, their items follow
        the line); ConnectionError when the broker is lost.  ``timeout``: at most that long without an item (TimeoutError).  Close the
        generator to stop watching."""
        devices = [device] if device is not None else [
            str(row["name"]) for row in self.devices() if row["online"] and not row.get("clash")]
        if not devices:
            raise ControlError(f"no device online in the fleet {self.fleet.url}", "UnknownDevice")
        watcher = FleetClient(self.fleet.url, timeout=self.fleet.timeout)
        watcher.fleet.on_offline = on_offline
        watcher.fleet.on_back = on_back
        try:
            for name in devices:
                watcher._run(watcher.fleet.watch(name, names, period))
            while True:
                item = watcher._run(watcher.fleet.next_item(timeout))
                if item is None:
                    return
                yield item
        finally:
            watcher.close()

    def advance(self, seconds: float, device: str | None = None) -> Any:  # type: ignore[override]
        """Advance the process serving ``device`` (its new time), or every process ({process: time})."""
        return self.call(rq.Advance(seconds, device))

    def now(self, device: str | None = None) -> Any:  # type: ignore[override]
        return self.call(rq.Now(device))
