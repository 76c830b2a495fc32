"""Line fault injection: every kind on a virtual clock, combinations, and one real pty."""

from __future__ import annotations

import asyncio
import random
import sys
from collections.abc import Callable

import pytest
import serial

from devsim.core.clock import RealClock, VirtualClock
from devsim.core.device import SerialSettings
from devsim.transports.faults import MAX_NOISE_RATE
from devsim.transports.line import DEFAULT_SPLIT_GAP, FaultHandle, Line, LineFault, garble
from devsim.transports.pacing import MAX_PENDING
from devsim.transports.pty import PtyTransport
from devsim.transports.trace import Tracer

S = SerialSettings


class Target:
    """A recording device for a line: what arrived and when; ``echo`` sends it back."""

    def __init__(
        self, clock: VirtualClock | RealClock, settings: SerialSettings | None = None, echo: bool = False
    ):
        self.clock = clock
        self.serial_settings = settings or S(9600)
        self.echo = echo
        self.chunks: list[tuple[float, bytes]] = []
        self.disconnects = 0
        self._write: Callable[[bytes], None] | None = None

    @property
    def received(self) -> bytes:
        return b"".join(data for _, data in self.chunks)

    def attach(self, write: Callable[[bytes], None] | None) -> None:
        self._write = write

    def feed(self, data: bytes) -> None:
        self.chunks.append((self.clock.now(), data))
        if self.echo:
            self.send(data)

    def send(self, data: bytes) -> None:
        assert self._write is not None
        self._write(data)

    def host_disconnected(self) -> None:
        self.disconnects += 1


class Host:
    """The transport side: records what reaches the host and when."""

    def __init__(self, clock: VirtualClock) -> None:
        self.clock = clock
        self.chunks: list[tuple[float, bytes]] = []

    @property
    def received(self) -> bytes:
        return b"".join(data for _, data in self.chunks)

    def __call__(self, data: bytes) -> None:
        self.chunks.append((self.clock.now(), data))


def make_line(
    settings: SerialSettings | None = None, echo: bool = False, **kw
) -> tuple[VirtualClock, Target, Host, Line]:
    clock = VirtualClock()
    target = Target(clock, settings, echo)
    line = Line(target, clock, **kw)
    host = Host(clock)
    line.attach(host)
    return clock, target, host, line


def flipped(data: bytes, seed: int) -> bytes:
    """What ``corrupt`` with ``seed`` makes of the first bytes it sees."""
    rng = random.Random(seed)
    return bytes(b ^ (1 << rng.randrange(8)) for b in data)


def one_bit_apart(a: bytes, b: bytes) -> bool:
    return len(a) == len(b) and all(bin(x ^ y).count("1") == 1 for x, y in zip(a, b, strict=True))


# -- corrupt -----------------------------------------------------------------------------------


def test_corrupt_count_flips_one_bit_in_each_of_the_next_bytes_then_ends() -> None:
    clock, target, host, line = make_line()
    handle = line.inject(LineFault("corrupt", direction="to_device", count=2, seed=7))
    line.feed(b"#O")
    assert target.received == flipped(b"#O", 7)
    assert one_bit_apart(target.received, b"#O")
    assert not handle.active and line.faults == []  # count used up: ended by itself
    line.feed(b"N\r")
    assert target.received == flipped(b"#O", 7) + b"N\r"


def test_corrupt_count_spans_chunks_and_leaves_the_rest_of_a_chunk_alone() -> None:
    clock, target, host, line = make_line()
    line.inject(LineFault("corrupt", direction="to_device", count=3, seed=1))
    line.feed(b"AB")
    line.feed(b"CDE")
    # one RNG for the whole fault: the third byte uses its third draw
    assert target.received == flipped(b"ABC", 1) + b"DE"


def test_corrupt_duration_corrupts_everything_to_host_until_it_ends() -> None:
    clock, target, host, line = make_line(echo=True)
    line.inject(LineFault("corrupt", direction="to_host", duration=1.0, seed=3))
    line.feed(b"#ON\r")
    assert target.received == b"#ON\r"  # to_host only: the device reads clean data
    assert host.received == flipped(b"#ON\r", 3)
    assert one_bit_apart(host.received, b"#ON\r")
    clock.advance(0.5)
    line.feed(b"XY")
    assert one_bit_apart(host.received[4:], b"XY")
    clock.advance(0.5)
    assert line.faults == []
    line.feed(b"ok")
    assert host.received.endswith(b"ok")


