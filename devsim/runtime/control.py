"""The control API out of process: newline-delimited JSON over a Unix socket or loopback TCP.

In process the control API is :class:`devsim.runtime.Runtime` itself (``read``, ``set``,
``state``, ``power_cycle``, ``advance``, ``now``).  ``devsim run --control ADDR`` puts a
:class:`ControlServer` in front of the same methods; :class:`ControlClient` is a small blocking
client with the same method names, and ``devsim ctl`` is a command line on top of the client.

Addresses: ``unix:/path/to.sock``, or ``[HOST:]PORT`` for TCP (``tcp:`` prefix optional, IPv6
hosts in brackets).  TCP servers refuse a non-loopback host unless ``allow_remote`` is given: a
control port can move machinery.

Protocol: one JSON object per line each way; one connection serves any number of requests, in
order.  Requests and responses are typed (:class:`Request`, :class:`OkResponse`,
:class:`ErrorResponse`)::

    → {"id": 1, "op": "read", "device": "sers", "name": "axis.position"}
    ← {"id": 1, "ok": true, "result": 0.0}
    → {"id": 2, "op": "read", "device": "sers", "name": "nope"}
    ← {"id": 2, "ok": false, "error": "sers has no 'nope'", "type": "UnknownName"}

Ops: ``read`` (device, name), ``set`` (device, name, value), ``state`` (device),
``power_cycle`` (device, wipe), ``advance`` (seconds; virtual time only), ``now``, ``devices``,
``line`` (device, port: status of the line serving that port), ``names`` (device: its declared
points), ``fault`` (device, kind, active: a declared device fault on or off), ``line_fault``
(device, port, kind, active, params: a fault on the line serving a port, e.g. ``noise`` with
``{"rate": 100}``), ``telegrams`` (device, port, count: the last telegrams on that port's line,
each ``{"t", "dir", "hex", "text"}`` and ``decoded`` where the kind's protocol is known; kept
from the first such request on), ``watch`` (device,
names, period: a subscription, see below).

``watch`` answers once (``result``: the watched names and the device time) and then keeps
sending one line per change or event until the connection closes or the simulator stops:
``{"watch": ID, "t": 12.3, "device": "sers", "type": "change", "name": "axis.position",
"value": 1234.0}`` (types in :mod:`devsim.runtime.watch_stream`).  The connection still answers
requests meanwhile; :meth:`ControlClient.watch` opens a connection of its own for the stream.
"""

from __future__ import annotations

import asyncio
import contextlib
import enum
import ipaddress
import json
import math
import os
import socket
import threading
from collections.abc import Iterator
from pathlib import Path
from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, ValidationError

from devsim.core.points import parse_bool
from devsim.core.record import asdict, is_record, record
from devsim.runtime.process import Runtime, port_key
from devsim.runtime.watch_stream import WatchStream

__all__ = [
    "BadRequest",
    "ControlAddress",
    "ControlAddressError",
    "ControlClient",
    "ControlError",
    "ControlOps",
    "ControlServer",
    "ErrorResponse",
    "OkResponse",
    "Op",
    "Request",
    "parse_address",
]

Op = Literal["read", "set", "state", "power_cycle", "advance", "now", "devices", "line", "names", "fault", "line_fault",
             "telegrams", "watch"]

MAX_LINE = 1 << 20  # bytes in one request line
MAX_DEPTH = 64  # nesting of lists and objects in one request
MAX_BACKLOG = 4 << 20  # bytes of watch output a slow reader may leave unread before its watch ends


# -- messages ------------------------------------------------------------------------------
class Request(BaseModel):
    """One control request."""

    model_config = ConfigDict(extra="forbid")

    id: int | str | None = None
    op: Op
    device: str | None = None
    name: str | None = None
    value: Any = None
    wipe: bool = False
    seconds: float | None = None
    port: str = "main"
    kind: str | None = None
    active: Any = True
    params: dict[str, Any] = {}
    names: list[str] | None = None
    period: float | None = None
    count: int = 20


class OkResponse(BaseModel):
    id: int | str | None = None
    ok: Literal[True] = True
    result: Any = None


class ErrorResponse(BaseModel):
    id: int | str | None = None
    ok: Literal[False] = False
    error: str
    type: str


class ControlError(Exception):
    """The server answered with an error; ``type`` is the server-side exception's class name
    (``UnknownName``, ``UnknownDevice``, ``BadRequest``, ``RuntimeError``, ...)."""

    def __init__(self, message: str, type: str = "Error") -> None:  # noqa: A002 - protocol name
        super().__init__(message)
        self.type = type

    def __str__(self) -> str:
        return f"{self.type}: {self.args[0]}"


