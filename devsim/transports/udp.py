"""UDP: one telegram per datagram, as Ether-S-Bus and other fieldbus-over-IP protocols use it.

Each datagram that arrives is handed to the endpoint as one chunk (``endpoint.feed(data)``);
each chunk the device writes goes out as one datagram, to the sender of the most recent
datagram – also when the device answers later, from a timer on its clock.  A device served
over UDP should therefore write each telegram in one call (and the line should not pace it,
which would cut the telegram into pieces).  Empty datagrams are ignored.

**No connection, no disconnect.**  UDP has no session: any number of hosts may send, one after
another or interleaved, and each answer goes to whoever sent last.  The endpoint is attached
(``endpoint.attach(write)``) when the first datagram arrives and detached when the port closes;
``host_disconnected()`` is never called – a host that stops sending has not "gone away" in any
way the port could see, and a new sender is not a reconnect.  Output before any datagram
arrived has nowhere to go and is dropped, as on a line nobody listens to.

Errors the kernel reports for sent datagrams (ICMP port unreachable, a datagram too big) are
counted in :attr:`UdpTransport.errors` and otherwise ignored.  The port binds to loopback unless
told otherwise; :attr:`UdpTransport.url` reads ``udp://127.0.0.1:5050``.
"""

from __future__ import annotations

import asyncio
import socket
from typing import Any

from devsim.transports.base import Endpoint, Transport

__all__ = ["UdpTransport"]


class _Protocol(asyncio.DatagramProtocol):
    def __init__(self, owner: UdpTransport) -> None:
        self.owner = owner

    def datagram_received(self, data: bytes, addr: Any) -> None:
        self.owner._received(data, addr)

    def error_received(self, exc: Exception) -> None:
        self.owner.errors += 1


class UdpTransport(Transport):
    """A UDP port serving one endpoint: datagrams in, datagrams back to the latest sender."""

    scheme = "udp"

    def __init__(self, host: str = "127.0.0.1", port: int = 0, *, max_buffer: int = 64 * 1024) -> None:
        self.host = host
        self.port = port
        self.max_buffer = max_buffer
        self.address = ""
        #: Datagrams received and sent, bytes dropped (nobody to send to, or a full buffer),
        #: and errors the kernel reported for sent datagrams.
        self.received = 0
        self.sent = 0
        self.dropped = 0
        self.errors = 0
        self._transport: asyncio.DatagramTransport | None = None
        self._sock: socket.socket | None = None
        self._endpoint: Endpoint | None = None
        self._peer: Any = None
        self._attached = False

    @property
    def url(self) -> str:
        host = f"[{self.host}]" if ":" in self.host else self.host
        return f"{self.scheme}://{host}:{self.port}"

    @property
    def peer(self) -> tuple[str, int] | None:
        """The sender of the most recent datagram (where answers go), if any."""
        if self._peer is None:
            return None
        return str(self._peer[0]), int(self._peer[1])

    def trace_peers(self) -> tuple[tuple[str, int], tuple[str, int]] | None:
        """The latest sender and this port's address (``None`` before the first datagram)."""
        peer = self.peer
        return None if peer is None else (peer, (self.host, self.port))

    async def start(self, endpoint: Endpoint) -> None:
        if self._transport is not None:
            raise RuntimeError("transport already started")
        loop = asyncio.get_running_loop()
        family = socket.AF_INET6 if ":" in self.host else socket.AF_INET
        sock = socket.socket(family, socket.SOCK_DGRAM)
        try:
            sock.bind((self.host, self.port))
            sock.setblocking(False)
            transport, _ = await loop.create_datagram_endpoint(lambda: _Protocol(self), sock=sock)
        except BaseException:
            sock.close()
            raise
        self._transport = transport
        self._sock = sock
        self._endpoint = endpoint
        self.port = sock.getsockname()[1]
        host = f"[{self.host}]" if ":" in self.host else self.host
        self.address = f"{host}:{self.port}"

    async def close(self) -> None:
        transport, self._transport = self._transport, None
        if transport is None:
            return
        endpoint, self._endpoint = self._endpoint, None
        if endpoint is not None and self._attached:
            endpoint.attach(None)
        self._attached = False
        transport.abort()  # stops reading now; the transport closes the socket a loop turn later ...
        if self._sock is not None:
            self._sock.close()  # ... so close it here: the port is free when close() returns
            self._sock = None

    def _received(self, data: bytes, addr: Any) -> None:
        endpoint = self._endpoint
        if endpoint is None or not data:
            return
        self.received += 1
        self._peer = addr
        if not self._attached:
            self._attached = True
            endpoint.attach(self._send)
        endpoint.feed(data)

    def _send(self, data: bytes) -> None:
        transport, peer = self._transport, self._peer
        if not data:
            return
        if transport is None or peer is None or transport.is_closing():
            self.dropped += len(data)
            return
        if transport.get_write_buffer_size() > self.max_buffer:
            self.dropped += len(data)
            return
        transport.sendto(data, peer)
        self.sent += 1
