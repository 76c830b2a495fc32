"""How many hosts a TCP port serves (issue 32, item 5), with real sockets: a one-host port (a serial
device reached over TCP) refuses a second client at once and says who holds it; an idle host makes
room for a newcomer; a several-host port answers every client, each its own answers; the listen
backlog is the system's."""

from __future__ import annotations

import asyncio
import subprocess
from collections.abc import Callable

import pytest

from devsim.transports.hosts import listen_backlog
from devsim.transports.tcp import MAX_WAITING, TcpTransport
from tests.support.programs import needs_program
from tests.transports.transport_helpers import Recorder


async def _read(reader: asyncio.StreamReader, n: int) -> bytes:
    return await asyncio.wait_for(reader.readexactly(n), 3)


async def _closed(reader: asyncio.StreamReader) -> bool:
    """Whether the server closed the connection (EOF or reset) – waited for, at most 3 s."""
    try:
        return await asyncio.wait_for(reader.read(100), 3) == b""
    except ConnectionResetError:
        return True


async def test_a_one_host_port_refuses_a_second_client_at_once_naming_the_holder(
        echo: Recorder, capsys: pytest.CaptureFixture[str]) -> None:
    transport = TcpTransport()
    await transport.start(echo)
    try:
        r1, w1 = await asyncio.open_connection("127.0.0.1", transport.port)
        w1.write(b"A")
        assert await _read(r1, 1) == b"A"
        holder = w1.get_extra_info("sockname")
        r2, w2 = await asyncio.open_connection("127.0.0.1", transport.port)
        newcomer = w2.get_extra_info("sockname")
        w2.write(b"B")
        assert await _closed(r2)  # refused at once, not left waiting
        log = capsys.readouterr().err
        assert f"{transport.address}: refused 127.0.0.1:{newcomer[1]}" in log
        assert f"held by 127.0.0.1:{holder[1]} since 20" in log
        w1.write(b"C")  # the holder is served on
        assert await _read(r1, 1) == b"C"
        assert echo.data == b"AC" and transport.refused == 1
        w1.close()
        w2.close()
    finally:
        await transport.close()


async def test_an_idle_host_is_dropped_when_another_client_comes(
        echo: Recorder, capsys: pytest.CaptureFixture[str]) -> None:
    transport = TcpTransport(idle_drop=0.0)  # any pause counts as idle
    await transport.start(echo)
    try:
        r1, w1 = await asyncio.open_connection("127.0.0.1", transport.port)
        w1.write(b"A")
        assert await _read(r1, 1) == b"A"
        r2, w2 = await asyncio.open_connection("127.0.0.1", transport.port)
        w2.write(b"B")
        assert await _read(r2, 1) == b"B"  # the newcomer is the host now
        assert await _closed(r1)
        assert f"{transport.address}: dropped 127.0.0.1:{w1.get_extra_info('sockname')[1]}, idle" in (
            capsys.readouterr().err)
        assert transport.idle_dropped == 1 and transport.clients == 1
        w1.close()
        w2.close()
    finally:
        await transport.close()


async def test_a_several_host_port_serves_each_and_refuses_one_more(
        echo: Recorder, capsys: pytest.CaptureFixture[str]) -> None:
    transport = TcpTransport()
    transport.limit_hosts(2)
    await transport.start(echo)
    try:
        (r1, w1), (r2, w2) = [await asyncio.open_connection("127.0.0.1", transport.port) for _ in range(2)]
        w2.write(b"two")
        w1.write(b"one")
        assert await _read(r1, 3) == b"one" and await _read(r2, 3) == b"two"
        r3, w3 = await asyncio.open_connection("127.0.0.1", transport.port)
        assert await _closed(r3)
        assert "it serves 2 hosts at once" in capsys.readouterr().err
        for writer in (w1, w2, w3):
            writer.close()
    finally:
        await transport.close()


class _Later(Recorder):
    """An endpoint that answers each message only when the test says so (as the PCD answers
    after its response delay, from a timer)."""

    def __init__(self) -> None:
        super().__init__()
        self.pending: list[bytes] = []
        self.attached = 0

    def attach(self, write: Callable[[bytes], None] | None) -> None:
        self.attached += write is not None
        super().attach(write)

    def feed(self, data: bytes) -> None:
        super().feed(data)
        self.pending.append(data.upper())

    def answer(self) -> None:
        assert self.write is not None
        self.write(self.pending.pop(0))