class ControlAddressError(ValueError):
    """A control address that cannot be parsed or must not be served."""


# -- addresses -----------------------------------------------------------------------------
@record
class ControlAddress:
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
    try:
        port = int(port_text)
    except ValueError:
        raise ControlAddressError(
            f"{addr!r}: expected unix:/path/to.sock or [HOST:]PORT"
        ) from None
    if not 0 <= port <= 65535:
        raise ControlAddressError(f"{addr!r}: port must be 0..65535")
    return ControlAddress(host=host, port=port)


# -- server --------------------------------------------------------------------------------
def _jsonable(value: Any) -> Any:
    """Make results JSON-safe (tuples, sets, bytes, enums, records, non-finite floats)."""
    if value is None or isinstance(value, bool | int | str):
        return value
    if isinstance(value, float):
        return value if math.isfinite(value) else str(value)
    if isinstance(value, dict):
        return {str(k): _jsonable(v) for k, v in value.items()}
    if isinstance(value, list | tuple | set | frozenset):
        return [_jsonable(v) for v in value]
    if isinstance(value, bytes | bytearray):
        return value.decode("latin-1")
    if isinstance(value, BaseModel):
        return _jsonable(value.model_dump(mode="json"))
    if isinstance(value, enum.Enum):
        return _jsonable(value.value)
    if is_record(value):
        return _jsonable(asdict(value))
    return str(value)


def _clip(text: str, limit: int = 300) -> str:
    """Error texts never echo a huge request back."""
    return text if len(text) <= limit else text[: limit - 3] + "..."


def _depth(value: Any) -> int:
    """Nesting depth of parsed JSON, iteratively (no recursion on hostile input)."""
    deepest = 0
    stack = [(value, 1)]
    while stack:
        node, depth = stack.pop()
        if isinstance(node, dict | list):
            deepest = max(deepest, depth)
            if depth > MAX_DEPTH:
                return depth
            stack.extend((child, depth + 1) for child in (node.values() if isinstance(node, dict) else node))
    return deepest