# -- drop --------------------------------------------------------------------------------------


def test_drop_count_is_shared_by_both_directions() -> None:
    clock, target, host, line = make_line()
    handle = line.inject(LineFault("drop", count=3))
    line.feed(b"AB")  # two of three
    assert target.received == b""
    target.send(b"XYZ")  # the third byte is the X
    assert host.received == b"YZ"
    assert not handle.active
    line.feed(b"CD")
    assert target.received == b"CD"


def test_drop_duration_to_host_only() -> None:
    clock, target, host, line = make_line(echo=True)
    line.inject(LineFault("drop", direction="to_host", duration=0.2))
    line.feed(b"#ON\r")
    assert target.received == b"#ON\r"
    assert host.received == b""
    clock.advance(0.2)
    line.feed(b"A")
    assert host.received == b"A"
    assert line.status()["bytes_out"] == 5  # the device did send them


# -- split -------------------------------------------------------------------------------------


def test_split_delivers_one_byte_at_a_time_with_the_default_gap() -> None:
    clock, target, host, line = make_line()
    line.inject(LineFault("split", direction="to_device"))
    line.feed(b"ABC")
    assert target.chunks == [(0.0, b"A")]
    clock.advance(0.1)
    assert [d for _, d in target.chunks] == [b"A", b"B", b"C"]
    assert [t for t, _ in target.chunks] == pytest.approx([0.0, 0.005, 0.010])


def test_split_count_then_rest_of_chunk_in_one_piece_and_fault_ends() -> None:
    clock, target, host, line = make_line()
    handle = line.inject(LineFault("split", direction="to_host", count=2, delay=0.01))
    target.send(b"ABCD")
    assert not handle.active
    clock.advance(1.0)
    assert [d for _, d in host.chunks] == [b"A", b"B", b"CD"]
    assert [t for t, _ in host.chunks] == pytest.approx([0.0, 0.01, 0.02])
    target.send(b"EF")  # unaffected, delivered at once
    assert host.chunks[-1] == (1.0, b"EF")


def test_split_keeps_the_gap_between_consecutive_chunks() -> None:
    clock, target, host, line = make_line()
    line.inject(LineFault("split", direction="to_device", delay=0.01, duration=1.0))
    line.feed(b"AB")
    line.feed(b"C")  # still in flight: queued a gap after the B
    clock.advance(0.1)
    assert target.chunks == [(0.0, b"A"), (pytest.approx(0.01), b"B"), (pytest.approx(0.02), b"C")]


# -- delay and jitter --------------------------------------------------------------------------


def test_delay_holds_every_chunk_back_and_ends_by_itself() -> None:
    clock, target, host, line = make_line()
    line.inject(LineFault("delay", direction="to_host", delay=0.1, duration=0.5))
    target.send(b"X")
    clock.advance(0.05)
    target.send(b"Y")
    assert host.chunks == []
    assert line.status()["pending_out"] == 2
    clock.advance(0.2)
    assert host.chunks == [(pytest.approx(0.1), b"X"), (pytest.approx(0.15), b"Y")]
    line.feed(b"to device")  # direction to_host: the host's bytes are not delayed
    assert target.chunks == [(0.25, b"to device")]
    clock.advance(0.25)
    assert line.faults == []
    target.send(b"Z")
    assert host.chunks[-1] == (0.5, b"Z")


def test_chunk_after_delay_ended_waits_for_the_one_still_in_flight() -> None:
    clock, target, host, line = make_line()
    line.inject(LineFault("delay", direction="to_device", delay=0.1, duration=0.05))
    line.feed(b"A")
    clock.advance(0.06)  # fault over, A still on its way
    assert line.faults == []
    line.feed(b"B")
    assert target.chunks == []  # B does not overtake A
    clock.advance(0.1)
    assert target.received == b"AB"
    assert target.chunks[0][0] == pytest.approx(0.1)