async def test_a_late_answer_goes_to_the_host_that_asked() -> None:
    later = _Later()
    transport = TcpTransport()
    transport.limit_hosts(2, split=_lines)
    await transport.start(later)
    try:
        (r1, w1), (r2, w2) = [await asyncio.open_connection("127.0.0.1", transport.port) for _ in range(2)]
        w1.write(b"fir")  # half a message: not handed on yet
        await w1.drain()
        w1.write(b"st\n")
        await later.wait_for(lambda: later.chunks == [b"first\n"])
        w2.write(b"second\n")
        await w2.drain()
        w1.write(b"third\n")  # the asker's next message goes straight on (same host)
        await later.wait_for(lambda: len(later.chunks) == 2)
        assert later.chunks[1] == b"third\n"  # the second host waits for the first one's answer
        later.answer()
        assert await _read(r1, 6) == b"FIRST\n"
        later.answer()
        assert await _read(r1, 6) == b"THIRD\n"
        await later.wait_for(lambda: len(later.chunks) == 3)
        later.answer()
        assert await _read(r2, 7) == b"SECOND\n"
        assert later.attached == 1  # one connect for the line (a log line), not one per turn
        w1.close()
        w2.close()
    finally:
        await transport.close()


async def test_a_host_flooding_a_several_host_port_is_held_back_not_queued_without_end() -> None:
    """A host that sends messages faster than the device takes them (here: none answered, each
    holds the turn for TURN_GRACE) has at most about MAX_WAITING of them waiting, plus what one
    read brought; its socket is not read meanwhile, and TCP holds it back (before: every message
    of the flood was kept, 4 M lines here)."""
    later = _Later()
    transport = TcpTransport()
    transport.limit_hosts(2, split=_lines)
    await transport.start(later)
    try:
        reader, writer = await asyncio.open_connection("127.0.0.1", transport.port)
        writer.write(b"x\n" * 4_000_000)  # 8 MB: more than the sockets' buffers hold
        await later.wait_for(lambda: bool(later.chunks))
        session = transport._served[0]
        assert session.transport is not None
        await later.wait_for(lambda: not session.transport.is_reading() or transport.waiting > 100_000)
        assert transport.waiting <= MAX_WAITING + 64 * 1024 // 2  # (one read: at most 64 KiB of 2-byte lines)
        writer.transport.abort()
    finally:
        await transport.close()


def _lines(buffer: bytes) -> tuple[list[bytes], bytes]:
    *whole, rest = buffer.split(b"\n")
    return [line + b"\n" for line in whole], rest


async def test_the_listen_backlog_is_the_systems(echo: Recorder) -> None:
    ss = needs_program("ss")
    transport = TcpTransport()
    await transport.start(echo)
    try:
        out = subprocess.run([ss, "-ltnH", f"sport = :{transport.port}"], capture_output=True, text=True,
                             check=True).stdout.split()
        assert int(out[2]) == listen_backlog() >= 128  # Send-Q of a listening socket: its backlog
    finally:
        await transport.close()





def test_devsim_run_idle_drop_lets_a_new_client_in_and_says_so() -> None:
    """``devsim run sers --tcp PORT --idle-drop 0``: a second client takes the idle holder's place,
    the log says whom it dropped."""
    import socket

    from tests.support.process import DevsimProcess, free_port

    port = free_port()
    run = DevsimProcess("run", "sers", "--tcp", str(port), "--idle-drop", "0", "--no-control")
    try:
        run.next_match(run.out, lambda line: f":{port}" in line, 30, "the tcp port")
        with socket.create_connection(("127.0.0.1", port), timeout=5) as first:  # connected, then idle
            with socket.create_connection(("127.0.0.1", port), timeout=5) as second:
                line = run.next_match(run.err, lambda text: "dropped" in text, 10, "the drop line")
                assert f"dropped 127.0.0.1:{first.getsockname()[1]}, idle" in line
                assert f"for 127.0.0.1:{second.getsockname()[1]}" in line
                try:
                    assert first.recv(100) == b""
                except ConnectionResetError:
                    pass
    finally:
        run.interrupt()
