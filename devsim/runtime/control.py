"""The control API out of process: newline-delimited JSON over a Unix socket or loopback TCP.

In process the control API is :func:`devsim.runtime.ops.run` with a typed request (or the
:class:`devsim.runtime.Runtime`'s own methods).  ``devsim run --control ADDR`` puts a
:class:`ControlServer` in front of the same op table; :class:`devsim.runtime.client.ControlClient`
is a small blocking client with a method per op, and ``devsim ctl`` is a command line on top of
the client.

Addresses: ``unix:/path/to.sock``, or ``[HOST:]PORT`` for TCP (``tcp:`` prefix optional, IPv6
hosts in brackets).  TCP servers refuse a non-loopback host unless ``allow_remote`` is given: a
control port can move machinery.

Protocol: one JSON object per line each way; one connection serves any number of requests, in
order.  The ops, their handlers and their typed requests are one table,
:data:`devsim.runtime.ops.CONTROL`; answers are :class:`~devsim.runtime.ops.OkResponse` and
:class:`~devsim.runtime.ops.ErrorResponse`::

    → {"id": 1, "op": "read", "device": "sers", "name": "axis.position"}
    ← {"id": 1, "ok": true, "result": 0.0}
    → {"id": 2, "op": "read", "device": "sers", "name": "nope"}
    ← {"id": 2, "ok": false, "error": "sers has no 'nope'", "type": "UnknownName"}

The ops are the rows of :data:`~devsim.runtime.ops.CONTROL` (what each does: its ``doc``); the
fields of each are those of its request record in :mod:`devsim.runtime.requests` (``line_fault``'s
``params``, e.g. ``{"rate": 100}`` for ``noise``; ``telegrams`` answers a list of
``{"t", "dir", "hex", "text"}`` with ``decoded`` where the port declares its framing).

``watch`` answers once (``result``: the watched names and the device time) and then keeps
sending one line per change or event until the connection closes or the simulator stops:
``{"watch": ID, "t": 12.3, "device": "sers", "type": "change", "name": "axis.position",
"value": 1234.0}`` (types in :mod:`devsim.runtime.watch_stream`).  The connection still answers
requests meanwhile; :meth:`devsim.runtime.client.ControlClient.watch` opens a connection of its own for the stream.

``capture`` answers once (``result``: the device, port, link type, protocol and port bytes,
:func:`devsim.runtime.capture_stream.capture_info`, and the device time) and then sends one line
per chunk that crosses the port's line, ``{"capture": ID, "type": "chunk", "t": …, "dir": "H>D",
"data": HEX, "settings": {…}}``, from a bounded queue: a reader too slow for the traffic gets a
``{"capture": ID, "type": "dropped", "count": N}`` line instead of the chunks that did not fit
(:mod:`devsim.runtime.capture_stream`), and the device never waits for it.
"""

from __future__ import annotations

import asyncio
import contextlib
import os
import socket
import stat
from typing import TYPE_CHECKING, Any

import msgspec

from devsim.core.points import ascii_digits
from devsim.transports.fdlimit import CLIENT_SHARE, MAX_CLIENTS, client_bound  # (beside the ports' budget)

if TYPE_CHECKING:  # imported where used: `devsim run` serves its ports before anyone asks
    from devsim.runtime.ops import ErrorResponse, OkResponse
    from devsim.runtime.process import Runtime

__all__ = [
    "ControlAddress",
    "ControlAddressError",
    "CLIENT_SHARE",
    "MAX_CLIENTS",
    "ControlServer",
    "client_bound",
    "host_problem",
    "parse_address",
]

MAX_LINE = 1 << 20  # bytes in one request line
MAX_BACKLOG = 4 << 20  # bytes of watch output a slow reader may leave unread before its watch ends
class ControlAddressError(ValueError):
    """A control address that cannot be parsed or must not be served."""


# -- addresses -----------------------------------------------------------------------------
class ControlAddress(msgspec.Struct, frozen=True):
    """A parsed control address: ``path`` for a Unix socket, else ``host`` and ``port``."""

    path: str | None = None
    host: str = "127.0.0.1"
    port: int = 0

    @property
    def is_unix(self) -> bool:
        return self.path is not None

    def __str__(self) -> str:
        if self.path is not None:
            return f"unix:{self.path}"
        host = f"[{self.host}]" if ":" in self.host else self.host
        return f"{host}:{self.port}"

    def is_loopback(self) -> bool:
        """True for Unix sockets and for hosts that resolve only to loopback addresses."""
        if self.path is not None:
            return True
        if self.host == "localhost":
            return True
        import ipaddress

        try:
            return ipaddress.ip_address(self.host).is_loopback
        except ValueError:
            pass
        try:
            infos = socket.getaddrinfo(self.host, None)
        except OSError:
            return False
        addrs = {info[4][0] for info in infos}
        return bool(addrs) and all(ipaddress.ip_address(str(a).split("%")[0]).is_loopback for a in addrs)


