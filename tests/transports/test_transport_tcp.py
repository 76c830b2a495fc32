"""TcpTransport: raw TCP like a serial device server, one client at a time."""

from __future__ import annotations

import asyncio
import socket
import threading

import pytest

from devsim.transports.tcp import TcpTransport
from tests.transports.transport_helpers import Recorder


async def _read_exactly(reader: asyncio.StreamReader, n: int) -> bytes:
    return await asyncio.wait_for(reader.readexactly(n), 3)


async def test_address_url_and_loopback_default(echo: Recorder) -> None:
    transport = TcpTransport()
    await transport.start(echo)
    try:
        assert transport.port != 0
        assert transport.address == f"127.0.0.1:{transport.port}"
        assert transport.url == f"socket://127.0.0.1:{transport.port}"
    finally:
        await transport.close()


async def test_round_trip_and_disconnect_notification(echo: Recorder) -> None:
    transport = TcpTransport()
    await transport.start(echo)
    try:
        reader, writer = await asyncio.open_connection("127.0.0.1", transport.port)
        raw = b"#ON\r\x00\x11\x13\xff"
        writer.write(raw)
        assert await _read_exactly(reader, len(raw)) == raw
        assert echo.data == raw
        assert echo.settings == []  # a raw client never reports line settings
        writer.close()
        await writer.wait_closed()
        await echo.wait_for(lambda: echo.disconnects == 1)
        assert echo.write is None
    finally:
        await transport.close()


async def test_a_second_client_is_refused_while_the_first_holds_the_port(echo: Recorder) -> None:
    """One host at a time (issue 32: refused at once, no longer left waiting); the next client
    after the holder left is the host.  More in test_tcp_hosts.py."""
    transport = TcpTransport()
    await transport.start(echo)
    try:
        r1, w1 = await asyncio.open_connection("127.0.0.1", transport.port)
        w1.write(b"A")
        assert await _read_exactly(r1, 1) == b"A"
        r2, w2 = await asyncio.open_connection("127.0.0.1", transport.port)
        w2.write(b"B")
        assert await asyncio.wait_for(r2.read(), 3) == b""
        w1.close()
        await w1.wait_closed()
        await echo.wait_for(lambda: echo.disconnects == 1)
        r3, w3 = await asyncio.open_connection("127.0.0.1", transport.port)
        w3.write(b"D")
        assert await _read_exactly(r3, 1) == b"D"
        assert echo.data == b"AD"
        w2.close()
        w3.close()
        await w3.wait_closed()
        await echo.wait_for(lambda: echo.disconnects == 2)
    finally:
        await transport.close()


async def test_new_client_after_first_left(echo: Recorder) -> None:
    transport = TcpTransport()
    await transport.start(echo)
    try:
        for i in range(3):
            reader, writer = await asyncio.open_connection("127.0.0.1", transport.port)
            msg = f"#{i}\r".encode()
            writer.write(msg)
            assert await _read_exactly(reader, len(msg)) == msg
            writer.close()
            await writer.wait_closed()
            await echo.wait_for(lambda n=i + 1: echo.disconnects == n)
    finally:
        await transport.close()


async def test_close_disconnects_the_host(echo: Recorder) -> None:
    transport = TcpTransport()
    await transport.start(echo)
    reader, writer = await asyncio.open_connection("127.0.0.1", transport.port)
    writer.write(b"x")
    assert await _read_exactly(reader, 1) == b"x"
    await transport.close()
    assert echo.disconnects == 1
    assert await asyncio.wait_for(reader.read(), 3) == b""
    writer.close()


