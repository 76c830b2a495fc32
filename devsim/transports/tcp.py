"""Raw TCP, like a serial device server (Moxa NPort, Lantronix in "TCP server" mode).

Bytes on the socket are bytes on the serial line, nothing else: a raw client cannot tell the
device its line settings, so the line treats it as matching.  Open it with pyserial as
``socket://HOST:PORT`` (:attr:`TcpTransport.url`).

**One host at a time.**  A serial port has one host, so the transport serves clients one after
another: a client that connects while another one is being served is accepted by the kernel but
*waits* – nothing is read from it and nothing is sent to it – until every earlier client has
disconnected; then it becomes the host, and whatever it sent in the meantime reaches the device
in order.  A waiting client that gives up is noticed only when its turn comes.

When the serving client disconnects, the endpoint gets ``host_disconnected()``.  Output that a
client does not read piles up in the socket; beyond ``max_buffer`` bytes further output is
dropped, as on a line nobody listens to.  The server binds to loopback unless told otherwise.

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
from collections import deque

from devsim.transports import fdlimit
from devsim.transports.base import Endpoint, Transport

__all__ = ["SLICE", "TcpTransport"]

#: Most host bytes handed to a device in one loop turn (the rest waits for the next turns).
SLICE = 16 * 1024
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
    """One TCP client; the owning transport decides whether it is the host or waits."""

    def __init__(self, owner: TcpTransport) -> None:
        self.owner = owner
        self._view = _read_buffer()  # (a session is made in its loop's thread)
        self.transport: asyncio.Transport | None = None
        self.closed = False
        self.state: object = None  # per-client protocol state of subclasses (RFC 2217)
        self.backlog: deque[memoryview] = deque()  # host input not yet handed to the device

    def connection_made(self, transport: asyncio.BaseTransport) -> None:
        assert isinstance(transport, asyncio.Transport)
        self.transport = transport
        sock = transport.get_extra_info("socket")
        if sock is not None:
            with contextlib.suppress(OSError):
                sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self.owner._connected(self)

    def get_buffer(self, sizehint: int) -> memoryview:
        return self._view

    def buffer_updated(self, nbytes: int) -> None:
        self.owner._received(self, bytes(self._view[:nbytes]))

    def eof_received(self) -> bool:
        return False  # half-close ends the session

    def connection_lost(self, exc: Exception | None) -> None:
        self.closed = True
        self.owner._lost(self)

    def send(self, data: bytes) -> None:
        if self.closed or self.transport is None or self.transport.is_closing():
            return
        if self.transport.get_write_buffer_size() > self.owner.max_buffer:
            self.owner.dropped += len(data)
            return
        self.transport.write(data)


class TcpTransport(Transport):
    """A raw TCP server port serving one endpoint, one client at a time."""

    scheme = "socket"

    def __init__(self, host: str = "127.0.0.1", port: int = 0, *, max_buffer: int = 64 * 1024) -> None:
        self.host = host
        self.port = port
        self.max_buffer = max_buffer
        self.address = ""
        #: Bytes dropped because the client did not read them.
        self.dropped = 0
        self._server: socket.socket | None = None
        self._loop: asyncio.AbstractEventLoop | None = None
        self._paused: asyncio.TimerHandle | None = None
        self._endpoint: Endpoint | None = None
        self._active: _Session | None = None
        self._waiting: deque[_Session] | tuple[()] = ()  # a deque when a second client waits
        #: No protocol variant: the client's bytes go to the endpoint as they are, and back.
        self._plain = type(self)._session_data is TcpTransport._session_data

    @property
    def url(self) -> str:
        host = f"[{self.host}]" if ":" in self.host else self.host
        return f"{self.scheme}://{host}:{self.port}"

    @property
    def connected(self) -> bool:
        """Whether a client is being served."""
        return self._active is not None

    def trace_peers(self) -> tuple[tuple[str, int], tuple[str, int]] | None:
        """The serving client's address and the listening address (``None`` with no client)."""
        session = self._active
        if session is None or session.transport is None:
            return None
        peer = session.transport.get_extra_info("peername")
        if not peer:
            return None
        return (str(peer[0]), int(peer[1])), (self.host, self.port)

    @property
    def waiting(self) -> int:
        """Clients queued behind the one being served."""
        return len(self._waiting)

    async def start(self, endpoint: Endpoint) -> None:
        if self._server is not None:
            raise RuntimeError("transport already started")
        loop = asyncio.get_running_loop()
        family = socket.AF_INET6 if ":" in self.host else socket.AF_INET
        listener = socket.create_server((self.host, self.port), family=family, backlog=16, reuse_port=False)
        listener.setblocking(False)
        self._loop = loop
        self._endpoint = endpoint
        self._server = listener
        self.port = listener.getsockname()[1]
        host = f"[{self.host}]" if ":" in self.host else self.host
        self.address = f"{host}:{self.port}"
        fdlimit.keep_reserve()
        loop.add_reader(listener.fileno(), self._accept)

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
            await loop.connect_accepted_socket(lambda: _Session(self), conn)
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
        if self._loop is not None:
            self._loop.remove_reader(server.fileno())
        server.close()
        sessions = ([self._active] if self._active else []) + list(self._waiting)
        self._waiting = ()
        for session in sessions:
            if session.transport is not None:
                session.transport.abort()
        if self._active is not None:  # abort() reports connection_lost on the next loop turn
            self._deactivate(self._active)
        self._endpoint = None

    # -- sessions ---------------------------------------------------------------------------
    def _connected(self, session: _Session) -> None:
        if self._server is None:
            assert session.transport is not None
            session.transport.abort()
            return
        if self._active is None:
            self._activate(session)
        else:
            assert session.transport is not None
            session.transport.pause_reading()
            if not self._waiting:
                self._waiting = deque()
            self._waiting.append(session)

    def _activate(self, session: _Session) -> None:
        self._active = session
        endpoint = self._endpoint
        if endpoint is None:
            return
        self._session_started(session, endpoint)

        # (the endpoint is detached again when the session ends: _deactivate; a plain TCP port
        # hands the device's output to the session itself: one call less per answer)
        plain = type(self)._send is TcpTransport._send
        endpoint.attach(session.send if plain else functools.partial(self._send, session))

    def _deactivate(self, session: _Session) -> None:
        if self._active is not session:
            return
        self._active = None
        endpoint = self._endpoint
        if endpoint is not None:
            endpoint.attach(None)
            endpoint.host_disconnected()

    def _received(self, session: _Session, data: bytes) -> None:
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

    def _lost(self, session: _Session) -> None:
        if self._active is session:
            self._deactivate(session)
            while self._waiting and self._active is None:
                nxt = self._waiting.popleft()  # type: ignore[union-attr]
                if nxt.closed:
                    continue
                self._activate(nxt)
                if nxt.transport is not None:
                    nxt.transport.resume_reading()
        elif session in self._waiting:
            self._waiting.remove(session)  # type: ignore[union-attr]

    # -- hooks for protocol variants (RFC 2217) ---------------------------------------------
    def _session_started(self, session: _Session, endpoint: Endpoint) -> None:
        """A client became the host."""

    def _session_data(self, session: _Session, data: bytes, endpoint: Endpoint) -> None:
        """Bytes from the serving client."""
        endpoint.feed(data)

    def _send(self, session: _Session, data: bytes) -> None:
        """Device output to the serving client."""
        session.send(data)