def test_a_delay_or_split_holds_at_most_max_pending_bytes_and_answers_after_the_flood() -> None:
    """A host that floods a delayed or split line: the stage holds at most ``MAX_PENDING``
    bytes (the rest is lost, as in a full receive buffer), so a request sent once the held bytes
    have passed arrives (before: every byte was queued, a split flood of 1 MB took 5,000 s of
    gaps and the line's memory grew with the host's bytes)."""
    for fault in (LineFault("delay", direction="to_device", delay=1.0),
                  LineFault("split", direction="to_device")):
        clock, target, host, line = make_line()
        line.inject(fault)
        for _ in range(64):
            line.feed(b"x" * 16 * 1024)  # 1 MiB at once
        assert line.status()["pending_in"] <= MAX_PENDING
        line.clear_faults()
        clock.advance(MAX_PENDING * DEFAULT_SPLIT_GAP + 1.0)
        assert line.status()["pending_in"] == 0
        assert 0 < len(target.received) <= MAX_PENDING + 1  # (a split hands its first byte on at once)
        line.feed(b"#VER\r")
        assert target.received.endswith(b"#VER\r")


def test_jitter_delays_randomly_but_never_reorders() -> None:
    clock, target, host, line = make_line()
    seed, spread = 5, 0.02
    line.inject(LineFault("jitter", direction="to_device", delay=spread, seed=seed))
    message = bytes(range(65, 65 + 50))
    for c in message:  # one byte per millisecond, each its own chunk
        line.feed(bytes([c]))
        clock.advance(0.001)
    clock.advance(1.0)
    assert target.received == message  # order preserved

    # arrival time of each byte: the seeded draw, but never before its predecessor
    rng = random.Random(seed)
    raw = [i * 0.001 + rng.uniform(0.0, spread) for i in range(len(message))]
    assert any(b < a for a, b in zip(raw, raw[1:], strict=False))  # unordered jitter would overtake
    expected, last = [], 0.0
    for t in raw:
        last = max(last, t)
        expected.append(last)
    arrivals = [when for when, data in target.chunks for _ in data]
    assert arrivals == pytest.approx(expected, abs=1e-9)
    assert all(a >= i * 0.001 for i, a in enumerate(arrivals))
    assert max(a - i * 0.001 for i, a in enumerate(arrivals)) <= spread + 1e-9


# -- noise -------------------------------------------------------------------------------------


def test_noise_rate_to_device_and_duration() -> None:
    clock, target, host, line = make_line()
    line.inject(LineFault("noise", direction="to_device", rate=100.0, duration=2.0, seed=11))
    clock.advance(1.0)
    assert len(target.received) == 100
    assert host.received == b""
    clock.advance(5.0)
    assert len(target.received) == 200  # stopped after two seconds
    assert line.faults == []
    assert clock.next_event() is None  # no timer left behind


def test_noise_is_deterministic_per_seed_and_goes_both_ways() -> None:
    def run(seed: int) -> tuple[bytes, bytes]:
        clock, target, host, line = make_line()
        line.inject(LineFault("noise", rate=30.0, duration=1.0, seed=seed))
        clock.advance(1.0)
        return target.received, host.received

    to_device, to_host = run(4)
    assert len(to_device) == len(to_host) == 30
    assert run(4) == (to_device, to_host)
    assert run(5) != (to_device, to_host)


def test_noise_at_the_most_a_line_allows() -> None:
    """At :data:`MAX_NOISE_RATE` a second of the line's time brings exactly that many bytes."""
    clock, target, host, line = make_line()
    line.inject(LineFault("noise", direction="to_device", rate=MAX_NOISE_RATE, duration=1.0, seed=3))
    clock.advance(1.0)
    assert len(target.received) == MAX_NOISE_RATE
    assert len(set(target.received)) == 256


def test_noise_cancelled_midway_emits_what_was_due() -> None:
    clock, target, host, line = make_line()
    handle = line.inject(LineFault("noise", direction="to_host", rate=1000.0))
    clock.advance(0.2555)
    handle.cancel()
    assert len(host.received) == 255
    clock.advance(1.0)
    assert len(host.received) == 255


# -- baud mismatch -----------------------------------------------------------------------------