def _error_text(exc: BaseException) -> str:
    if isinstance(exc, KeyError) and len(exc.args) == 1 and isinstance(exc.args[0], str):
        return exc.args[0]  # KeyError's str() would add quotes
    return str(exc) or type(exc).__name__


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

    async def start(self) -> ControlAddress:
        """Listen; returns the bound address (with the actual port when port 0 was asked for)."""
        req = self.requested
        if req.path is not None:
            path = Path(req.path)
            if path.is_socket():
                if _unix_socket_alive(req.path):
                    raise ControlAddressError(f"{req}: another process is serving on this socket")
                with contextlib.suppress(OSError):
                    path.unlink()  # a stale socket from a killed run
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
        task = asyncio.current_task()
        assert task is not None
        self._clients.add(task)
        streams: list[WatchStream] = []
        try:
            while True:
                try:
                    raw = await reader.readline()
                except (asyncio.LimitOverrunError, ValueError):
                    writer.write(self._encode(ErrorResponse(error="request line too long", type="BadRequest")))
                    break
                if not raw:
                    break
                if not raw.strip():
                    continue
                response = self.handle_line(raw)
                if isinstance(response, OkResponse) and isinstance(response.result, _WatchStart):
                    response = self._start_watch(response, writer, streams)
                if response is not _ALREADY_SENT:
                    writer.write(self._encode(response))
                await writer.drain()
        except (ConnectionError, asyncio.CancelledError):
            pass
        finally:
            for stream in streams:
                stream.stop()
            self._clients.discard(task)
            with contextlib.suppress(Exception):
                writer.close()

    def _start_watch(self, response: OkResponse, writer: asyncio.StreamWriter,
                     streams: list[WatchStream]) -> OkResponse | ErrorResponse:
        """Answer a ``watch`` request, then start its stream (the answer goes out first)."""
        start: _WatchStart = response.result
        watch_id = response.id

        def send(item: dict[str, Any]) -> None:
            if writer.is_closing():
                return
            transport = writer.transport
            if transport.get_write_buffer_size() > MAX_BACKLOG:  # nobody reads: end this watch
                stream.stop()
                return
            writer.write((json.dumps({"watch": watch_id, **_jsonable(item)}, separators=(",", ":")) + "\n")
                         .encode("utf-8"))

        try:
            stream = WatchStream(self.runtime, self.runtime.device(start.device), send, names=start.names,
                                 period=start.period)
        except Exception as exc:
            return ErrorResponse(id=watch_id, error=_clip(_error_text(exc)), type=type(exc).__name__)
        streams.append(stream)
        writer.write(self._encode(OkResponse(id=watch_id, result={
            "device": start.device, "names": stream.names, "period": stream.period, "t": self.runtime.clock.now()})))
        stream.start()
        return _ALREADY_SENT

    @staticmethod
    def _encode(response: OkResponse | ErrorResponse) -> bytes:
        data = response.model_dump()
        if isinstance(response, OkResponse):
            data["result"] = _jsonable(response.result)
        return (json.dumps(data, separators=(",", ":")) + "\n").encode("utf-8")

    def handle_line(self, raw: bytes | str) -> OkResponse | ErrorResponse:
        """Answer one request line (runs in the loop thread)."""
        try:
            payload = json.loads(raw)
        except RecursionError:
            return ErrorResponse(error=f"request nested deeper than {MAX_DEPTH} levels", type="BadRequest")
        except ValueError as exc:
            return ErrorResponse(error=f"not JSON: {_clip(str(exc))}", type="BadRequest")
        if _depth(payload) > MAX_DEPTH:
            return ErrorResponse(error=f"request nested deeper than {MAX_DEPTH} levels", type="BadRequest")
        req_id = payload.get("id") if isinstance(payload, dict) else None
        if not isinstance(req_id, int | str):
            req_id = None
        try:
            request = Request.model_validate(payload)
        except ValidationError as exc:
            first = exc.errors()[0]
            where = ".".join(str(p) for p in first.get("loc", ())) or "request"
            return ErrorResponse(id=req_id, error=_clip(f"{where}: {first.get('msg')}"), type="BadRequest")
        try:
            return OkResponse(id=request.id, result=self.execute(request))
        except Exception as exc:  # every failure becomes a typed error response
            return ErrorResponse(id=request.id, error=_clip(_error_text(exc)), type=type(exc).__name__)

    def execute(self, req: Request) -> Any:
        """Run one validated request against the runtime."""
        rt = self.runtime
        op = req.op
        if op == "now":
            return rt.now()
        if op == "devices":
            return [
                {
                    "name": name,
                    "kind": dev.kind,
                    "port": rt.ports.get(port_key(name, dev.port_names()[0])),
                    "ports": {p: rt.ports.get(port_key(name, p)) for p in dev.port_names()},
                    "faults": dev.faults.names(),
                }
                for name, dev in rt.devices.items()
            ]
        if op == "advance":
            if req.seconds is None:
                raise BadRequest("advance needs 'seconds'")
            if not math.isfinite(req.seconds) or req.seconds < 0:
                raise BadRequest("'seconds' must be a finite number, not negative")
            return rt.advance(req.seconds)
        device = _need(req.device, "device", op)
        if op == "state":
            return rt.state(device)
        if op == "power_cycle":
            rt.power_cycle(device, wipe=req.wipe)
            return None
        if op == "line":
            rt.device(device)
            return rt.line_status(device, req.port)
        if op == "names":
            return rt.names(device)
        if op == "fault":
            rt.fault(device, _need(req.kind, "kind", op), req.active)
            return None
        if op == "telegrams":
            from devsim.replay.kinds import protocol_of
            from devsim.transports.tap import tap

            line = self.runtime.lines.get(port_key(device, req.port))
            if line is None:
                rt.line_status(device, req.port)  # the reason: no such device, port or line
            decoder = protocol_of(rt.device(device).kind, req.port).decoder
            return tap(line, decoder).last(max(0, min(req.count, 200)))
        if op == "watch":
            if req.period is not None and not (math.isfinite(req.period) and req.period > 0):
                raise BadRequest("'period' must be a positive number of seconds")
            rt.device(device)
            return _WatchStart(device=device, names=req.names, period=req.period)
        if op == "line_fault":
            rt.line_fault(device, _need(req.kind, "kind", op), parse_bool(req.active), port=req.port, **req.params)
            return None
        name = _need(req.name, "name", op)
        if op == "read":
            return rt.read(device, name)
        if op == "set":
            rt.set(device, name, req.value)
            return None
        raise BadRequest(f"unknown op {op!r}")  # pragma: no cover - Request validates op


@record
class _WatchStart:
    """What ``execute`` hands ``_serve`` for a ``watch`` request: the stream needs the connection."""

    device: str
    names: list[str] | None = None
    period: float | None = None


#: ``_start_watch`` wrote its answer itself.
_ALREADY_SENT = ErrorResponse(error="", type="")


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


class BadRequest(ValueError):
    """A request that is well-formed JSON but misses what its op needs."""


def _need(value: str | None, field: str, op: str) -> str:
    if not value:
        raise BadRequest(f"{op} needs {field!r}")
    return value


