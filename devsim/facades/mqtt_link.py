"""devsim's own MQTT 5 client connection over asyncio (packets in :mod:`devsim.facades.mqtt_wire`,
OASIS MQTT 5.0 sections 3 and 4): what a fleet member and a fleet client speak.

Built for a member's load (many small requests, each answered at once): every message that
arrives is handed to the ``on_message`` callback in the same step that read it, and what is
published is written to the socket once per loop turn – the answers to all the requests of one
read leave in one write, with no task or future per message.  Only the rare exchanges wait for
the broker: the CONNACK, a SUBACK, an UNSUBACK, the PUBACK of a QoS 1 publish that asks for it.

The link holds its socket itself, without an asyncio transport: the loop calls it when the
socket is readable (``add_reader``), it reads into a buffer of its own, and it sends with
``socket.send`` while nothing waits unsent.  What the socket does not take waits in order in
the link's own buffer, sent when the socket is writable again (``add_writer``); beyond
``PAUSED_LIMIT`` bytes waiting, :meth:`MqttLink.drain` waits until they are down to a quarter.
Its pings are kept by :mod:`devsim.facades.mqtt_keepalive`, not by a timer in the loop.

A connection that is lost, a broker that sends a DISCONNECT, or one silent for 1.5 keep-alive
intervals (3.1.2.10) ends :attr:`MqttLink.closed` with a :class:`LinkLost`; the caller reconnects
with a new link.
"""

from __future__ import annotations

import asyncio
import contextlib
import socket
import threading
import time
from collections.abc import Callable

from devsim.facades import mqtt_wire as wire
from devsim.facades.mqtt_keepalive import keepalive_clock
from devsim.facades.mqtt_wire import Publish, Will

__all__ = ["LinkLost", "MqttLink", "open_link"]

PAUSED_LIMIT = 1 << 20  # bytes the socket may hold before drain() waits
PING_SHARE = 0.75  # a PINGREQ every this share of the keep alive (a device's idle will connection pings, too)
READ_SIZE = 64 * 1024  # bytes a read takes at most (asyncio's plain protocol allocates 256 KiB per read)


_per_thread = threading.local()


def _read_buffer() -> memoryview:
    """The read buffer of the links of this thread's loop: a read copies its bytes out at once
    (as a TCP port's sessions do, :mod:`devsim.transports.tcp`), so the links share it – the
    MQTT facade holds a link per device for its will, which would be 64 KiB each."""
    view: memoryview | None = getattr(_per_thread, "view", None)
    if view is None:
        view = _per_thread.view = memoryview(bytearray(READ_SIZE))
    return view


class LinkLost(ConnectionError):
    """The broker connection is gone (or never came up)."""


