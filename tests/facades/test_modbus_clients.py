"""Several Modbus TCP clients at once (issue 32, item 5; Messaging on TCP/IP §4.2.1): each is
answered, one more than the server serves is refused with a line in the log, and an idle one makes
room for a newcomer.  Real sockets, the facade's own server."""

from __future__ import annotations

import asyncio
import socket
import struct

import pytest

from devsim.core.clock import VirtualClock
from devsim.devices.sers import SersDevice
from devsim.facades.modbus import MODBUS_TCP_HOSTS, ModbusFacade, serve_tcp


def _read_holding(transaction: int) -> bytes:
    return struct.pack(">HHHBBHH", transaction, 0, 6, 1, 3, 0, 1)


async def _ask(reader: asyncio.StreamReader, writer: asyncio.StreamWriter, transaction: int) -> int:
    writer.write(_read_holding(transaction))
    header = await asyncio.wait_for(reader.readexactly(7), 3)
    got, _protocol, length, _unit = struct.unpack(">HHHB", header)
    await asyncio.wait_for(reader.readexactly(length - 1), 3)
    return int(got)


async def _refused(reader: asyncio.StreamReader) -> bool:
    try:
        return await asyncio.wait_for(reader.read(100), 3) == b""
    except ConnectionResetError:
        return True


def _facade() -> ModbusFacade:
    return ModbusFacade(SersDevice(clock=VirtualClock(), config={}))


async def test_several_clients_are_answered_and_one_more_refused(capsys: pytest.CaptureFixture[str]) -> None:
    server, port = await serve_tcp(_facade(), port=0)
    clients = []
    try:
        for _ in range(MODBUS_TCP_HOSTS):  # the first stays idle throughout
            clients.append(await asyncio.open_connection("127.0.0.1", port))
        for n, (reader, writer) in enumerate(reversed(clients)):
            assert await _ask(reader, writer, n + 1) == n + 1
        reader, writer = await asyncio.open_connection("127.0.0.1", port)
        clients.append((reader, writer))
        assert await _refused(reader)
        assert f"it serves {MODBUS_TCP_HOSTS} hosts at once" in capsys.readouterr().err
    finally:
        for _, writer in clients:
            writer.close()
        await server.shutdown()


async def test_an_idle_client_makes_room_for_a_new_one(capsys: pytest.CaptureFixture[str]) -> None:
    server, port = await serve_tcp(_facade(), port=0, hosts=1, idle_drop=0.0)
    try:
        r1, w1 = await asyncio.open_connection("127.0.0.1", port)
        assert await _ask(r1, w1, 1) == 1
        r2, w2 = await asyncio.open_connection("127.0.0.1", port)
        assert await _ask(r2, w2, 2) == 2
        assert await _refused(r1)
        assert "dropped 127.0.0.1:" in capsys.readouterr().err
        w1.close()
        w2.close()
    finally:
        await server.shutdown()


async def test_a_client_that_does_not_read_its_answers_is_not_read_either() -> None:
    """A client pipelines 2,000 reads of 125 registers (24 KB of requests, 518 KB of answers)
    and reads nothing until the server has stopped reading it (or took every request): the server
    holds at most HELD bytes and one answer unsent ([SIM-CHOICE], docs/facades/modbus.md), and
    then every answer comes, in order.  Before, every request was answered into asyncio's
    unbounded write buffer (devsim run sers --modbus: 32 -> 40 MB in 24 s of such a flood, and a
    SIGTERM not obeyed in 20 s)."""
    from devsim.facades.modbus import HELD

    count, answer = 2_000, 7 + 2 + 250
    loop = asyncio.get_running_loop()
    server, port = await serve_tcp(_facade(), port=0)
    client = socket.socket()
    client.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
    client.setblocking(False)
    try:
        await loop.sock_connect(client, ("127.0.0.1", port))
        requests = b"".join(struct.pack(">HHHBBHH", n, 0, 6, 1, 3, 0, 125) for n in range(count))
        sending = loop.create_task(loop.sock_sendall(client, requests))
        while not server.sessions:
            await asyncio.sleep(0)  # (the loop accepts the connection)
        [session] = server.sessions
        while session.transport is not None and session.transport.is_reading() and not sending.done():
            await asyncio.sleep(0)  # (the loop reads and answers)
        answers = bytearray()
        while len(answers) < count * answer:
            chunk = await asyncio.wait_for(loop.sock_recv(client, 65536), 10)
            assert chunk, "the server closed the connection"
            answers += chunk
        await sending
        transactions = [struct.unpack_from(">HHHBBB", answers, n * answer) for n in range(count)]
        assert transactions == [(n, 0, 253, 1, 3, 250) for n in range(count)]
        assert HELD < session.held_peak <= HELD + answer  # (it reached the bound, and stopped there)
    finally:
        client.close()
        await server.shutdown()
