"""The lean lane (devsim/transports/lane.py): a plain one-host TCP session hands the host's bytes
to the device's port and the answers to the socket without the line, while no line feature is
active; the line closes the lane when one is switched on mid-stream (a fault, a trace, a tap)
and opens it again when it is off, and the bytes, answers and counters are those of the line's
own path.  Through a real TCP socket and a real device with a face."""

from __future__ import annotations

import asyncio
from collections.abc import AsyncIterator
from typing import Any, ClassVar

import pytest

from devsim.core.changes import CHANGES
from devsim.core.clock import RealClock
from devsim.core.device import Device, Face
from devsim.transports import tcp
from devsim.transports.line import Line, LineFault
from devsim.transports.tap import chunk_tap, untap_chunks
from devsim.transports.tcp import SLICE, TcpTransport

ANSWER = b"<ok>"


class _EchoFace(Face):
    """Echoes every byte, and answers each CR with ANSWER (two sends: the port joins them); a
    chunk ``Q`` CR (a host's poll) it answers at once, the same bytes (:attr:`Face.answer_at_once`)."""

    __slots__ = ("at_once",)

    def __init__(self, model: Any, port: Any) -> None:
        super().__init__(model, port)
        self.at_once = 0  # chunks answered at once

    def feed(self, data: bytes) -> None:
        self.send(data)
        for _ in range(data.count(b"\r")):
            self.send(ANSWER)

    def answer_at_once(self, data: bytes) -> bytes | None:
        if data == b"S\r":  # (a reply that stands while nothing changes: the port's to give again)
            self.at_once += 1
            self.port.standing.hold(data, data + ANSWER)
            return data + ANSWER
        if data != b"Q\r":
            return None
        self.at_once += 1
        return data + ANSWER


class _EchoDevice(Device):
    kind: ClassVar[str] = "lane-echo"
    face_classes: ClassVar[dict[str, Any]] = {"main": _EchoFace}


class _Sink:
    """A trace sink that keeps what the line records."""

    def __init__(self) -> None:
        self.records: list[tuple[str, bytes]] = []
        self.notes: list[str] = []

    def record(self, direction: str, data: bytes, when: float, note: str | None = None) -> None:
        self.records.append((direction, data))

    def note(self, text: str, when: float) -> None:
        self.notes.append(text)

    def close(self) -> None:
        pass


class _Plant:
    def __init__(self, device: Device, line: Line, transport: TcpTransport, direct: bool = True) -> None:
        self.device, self.line, self.transport = device, line, transport
        self.direct = direct  # (the sessions read their sockets themselves)

    async def connect(self) -> tuple[asyncio.StreamReader, asyncio.StreamWriter]:
        reader, writer = await asyncio.open_connection("127.0.0.1", self.transport.port)
        await self.until(lambda: self.transport.clients >= 1)
        return reader, writer

    async def until(self, predicate: Any, what: str = "the condition") -> None:
        async def wait() -> None:
            while not predicate():
                await asyncio.sleep(0.001)  # (the transport reports nothing to wait on: look again)

        try:
            await asyncio.wait_for(wait(), 3)
        except TimeoutError:
            raise AssertionError(f"timed out waiting for {what}") from None


@pytest.fixture(params=[True, False], ids=["own reader", "transport's reader"])
async def plant(request: pytest.FixtureRequest, monkeypatch: pytest.MonkeyPatch) -> AsyncIterator[_Plant]:
    """A device on a line served by TCP; its sessions read their sockets themselves, or (on a loop
    where they cannot: :func:`devsim.transports.tcp._reads_directly`) through the transport."""
    if not request.param:
        monkeypatch.setattr(tcp, "_reads_directly", lambda transport: False)
    clock = RealClock()
    device = _EchoDevice(clock=clock)
    line = Line(device.port("main"), clock)
    transport = TcpTransport()
    await transport.start(line)
    try:
        yield _Plant(device, line, transport, direct=request.param)
    finally:
        await transport.close()
        line.close()
        device.close()


async def _poll(reader: asyncio.StreamReader, writer: asyncio.StreamWriter, query: bytes) -> bytes:
    writer.write(query)
    expected = query + ANSWER * query.count(b"\r")
    return await asyncio.wait_for(reader.readexactly(len(expected)), 3)


def _counts(line: Line) -> tuple[int, int, int]:
    status = line.status()
    assert (status["bytes_in"], status["bytes_out"]) == (line.bytes_in, line.bytes_out)
    return line.bytes_in, line.bytes_out, line.bytes_delivered


async def test_a_plain_session_rides_the_lean_lane_with_the_lines_counts(plant: _Plant) -> None:
    assert not plant.line.lean  # nobody connected
    reader, writer = await plant.connect()
    assert plant.line.lean
    for query in (b"#P11?\r", b"\x00\x11\x13\xff\r", b"#1\r#2\r"):
        assert await _poll(reader, writer, query) == query + ANSWER * query.count(b"\r")
    sent = len(b"#P11?\r\x00\x11\x13\xff\r#1\r#2\r")
    assert _counts(plant.line) == (sent, sent + 4 * len(ANSWER), sent + 4 * len(ANSWER))
    writer.close()
    await writer.wait_closed()
    await plant.until(lambda: not plant.line.lean, "the lane closed with the host gone")
    assert _counts(plant.line) == (sent, sent + 4 * len(ANSWER), sent + 4 * len(ANSWER))