class MqttLink:
    """One MQTT session, clean start, on a connected socket of its own (see the module docstring).
    Its attributes are slots: a request's read touches one block of them."""

    __slots__ = ("keepalive", "v5", "on_message", "_route", "_loop", "closed", "_sock", "_fd", "_reader", "_out",
                 "_unsent", "_closing", "_flush_soon", "_waiting", "_next_id", "_heard", "_paused", "_reading",
                 "_view")

    def __init__(self, sock: socket.socket, keepalive: int, v5: bool = True) -> None:
        self.keepalive = keepalive
        self.v5 = v5
        self.on_message: Callable[[Publish], None] = lambda message: None
        self._route: tuple[bytes, Callable[[bytes], None]] | None = None  # (head of its PUBLISH, handler)
        self._loop = asyncio.get_running_loop()
        self.closed: asyncio.Future[None] = self._loop.create_future()
        self._sock: socket.socket | None = sock  # (None once closed)
        self._fd = sock.fileno()
        self._reader = wire.PacketReader()
        self._out: list[bytes] = []  # this loop turn's packets
        self._unsent = bytearray()  # what the socket did not take yet, in order
        self._closing = False  # close the socket once the unsent bytes are out
        self._flush_soon: asyncio.Handle | None = None
        self._waiting: dict[tuple[int, int], asyncio.Future[bytes]] = {}  # (ack type, packet id) -> ack body
        self._next_id = 0
        self._heard = time.monotonic()
        self._paused: asyncio.Future[None] | None = None
        self._reading = False  # inside _readable: its end flushes
        self._view = _read_buffer()
        sock.setblocking(False)
        if sock.family in (socket.AF_INET, socket.AF_INET6):
            sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)  # requests are small and waited for
        self._loop.add_reader(self._fd, self._readable)

    # -- the socket ------------------------------------------------------------------------
    def _readable(self) -> None:
        """The loop's call when the socket has bytes (or its end): every packet read is handled
        in this step, and the answers leave in one write at its end."""
        try:
            nbytes = self._sock.recv_into(self._view)  # type: ignore[union-attr]  (read only while open)
        except (BlockingIOError, InterruptedError):
            return
        except OSError as exc:
            self._lose(LinkLost(f"connection to the broker lost: {exc}"))
            return
        if not nbytes:
            self._lose(LinkLost("connection to the broker lost"))
            return
        self._heard = time.monotonic()  # (what the loop's time() returns, without its call)
        data = bytes(self._view[:nbytes])
        route = self._route
        self._reading = True
        try:
            payload = None if route is None else self._reader.single_publish(data, route[0])
            if payload is not None:  # one request, read whole: the common case of a member
                route[1](payload)
            else:
                self._handle(data, route)
        except (wire.MalformedPacket, LinkLost) as exc:
            self._lose(exc if isinstance(exc, LinkLost) else LinkLost(f"malformed packet from the broker: {exc}"))
            return
        except Exception as exc:  # a handler's own failure: the connection ends, as asyncio ended it
            self._lose(LinkLost(f"a message's handler failed: {exc!r}"))
            raise
        finally:
            self._reading = False
        out = self._out  # the answers to everything read now, in one write (flush without its call)
        if out and self._sock is not None and not self._closing:  # (else: lost meanwhile, nothing goes out)
            self._out = []
            self._write(out[0] if len(out) == 1 else b"".join(out))

    def _handle(self, data: bytes, route: tuple[bytes, Callable[[bytes], None]] | None) -> None:
        """Every packet of ``data`` (after what an earlier read left), in order."""
        for kind, flags, body in self._reader.feed(data):
            if kind == wire.PUBLISH:
                if route is not None and not flags and body.startswith(route[0]):  # QoS 0, not retained
                    route[1](body[len(route[0]):])
                    continue
                message = wire.parse_publish(flags, body, self.v5)
                if message.qos == 1:
                    self._out.append(wire.puback(message.packet_id))
                self.on_message(message)
            elif kind == wire.SERVER_DISCONNECT:
                raise LinkLost(f"the broker disconnected (reason {body[0] if body else 0})")
            else:
                self._acked(kind, body)

    def _write(self, data: bytes) -> None:
        """Send ``data`` after what waits unsent; what the socket does not take waits for it."""
        unsent = self._unsent
        if not unsent:
            try:
                sent = self._sock.send(data)  # type: ignore[union-attr]  (written only while open)
            except (BlockingIOError, InterruptedError):
                sent = 0
            except OSError as exc:
                self._lose(LinkLost(f"connection to the broker lost: {exc}"))
                return
            if sent == len(data):
                return
            self._loop.add_writer(self._fd, self._writable)
            data = data[sent:]
        unsent += data
        if len(unsent) > PAUSED_LIMIT and self._paused is None:
            self._paused = self._loop.create_future()

    def _writable(self) -> None:
        """The loop's call when the socket takes bytes again while some wait unsent."""
        unsent = self._unsent
        try:
            sent = self._sock.send(unsent)  # type: ignore[union-attr]  (a writer only while open)
        except (BlockingIOError, InterruptedError):
            return
        except OSError as exc:
            unsent.clear()
            self._close_socket()
            self._lose(LinkLost(f"connection to the broker lost: {exc}"))
            return
        del unsent[:sent]
        if len(unsent) <= PAUSED_LIMIT // 4:
            self._resume()
        if not unsent:
            self._loop.remove_writer(self._fd)
            if self._closing:
                self._close_socket()

    def _close_socket(self, now: bool = True) -> None:
        """Stop reading; close the socket now, or (``now=False``) once the unsent bytes are out."""
        sock = self._sock
        if sock is None:
            return
        self._loop.remove_reader(self._fd)
        if self._unsent and not now:
            self._closing = True
            return
        self._loop.remove_writer(self._fd)
        self._unsent.clear()
        self._sock = None
        sock.close()

    def _resume(self) -> None:
        paused, self._paused = self._paused, None
        if paused is not None and not paused.done():
            paused.set_result(None)

    @property
    def behind(self) -> bool:
        """More than ``PAUSED_LIMIT`` bytes wait unsent (the socket took what it could: a broker
        that does not read), and they are not yet down to a quarter; :meth:`drain` waits meanwhile."""
        return self._paused is not None

    # -- sending ---------------------------------------------------------------------------
    def publish(self, topic: str, payload: bytes, qos: int = 0, retain: bool = False,
                correlation: bytes | None = None, expiry: int | None = None) -> asyncio.Future[bytes] | None:
        """Queue a PUBLISH for this loop turn's write; at QoS 1 the future of its PUBACK."""
        if correlation is None and expiry is None:
            props = b"\x00" if self.v5 else b""
        elif self.v5:
            props = wire.properties(expiry=expiry, correlation=correlation)
        else:
            raise ValueError("MQTT 3.1.1 has no properties (correlation data, message expiry)")
        if not qos:
            self._send(wire.publish(topic, payload, 0, retain, props=props))
            return None
        packet_id = self._packet_id()
        acked = self._expect(wire.PUBACK, packet_id)
        self._send(wire.publish(topic, payload, qos, retain, packet_id, props))
        return acked

    def publish_headed(self, head: bytes, payload: bytes) -> None:
        """Queue a PUBLISH at QoS 0, not retained, without properties, for this loop turn's write:
        ``head`` from :meth:`head` (a topic answered again and again)."""
        if self.closed.done():  # (what _send does, without its call: a member's every answer)
            self._raise_if_lost()
        self._out.append(wire.publish_headed(head, payload))
        if self._flush_soon is None and not self._reading:
            self._flush_soon = self._loop.call_soon(self.flush)

    def head(self, topic: str) -> bytes:
        """What :meth:`publish_headed` puts before a payload on ``topic`` (:func:`mqtt_wire.publish_head`)."""
        return wire.publish_head(topic, self.v5)

    def route(self, topic: str, handler: Callable[[bytes], None]) -> None:
        """Hand the payload of each PUBLISH on ``topic`` at QoS 0, not retained, without properties
        straight to ``handler`` (a member's requests), in the step that read it; the other messages
        on it, with properties or a QoS, go to :attr:`on_message` as :class:`Publish` records."""
        self._route = (self.head(topic), handler)

    async def publish_acked(self, topic: str, payload: bytes, qos: int = 1, retain: bool = False,
                            timeout: float = 10.0) -> None:
        """Publish and wait for the broker's PUBACK (QoS 1)."""
        acked = self.publish(topic, payload, qos, retain)
        if acked is not None:
            await self._wait(acked, timeout)

    async def subscribe(self, topic: str, qos: int = 0, timeout: float = 10.0) -> None:
        packet_id = self._packet_id()
        acked = self._expect(wire.SUBACK, packet_id)
        self._send(wire.subscribe(packet_id, topic, qos, self.v5))
        refused = wire.suback_refused(await self._wait(acked, timeout), self.v5)
        if refused is not None:
            raise LinkLost(f"the broker refused the subscription to {topic!r} (reason 0x{refused:02x})")

    async def unsubscribe(self, topic: str, timeout: float = 10.0) -> None:
        packet_id = self._packet_id()
        acked = self._expect(wire.UNSUBACK, packet_id)
        self._send(wire.unsubscribe(packet_id, topic, self.v5))
        await self._wait(acked, timeout)

    async def drain(self) -> None:
        """Wait while the socket holds more than the transport's high-water mark."""
        self.flush()
        while self._paused is not None and not self.closed.done():
            await asyncio.wait({self._paused, self.closed}, return_when=asyncio.FIRST_COMPLETED)
        self._raise_if_lost()

    def flush(self) -> None:
        if self._flush_soon is not None:
            self._flush_soon.cancel()
            self._flush_soon = None
        out = self._out
        if out and self._sock is not None and not self.closed.done():
            self._write(out[0] if len(out) == 1 else b"".join(out))
        out.clear()

    def abort(self) -> None:
        """Close without a DISCONNECT: the broker sends the will."""
        self._close_socket()
        self._lose(LinkLost("aborted"))

    async def disconnect(self) -> None:
        """A clean DISCONNECT (the broker drops the will) and close."""
        if self._sock is not None and not self.closed.done():
            self._send(wire.DISCONNECT)
            self.flush()
            self._close_socket(now=False)
        self._lose(LinkLost("disconnected"))

    # -- inside ----------------------------------------------------------------------------
    def _send(self, packet: bytes) -> None:
        if self.closed.done():
            self._raise_if_lost()
        self._out.append(packet)
        if self._flush_soon is None and not self._reading:
            self._flush_soon = self._loop.call_soon(self.flush)

    def _packet_id(self) -> int:
        self._next_id = self._next_id % 65535 + 1
        return self._next_id

    def _expect(self, kind: int, packet_id: int) -> asyncio.Future[bytes]:
        future: asyncio.Future[bytes] = self._loop.create_future()
        self._waiting[(kind, packet_id)] = future
        return future

    def _acked(self, kind: int, body: bytes) -> None:
        if kind == wire.CONNACK:
            key = (kind, 0)
        elif kind in (wire.PUBACK, wire.SUBACK, wire.UNSUBACK) and len(body) >= 2:
            key = (kind, (body[0] << 8) | body[1])
        else:
            return  # PINGRESP: hearing it is enough
        future = self._waiting.pop(key, None)
        if future is not None and not future.done():
            future.set_result(body)

    async def _wait(self, future: asyncio.Future[bytes], timeout: float) -> bytes:
        done, _ = await asyncio.wait({future, self.closed}, timeout=timeout, return_when=asyncio.FIRST_COMPLETED)
        if future in done and not future.cancelled():  # cancelled: the link was lost meanwhile
            return future.result()
        self._raise_if_lost()
        self._lose(LinkLost(f"the broker did not answer within {timeout:g} s"))
        self._raise_if_lost()
        raise AssertionError("unreachable")

    def _raise_if_lost(self) -> None:
        """LinkLost (with why) once :attr:`closed` is done, however it ended (a task that awaited
        it and was cancelled cancels it too)."""
        if self.closed.done():
            why = None if self.closed.cancelled() else self.closed.exception()
            raise LinkLost(str(why) if why is not None else "the connection is closed")

    def _ping(self) -> None:
        if self.closed.done():  # (the last call the keep-alive clock had for it)
            return
        if time.monotonic() - self._heard > 1.5 * self.keepalive:
            self._lose(LinkLost(f"the broker was silent for {1.5 * self.keepalive:g} s"))
            return
        with contextlib.suppress(LinkLost):
            self._send(wire.PINGREQ)
        self._start_pinging()

    def _start_pinging(self) -> None:
        """The next ping, on the keep-alive clock's thread (no timer in the loop)."""
        keepalive_clock().call_at(time.monotonic() + self.keepalive * PING_SHARE, self._loop, self._ping)

    def _lose(self, exc: LinkLost) -> None:
        if self._flush_soon is not None:
            self._flush_soon.cancel()
            self._flush_soon = None
        if not self.closed.done():
            self.closed.set_exception(exc)
            self.closed.exception()  # retrieved: nobody need await it
        if not self._closing:  # (closing: the DISCONNECT still goes out)
            self._close_socket()
        for future in self._waiting.values():
            if not future.done():
                future.cancel()
        self._waiting.clear()
        self._resume()