def test_baud_mismatch_garbles_both_ways_while_active() -> None:
    device = S(19200)
    clock, target, host, line = make_line(device, echo=True)
    line.inject(LineFault("baud_mismatch", baudrate=9600, duration=1.0))
    assert line.status()["mismatch"] is True
    assert line.mismatch and line.host is None  # the host's reported settings are untouched
    line.feed(b"#ON\r")
    seen = garble(b"#ON\r", S(9600), device)
    assert target.received == seen != b"#ON\r"
    assert host.received == garble(seen, device, S(9600))
    clock.advance(1.0)
    assert line.status()["mismatch"] is False
    assert line.status()["faults"] == []
    line.feed(b"#ON\r")
    assert target.received == seen + b"#ON\r"


def test_baud_mismatch_keeps_the_hosts_frame_format() -> None:
    device = S(9600, 7, "E")
    clock, target, host, line = make_line(device)
    line.host_settings(S(9600, 7, "E"))
    line.inject(LineFault("baud_mismatch", baudrate=4800))
    line.feed(b"A")
    assert target.received == garble(b"A", S(4800, 7, "E"), device)
    line.clear_faults()
    assert not line.mismatch


# -- unplug, hang, silent ----------------------------------------------------------------------


def test_unplug_disconnects_and_loses_everything_both_ways() -> None:
    clock, target, host, line = make_line()
    line.inject(LineFault("unplug", duration=0.5))
    assert target.disconnects == 1
    line.feed(b"lost")
    target.send(b"lost too")
    clock.advance(0.5)
    assert target.received == b"" and host.received == b""  # not queued either
    line.feed(b"A")
    target.send(b"B")
    assert target.received == b"A" and host.received == b"B"
    assert target.disconnects == 1


def test_unplug_loses_bytes_in_flight() -> None:
    clock, target, host, line = make_line()
    line.inject(LineFault("delay", delay=0.1))
    line.feed(b"A")
    target.send(b"B")
    clock.advance(0.05)
    line.inject(LineFault("unplug", duration=0.1))
    clock.advance(1.0)
    assert target.received == b"" and host.received == b""


def test_hang_blocks_both_ways_without_disconnect() -> None:
    clock, target, host, line = make_line(echo=True)
    line.inject(LineFault("hang", duration=1.0))
    line.feed(b"#ON\r")
    target.send(b"spontaneous")
    assert target.received == b"" and host.received == b""
    assert target.disconnects == 0
    clock.advance(1.0)
    line.feed(b"#ON\r")
    assert target.received == b"#ON\r" and host.received == b"#ON\r"


def test_silent_device_still_acts_on_input() -> None:
    clock, target, host, line = make_line(echo=True)
    line.inject(LineFault("silent", duration=0.3))
    line.feed(b"#ON\r")
    assert target.received == b"#ON\r"
    assert host.received == b""
    clock.advance(0.3)
    line.feed(b"?")
    assert host.received == b"?"


# -- lifecycle, combination, status, trace -----------------------------------------------------


def test_cancel_and_clear_faults() -> None:
    clock, target, host, line = make_line()
    drop = line.inject(LineFault("drop", direction="to_device"))
    silent = line.inject(LineFault("silent"))
    assert isinstance(drop, FaultHandle) and drop.active
    assert line.faults == [LineFault("drop", direction="to_device"), LineFault("silent")]
    line.feed(b"A")
    assert target.received == b""
    drop.cancel()
    drop.cancel()  # idempotent
    assert not drop.active and silent.active
    line.feed(b"B")
    target.send(b"C")
    assert target.received == b"B" and host.received == b""
    line.clear_faults()
    assert not silent.active and line.faults == []
    target.send(b"D")
    assert host.received == b"D"


def test_drop_then_corrupt_combine_in_a_fixed_order() -> None:
    clock, target, host, line = make_line()
    line.inject(LineFault("corrupt", direction="to_device", count=1, seed=2))
    line.inject(LineFault("drop", direction="to_device", count=1))
    line.feed(b"ABC")
    # drop first (A vanishes), then corrupt the next byte that is left (B)
    assert target.received == flipped(b"B", 2) + b"C"
    assert line.faults == []