def test_a_flood_on_one_port_does_not_stall_another(monkeypatch: pytest.MonkeyPatch) -> None:
    """A port flooded without end does not hold back its neighbour: the neighbour answers while
    the flood still flows (a stalled neighbour would answer only after the flood, which here never
    ends: its read would time out), and the flooded port takes at most a slice per loop turn."""
    import socket
    import threading

    from devsim.runtime import Runtime
    from devsim.transports.tcp import SLICE, TcpTransport

    monkeypatch.setenv("DEVSIM_EXTRA_KINDS", "echo=tests.support.echo:EchoDevice")
    rt = Runtime(virtual=True).start()
    try:
        noisy, quiet = rt.add_device("echo", "noisy"), rt.add_device("echo", "quiet")
        rt.set("noisy", "input.mute", True)
        ports = [TcpTransport(), TcpTransport()]
        rt.serve_sync(noisy, ports[0])
        rt.serve_sync(quiet, ports[1])
        a = socket.create_connection(("127.0.0.1", ports[0].port), timeout=30)
        b = socket.create_connection(("127.0.0.1", ports[1].port), timeout=30)
        stop, sent = threading.Event(), [0]

        def flood() -> None:
            chunk = bytes(64 * 1024)
            while not stop.is_set():
                a.sendall(chunk)
                sent[0] += len(chunk)

        sender = threading.Thread(target=flood, daemon=True)
        sender.start()
        while rt.read("noisy", "received") == 0:  # the flood has begun arriving
            pass
        b.sendall(b"?")
        assert b.recv(1) == b"?"  # answered while the flood flows
        stop.set()
        sender.join(60)
        assert not sender.is_alive()
        while rt.read("noisy", "received") < sent[0]:
            pass  # and all of it arrives in the end
        assert rt.read("noisy", "received") == sent[0]
        assert rt.read("noisy", "largest") <= SLICE  # never more than a slice per loop turn
        a.close()
        b.close()
    finally:
        rt.stop()


async def test_reads_land_in_one_reused_buffer(echo: Recorder) -> None:
    """Every read lands in one reused buffer (asyncio's BufferedProtocol): a plain protocol
    gets a fresh 256 KiB object per read, which glibc may serve with mmap/munmap – a system-call
    pair per poll that made 500-device plants 1.7× as expensive (benchmarks/scale.py)."""
    transport = TcpTransport()
    await transport.start(echo)
    try:
        reader, writer = await asyncio.open_connection("127.0.0.1", transport.port)
        writer.write(b"one")
        assert await _read_exactly(reader, 3) == b"one"
        session = transport._active  # the serving client
        assert isinstance(session, asyncio.BufferedProtocol)
        first = session.get_buffer(-1)
        writer.write(b"two")
        assert await _read_exactly(reader, 3) == b"two"
        assert session.get_buffer(-1) is first and len(first) <= 128 * 1024  # (below glibc's mmap threshold)
        writer.close()
        await writer.wait_closed()
    finally:
        await transport.close()


async def _serve_two_clients() -> tuple[memoryview, memoryview, list[bytes]]:
    """Two ports of one event loop, each with a client, their bytes interleaved; returns the two
    sessions' read buffers and what each device received."""
    ends = [Recorder(echo=True), Recorder(echo=True)]
    transports = [TcpTransport(), TcpTransport()]
    for transport, end in zip(transports, ends, strict=True):
        await transport.start(end)
    try:
        clients = [await asyncio.open_connection("127.0.0.1", t.port) for t in transports]
        for round_ in range(3):
            for index, (reader, writer) in enumerate(clients):
                text = f"<{index}:{round_}>".encode()
                writer.write(text)
                assert await _read_exactly(reader, len(text)) == text
        buffers = [t._active.get_buffer(-1) for t in transports]  # type: ignore[union-attr]
        for _reader, writer in clients:
            writer.close()
            await writer.wait_closed()
        return buffers[0], buffers[1], [bytes(end.data) for end in ends]
    finally:
        for transport in transports:
            await transport.close()