def parse_address(addr: str) -> ControlAddress:
    """Parse ``unix:/path``, ``PORT``, ``HOST:PORT``, ``[V6]:PORT`` (optionally ``tcp:``-prefixed)."""
    text = addr.strip()
    if text.startswith("unix:"):
        path = text[5:]
        if not path:
            raise ControlAddressError(f"{addr!r}: unix: needs a socket path, e.g. unix:/tmp/devsim.sock")
        return ControlAddress(path=path)
    if text.startswith("tcp:"):
        text = text[4:]
    host = "127.0.0.1"
    port_text = text
    if text.startswith("["):
        end = text.find("]")
        if end < 0 or text[end + 1 : end + 2] != ":":
            raise ControlAddressError(f"{addr!r}: expected [HOST]:PORT")
        host, port_text = text[1:end], text[end + 2 :]
    elif ":" in text:
        host, _, port_text = text.rpartition(":")
        if not host:
            host = "127.0.0.1"
    if not ascii_digits(port_text):  # (int() read '٣' as port 3, and '-0')
        raise ControlAddressError(f"{addr!r}: expected unix:/path/to.sock or [HOST:]PORT")
    port = int(port_text) if len(port_text) <= 5 else -1  # (int() raises past 4300 digits)
    if not 0 <= port <= 65535:
        raise ControlAddressError(f"{addr!r}: port must be 0..65535")
    problem = host_problem(host)
    if problem is not None:
        raise ControlAddressError(f"{addr!r}: {problem}")
    return ControlAddress(host=host, port=port)


def host_problem(host: str) -> str | None:
    """Why ``host`` cannot be looked up at all (a label empty or longer than 63 characters:
    getaddrinfo's IDNA encoding raises UnicodeError, which is no OSError and was a traceback
    where an address is opened), or None."""
    try:
        host.encode("idna")
    except UnicodeError:
        return f"{host!r} is no host name (a label empty or longer than 63 characters)"
    return None


