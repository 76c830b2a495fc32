"""How the CAN side of ``devsim run --canopen`` waits and stops: its threads wake for frames only
(no timeout while the bus is quiet, none at the stop), a flooding client leaves the event loop a
turn after every read, and a request whose device access is underway when the stop begins is
still answered.  (Before: python-can's notifier threads woke every second and ``stop`` waited for
that second, once per client and once for the node's network, in the event loop; a flooding
client held the loop for its whole receive buffer; ``devsim run sers --canopen`` took 1.6 to 13 s
to exit after SIGTERM under floods of one to three clients.)"""

from __future__ import annotations

import asyncio
import socket
import threading
import uuid
from typing import Any

import canopen
import pytest
from can.interfaces import virtual

from devsim.core.clock import VirtualClock
from devsim.facades.canopen_node import serve_nodes
from devsim.runtime import Runtime
from devsim.transports.socketcand import BUS_BACKLOG, SocketcandServer

VirtualBus = virtual.VirtualBus  # (python-can's own: the fixture ``buses`` puts a watched one in its place)
UPLOAD_1000 = b"< send 605 8 40 00 10 00 00 00 00 00 >"  # SDO upload of 1000h (device type) from node 5
UPLOAD_6041 = b"< send 605 8 40 41 60 00 00 00 00 00 >"  # the statusword (a device access: Runtime.call)


async def _raw_client(port: int) -> tuple[asyncio.StreamReader, asyncio.StreamWriter]:
    reader, writer = await asyncio.open_connection("127.0.0.1", port)
    assert await reader.readuntil(b">") == b"< hi >"
    for command in (b"< open can0 >", b"< rawmode >"):
        writer.write(command)
        assert await reader.readuntil(b">") == b"< ok >"
    return reader, writer


async def _frame(reader: asyncio.StreamReader, start: bytes) -> bytes:
    """The next frame the server sends that starts with ``start`` (those before it skipped)."""
    while not (text := await reader.readuntil(b">")).startswith(start):
        pass
    return text


def _port(line: str) -> int:
    return int(line.split()[2].rpartition(":")[2])  # NAME.canopen: socketcand HOST:PORT can0 node N


@pytest.fixture
def buses(monkeypatch: pytest.MonkeyPatch) -> dict[str, list[Any]]:
    """Every python-can virtual bus made from now on (``made``) and each time a read of one came
    back without a frame (``empty``: the timeout it had), python-can's and devsim's alike."""
    seen: dict[str, list[Any]] = {"made": [], "empty": []}

    class Watched(virtual.VirtualBus):
        def __init__(self, *args: Any, **kwargs: Any) -> None:
            super().__init__(*args, **kwargs)
            seen["made"].append(self)

        def _recv_internal(self, timeout: float | None) -> Any:
            message, filtered = super()._recv_internal(timeout)
            if message is None:
                seen["empty"].append(timeout)
            return message, filtered

    monkeypatch.setattr(virtual, "VirtualBus", Watched)
    return seen


def _readers(buses: list[Any]) -> list[str]:
    """The threads still running that read one of ``buses`` (named after its channel, devsim's
    readers and python-can's notifiers alike)."""
    channels = [f"Virtual bus channel {bus.channel_id}" for bus in buses]
    return [t.name for t in threading.enumerate() if any(channel in t.name for channel in channels)]


async def test_the_can_threads_wake_only_for_frames_and_the_stop_waits_for_none(buses: dict[str, list[Any]]) -> None:
    """A node served over socketcand (``devsim run --canopen``'s path) with one raw-mode client
    that reads the device type: no thread that reads a virtual bus (the node's network, the
    client's session) comes back from a read without a frame, neither while the bus is quiet nor
    when the runtime closes, and none is left running after it.  (Before: each was python-can's
    notifier, which waits 1 s for a frame and then looks whether it was stopped: the close of the
    runtime waited for that second, once per bus, in the event loop.)"""
    async with Runtime(clock=VirtualClock()) as runtime:
        device = runtime.add_device("sers", "sers", {})
        (line,) = await serve_nodes(runtime, [(device, 5)], "127.0.0.1:0")
        reader, writer = await _raw_client(_port(line))
        writer.write(UPLOAD_1000)
        assert (await _frame(reader, b"< frame 585 ")).endswith(b" 4300100092010200 >")
        assert len(buses["made"]) == 2  # the network's and the session's
    writer.close()
    assert buses["empty"] == []
    assert _readers(buses["made"]) == []