def test_delay_and_corrupt_combine() -> None:
    clock, target, host, line = make_line()
    line.inject(LineFault("delay", direction="to_host", delay=0.2, duration=1.0))
    line.inject(LineFault("corrupt", direction="to_host", duration=1.0, seed=9))
    target.send(b"OK\r")
    assert host.chunks == []
    clock.advance(0.2)
    assert host.chunks == [(pytest.approx(0.2), flipped(b"OK\r", 9))]


def test_status_lists_active_faults() -> None:
    clock, target, host, line = make_line()
    assert line.status()["faults"] == []
    line.inject(LineFault("jitter", delay=0.01, duration=1.0))
    line.inject(LineFault("noise", rate=10.0, duration=2.0))
    assert line.status()["faults"] == ["jitter", "noise"]
    clock.advance(1.0)
    assert line.status()["faults"] == ["noise"]
    clock.advance(1.0)
    assert line.status()["faults"] == []


def test_trace_notes_fault_start_and_end(tmp_path) -> None:
    clock = VirtualClock()
    path = tmp_path / "wire.trace"
    tracer = Tracer(path)
    target = Target(clock)
    line = Line(target, clock, tracer=tracer)
    line.attach(lambda data: None)
    clock.advance(1.0)
    line.inject(LineFault("drop", direction="to_device", duration=0.5))
    line.feed(b"A")
    clock.advance(0.5)
    handle = line.inject(LineFault("unplug"))
    line.feed(b"B")
    handle.cancel()
    line.inject(LineFault("drop", direction="to_host", count=1))
    target.send(b"CD")
    tracer.close()
    assert path.read_text().splitlines() == [
        "1.000000 -- fault start: drop to_device duration=0.5",
        '1.000000 H>D 41 "A"  (device read "")',
        "1.500000 -- fault ended: drop to_device duration=0.5",
        "1.500000 -- fault start: unplug",
        '1.500000 H>D 42 "B"  (lost: unplug)',
        "1.500000 -- fault cancelled: unplug",
        "1.500000 -- fault start: drop to_host count=1",
        '1.500000 D>H 43 44 "CD"  (host read "D")',
        "1.500000 -- fault ended: drop to_host count=1",
    ]


def test_close_ends_faults_and_timers() -> None:
    clock, target, host, line = make_line()
    handle = line.inject(LineFault("noise", rate=10.0))
    line.inject(LineFault("delay", delay=1.0))
    line.feed(b"A")
    line.close()
    assert not handle.active
    assert clock.next_event() is None


@pytest.mark.parametrize(
    "kwargs",
    [
        {"kind": "lightning"},
        {"kind": "drop", "direction": "sideways"},
        {"kind": "drop", "count": 0},
        {"kind": "delay"},  # needs delay
        {"kind": "noise"},  # needs rate
        {"kind": "noise", "rate": 0.0},
        {"kind": "noise", "rate": 1e308},  # (its first tick drew more bytes than memory holds)
        {"kind": "noise", "rate": MAX_NOISE_RATE * 1.01},
        {"kind": "baud_mismatch"},  # needs baudrate
        {"kind": "unplug", "count": 3},  # count only for corrupt/drop/split
        {"kind": "hang", "delay": 1.0},
        {"kind": "silent", "duration": -1.0},
    ],
)
def test_invalid_faults_are_rejected(kwargs) -> None:
    with pytest.raises(ValueError):
        LineFault(**kwargs)


# -- through a real pty ------------------------------------------------------------------------


@pytest.mark.skipif(sys.platform == "win32", reason="ptys are POSIX only")
async def test_drop_and_corrupt_on_a_real_pty() -> None:
    clock = RealClock()
    target = Target(clock, S(9600), echo=True)
    line = Line(target, clock)
    transport = PtyTransport()
    await transport.start(line)
    try:
        line.inject(LineFault("drop", direction="to_device", count=1))
        line.inject(LineFault("corrupt", direction="to_host", count=2, seed=42))

        def host() -> bytes:
            with serial.Serial(transport.address, 9600, timeout=3) as port:
                port.write(b"#ON\r")
                port.flush()
                return port.read(3)

        got = await asyncio.to_thread(host)
        assert target.received == b"ON\r"  # the '#' never reached the device
        assert got == flipped(b"ON", 42) + b"\r"  # and its echo came back with two bits flipped
        assert line.faults == []
    finally:
        await transport.close()
        line.close()