# -- server --------------------------------------------------------------------------------
class ControlServer:
    """Serves the control API of a :class:`Runtime` on a Unix socket or a TCP port.

    Runs in the runtime's event loop: ``await server.start()`` there (or ``server.start_sync()``
    from another thread when the runtime runs in its own thread).
    """

    def __init__(self, runtime: Runtime, address: str | ControlAddress, *, allow_remote: bool = False) -> None:
        self.runtime = runtime
        self.requested = parse_address(address) if isinstance(address, str) else address
        if not allow_remote and not self.requested.is_loopback():
            raise ControlAddressError(
                f"refusing to serve the control API on non-loopback host {self.requested.host!r} "
                "(pass --control-allow-remote to allow it)"
            )
        self.address: ControlAddress = self.requested
        self._server: asyncio.AbstractServer | None = None
        self._clients: set[asyncio.Task[None]] = set()
        self.max_clients = client_bound()

    async def start(self) -> ControlAddress:
        """Listen; returns the bound address (with the actual port when port 0 was asked for)."""
        req = self.requested
        if req.path is not None:
            if _is_socket(req.path):
                if _unix_socket_alive(req.path):
                    raise ControlAddressError(f"{req}: another process is serving on this socket")
                with contextlib.suppress(OSError):
                    os.unlink(req.path)  # a stale socket from a killed run
            self._server = await asyncio.start_unix_server(self._serve, path=req.path, limit=MAX_LINE)
            with contextlib.suppress(OSError):
                os.chmod(req.path, 0o600)
        else:
            self._server = await asyncio.start_server(self._serve, host=req.host, port=req.port, limit=MAX_LINE)
            sockname = self._server.sockets[0].getsockname()
            self.address = ControlAddress(host=req.host, port=int(sockname[1]))
        return self.address

    def start_sync(self) -> ControlAddress:
        return self.runtime.run(self.start())

    async def close(self) -> None:
        if self._server is not None:
            self._server.close()
            for task in list(self._clients):
                task.cancel()
            await asyncio.gather(*self._clients, return_exceptions=True)
            with contextlib.suppress(Exception):
                await asyncio.wait_for(self._server.wait_closed(), 2)
            self._server = None
            if self.address.path is not None:
                with contextlib.suppress(OSError):
                    os.unlink(self.address.path)

    def close_sync(self) -> None:
        self.runtime.run(self.close())

    async def _serve(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        # The op table is imported by the first connection, not by the start: a simulator
        # serves its ports sooner (issue 31), and most runs are never asked anything.
        from devsim.runtime import ops
        from devsim.runtime.ops import CaptureStart, ErrorResponse, OkResponse, WatchStart

        task = asyncio.current_task()
        assert task is not None
        if len(self._clients) >= self.max_clients:
            await self._refuse(reader, writer, ops.encode(ErrorResponse(
                error=f"the simulator serves at most {self.max_clients} control connections at once", type="Busy")))
            return
        self._clients.add(task)
        streams: list[Any] = []  # the watch and capture streams of this connection
        pumps: list[asyncio.Task[None]] = []
        try:
            while True:
                try:
                    raw = await reader.readline()
                except (asyncio.LimitOverrunError, ValueError):
                    writer.write(ops.encode(ErrorResponse(error="request line too long", type="BadRequest")))
                    break
                if not raw:
                    break
                if not raw.strip():
                    continue
                response = self.handle_line(raw)
                if isinstance(response, OkResponse) and isinstance(response.result, WatchStart):
                    response = self._start_watch(response, writer, streams)
                elif isinstance(response, OkResponse) and isinstance(response.result, CaptureStart):
                    response = self._start_capture(response, writer, streams, pumps)
                if response is not _ALREADY_SENT:
                    writer.write(ops.encode(response))
                await writer.drain()
        except (ConnectionError, asyncio.CancelledError):
            pass
        finally:
            for stream in streams:
                stream.stop()
            for pump in pumps:
                pump.cancel()
            self._clients.discard(task)
            with contextlib.suppress(Exception):
                writer.close()

    async def _refuse(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter, line: bytes) -> None:
        """One connection more than :attr:`max_clients`: its one error line, and a line in the
        log (at most one every few seconds, :func:`devsim.transports.fdlimit.report`).  What the
        client sent is read for a second at most before the close, so that the close does not
        reset the connection (and the error line with it) for a request left unread."""
        from devsim.transports.fdlimit import report

        report("control-full", f"control {self.address}: refused a connection, {self.max_clients} are open")
        with contextlib.suppress(Exception, asyncio.CancelledError):  # (the simulator stopping meanwhile)
            writer.write(line)
            writer.write_eof()
            async with asyncio.timeout(1.0):
                while await reader.read(MAX_LINE):
                    pass
        with contextlib.suppress(Exception):
            writer.close()

    def _start_capture(self, response: OkResponse, writer: asyncio.StreamWriter,
                       streams: list[Any],
                       pumps: list[asyncio.Task[None]]) -> OkResponse | ErrorResponse:
        """Answer a ``capture`` request, then stream the port's chunks from a bounded queue,
        as fast as the reader takes them (the answer goes out first)."""
        import json

        from devsim.runtime import ops
        from devsim.runtime.capture_stream import CaptureStream
        from devsim.runtime.ops import CaptureStart, ErrorResponse, OkResponse

        start: CaptureStart = response.result
        capture_id = response.id
        try:
            stream = CaptureStream(self.runtime, start.device, start.port)
        except Exception as exc:
            return ErrorResponse(id=capture_id, error=ops.clip(ops.error_text(exc)), type=type(exc).__name__)
        streams.append(stream)
        writer.write(ops.encode(OkResponse(id=capture_id, result={**stream.info, "t": self.runtime.clock.now()})))
        stream.start()

        async def pump() -> None:
            try:
                async for batch in stream.batches():
                    writer.write(b"".join((json.dumps({"capture": capture_id, **item}, separators=(",", ":"))
                                           + "\n").encode("utf-8") for item in batch))
                    await writer.drain()  # a slow reader waits here; its queue fills, then drops
            except (ConnectionError, RuntimeError):
                pass
            finally:
                stream.stop()

        pumps.append(asyncio.get_running_loop().create_task(pump()))
        return _ALREADY_SENT

    def _start_watch(self, response: OkResponse, writer: asyncio.StreamWriter,
                     streams: list[Any]) -> OkResponse | ErrorResponse:
        """Answer a ``watch`` request, then start its stream (the answer goes out first)."""
        import json

        from devsim.runtime import ops
        from devsim.runtime.ops import ErrorResponse, OkResponse, WatchStart
        from devsim.runtime.watch_stream import WatchStream

        start: WatchStart = response.result
        watch_id = response.id

        def send(item: dict[str, Any]) -> None:
            if writer.is_closing():
                return
            transport = writer.transport
            if transport.get_write_buffer_size() > MAX_BACKLOG:  # nobody reads: end this watch
                stream.stop()
                return
            writer.write((json.dumps({"watch": watch_id, **ops.jsonable(item)}, separators=(",", ":")) + "\n")
                         .encode("utf-8"))

        try:
            stream = WatchStream(self.runtime, self.runtime.device(start.device), send, names=start.names,
                                 period=start.period)
        except Exception as exc:
            return ErrorResponse(id=watch_id, error=ops.clip(ops.error_text(exc)), type=type(exc).__name__)
        streams.append(stream)
        writer.write(ops.encode(OkResponse(id=watch_id, result={
            "device": start.device, "names": stream.names, "period": stream.period, "t": self.runtime.clock.now()})))
        stream.start()
        return _ALREADY_SENT

    def handle_line(self, raw: bytes | str) -> OkResponse | ErrorResponse:
        """Answer one request line (runs in the loop thread)."""
        from devsim.runtime import ops

        return ops.answer(self.runtime, raw)


#: ``_start_watch`` and ``_start_capture`` wrote their answers themselves.
_ALREADY_SENT: Any = object()


def _is_socket(path: str) -> bool:
    try:
        return stat.S_ISSOCK(os.stat(path).st_mode)
    except (OSError, ValueError):
        return False


def _unix_socket_alive(path: str) -> bool:
    probe = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    try:
        probe.settimeout(0.5)
        probe.connect(path)
        return True
    except OSError:
        return False
    finally:
        probe.close()
