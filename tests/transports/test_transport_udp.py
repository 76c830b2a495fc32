"""UdpTransport: one telegram per datagram, answers to the latest sender, on real sockets."""

from __future__ import annotations

import asyncio
import socket
from collections.abc import Iterator

import pytest

from devsim.runtime import Runtime
from devsim.transports.udp import UdpTransport
from tests.support.etherbus import read_request
from tests.transports.transport_helpers import Recorder

REQUEST = bytes.fromhex("00000010 01 00 0001 00 01 06 00 00D5 9409")
REPLY = bytes.fromhex("0000000F 01 00 0001 01 000003E8 7B16")


@pytest.fixture
def clients() -> Iterator[list[socket.socket]]:
    made: list[socket.socket] = []
    yield made
    for sock in made:
        sock.close()


def client(made: list[socket.socket]) -> socket.socket:
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sock.bind(("127.0.0.1", 0))
    sock.setblocking(False)
    made.append(sock)
    return sock


async def receive(sock: socket.socket, timeout: float = 3.0) -> bytes:
    """One datagram (waits on the socket, no sleeping)."""
    loop = asyncio.get_running_loop()
    return await asyncio.wait_for(loop.sock_recv(sock, 65536), timeout)


async def test_address_url_and_loopback_default(echo: Recorder) -> None:
    transport = UdpTransport()
    await transport.start(echo)
    try:
        assert transport.port != 0
        assert transport.address == f"127.0.0.1:{transport.port}"
        assert transport.url == f"udp://127.0.0.1:{transport.port}"
        assert transport.trace_peers() is None  # nobody has sent yet
        assert echo.write is None  # nobody to answer yet
    finally:
        await transport.close()


async def test_each_datagram_is_one_chunk_and_each_answer_one_datagram(
    echo: Recorder, clients: list[socket.socket]
) -> None:
    transport = UdpTransport()
    await transport.start(echo)
    try:
        sock = client(clients)
        raw = b"\x00\x0d\x0a\x11\x13\x7f\xff"
        sock.sendto(raw, ("127.0.0.1", transport.port))
        sock.sendto(b"second", ("127.0.0.1", transport.port))
        assert await receive(sock) == raw
        assert await receive(sock) == b"second"
        assert echo.chunks == [raw, b"second"]
        assert echo.settings == []
        assert transport.peer == sock.getsockname()
        assert transport.trace_peers() == (sock.getsockname(), ("127.0.0.1", transport.port))
    finally:
        await transport.close()


async def test_answers_go_to_the_latest_sender_also_later(recorder: Recorder, clients: list[socket.socket]) -> None:
    transport = UdpTransport()
    await transport.start(recorder)
    try:
        a, b = client(clients), client(clients)
        target = ("127.0.0.1", transport.port)
        for round_ in range(3):  # two hosts taking turns
            for sock, name in ((a, b"A"), (b, b"B")):
                before = len(recorder.chunks)
                sock.sendto(name + bytes([round_]), target)
                await recorder.wait_for(lambda before=before: len(recorder.chunks) == before + 1)
                assert recorder.write is not None
                recorder.write(b"to " + name)  # what the device answers, at any time
                assert await receive(sock) == b"to " + name
        b.sendto(b"B again", target)
        await recorder.wait_for(lambda: recorder.chunks[-1] == b"B again")
        recorder.write(b"late")  # e.g. from a timer on the device clock
        assert await receive(b) == b"late"
        a.sendto(b"A again", target)
        await recorder.wait_for(lambda: recorder.chunks[-1] == b"A again")
        recorder.write(b"to A")
        assert await receive(a) == b"to A"  # the next thing a gets: "late" never came to a
        assert recorder.disconnects == 0  # a new sender is no reconnect
    finally:
        await transport.close()
    assert recorder.write is None


async def test_close_releases_the_port(echo: Recorder) -> None:
    transport = UdpTransport()
    await transport.start(echo)
    number = transport.port
    await transport.close()
    again = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    try:
        again.bind(("127.0.0.1", number))  # free at once
    finally:
        again.close()
    await transport.close()  # twice is harmless


async def test_a_taken_port_is_an_error(echo: Recorder) -> None:
    first = UdpTransport()
    await first.start(echo)
    try:
        with pytest.raises(OSError):
            await UdpTransport(port=first.port).start(Recorder())
    finally:
        await first.close()


async def test_empty_datagrams_are_ignored(echo: Recorder, clients: list[socket.socket]) -> None:
    transport = UdpTransport()
    await transport.start(echo)
    try:
        sock = client(clients)
        sock.sendto(b"", ("127.0.0.1", transport.port))
        sock.sendto(b"x", ("127.0.0.1", transport.port))
        assert await receive(sock) == b"x"
        assert echo.chunks == [b"x"]
    finally:
        await transport.close()


def test_a_device_answers_datagrams_and_survives_garbage(monkeypatch: pytest.MonkeyPatch) -> None:
    """Through the runtime: a Line and a device behind the port; garbage is not answered and
    changes nothing; the two hosts each get the answer to their own request."""
    monkeypatch.setenv("DEVSIM_EXTRA_KINDS", "etherbus=tests.support.etherbus:EtherBusDevice")
    runtime = Runtime(virtual=True).start()
    a = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    b = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    try:
        device = runtime.add_device("etherbus", "pcd")
        port = UdpTransport()
        runtime.serve_sync(device, port, port="ether")
        assert runtime.ports["pcd.ether"] == port.url
        for sock in (a, b):
            sock.settimeout(3)
        target = ("127.0.0.1", port.port)
        a.sendto(bytes(range(256)) * 4, target)
        a.sendto(b"\xff" * 3, target)
        a.sendto(REQUEST[:-1] + b"\x00", target)  # bad CRC
        a.sendto(REQUEST, target)
        assert a.recv(100) == REPLY
        b.sendto(read_request(7, 1, 10), target)
        a.sendto(read_request(8, 1, 20, count=2), target)
        answer_b, answer_a = b.recv(100), a.recv(100)
        assert answer_b[6:8] == (7).to_bytes(2, "big") and answer_b[9:-2] == (50).to_bytes(4, "big")
        assert answer_a[6:8] == (8).to_bytes(2, "big")
        assert answer_a[9:-2] == (100).to_bytes(4, "big") + (105).to_bytes(4, "big")
        assert runtime.read("pcd", "ignored") == 3
        assert runtime.read("pcd", "answered") == 3
    finally:
        a.close()
        b.close()
        runtime.stop()