async def test_a_flooding_client_leaves_the_loop_a_turn_after_every_read() -> None:
    """A raw-mode client whose 600 frames are all in the server's socket before the session reads
    any: between two turns of another task the session puts at most one read's frames (4,096
    characters) on the bus.  (Before: ``StreamReader.read`` returns what is buffered without
    yielding, and the session put all 600 on the bus in one turn: under a flood the loop, the
    other clients and a SIGTERM waited for a whole receive buffer per client, 1 to 3 s in
    ``devsim run --canopen`` with three flooding clients.)"""
    channel = f"devsim-{uuid.uuid4().hex}"
    bus = VirtualBus(channel=channel)  # what the session sends (not read: 600 < BUS_BACKLOG)
    server = SocketcandServer(channel, port=0)
    frame = b"< send 123 8 01 02 03 04 05 06 07 08 >"
    frames = 600
    assert frames < BUS_BACKLOG  # (the session is not held back: a backlog waits)
    await server.start()
    client = socket.create_connection(("127.0.0.1", server.port))
    try:
        client.sendall(b"< open can0 >< rawmode >" + frame * frames)  # (the loop has not run since)
        seen = [0]
        while seen[-1] < frames:
            await asyncio.sleep(0)  # one turn of the loop
            seen.append(bus.queue.qsize())
            assert len(seen) < 1_000_000, seen[-1]
        steps = [after - before for before, after in zip(seen, seen[1:], strict=False)]
        assert max(steps) <= 4096 // len(frame) + 1, max(steps)
    finally:
        client.close()
        await server.close()
        bus.shutdown()


async def test_a_request_whose_device_access_is_underway_when_the_stop_begins_is_answered(
        buses: dict[str, list[Any]], monkeypatch: pytest.MonkeyPatch) -> None:
    """An SDO upload of the statusword reaches the node, and its device access (which runs in the event loop) is
    held until the node's network begins to disconnect: the closing runtime still serves that
    access, the answer goes out on the bus, and the close returns with the network's reader ended.
    (Before: the network disconnected in the event loop itself, so the access waited for the loop
    and the disconnect for the access: 5 s, canopen's NOTIFIER_SHUTDOWN_TIMEOUT, and the answer
    was lost on the bus already shut.)"""
    armed, entered, go = threading.Event(), threading.Event(), threading.Event()
    disconnect = canopen.Network.disconnect

    def disconnecting(network: canopen.Network) -> None:
        go.set()
        disconnect(network)

    monkeypatch.setattr(canopen.Network, "disconnect", disconnecting)
    writer: asyncio.StreamWriter | None = None
    async with Runtime(clock=VirtualClock()) as runtime:
        call = runtime.call

        def held(fn: Any, *args: Any, **kwargs: Any) -> Any:
            if armed.is_set() and threading.current_thread() is not threading.main_thread():
                entered.set()
                assert go.wait(30)
            return call(fn, *args, **kwargs)

        monkeypatch.setattr(runtime, "call", held)
        device = runtime.add_device("sers", "sers", {})
        (line,) = await serve_nodes(runtime, [(device, 5)], "127.0.0.1:0")
        watcher = VirtualBus(channel=buses["made"][0].channel_id)  # the node's network's channel
        _reader, writer = await _raw_client(_port(line))
        armed.set()
        writer.write(UPLOAD_6041)
        assert await asyncio.to_thread(entered.wait, 30)
    writer.close()  # (the runtime closed: its closers disconnected the network)
    answers = []
    while not watcher.queue.empty():
        message = watcher.queue.get_nowait()
        if message.arbitration_id == 0x585:
            answers.append(bytes(message.data))
    watcher.shutdown()
    assert [answer[:4] for answer in answers] == [bytes.fromhex("4B416000")]  # (expedited, 2 bytes: UNSIGNED16)
    assert _readers(buses["made"]) == []