async def test_the_sessions_of_one_loop_share_one_read_buffer() -> None:
    """A buffer per connected client would hold 64 KiB each (about 130 MB for a 2,000-device
    plant).  The bytes are copied out as soon as they are read, so the sessions of one event loop
    share one buffer, each device still gets its own bytes, and a loop in another thread (the
    runtime's, say) reads into a buffer of its own."""
    first, second, received = await _serve_two_clients()
    assert first.obj is second.obj
    assert received == [b"<0:0><0:1><0:2>", b"<1:0><1:1><1:2>"]
    holder: list[memoryview] = []
    thread = threading.Thread(target=lambda: holder.append(asyncio.run(_serve_two_clients())[0]))
    thread.start()
    thread.join(timeout=30)
    assert holder and holder[0].obj is not first.obj


async def test_output_a_client_does_not_read_is_dropped_beyond_max_buffer_until_it_reads_again(
        echo: Recorder) -> None:
    """The device's output piles up in the socket while the client reads nothing; beyond
    ``max_buffer`` bytes waiting in the server, further output is dropped (counted), and once the
    client has read what was accepted, output flows again."""
    transport = TcpTransport(max_buffer=4096)
    await transport.start(echo)
    try:
        reader, writer = await asyncio.open_connection("127.0.0.1", transport.port)
        writer.write(b"A")
        assert await _read_exactly(reader, 1) == b"A"
        assert echo.write is not None
        chunk = b"x" * 65536
        accepted = 0
        for _ in range(4000):  # the kernel's buffers fill first (a few MB), then the server's
            echo.write(chunk)
            if transport.dropped:
                break
            accepted += len(chunk)
            await asyncio.sleep(0)
        assert transport.dropped == len(chunk)
        echo.write(b"lost")  # still beyond the limit: dropped too
        assert transport.dropped == len(chunk) + 4
        got = await asyncio.wait_for(reader.readexactly(accepted), 30)
        assert got == b"x" * accepted  # whatever was accepted arrives whole, in order
        await asyncio.sleep(0)
        echo.write(b"again")
        assert await _read_exactly(reader, 5) == b"again"
        assert transport.dropped == len(chunk) + 4
        writer.close()
    finally:
        await transport.close()


async def test_output_beyond_what_the_socket_takes_at_once_arrives_whole_and_in_order(echo: Recorder) -> None:
    """A session sends through its socket directly while asyncio holds nothing unsent for it;
    what the socket does not take goes to asyncio's buffer, and later output queues behind it
    until that has left: numbered chunks written faster than the client reads (more than the
    kernel's buffers hold) arrive whole and in their order.  The client reads in a thread of its
    own, so the socket gains room while asyncio still holds bytes: output sent directly then
    would overtake them."""
    transport = TcpTransport(max_buffer=64 * 1024 * 1024)
    await transport.start(echo)
    try:
        client = socket.socket()
        client.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)  # a small window: the socket often full
        client.connect(("127.0.0.1", transport.port))
        client.settimeout(60)
        await asyncio.to_thread(client.sendall, b"A")
        assert await asyncio.to_thread(client.recv, 1) == b"A"
        assert echo.write is not None
        # (the session's send buffer small too, or the kernel takes the whole 2.1 MB at once)
        transport._active.sock.setsockopt(socket.SOL_SOCKET, socket.SO_SNDBUF, 4096)
        chunks = [(b"%06d|" % i) * 100 for i in range(3000)]  # 2.1 MB, each chunk different
        expected = b"".join(chunks)

        def read_all() -> bytes:
            got = bytearray()
            while len(got) < len(expected):
                piece = client.recv(4096)
                if not piece:
                    break
                got += piece
            return bytes(got)

        reading = asyncio.ensure_future(asyncio.to_thread(read_all))  # the client reads meanwhile
        for i, chunk in enumerate(chunks):
            echo.write(chunk)
            if i % 3 == 0:
                await asyncio.sleep(0)  # asyncio's writer gets a turn now and then
        got = await asyncio.wait_for(reading, 60)
        assert got == expected
        assert transport.dropped == 0
        client.close()
    finally:
        await transport.close()
