"""How the CAN side of ``devsim run --canopen`` waits and stops: its threads wake for frames only
(no timeout while the bus is quiet, none at the stop), a flooding client leaves the event loop a
turn after every read, and a request whose device access is underway when the stop begins is
still answered.  (Before: python-can's notifier threads woke every second and ``stop`` waited for
that second, once per client and once for the node's network, in the event loop; a flooding
client held the loop for its whole receive buffer; ``devsim run sers --canopen`` took 1.6 to 13 s
to exit after SIGTERM under floods of one to three clients.)"""

from __future__ import annotations

import asyncio
import threading
from typing import Any

import pytest
from can.interfaces import virtual

from devsim.core.clock import VirtualClock
from devsim.facades.canopen_node import serve_nodes
from devsim.runtime import Runtime

UPLOAD_1000 = b"< send 605 8 40 00 10 00 00 00 00 00 >"  # SDO upload of 1000h (device type) from node 5


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
