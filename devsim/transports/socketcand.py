"""A CAN network that hosts in other processes open with plain python-can
(``can.Bus(interface="socketcand", host=..., port=..., channel="can0")``): a server speaking the
socketcand protocol in raw mode, bridging each client to a python-can virtual bus channel in this
process (where the CANopen facades' nodes are).

The protocol (socketcand's ``doc/protocol.md``, as python-can's client uses it): the server greets
``< hi >``; the client asks ``< open CHANNEL >`` and ``< rawmode >``, each answered ``< ok >``;
then the server sends every frame on the bus as ``< frame ID SECONDS.MICROS HEXDATA >`` and the
client sends ``< send ID LENGTH B0 B1 … >``.  Loopback unless a host is named.  Extra ``[can]``.
"""

from __future__ import annotations

import asyncio
import contextlib

import can

__all__ = ["SocketcandServer", "frame_text", "parse_send", "split_commands"]

#: The longest text kept while a command's closing ``>`` has not come (a frame to send is about
#: 40 characters): what came before it in a longer run is dropped, never stored or scanned again.
_LONGEST = 4096


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


class SocketcandServer:
    """Serves the virtual bus ``channel`` to socketcand clients on ``host:port``."""

    def __init__(self, channel: str, host: str = "127.0.0.1", port: int = 29536) -> None:
        self.channel, self.host, self.port = channel, host, port
        self._server: asyncio.AbstractServer | None = None
        self._sessions: set[asyncio.Task[None]] = set()

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
        bus: can.BusABC | None = None
        notifier: can.Notifier | None = None
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
                            bus = can.Bus(interface="virtual", channel=self.channel, receive_own_messages=False)
                            queue = can.AsyncBufferedReader()
                            notifier = can.Notifier(bus, [queue], loop=asyncio.get_running_loop())
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
            if notifier is not None:
                notifier.stop()
            if bus is not None:
                bus.shutdown()
            writer.close()
            self._sessions.discard(task)

    async def _forward(self, queue: can.AsyncBufferedReader, writer: asyncio.StreamWriter) -> None:
        try:
            while not writer.is_closing():
                message = await queue.get_message()
                writer.write(frame_text(message))
                await writer.drain()
        except (ConnectionError, asyncio.CancelledError):
            return
