"""A TCP relay between one client and a server on 127.0.0.1, which a test can cut: the fleet
tests put it between a member and mosquitto to take the member off the broker at once, without
waiting for the broker's keep alive to give up on a frozen process.

``Relay(port).start()`` listens on an ephemeral loopback port (``url``: ``mqtt://127.0.0.1:PORT``)
and, for each connection it accepts, opens one to ``port`` and forwards the bytes both ways, as
they come.  :meth:`Relay.cut` ends the forwarding of every connection open now: the server's side
is reset (closed with SO_LINGER 0, no DISCONNECT: mosquitto sends the client's last will at once),
the client's side is held silent (nothing reaches it, what it sends is read and dropped; it cannot
tell it is cut off).  :meth:`Relay.restore` closes the client's side of the cut connections (it
reads the end of its connection); the relay accepts new connections throughout, so a client that
reconnects reaches the server again.

One thread of its own with a selector does all of it; :meth:`cut` and :meth:`restore` return once
that thread has done them.
"""

from __future__ import annotations

import queue
import selectors
import socket
import struct
import threading
from collections.abc import Callable

__all__ = ["Relay"]


class _Pair:
    """One relayed connection: the client's socket and the server's (None once reset)."""

    def __init__(self, client: socket.socket, server: socket.socket) -> None:
        self.client = client
        self.server: socket.socket | None = server
        self.closed = False


class Relay:
    """See the module docstring."""

    def __init__(self, port: int) -> None:
        self.target = ("127.0.0.1", port)
        self._listener = socket.create_server(("127.0.0.1", 0))
        self.port = int(self._listener.getsockname()[1])
        self.accepted = 0  #: connections accepted so far
        self._selector = selectors.DefaultSelector()
        self._wake_in, self._wake_out = socket.socketpair()
        self._calls: queue.Queue[Callable[[], None]] = queue.Queue()
        self._pairs: list[_Pair] = []  # open, forwarding
        self._held: list[_Pair] = []  # cut: the client's side held silent
        self._thread = threading.Thread(target=self._serve, name=f"relay-{self.port}", daemon=True)
        self._running = True

    @property
    def url(self) -> str:
        return f"mqtt://127.0.0.1:{self.port}"

    def start(self) -> Relay:
        self._selector.register(self._listener, selectors.EVENT_READ, self._accept)
        self._selector.register(self._wake_in, selectors.EVENT_READ, self._woken)
        self._thread.start()
        return self

    def cut(self) -> None:
        """Reset the server's side of every open connection, hold the client's side silent."""
        self._call(self._cut)

    def restore(self) -> None:
        """Close the client's side of the cut connections; new ones are relayed as before."""
        self._call(self._restore)

    def stop(self) -> None:
        if self._thread.is_alive():
            self._call(self._stop)
            self._thread.join(5)
        self._wake_out.close()

    # -- in the relay's thread -------------------------------------------------------------
    def _call(self, action: Callable[[], None], timeout: float = 5.0) -> None:
        done = threading.Event()

        def step() -> None:
            try:
                action()
            finally:
                done.set()

        self._calls.put(step)
        self._wake_out.send(b"x")
        assert done.wait(timeout), f"the relay on port {self.port} did not act within {timeout} s"

    def _serve(self) -> None:
        while self._running:
            for key, _events in self._selector.select():
                key.data(key.fileobj)
        for sock in [self._listener, self._wake_in, *self._sockets()]:
            sock.close()
        self._selector.close()

    def _sockets(self) -> list[socket.socket]:
        return [sock for pair in self._pairs + self._held for sock in (pair.client, pair.server) if sock is not None]

    def _woken(self, sock: socket.socket) -> None:
        sock.recv(4096)
        while not self._calls.empty():
            self._calls.get()()

    def _accept(self, listener: socket.socket) -> None:
        client, _address = listener.accept()
        self.accepted += 1
        try:
            server = socket.create_connection(self.target, timeout=5)
        except OSError:
            client.close()
            return
        server.settimeout(None)
        pair = _Pair(client, server)
        self._pairs.append(pair)
        self._selector.register(client, selectors.EVENT_READ, lambda sock: self._from_client(pair))
        self._selector.register(server, selectors.EVENT_READ, lambda sock: self._from_server(pair))

    def _from_client(self, pair: _Pair) -> None:
        if not pair.closed:  # (closed by an earlier event of the same select)
            self._forward(pair, pair.client, pair.server)  # (cut: the server's side is None, the bytes dropped)

    def _from_server(self, pair: _Pair) -> None:
        if not pair.closed and pair.server is not None:
            self._forward(pair, pair.server, pair.client)

    def _forward(self, pair: _Pair, source: socket.socket, to: socket.socket | None) -> None:
        """What ``source`` has, sent on to ``to``; either side's end or failure ends both."""
        try:
            data = source.recv(65536)
            if data and to is not None:
                to.sendall(data)
        except OSError:
            data = b""
        if not data:
            self._close(pair)

    def _reset(self, pair: _Pair, abrupt: bool = True) -> None:
        server, pair.server = pair.server, None
        if server is not None:
            self._selector.unregister(server)
            if abrupt:
                server.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))  # RST, not FIN
            server.close()

    def _close(self, pair: _Pair) -> None:
        """Either side ended: the other one is closed too (as the end of its connection)."""
        pair.closed = True
        self._reset(pair, abrupt=False)
        self._selector.unregister(pair.client)
        pair.client.close()
        for pairs in (self._pairs, self._held):
            if pair in pairs:
                pairs.remove(pair)

    def _cut(self) -> None:
        for pair in self._pairs:
            self._reset(pair)
        self._held += self._pairs
        self._pairs = []

    def _restore(self) -> None:
        for pair in list(self._held):
            self._close(pair)

    def _stop(self) -> None:
        self._running = False
