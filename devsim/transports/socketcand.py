"""A CAN network that hosts in other processes open with plain python-can
(``can.Bus(interface="socketcand", host=..., port=..., channel="can0")``): a server speaking the
socketcand protocol in raw mode, bridging each client to a python-can virtual bus channel in this
process (where the CANopen facades' nodes are).

The protocol (socketcand's ``doc/protocol.md``, as python-can's client uses it): the server greets
``< hi >``; the client asks ``< open CHANNEL >`` and ``< rawmode >``, each answered ``< ok >``;
then the server sends every frame on the bus as ``< frame ID SECONDS.MICROS HEXDATA >`` and the
client sends ``< send ID LENGTH B0 B1 … >``.  Loopback unless a host is named.  Extra ``[can]``.

A client that does not read costs at most :data:`CLIENT_QUEUE` frames (:class:`ClientQueue`): the
frames that come while its queue is full are dropped for it alone [SIM-CHOICE], as socketcand's
``state_raw.c`` loses them (it blocks in ``send()`` to that client while its CAN_RAW socket's
receive buffer fills, and the kernel drops what comes then); every other client and the nodes get
every frame.  A client that sends faster than a receiver on the bus (a node) takes the frames is
not read while that receiver has more than :data:`BUS_BACKLOG` frames waiting [SIM-CHOICE]: TCP's
flow control holds it back, as a full transmit queue holds back a CAN controller, and no frame is
lost.
"""

from __future__ import annotations

import asyncio
import contextlib
import socket
import threading
from collections import deque

import can
from can.interfaces import virtual

from devsim.transports.can_reader import BusReader

__all__ = ["BUS_BACKLOG", "CLIENT_QUEUE", "ClientQueue", "SocketcandServer", "frame_text", "parse_send", "split_commands"]

#: The longest text kept while a command's closing ``>`` has not come (a frame to send is about
#: 40 characters): what came before it in a longer run is dropped, never stored or scanned again.
_LONGEST = 4096

#: The most frames kept for one raw-mode client that has not taken them yet [SIM-CHOICE]: more than
#: a second of a 1 Mbit/s CAN bus at full load (about 8,000 frames), about 0.5 MB of text.
CLIENT_QUEUE = 10_000

#: A raw-mode client's socket send buffer (bytes; the kernel doubles it): fixed, so that a client that
#: does not read holds no more than that of the kernel's memory (autotuned, it grew to 4 MB here);
#: at 1 ms round trip still some 30 MB/s, far above a CAN bus's 8,000 frames/s.
SEND_BUFFER = 65_536

#: The most frames a receiver on the virtual bus (a node's bus, a session's) may have waiting before
#: the clients' sessions stop reading what their clients send [SIM-CHOICE].
BUS_BACKLOG = 1_000

#: How often a held-back session looks at the receivers' queues again (s): no device time, a thread's
#: progress (python-can's virtual bus says nothing when a queue is read).
_BACKLOG_POLL = 0.002


def frame_text(message: can.Message) -> bytes:
    """A frame as the server sends it."""
    width = 8 if message.is_extended_id else 3
    data = bytes(message.data[: message.dlc]).hex().upper()
    return f"< frame {message.arbitration_id:0{width}X} {message.timestamp:.6f} {data} >".encode("ascii")


def parse_send(text: str) -> can.Message | None:
    """``< send ID LENGTH B0 … >`` as a message, or None for anything else."""
    parts = text.strip("<> ").split()
    if len(parts) < 3 or parts[0] != "send":
        return None
    try:
        identifier, length = int(parts[1], 16), int(parts[2], 16)
        data = bytes(int(b, 16) for b in parts[3 : 3 + length])
    except ValueError:
        return None
    if len(data) != length or length > 8:
        return None
    return can.Message(arbitration_id=identifier, data=data, is_extended_id=len(parts[1]) > 3)


def split_commands(buffer: str) -> tuple[list[str], str]:
    """The whole ``< ... >`` commands in ``buffer`` (text before a ``<`` skipped) and the rest,
    at most :data:`_LONGEST` characters of it."""
    commands: list[str] = []
    while ">" in buffer:
        end = buffer.index(">") + 1
        start = buffer.find("<")
        commands.append(buffer[start:end] if 0 <= start < end else "")
        buffer = buffer[end:]
    return commands, buffer[-_LONGEST:]


class ClientQueue(can.Listener):
    """The frames one raw-mode client has not been sent yet, as the server's text: filled in the
    session's reader thread (:class:`~devsim.transports.can_reader.BusReader`), taken by its writer
    in the event loop.  At most ``limit`` frames: one that comes while it is full is dropped
    (counted in :attr:`dropped`) [SIM-CHOICE] (see the module's docstring).  The loop is woken once
    when the queue stops being empty, not once per frame (a wake-up per frame filled asyncio's ready
    queue and its self-pipe)."""

    def __init__(self, loop: asyncio.AbstractEventLoop, limit: int = CLIENT_QUEUE) -> None:
        self.limit = limit
        self.dropped = 0  #: frames dropped for this client
        self.peak = 0  #: the most frames it held at once
        self._loop = loop
        self._frames: deque[bytes] = deque()
        self._lock = threading.Lock()
        self._ready = asyncio.Event()

    def __len__(self) -> int:
        return len(self._frames)

    def on_message_received(self, msg: can.Message) -> None:
        text = frame_text(msg)
        with self._lock:
            if len(self._frames) >= self.limit:
                self.dropped += 1
                return
            self._frames.append(text)
            self.peak = max(self.peak, len(self._frames))
            first = len(self._frames) == 1
        if first:
            with contextlib.suppress(RuntimeError):  # (the loop closed: the session is gone)
                self._loop.call_soon_threadsafe(self._ready.set)

    async def take(self) -> bytes:
        """Every frame queued, as one text (waits for one)."""
        await self._ready.wait()
        with self._lock:
            self._ready.clear()
            frames = b"".join(self._frames)
            self._frames.clear()
        return frames