# -- client --------------------------------------------------------------------------------
class ControlOps:
    """The control API's operations as methods over one ``request(op, **fields)``: shared by the
    socket client (:class:`ControlClient`) and the fleet's (:class:`devsim.fleet.client.FleetClient`)."""

    def request(self, op: str, **fields: Any) -> Any:
        raise NotImplementedError

    def read(self, device: str, name: str) -> Any:
        return self.request("read", device=device, name=name)

    def set(self, device: str, name: str, value: Any) -> None:
        self.request("set", device=device, name=name, value=value)

    def state(self, device: str) -> dict[str, Any]:
        result: dict[str, Any] = self.request("state", device=device)
        return result

    def power_cycle(self, device: str, *, wipe: bool = False) -> None:
        self.request("power_cycle", device=device, wipe=wipe)

    def advance(self, seconds: float) -> float:
        return float(self.request("advance", seconds=seconds))

    def now(self) -> float:
        return float(self.request("now"))

    def devices(self) -> list[dict[str, Any]]:
        result: list[dict[str, Any]] = self.request("devices")
        return result

    def line(self, device: str, port: str = "main") -> dict[str, Any]:
        result: dict[str, Any] = self.request("line", device=device, port=port)
        return result

    def names(self, device: str) -> list[dict[str, Any]]:
        result: list[dict[str, Any]] = self.request("names", device=device)
        return result

    def fault(self, device: str, kind: str, active: bool = True) -> None:
        self.request("fault", device=device, kind=kind, active=active)

    def line_fault(self, device: str, kind: str, active: bool = True, *, port: str = "main", **params: Any) -> None:
        self.request("line_fault", device=device, kind=kind, active=active, port=port, params=params)


class ControlClient(ControlOps):
    """Blocking client of a :class:`ControlServer`; one connection, many requests.

    Methods mirror :class:`Runtime`'s control methods and raise :class:`ControlError` (with the
    server's error ``type``) when the server reports a failure.  Thread-safe; usable as a
    context manager.
    """

    def __init__(self, addr: str | ControlAddress, timeout: float | None = 10.0) -> None:
        self.address = parse_address(addr) if isinstance(addr, str) else addr
        self.timeout = timeout
        sock: socket.socket
        if self.address.path is not None:
            sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
            sock.settimeout(timeout)
            try:
                sock.connect(self.address.path)
            except OSError:
                sock.close()
                raise
        else:
            sock = socket.create_connection((self.address.host, self.address.port), timeout=timeout)
        self._sock = sock
        self._file = sock.makefile("rwb")
        self._lock = threading.Lock()
        self._next_id = 0

    def close(self) -> None:
        with contextlib.suppress(OSError):
            self._file.close()
        with contextlib.suppress(OSError):
            self._sock.close()

    def __enter__(self) -> ControlClient:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def request(self, op: str, **fields: Any) -> Any:
        """Send one request and return its ``result`` (or raise :class:`ControlError`)."""
        with self._lock:
            self._next_id += 1
            req_id = self._next_id
            message = {"id": req_id, "op": op, **{k: v for k, v in fields.items() if v is not None}}
            self._file.write((json.dumps(message) + "\n").encode("utf-8"))
            self._file.flush()
            line = self._file.readline()
        if not line:
            raise ConnectionError("control connection closed by the simulator")
        reply = json.loads(line)
        if reply.get("id") != req_id:
            raise ControlError(f"answer to request {reply.get('id')!r}, expected {req_id}", "ProtocolError")
        if not reply.get("ok"):
            raise ControlError(str(reply.get("error")), str(reply.get("type", "Error")))
        return reply.get("result")

    def telegrams(self, device: str, port: str = "main", count: int = 20) -> list[dict[str, Any]]:
        """The last ``count`` telegrams on the line of a port (kept from the first call on)."""
        result: list[dict[str, Any]] = self.request("telegrams", device=device, port=port, count=count)
        return result

    def watch(self, device: str, names: list[str] | None = None, *, period: float | None = None,
              timeout: float | None = None) -> Iterator[dict[str, Any]]:
        """Changes and events of ``device`` as they happen (see :mod:`devsim.runtime.watch_stream`),
        on a connection of its own; the first items are the present values.  Ends when the
        simulator stops (or closes the stream); ``timeout``: at most that long without an item
        (:class:`TimeoutError`), None waits for ever.  Close the generator to stop watching."""
        watcher = ControlClient(self.address, timeout=self.timeout)
        try:
            watcher.request("watch", device=device, names=names or None, period=period)
            watcher._sock.settimeout(timeout)
            while True:
                try:
                    line = watcher._file.readline()
                except OSError as exc:
                    if isinstance(exc, TimeoutError | socket.timeout):
                        raise TimeoutError(f"no change of {device} within {timeout} s") from None
                    return
                if not line:
                    return
                item = json.loads(line)
                if "watch" in item:
                    item.pop("watch")
                    yield item
        finally:
            watcher.close()