async def test_a_chunk_the_face_answers_at_once_leaves_as_on_the_lines_path_with_its_counts(plant: _Plant) -> None:
    reader, writer = await plant.connect()
    face = plant.device.face()
    assert plant.line.lean
    for query in (b"Q\r", b"A\r", b"Q\r", b"Q\r"):
        assert await _poll(reader, writer, query) == query + ANSWER
    assert face.at_once == 3
    sink = _Sink()
    plant.line.tracer = sink  # (the line's own path: the port hands the chunk to the face)
    assert not plant.line.lean
    assert await _poll(reader, writer, b"Q\r") == b"Q\r" + ANSWER
    assert sink.records == [("H>D", b"Q\r"), ("D>H", b"Q\r" + ANSWER)] and face.at_once == 4
    plant.line.tracer = None
    assert plant.line.lean
    assert await _poll(reader, writer, b"Q\r") == b"Q\r" + ANSWER
    assert face.at_once == 5
    sent = 6 * 2
    assert _counts(plant.line) == (sent, sent + 6 * len(ANSWER), sent + 6 * len(ANSWER))
    writer.close()


async def test_a_standing_reply_is_given_by_the_session_until_a_change_is_counted(plant: _Plant) -> None:
    """A reply the face holds standing (devsim.core.device.Standing) is written by the session for
    the same chunk without asking the face, with the line's counts, until any door counts a change
    (devsim.core.changes); then the face is asked again."""
    reader, writer = await plant.connect()
    face = plant.device.face()
    for _ in range(3):
        assert await _poll(reader, writer, b"S\r") == b"S\r" + ANSWER
    assert face.at_once == 1
    CHANGES.count += 1  # (any door)
    assert await _poll(reader, writer, b"S\r") == b"S\r" + ANSWER
    assert face.at_once == 2
    assert await _poll(reader, writer, b"A\r") == b"A\r" + ANSWER  # (the face's feed: a door)
    assert await _poll(reader, writer, b"S\r") == b"S\r" + ANSWER
    assert face.at_once == 3
    sent = 6 * 2
    assert _counts(plant.line) == (sent, sent + 6 * len(ANSWER), sent + 6 * len(ANSWER))
    writer.close()


async def test_a_fault_injected_mid_stream_closes_the_lane_until_it_ends(plant: _Plant) -> None:
    reader, writer = await plant.connect()
    assert await _poll(reader, writer, b"A\r") == b"A\r" + ANSWER
    handle = plant.line.inject(LineFault(kind="corrupt", direction="to_device", count=1, seed=7))
    assert not plant.line.lean
    writer.write(b"B\r")
    got = await asyncio.wait_for(reader.readexactly(2 + len(ANSWER)), 3)
    assert bin(got[0] ^ ord("B")).count("1") == 1  # the first byte reached the device with a bit flipped
    assert got[1:] == b"\r" + ANSWER
    await plant.until(lambda: plant.line.lean, "the lane open again once the count is used")
    assert not handle.active
    assert await _poll(reader, writer, b"C\r") == b"C\r" + ANSWER
    inside, outside = 6, 6 + 3 * len(ANSWER)
    assert _counts(plant.line) == (inside, outside, outside)
    writer.close()


async def test_a_drop_fault_towards_the_host_acts_on_the_next_answer(plant: _Plant) -> None:
    reader, writer = await plant.connect()
    assert await _poll(reader, writer, b"A\r") == b"A\r" + ANSWER
    plant.line.inject(LineFault(kind="drop", direction="to_host", duration=60))
    assert not plant.line.lean
    writer.write(b"B\r")
    await plant.until(lambda: plant.line.bytes_in == 4, "the device fed")
    assert plant.line.bytes_out == 2 * (2 + len(ANSWER)) and plant.line.bytes_delivered == 2 + len(ANSWER)
    plant.line.clear_faults()
    assert plant.line.lean
    assert await _poll(reader, writer, b"C\r") == b"C\r" + ANSWER  # (B's answer never left)
    writer.close()


async def test_a_trace_opened_mid_stream_sees_every_chunk_until_it_is_closed(plant: _Plant) -> None:
    reader, writer = await plant.connect()
    assert await _poll(reader, writer, b"A\r") == b"A\r" + ANSWER
    sink = _Sink()
    plant.line.tracer = sink
    assert not plant.line.lean
    assert await _poll(reader, writer, b"B\r") == b"B\r" + ANSWER
    assert sink.records == [("H>D", b"B\r"), ("D>H", b"B\r" + ANSWER)]
    plant.line.tracer = None
    assert plant.line.lean
    assert await _poll(reader, writer, b"C\r") == b"C\r" + ANSWER
    assert len(sink.records) == 2  # nothing recorded on the lane
    assert _counts(plant.line)[0] == 6
    writer.close()


