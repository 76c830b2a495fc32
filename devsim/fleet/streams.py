"""Watch streams over the fleet's broker: ``devsim ctl --fleet URL watch`` (the member's side).

Over ``--control`` a watch stream lives on its TCP connection (:mod:`devsim.runtime.control`);
over a broker there is no connection between a client and a member, so a stream is addressed and
kept alive by topics (:class:`devsim.fleet.topics.Topics`):

* the client publishes a retained ``1`` on ``ROOT/client/CLIENT/watching`` before it asks, with a
  last will that clears it (and clears it itself when it closes);
* it sends the control API's ``watch`` request with ``"stream_to": "ROOT/client/CLIENT/watch/N"``;
  the member answers as the control server does (device, names, period, t; plus ``stream``) and
  publishes every item of a :class:`~devsim.runtime.watch_stream.WatchStream` there as the
  control server's JSON line (``{"watch": ID, "t": …, "device": …, "type": …}``), QoS 0, in
  order;
* the member's last will ends its streams: a client stops taking them when the offline mark
  arrives, and the member, rejoining, stops them (:meth:`StreamServer.ended_by_will`); a client
  that still watches other members asks it again then;
* the member follows every client's ``watching`` and stops a client's streams when it is cleared
  (the client closed, or died: its will).  After a reconnection it takes the retained presences
  again and, at its own marker (``ROOT/client/PROCESS-streams/sync``, which the broker hands back
  after them), stops the streams of clients that are gone.

Runs in the runtime's loop, as the member does.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
from typing import Any

from devsim.facades.mqtt_link import LinkLost, MqttLink
from devsim.fleet.topics import Topics
from devsim.runtime import Runtime, ops
from devsim.runtime.ops import ErrorResponse, OkResponse, WatchStart
from devsim.runtime.watch_stream import WatchStream

__all__ = ["MAX_BACKLOG", "StreamServer"]

MAX_BACKLOG = 20000  # items waiting for the broker before the stream that adds one more ends


class StreamServer:
    """The watch streams one member serves, keyed by the client that watches."""

    def __init__(self, runtime: Runtime, topics: Topics, process: str) -> None:
        self.runtime = runtime
        self.topics = topics
        self.marker = topics.sync(f"{process}-streams")
        self.present: set[str] = set()  # clients whose `watching` is set
        self.streams: dict[str, list[WatchStream]] = {}  # client -> its streams
        self.outbox: asyncio.Queue[tuple[str, bytes]] = asyncio.Queue()

    # -- the connection ---------------------------------------------------------------------
    async def subscribe(self, link: MqttLink) -> None:
        """On each (re)connection: take every client's presence, then our marker."""
        self.present.clear()
        await link.subscribe(self.topics.presences, qos=1)
        await link.subscribe(self.marker, qos=0)
        link.publish(self.marker, b"sync", qos=0)

    async def pump(self, link: MqttLink) -> None:
        """Publish the streams' items in order until the connection fails (the member sees that
        and reconnects); what waits for the socket waits here, in the outbox."""
        with contextlib.suppress(LinkLost):
            while True:
                topic, payload = await self.outbox.get()
                link.publish(topic, payload, qos=0)
                while not self.outbox.empty():  # everything queued now, in one write
                    topic, payload = self.outbox.get_nowait()
                    link.publish(topic, payload, qos=0)
                await link.drain()

    def handle(self, topic: str, payload: Any) -> None:
        """A presence (``watching``) or our marker."""
        if topic == self.marker:
            for client in [c for c in self.streams if c not in self.present]:
                self.drop(client)
            return
        client = self.topics.client_of(topic)
        if client is None or topic != self.topics.watching(client):
            return
        if payload:
            self.present.add(client)
        else:
            self.present.discard(client)
            self.drop(client)

    # -- streams ----------------------------------------------------------------------------
    def start(self, start: WatchStart, watch_id: Any, stream_to: Any) -> OkResponse | ErrorResponse:
        """Start the stream a ``watch`` request asked for (its answer)."""
        client = self.topics.client_of(stream_to) if isinstance(stream_to, str) else None
        if client is None or any(c in stream_to for c in "+#\x00") or len(stream_to) > 1024:
            return ErrorResponse(id=watch_id, type="BadRequest", error=(
                f"watch over the fleet needs 'stream_to', a topic under {self.topics.root}/client/CLIENT/"
                f" (and a retained '1' on {self.topics.watching('CLIENT')} while CLIENT watches)"))
        if client not in self.present:
            return ErrorResponse(id=watch_id, type="BadRequest",
                                 error=f"{self.topics.watching(client)} is not set: nobody is watching")

        def send(item: dict[str, Any]) -> None:
            if self.outbox.qsize() >= MAX_BACKLOG:  # the broker does not take them: end this watch
                stream.stop()
                return
            line = json.dumps({"watch": watch_id, **ops.jsonable(item)}, separators=(",", ":"))
            self.outbox.put_nowait((stream_to, line.encode("utf-8")))

        try:
            stream = WatchStream(self.runtime, self.runtime.device(start.device), send, names=start.names,
                                 period=start.period)
        except Exception as exc:
            return ErrorResponse(id=watch_id, error=ops.clip(ops.error_text(exc)), type=type(exc).__name__)
        self.streams.setdefault(client, []).append(stream)
        answer = OkResponse(id=watch_id, result={"device": start.device, "names": stream.names, "period": stream.period,
                                                 "t": self.runtime.clock.now(), "stream": stream_to})
        stream.start()  # its first items (every value) go to the outbox; the answer to the reply topic
        return answer

    def ended_by_will(self) -> None:
        """Our last will marked us offline, and every watcher ended our streams then (a watch that
        goes on asks again when we are back): stop them all, and drop the items they left in
        the outbox.  Called on rejoining unless our announcement was still there, online."""
        self.close()
        while not self.outbox.empty():
            self.outbox.get_nowait()

    def drop(self, client: str) -> None:
        for stream in self.streams.pop(client, []):
            stream.stop()

    def close(self) -> None:
        for client in list(self.streams):
            self.drop(client)
