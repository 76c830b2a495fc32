"""Raw TCP, like a serial device server (Moxa NPort, Lantronix in "TCP server" mode), or a
device's own TCP port (Ether-S-Bus).

Bytes on the socket are bytes on the serial line, nothing else: a raw client cannot tell the
device its line settings, so the line treats it as matching.  Open it with pyserial as
``socket://HOST:PORT`` (:attr:`TcpTransport.url`).

**How many hosts.**  ``hosts`` says how many clients the port serves at once (the port's
:attr:`~devsim.core.kit.PortDef.hosts`, set by the runtime through :meth:`TcpTransport.limit_hosts`).
A serial port has one host: the default, 1.  A client that connects while the port serves as many
as it may is refused at once (closed, with a line in the log naming the holder of a one-host
port), unless a host has been idle (sent nothing) longer than ``idle_drop`` seconds: that one is
dropped and the newcomer served (:mod:`devsim.transports.hosts`).

A port serving several hosts hands the device one whole message at a time (cut by the port's
declared framing, ``split``; without one, each chunk read is a message) and sends the device's
answer to the host whose message it answers: a host's messages hold the port's *turn* until the
device has answered each (one write an answer), or for :data:`TURN_GRACE` seconds after the last
when one gets no answer; the other hosts' messages wait in turn, as the telegrams of several connections wait for a real PLC's one
communication task.

When the serving client disconnects (on a several-host port: the last one), the endpoint gets
``host_disconnected()``.  Output that a client does not read piles up in the socket; beyond
``max_buffer`` bytes further output is dropped, as on a line nobody listens to.  The server
binds to loopback unless told otherwise; its listen backlog is the system's ``somaxconn``
(:func:`~devsim.transports.hosts.listen_backlog`).

**Out of descriptors.**  When the process cannot accept another connection (``ulimit -n``), the
waiting connection is accepted with a reserve descriptor and closed at once, and the cause is
reported once per ten seconds (:mod:`devsim.transports.fdlimit`); the ports and hosts already
served go on.
"""

from __future__ import annotations

import asyncio
import contextlib
import functools
import socket
import threading
import time
from collections import deque
from collections.abc import Callable

from devsim.transports import fdlimit
from devsim.transports.base import Endpoint, Transport
from devsim.transports.hosts import DEFAULT_IDLE_DROP, admit, dropped, listen_backlog, refuse
from devsim.transports.lane import Lane

__all__ = ["MAX_WAITING", "SLICE", "TURN_GRACE", "TcpTransport"]

#: Seconds a host's message on a several-host port holds the turn when the device does not answer it.
TURN_GRACE = 0.2

#: Most host bytes handed to a device in one loop turn (the rest waits for the next turns).
SLICE = 16 * 1024

#: Messages a host of a several-host port may have waiting for the turn: with more, its socket is
#: not read until the device has taken some, and TCP holds the host back, as a device's own stack
#: does when its one communication task is behind.  [SIM-CHOICE] no manual gives the number:
#: without a bound a host flooding unanswered messages (each holds the turn for TURN_GRACE) made
#: the port keep every one of them (20 MB of Ether-S-Bus frames: 55 MB more resident).
MAX_WAITING = 64
#: Bytes one socket read takes at most.  A session reads into a buffer of its own: asyncio's plain
#: protocols allocate a 256 KiB object for every read, which glibc serves with mmap/munmap when
#: its dynamic threshold has not risen – a system call pair per poll, seen in 500-device plants.
READ_SIZE = 64 * 1024
_per_thread = threading.local()


def _read_buffer() -> memoryview:
    """The read buffer of the sessions served in this thread (an event loop runs in one).
    asyncio fills it and calls :meth:`_Session.buffer_updated` at once, which copies the bytes
    out, so the sessions can share it: a buffer each would hold 64 KiB per connected client
    (about 130 MB for a 2,000-device plant), and reads would walk through as many buffers."""
    view: memoryview | None = getattr(_per_thread, "view", None)
    if view is None:
        view = _per_thread.view = memoryview(bytearray(READ_SIZE))
    return view