class SocketcandServer:
    """Serves the virtual bus ``channel`` to socketcand clients on ``host:port``; each raw-mode
    client's frames wait in a :class:`ClientQueue` of ``client_queue`` frames.  Every bus on the
    channel in this process must be read (a canopen network reads its own): one that is not holds
    the clients' frames back once it has :data:`BUS_BACKLOG` of them (python-can would keep them all)."""

    def __init__(self, channel: str, host: str = "127.0.0.1", port: int = 29536,
                 client_queue: int = CLIENT_QUEUE) -> None:
        self.channel, self.host, self.port = channel, host, port
        self.client_queue = client_queue
        self._server: asyncio.AbstractServer | None = None
        self._sessions: set[asyncio.Task[None]] = set()
        self._queues: list[ClientQueue] = []
        self.backlog_peak = 0  #: the largest :meth:`backlog` a session saw after sending its frames

    def backlog(self) -> int:
        """The most frames one receiver on the virtual bus (python-can keeps a queue per bus) has
        not taken yet."""
        with virtual.channels_lock:
            queues = list(virtual.channels.get(self.channel, ()))
        return max((queue.qsize() for queue in queues), default=0)

    async def _bus_free(self) -> None:
        """Wait while a receiver has more than :data:`BUS_BACKLOG` frames waiting (called after a
        session sent what it read: what clients send reaches the receivers' queues only then, so
        :attr:`backlog_peak` is the most a node's queue held of it)."""
        backlog = self.backlog()
        self.backlog_peak = max(self.backlog_peak, backlog)
        while backlog > BUS_BACKLOG:
            await asyncio.sleep(_BACKLOG_POLL)
            backlog = self.backlog()

    @property
    def queues(self) -> list[ClientQueue]:
        """The queues of the clients in raw mode now, in the order they asked for it."""
        return list(self._queues)

    @property
    def address(self) -> str:
        return f"{self.host}:{self.port}"

    async def start(self) -> None:
        self._server = await asyncio.start_server(self._session, self.host, self.port)
        self.port = int(self._server.sockets[0].getsockname()[1])

    async def close(self) -> None:
        if self._server is not None:
            self._server.close()
            await self._server.wait_closed()
            self._server = None
        for task in list(self._sessions):
            task.cancel()
        for task in list(self._sessions):
            with contextlib.suppress(asyncio.CancelledError, Exception):
                await task

    async def _session(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        task = asyncio.current_task()
        assert task is not None
        self._sessions.add(task)
        bus: virtual.VirtualBus | None = None
        bus_reader: BusReader | None = None
        queue: ClientQueue | None = None
        forward: asyncio.Task[None] | None = None
        try:
            writer.write(b"< hi >")
            await writer.drain()
            raw = False
            buffer = ""
            while True:
                chunk = await reader.read(4096)
                if not chunk:
                    return
                commands, buffer = split_commands(buffer + chunk.decode("ascii", "replace"))
                for command in commands:
                    words = command.strip("<> ").split()
                    if not raw:
                        if words[:1] == ["open"] and len(words) == 2:
                            writer.write(b"< ok >")
                        elif words == ["rawmode"]:
                            bus = virtual.VirtualBus(channel=self.channel, receive_own_messages=False)
                            with contextlib.suppress(OSError, AttributeError):
                                writer.get_extra_info("socket").setsockopt(
                                    socket.SOL_SOCKET, socket.SO_SNDBUF, SEND_BUFFER)
                            queue = ClientQueue(asyncio.get_running_loop(), self.client_queue)
                            self._queues.append(queue)
                            bus_reader = BusReader(bus, [queue])
                            raw = True
                            writer.write(b"< ok >")
                            forward = asyncio.get_running_loop().create_task(self._forward(queue, writer))
                        else:
                            writer.write(b"< error >")
                        await writer.drain()
                        continue
                    message = parse_send(command)
                    if message is not None and bus is not None:
                        bus.send(message)
                if raw:
                    await self._bus_free()
                await asyncio.sleep(0)  # (read() returns what is buffered without yielding: a client that
                # floods would hold the loop, the other sessions and a stop, for its whole buffer)
        except ConnectionError:
            return  # the client reset the connection: it is gone, as after an orderly close
        except asyncio.CancelledError:
            return  # the server closes (close()): the session ends, not cancelled (asyncio 3.11's
            # stream callback asks a cancelled task for its exception: a traceback per client)
        finally:
            if forward is not None:
                forward.cancel()
                with contextlib.suppress(asyncio.CancelledError, Exception):
                    await forward
            if bus_reader is not None:
                bus_reader.stop()
            if bus is not None:
                bus.shutdown()
            if queue is not None:
                self._queues.remove(queue)
            writer.close()
            self._sessions.discard(task)

    async def _forward(self, queue: ClientQueue, writer: asyncio.StreamWriter) -> None:
        try:
            while not writer.is_closing():
                writer.write(await queue.take())  # (a client that does not read: drain() waits,
                await writer.drain()  # and its queue fills up to its limit)
        except (ConnectionError, asyncio.CancelledError):
            return