async def _connected(host: str, port: int) -> socket.socket:
    """A TCP socket connected to ``host``:``port``, its addresses tried in turn (an address
    given as numbers without a resolver's thread)."""
    loop = asyncio.get_running_loop()
    try:
        addresses = socket.getaddrinfo(host, port, type=socket.SOCK_STREAM, flags=socket.AI_NUMERICHOST)
    except socket.gaierror:
        addresses = await loop.getaddrinfo(host, port, type=socket.SOCK_STREAM)
    error: OSError = OSError(f"no address for {host}")
    for family, kind, proto, _name, address in addresses:
        sock = socket.socket(family, kind, proto)
        try:
            sock.setblocking(False)
            await loop.sock_connect(sock, address)
        except OSError as exc:
            sock.close()
            error = exc
            continue
        except BaseException:  # cancelled (a timeout)
            sock.close()
            raise
        return sock
    raise error


async def open_link(host: str, port: int, identifier: str, *, keepalive: int = 15, will: Will | None = None,
                    username: str | None = None, password: str | None = None, timeout: float = 10.0,
                    v5: bool = True) -> MqttLink:
    """Connect and wait for the broker's CONNACK; :class:`LinkLost` when it cannot be reached
    or refuses.  ``v5=False``: MQTT 3.1.1 (for brokers such as amqtt that speak only that)."""
    try:
        sock = await asyncio.wait_for(_connected(host, port), timeout)
    except (OSError, TimeoutError) as exc:
        raise LinkLost(f"cannot connect to {host}:{port}: {exc or 'timed out'}") from None
    link = MqttLink(sock, keepalive, v5)
    connack = link._expect(wire.CONNACK, 0)
    link._send(wire.connect(identifier, keepalive, will=will, username=username, password=password, v5=v5))
    try:
        body = await link._wait(connack, timeout)
        reason, props = wire.parse_connack(body, v5)
    except (LinkLost, asyncio.CancelledError, wire.MalformedPacket) as exc:
        await link.disconnect()
        if isinstance(exc, asyncio.CancelledError):
            raise
        raise LinkLost(f"no CONNACK from {host}:{port}: {exc}") from None
    if reason >= 0x80:
        await link.disconnect()
        raise LinkLost(f"the broker at {host}:{port} refused the connection (reason 0x{reason:02x})")
    server_keepalive = props.get(wire.SERVER_KEEP_ALIVE)
    if isinstance(server_keepalive, int) and server_keepalive > 0:
        link.keepalive = server_keepalive
    link._start_pinging()
    return link