class _Session(asyncio.BufferedProtocol):
    """One TCP client; the owning transport decides whether it is served or refused.

    A poll touches a session, its asyncio transport and its socket: the attributes are slots
    (one block of memory, not an object and its values array), and a plain session sends
    through its socket directly while asyncio holds nothing unsent for it (:meth:`send`).  While
    its line's lean lane is open (:mod:`devsim.transports.lane`) the session hands what it reads
    to the line's target itself and counts what it carries."""

    __slots__ = ("owner", "_view", "transport", "closed", "full", "state", "backlog", "peer", "since",
                 "heard", "rest", "messages", "deliver", "sock", "lane", "queued")

    def __init__(self, owner: TcpTransport, sock: socket.socket | None = None) -> None:
        self.owner = owner
        #: The connection's socket, for :meth:`send`'s direct path (None: always through asyncio).
        self.sock = sock
        #: The bytes read are copied out of a slice of it (``tobytes``: one copy, where
        #: ``bytes()`` of a bytearray's slice makes two and parses its arguments)
        self._view = _read_buffer()  # (a session is made in its loop's thread)
        self.transport: asyncio.Transport | None = None
        self.closed = False
        self.full = False  # output beyond the owner's max_buffer waits in the socket: dropped
        self.state: object = None  # per-client protocol state of subclasses (RFC 2217)
        self.backlog: deque[memoryview] = deque()  # host input not yet handed to the device
        self.peer: object = None
        self.since = 0.0  # connected at (wall clock, for the log)
        self.heard = 0.0  # last received from (time.monotonic(), for the idle drop)
        self.rest = b""  # an unfinished message (several-host ports)
        self.messages: deque[bytes] | tuple[()] = ()  # whole messages waiting for the turn
        #: The endpoint's ``feed`` while this client is the served host of a plain one-host port
        #: (what :meth:`TcpTransport._received` would call, one call and five checks less per read)
        self.deliver: Callable[[bytes], None] | None = None
        #: The line's lean lane while this session carries it (the host of a plain one-host port)
        self.lane: Lane | None = None
        #: Output handed to asyncio's transport (it may hold some unsent): later output goes after it
        self.queued = False

    def connection_made(self, transport: asyncio.BaseTransport) -> None:
        assert isinstance(transport, asyncio.Transport)
        self.transport = transport
        self.peer = transport.get_extra_info("peername")
        self.since, self.heard = time.time(), time.monotonic()
        # (asyncio says when more than max_buffer bytes wait to be sent: pause_writing)
        transport.set_write_buffer_limits(high=self.owner.max_buffer, low=self.owner.max_buffer)
        sock = transport.get_extra_info("socket")
        if sock is not None:
            with contextlib.suppress(OSError):
                sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self.owner._connected(self)
        # (after the transport's own reader, which asyncio adds in a callback of its own)
        asyncio.get_running_loop().call_soon(self.read_directly)

    def read_directly(self) -> None:
        """Let the session's :meth:`_read` take the socket's reads from the transport's reader
        (while the transport reads at all).  The transport puts its own back when it resumes
        reading (after a flood, :meth:`TcpTransport._drain`), and takes either away when it
        pauses or closes: both are the reader of the same descriptor."""
        transport, sock = self.transport, self.sock
        if transport is None or sock is None or self.closed or not transport.is_reading() or not _reads_directly(transport):
            return
        loop = asyncio.get_running_loop()
        loop._remove_reader(sock.fileno())  # type: ignore[attr-defined]
        loop._add_reader(sock.fileno(), self._read)  # type: ignore[attr-defined]

    def _read(self) -> None:
        """One read of the socket, as the transport's reader does it (asyncio's
        ``_SelectorSocketTransport._read_ready__get_buffer``: into :meth:`get_buffer`, then
        :meth:`buffer_updated`; the end of the stream and errors handed to the transport), in one
        call instead of four: a poll passes here.  On the lean lane a chunk whose reply stands
        (:class:`~devsim.core.device.Standing`) or that the face answers at once goes back here
        without the port (what :meth:`~devsim.core.device.Port.feed` would write)."""
        transport = self.transport
        try:
            nbytes = self.sock.recv_into(self._view)  # type: ignore[union-attr]
        except (BlockingIOError, InterruptedError):
            return
        except (SystemExit, KeyboardInterrupt):
            raise
        except BaseException as exc:
            transport._fatal_error(exc, "Fatal read error on socket transport")  # type: ignore[union-attr]
            return
        if not nbytes:
            transport._read_ready__on_eof()  # type: ignore[union-attr]
            return
        try:
            lane = self.lane
            if lane is None or nbytes > SLICE or self.backlog:
                self.buffer_updated(nbytes)
                return
            self.heard = time.monotonic()
            lane.bytes_in += nbytes
            data = self._view[:nbytes].tobytes()
            if (standing := lane.standing) is not None and (reply := standing.given(data)) is not None:
                self.send(reply)  # (nothing changed since it was held)
            elif (at_once := lane.at_once) is not None and (reply := at_once(data)) is not None:
                if reply:
                    self.send(reply)
            else:
                lane.feed(data)
        except (SystemExit, KeyboardInterrupt):
            raise
        except BaseException as exc:
            transport._fatal_error(exc, "Fatal error: protocol.buffer_updated() call failed.")  # type: ignore[union-attr]

    def get_buffer(self, sizehint: int) -> memoryview:
        return self._view

    def buffer_updated(self, nbytes: int) -> None:
        self.heard = time.monotonic()
        data = self._view[:nbytes].tobytes()
        lane = self.lane
        if lane is not None and nbytes <= SLICE and not self.backlog:
            lane.bytes_in += nbytes
            lane.feed(data)  # (the port gives a standing reply, or one made at once, itself)
            return
        deliver = self.deliver
        if deliver is not None and nbytes <= SLICE and not self.backlog:
            deliver(data)
        else:
            self.owner._received(self, data)

    def eof_received(self) -> bool:
        return False  # half-close ends the session

    def connection_lost(self, exc: Exception | None) -> None:
        self.closed = True
        self.owner._lost(self)

    def pause_writing(self) -> None:
        self.full = True  # more than the owner's max_buffer bytes wait to be sent

    def resume_writing(self) -> None:
        self.full = False

    def send(self, data: bytes) -> None:
        """Bytes for the client (on the lean lane: the target's output, counted for the line)."""
        size = len(data)
        lane = self.lane
        if lane is not None:
            lane.bytes_out += size
        transport = self.transport
        if transport is None or self.closed or transport.is_closing():
            return
        if self.full:
            self.owner.dropped += size
            return
        if self.queued:
            if transport.get_write_buffer_size():
                transport.write(data)  # (after what asyncio holds unsent)
                return
            self.queued = False  # what asyncio held has gone out
        sock = self.sock
        if sock is not None:
            # what transport.write does first when nothing waits to be sent, without its checks;
            # what the socket does not take now (or an error) goes the usual way
            try:
                sent = sock.send(data)
            except (BlockingIOError, InterruptedError):
                sent = 0
            except OSError:
                sent = 0  # (transport.write meets the error again and closes the connection)
            if sent == size:
                return
            data = data[sent:]
        self.queued = True
        transport.write(data)


