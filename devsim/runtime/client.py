"""The control API's client: :class:`ControlClient`, blocking, one connection to a
:class:`devsim.runtime.control.ControlServer` for any number of requests; :class:`ControlOps`,
the operations as methods, shared with the fleet's client."""

from __future__ import annotations

import contextlib
import json
import socket
import threading
from collections.abc import Iterator
from typing import Any

import msgspec

from devsim.runtime import requests as rq
from devsim.runtime.control import ControlAddress, parse_address
from devsim.runtime.ops import op_of

__all__ = ["CaptureSubscription", "ControlClient", "ControlError", "ControlOps"]


class ControlError(Exception):
    """The server answered with an error; ``type`` is the server-side exception's class name
    (``UnknownName``, ``UnknownDevice``, ``BadRequest``, ``RuntimeError``, ...)."""

    def __init__(self, message: str, type: str = "Error") -> None:  # noqa: A002 - protocol name
        super().__init__(message)
        self.type = type

    def __str__(self) -> str:
        return f"{self.type}: {self.args[0]}"


class ControlOps:
    """The control API's operations as methods over one ``request(op, **fields)``: shared by the
    socket client (:class:`ControlClient`) and the fleet's (:class:`devsim.fleet.client.FleetClient`).
    :meth:`call` sends a typed request (:mod:`devsim.runtime.requests`) under its op in
    :data:`devsim.runtime.ops.CONTROL`; the named methods are its shorthands."""

    def request(self, op: str, **fields: Any) -> Any:
        raise NotImplementedError

    def call(self, request: rq.ControlRequest) -> Any:
        """Send one typed request; its result."""
        return self.request(op_of(request), **msgspec.structs.asdict(request))

    def read(self, device: str, name: str) -> Any:
        return self.call(rq.Read(device, name))

    def set(self, device: str, name: str, value: Any) -> None:
        self.call(rq.Set(device, name, value))

    def state(self, device: str) -> dict[str, Any]:
        result: dict[str, Any] = self.call(rq.State(device))
        return result

    def power_cycle(self, device: str, *, wipe: bool = False) -> None:
        self.call(rq.PowerCycle(device, wipe))

    def advance(self, seconds: float) -> float:
        return float(self.call(rq.Advance(seconds)))

    def now(self) -> float:
        return float(self.call(rq.Now()))

    def devices(self) -> list[dict[str, Any]]:
        result: list[dict[str, Any]] = self.call(rq.Devices())
        return result

    def line(self, device: str, port: str = "main") -> dict[str, Any]:
        result: dict[str, Any] = self.call(rq.Line(device, port))
        return result

    def names(self, device: str) -> list[dict[str, Any]]:
        result: list[dict[str, Any]] = self.call(rq.Names(device))
        return result

    def fault(self, device: str, kind: str, active: bool = True) -> None:
        self.call(rq.SwitchFault(device, kind, active))

    def line_fault(self, device: str, kind: str, active: bool = True, *, port: str = "main", **params: Any) -> None:
        self.call(rq.LineFault(device, kind, active, port, params))

    def telegrams(self, device: str, port: str = "main", count: int = 20) -> list[dict[str, Any]]:
        """The last ``count`` telegrams on the line of a port (kept from the first call on)."""
        result: list[dict[str, Any]] = self.call(rq.Telegrams(device, port, count))
        return result


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
        if reply.get("id") is None and not reply.get("ok"):  # refused before it was read (Busy, a line too long)
            raise ControlError(str(reply.get("error")), str(reply.get("type", "Error")))
        if reply.get("id") != req_id:
            raise ControlError(f"answer to request {reply.get('id')!r}, expected {req_id}", "ProtocolError")
        if not reply.get("ok"):
            raise ControlError(str(reply.get("error")), str(reply.get("type", "Error")))
        return reply.get("result")

    def watch(self, device: str, names: list[str] | None = None, *, period: float | None = None,
              timeout: float | None = None) -> Iterator[dict[str, Any]]:
        """Changes and events of ``device`` as they happen (see :mod:`devsim.runtime.watch_stream`),
        on a connection of its own; the first items are the present values.  Ends when the
        simulator stops (or closes the stream); ``timeout``: at most that long without an item
        (:class:`TimeoutError`), None waits for ever.  Close the generator to stop watching."""
        watcher = ControlClient(self.address, timeout=self.timeout)
        try:
            watcher.call(rq.Watch(device, names or None, period))
            watcher._sock.settimeout(timeout)
            yield from stream_items(watcher, "watch", f"no change of {device} within {timeout} s")
        finally:
            watcher.close()



def stream_items(client: ControlClient, key: str, silence: str) -> Iterator[dict[str, Any]]:
    """The items of a stream op (``watch``, ``capture``) on ``client``'s connection: each line
    that carries ``key`` (taken out), until the simulator ends it; :class:`TimeoutError` with
    ``silence`` when the connection's timeout passes without a line."""
    while True:
        try:
            line = client._file.readline()
        except OSError as exc:
            if isinstance(exc, TimeoutError | socket.timeout):
                raise TimeoutError(silence) from None
            return
        if not line:
            return
        item = json.loads(line)
        if key in item:
            del item[key]
            yield item

class CaptureSubscription:
    """A port's chunks as they cross (the ``capture`` op, :mod:`devsim.runtime.capture_stream`)
    on a connection of its own: :attr:`info` says how the port is captured (``link``,
    ``protocol``, ``port_byte``, ``t``); iterating yields the ``chunk`` and ``dropped`` items until
    the simulator stops or :meth:`close`.  ``timeout``: at most that long without an item
    (:class:`TimeoutError`), None waits for ever."""

    def __init__(self, address: str | ControlAddress, device: str, port: str = "main", *,
                 timeout: float | None = None, connect_timeout: float | None = 10.0) -> None:
        self._client = ControlClient(address, timeout=connect_timeout)
        try:
            self.info: dict[str, Any] = self._client.call(rq.Capture(device, port))
        except BaseException:
            self._client.close()
            raise
        self._client._sock.settimeout(timeout)
        self.timeout = timeout

    def __iter__(self) -> Iterator[dict[str, Any]]:
        return stream_items(self._client, "capture", f"no chunk within {self.timeout} s")

    def close(self) -> None:
        self._client.close()

    def __enter__(self) -> CaptureSubscription:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