async def test_a_live_capture_closes_the_lane_while_it_listens(plant: _Plant) -> None:
    """The capture path (Wireshark's extcap, the control op ``capture``): a chunk tap on the
    line's trace; when its last listener leaves, the tap leaves and the lane opens again."""
    reader, writer = await plant.connect()
    assert await _poll(reader, writer, b"A\r") == b"A\r" + ANSWER
    seen: list[tuple[str, bytes]] = []

    def listener(direction: str, data: bytes, when: float) -> None:
        seen.append((direction, data))

    chunk_tap(plant.line).listeners.append(listener)
    assert not plant.line.lean
    assert await _poll(reader, writer, b"B\r") == b"B\r" + ANSWER
    assert seen == [("H>D", b"B\r"), ("D>H", b"B\r" + ANSWER)]
    untap_chunks(plant.line, listener)
    assert plant.line.tracer is None and plant.line.lean
    assert await _poll(reader, writer, b"C\r") == b"C\r" + ANSWER
    assert len(seen) == 2
    writer.close()


async def test_the_lane_follows_the_host_a_second_host_after_the_first(plant: _Plant) -> None:
    r1, w1 = await plant.connect()
    assert await _poll(r1, w1, b"A\r") == b"A\r" + ANSWER
    r2, w2 = await asyncio.open_connection("127.0.0.1", plant.transport.port)  # refused: the port holds one
    assert await asyncio.wait_for(r2.read(), 3) == b""
    assert plant.line.lean
    assert await _poll(r1, w1, b"B\r") == b"B\r" + ANSWER
    w1.close()
    await w1.wait_closed()
    await plant.until(lambda: plant.transport.clients == 0, "the first host gone")
    r3, w3 = await plant.connect()
    assert plant.line.lean
    assert await _poll(r3, w3, b"C\r") == b"C\r" + ANSWER
    assert plant.line.bytes_in == 6
    w2.close()
    w3.close()


async def test_an_idle_host_dropped_for_a_newcomer_hands_it_the_lane(plant: _Plant) -> None:
    plant.transport.idle_drop = 0.0  # (any host that sent nothing since its last poll is idle)
    r1, w1 = await plant.connect()
    assert await _poll(r1, w1, b"A\r") == b"A\r" + ANSWER
    r2, w2 = await asyncio.open_connection("127.0.0.1", plant.transport.port)
    assert await asyncio.wait_for(r1.read(), 3) == b""  # the idle one dropped
    await plant.until(lambda: plant.line.lean, "the lane open for the newcomer")
    assert await _poll(r2, w2, b"B\r") == b"B\r" + ANSWER
    assert _counts(plant.line)[0] == 4
    w1.close()
    w2.close()


async def test_a_flood_beyond_a_slice_leaves_the_lane_and_arrives_whole(plant: _Plant) -> None:
    reader, writer = await plant.connect()
    flood = bytes(range(256)).replace(b"\r", b"") * (3 * SLICE // 255)
    writer.write(flood + b"\r")
    expected = flood + b"\r" + ANSWER
    assert await asyncio.wait_for(reader.readexactly(len(expected)), 10) == expected
    assert plant.line.lean
    assert await _poll(reader, writer, b"A\r") == b"A\r" + ANSWER
    assert _counts(plant.line)[0] == len(flood) + 3
    writer.close()


def _reader_of(session: Any) -> Any:
    """What the loop calls when the session's socket is readable."""
    key = asyncio.get_running_loop()._selector.get_key(session.sock.fileno())  # type: ignore[attr-defined]
    return key.data[0]._callback


async def test_a_session_reads_its_socket_itself_and_again_after_a_flood(plant: _Plant) -> None:
    """A poll passes the session's own reader, not the transport's four calls
    (:meth:`~devsim.transports.tcp._Session.read_directly`): from the first poll on, and again once
    a flood has paused the transport's reading and its slices are fed (where the session cannot,
    the transport's reader throughout); the host's bytes and the answers are the same on either
    reader (the tests above run on both)."""
    reader, writer = await plant.connect()
    assert await _poll(reader, writer, b"A\r") == b"A\r" + ANSWER
    (session,) = plant.transport._served
    expected_reader = session._read if plant.direct else session.transport._read_ready
    assert _reader_of(session) == expected_reader
    flood = b"x" * (3 * SLICE)
    writer.write(flood + b"\r")
    expected = flood + b"\r" + ANSWER
    assert await asyncio.wait_for(reader.readexactly(len(expected)), 10) == expected
    assert _reader_of(session) == expected_reader
    assert await _poll(reader, writer, b"B\r") == b"B\r" + ANSWER
    writer.close()
    await plant.until(lambda: plant.transport.clients == 0)  # the end of the stream, on either reader