class TcpTransport(Transport):
    """A raw TCP server port serving one endpoint to ``hosts`` clients at once (default one)."""

    scheme = "socket"

    def __init__(self, host: str = "127.0.0.1", port: int = 0, *, max_buffer: int = 64 * 1024,
                 hosts: int = 1, idle_drop: float = DEFAULT_IDLE_DROP) -> None:
        self.host = host
        self.port = port
        self.max_buffer = max_buffer
        self.address = ""
        #: Bytes dropped because the client did not read them.
        self.dropped = 0
        #: Clients refused (the port full) and idle hosts dropped for a newcomer.
        self.refused = 0
        self.idle_dropped = 0
        self.hosts = hosts
        self.idle_drop = idle_drop
        #: How a several-host port cuts a host's bytes into messages (None: each chunk read is one).
        self.split: Callable[[bytes], tuple[list[bytes], bytes]] | None = None
        self._server: socket.socket | None = None
        self._loop: asyncio.AbstractEventLoop | None = None
        self._paused: asyncio.TimerHandle | None = None
        self._endpoint: Endpoint | None = None
        self._active: _Session | None = None  # the host; on a several-host port, the one answered
        self._served: list[_Session] = []
        self._ready: deque[_Session] | tuple[()] = ()  # several-host: hosts with messages waiting
        self._turn: _Session | None = None
        self._owed = 0  # messages of the turn's host not answered yet
        self._turn_timer: asyncio.TimerHandle | None = None
        #: No protocol variant: the client's bytes go to the endpoint as they are, and back.
        self._plain = type(self)._session_data is TcpTransport._session_data

    def limit_hosts(self, hosts: int, idle_drop: float | None = None,
                    split: Callable[[bytes], tuple[list[bytes], bytes]] | None = None) -> None:
        """Serve ``hosts`` clients at once (a one-host port: 1); drop a host idle for longer than
        ``idle_drop`` seconds when another client waits; ``split`` cuts a host's bytes into
        messages on a several-host port (the port's declared framing).  Before :meth:`start`."""
        if hosts < 1:
            raise ValueError(f"a port serves at least one host, not {hosts}")
        self.hosts = hosts
        if idle_drop is not None:
            self.idle_drop = idle_drop
        self.split = split

    @property
    def url(self) -> str:
        host = f"[{self.host}]" if ":" in self.host else self.host
        return f"{self.scheme}://{host}:{self.port}"

    @property
    def connected(self) -> bool:
        """Whether a client is being served."""
        return bool(self._served)

    @property
    def clients(self) -> int:
        """How many clients are being served."""
        return len(self._served)

    @property
    def waiting(self) -> int:
        """Messages of a several-host port's hosts waiting for the turn (each host at most about
        :data:`MAX_WAITING`, and what its last read brought)."""
        return sum(len(session.messages) for session in self._served)

    def trace_peers(self) -> tuple[tuple[str, int], tuple[str, int]] | None:
        """The serving client's address and the listening address (``None`` with no client)."""
        session = self._active
        if session is None or session.transport is None:
            return None
        peer = session.transport.get_extra_info("peername")
        if not peer:
            return None
        return (str(peer[0]), int(peer[1])), (self.host, self.port)

    async def start(self, endpoint: Endpoint) -> None:
        if self._server is not None:
            raise RuntimeError("transport already started")
        loop = asyncio.get_running_loop()
        family = socket.AF_INET6 if ":" in self.host else socket.AF_INET
        listener = socket.create_server((self.host, self.port), family=family, backlog=listen_backlog(),
                                        reuse_port=False)
        listener.setblocking(False)
        self._loop = loop
        self._endpoint = endpoint
        self._server = listener
        self.port = listener.getsockname()[1]
        host = f"[{self.host}]" if ":" in self.host else self.host
        self.address = f"{host}:{self.port}"
        fdlimit.keep_reserve()
        loop.add_reader(listener.fileno(), self._accept)
        offer = getattr(endpoint, "offer_lane", None)  # (a line; other endpoints have no lean lane)
        if offer is not None and self._plain and self.hosts == 1 and type(self)._send is TcpTransport._send:
            offer(self._take_lane)

    def _accept(self) -> None:
        listener, loop = self._server, self._loop
        if listener is None or loop is None:
            return
        for _ in range(16):  # a bounded share of one loop turn
            try:
                conn, _addr = listener.accept()
            except (BlockingIOError, InterruptedError):
                return
            except OSError as exc:
                if not fdlimit.is_out_of_fds(exc):
                    fdlimit.report(f"accept {self.address}", f"{self.address}: accept failed: {exc}")
                    return
                refused = fdlimit.shed(listener)
                fdlimit.report(
                    "accept",
                    f"out of file descriptors (limit {fdlimit.fd_limit()}): refusing connections"
                    f" on {self.address} and other ports",
                )
                if not refused:  # no reserve left: look again in a moment instead of spinning
                    self._pause(loop, listener)
                return
            conn.setblocking(False)
            loop.create_task(self._adopt(loop, conn))

    async def _adopt(self, loop: asyncio.AbstractEventLoop, conn: socket.socket) -> None:
        try:
            await loop.connect_accepted_socket(lambda: _Session(self, conn), conn)
        except OSError:
            conn.close()

    def _pause(self, loop: asyncio.AbstractEventLoop, listener: socket.socket) -> None:
        loop.remove_reader(listener.fileno())

        def resume() -> None:
            self._paused = None
            if self._server is listener:
                loop.add_reader(listener.fileno(), self._accept)

        self._paused = loop.call_later(0.5, resume)

    async def close(self) -> None:
        server, self._server = self._server, None
        if server is None:
            return
        if self._paused is not None:
            self._paused.cancel()
        if self._turn_timer is not None:
            self._turn_timer.cancel()
        if self._loop is not None:
            self._loop.remove_reader(server.fileno())
        server.close()
        offer = getattr(self._endpoint, "offer_lane", None)
        if offer is not None:
            offer(None)
        sessions, self._served, self._ready, self._turn = list(self._served), [], (), None
        for session in sessions:
            session.deliver = session.lane = None
            if session.transport is not None:
                session.transport.abort()
        if sessions:  # abort() reports connection_lost on the next loop turn
            self._detach()
        self._active = None
        self._endpoint = None

    # -- sessions ---------------------------------------------------------------------------
    def _connected(self, session: _Session) -> None:
        assert session.transport is not None
        if self._server is None:
            session.transport.abort()
            return
        admission = admit(self._served, self.hosts, self.idle_drop, _heard)
        if admission.action == "refuse":
            self.refused += 1
            refuse(self.address, session.peer, self.hosts, [(s.peer, s.since) for s in self._served])
            session.transport.close()
            return
        if admission.action == "drop":
            victim = admission.victim
            assert isinstance(victim, _Session)
            self.idle_dropped += 1
            dropped(self.address, victim.peer, time.monotonic() - victim.heard, session.peer)
            if victim.transport is not None:
                victim.transport.abort()
            self._lost(victim)  # (its connection_lost comes later and finds it gone)
        self._served.append(session)
        if self.hosts == 1:
            self._activate(session)
        elif len(self._served) == 1 and self._endpoint is not None:
            self._endpoint.attach(self._turn_output)  # (once: the line sees one connect, not one per turn)

    def _activate(self, session: _Session) -> None:
        self._active = session
        endpoint = self._endpoint
        if endpoint is None:
            return
        self._session_started(session, endpoint)
        # (the endpoint is detached again when the session ends: _detach; a plain TCP port
        # hands the device's output to the session itself: one call less per answer)
        plain = type(self)._send is TcpTransport._send
        endpoint.attach(session.send if plain else functools.partial(self._send, session))
        if self._plain:
            session.deliver = endpoint.feed

    def _take_lane(self, lane: Lane | None) -> Callable[[bytes], None] | None:
        """The line's lean lane (:meth:`Line.offer_lane <devsim.transports.line.Line.offer_lane>`):
        carried by the session of the host; ``None``: closed again."""
        for served in self._served:
            served.lane = None
        session = self._active
        if lane is None or session is None or session.closed or self._endpoint is None:
            return None
        session.lane = lane
        return session.send

    def _detach(self) -> None:
        self._active = None
        endpoint = self._endpoint
        if endpoint is not None:
            endpoint.attach(None)
            endpoint.host_disconnected()

    def _received(self, session: _Session, data: bytes) -> None:
        if self.hosts > 1:
            self._message_data(session, data)
            return
        if self._active is not session or self._endpoint is None:
            return
        if session.backlog or len(data) > SLICE:
            self._queue_input(session, data)
        elif self._plain:
            self._endpoint.feed(data)  # (what _session_data does for a plain TCP port)
        else:
            self._session_data(session, data, self._endpoint)

    def _queue_input(self, session: _Session, data: bytes) -> None:
        """A big chunk (noise, a flood) goes to the device :data:`SLICE` bytes per loop turn,
        with reading paused meanwhile, so the other ports of the process are served between."""
        first = not session.backlog
        session.backlog.append(memoryview(data))
        if session.transport is not None:
            session.transport.pause_reading()
        if first and self._loop is not None:
            self._loop.call_soon(self._drain, session)

    def _drain(self, session: _Session) -> None:
        if self._active is not session or self._endpoint is None or session.closed:
            session.backlog.clear()
            return
        head = session.backlog[0]
        piece, rest = head[:SLICE], head[SLICE:]
        if len(rest):
            session.backlog[0] = rest
        else:
            session.backlog.popleft()
        self._session_data(session, bytes(piece), self._endpoint)
        if session.backlog:
            assert self._loop is not None
            self._loop.call_soon(self._drain, session)
        elif session.transport is not None and not session.transport.is_closing():
            session.transport.resume_reading()
            session.read_directly()

    def _lost(self, session: _Session) -> None:
        session.deliver = session.lane = None
        if session not in self._served:
            return
        self._served.remove(session)
        session.messages = ()
        if session in self._ready:
            self._ready.remove(session)  # type: ignore[union-attr]
        if self._turn is session:
            self._end_turn()
        if not self._served:
            self._detach()
        elif self._active is session:
            self._active = None

    # -- several hosts: one message at a time, the answer to its sender ----------------------
    def _message_data(self, session: _Session, data: bytes) -> None:
        if session not in self._served or self._endpoint is None:
            return
        if self.split is None:
            messages, session.rest = [data], b""
        else:
            messages, session.rest = self.split(session.rest + data)
            if len(session.rest) > SLICE:  # no message ends in sight: hand it on as it is
                messages, session.rest = [*messages, session.rest], b""
        if not messages:
            return
        if not session.messages:
            session.messages = deque()
        was_waiting = bool(session.messages)
        session.messages.extend(messages)  # type: ignore[union-attr]
        if len(session.messages) >= MAX_WAITING and session.transport is not None:
            session.transport.pause_reading()  # (resumed by _next_turn as the device takes them)
        if not was_waiting and session is not self._turn:
            if not self._ready:
                self._ready = deque()
            self._ready.append(session)  # type: ignore[union-attr]
        if self._turn is None or self._turn is session:
            self._next_turn(session if self._turn is session else None)

    def _next_turn(self, holder: _Session | None = None) -> None:
        """Hand the device the next message: ``holder``'s (it has the turn), else the first
        waiting host's."""
        endpoint = self._endpoint
        if endpoint is None:
            return
        session = holder
        if session is None or not session.messages:
            if not self._ready:
                return
            session = self._ready.popleft()  # type: ignore[union-attr]
        if self._turn_timer is not None:
            self._turn_timer.cancel()
        if self._turn is not session:
            self._turn, self._owed = session, 0
        self._owed += 1
        self._active = session  # the device's output goes to it (_turn_output)
        message = session.messages.popleft()  # type: ignore[union-attr]
        transport = session.transport
        if len(session.messages) < MAX_WAITING and transport is not None and not transport.is_reading() \
                and not transport.is_closing():
            transport.resume_reading()
            session.read_directly()
        if session.messages and session not in self._ready and holder is None:
            self._ready.append(session)  # type: ignore[union-attr]
        assert self._loop is not None
        self._turn_timer = self._loop.call_later(TURN_GRACE, self._end_turn)
        endpoint.feed(message)

    def _turn_output(self, data: bytes) -> None:
        """The device's output on a several-host port: to the host whose message it answers."""
        session = self._active
        if session is None:
            return
        self._send(session, data)
        if self._turn is session:
            self._owed -= 1
            if self._owed <= 0:
                self._end_turn()

    def _end_turn(self) -> None:
        if self._turn_timer is not None:
            self._turn_timer.cancel()
            self._turn_timer = None
        holder, self._turn, self._owed = self._turn, None, 0
        if holder is not None and holder.messages and holder not in self._ready:
            if not self._ready:
                self._ready = deque()
            self._ready.append(holder)  # type: ignore[union-attr]
        if self._loop is not None and self._ready:
            self._loop.call_soon(self._next_turn)

    # -- hooks for protocol variants (RFC 2217) ---------------------------------------------
    def _session_started(self, session: _Session, endpoint: Endpoint) -> None:
        """A client became the host."""

    def _session_data(self, session: _Session, data: bytes, endpoint: Endpoint) -> None:
        """Bytes from the serving client."""
        endpoint.feed(data)

    def _send(self, session: _Session, data: bytes) -> None:
        """Device output to the serving client."""
        session.send(data)


def _reads_directly(transport: asyncio.BaseTransport) -> bool:
    """Whether a session may read its socket itself (:meth:`_Session.read_directly`): the
    transport is asyncio's selector socket transport of this Python, with the parts the session's
    reader hands the end of the stream and errors to, on a selector loop (not another loop's
    transport, where the session reads through the transport as any protocol)."""
    loop = asyncio.get_running_loop()
    return (isinstance(transport, _SOCKET_TRANSPORT) and isinstance(loop, asyncio.selector_events.BaseSelectorEventLoop)
            and all(hasattr(transport, name) for name in ("_fatal_error", "_read_ready__on_eof"))
            and all(hasattr(loop, name) for name in ("_add_reader", "_remove_reader")))


#: asyncio's socket transport of a selector loop (private to asyncio: what :func:`_reads_directly` checks)
_SOCKET_TRANSPORT: type = getattr(asyncio.selector_events, "_SelectorSocketTransport", type(None))


def _heard(session: _Session) -> float:
    return session.heard
