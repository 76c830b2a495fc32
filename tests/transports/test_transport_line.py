"""Line: garbling on mismatched settings, pacing on the device clock, tracing."""

from __future__ import annotations

import asyncio
from typing import Any, ClassVar

import pytest

from devsim.core.bus import Bus
from devsim.core.clock import RealClock, VirtualClock
from devsim.core.device import Device, Face, SerialSettings
from devsim.transports.line import Line, garble, settings_match
from devsim.transports.pacing import MAX_PENDING
from devsim.transports.trace import Tracer, render
from tests.transports.transport_helpers import EchoTarget

S = SerialSettings
STANDARD = [300, 600, 1200, 2400, 4800, 9600, 19200, 38400, 57600, 115200]
ASCII = bytes(range(0x20, 0x7F)) + b"\r\n"


# -- garble ------------------------------------------------------------------------------------


def test_garble_identity_when_settings_match() -> None:
    assert garble(b"#ON\r", S(9600), S(9600)) == b"#ON\r"
    assert garble(b"", S(9600), S(19200)) == b""


@pytest.mark.parametrize("host", STANDARD)
@pytest.mark.parametrize("device", STANDARD)
def test_garble_changes_every_ascii_char_at_wrong_baud(host: int, device: int) -> None:
    if host == device:
        return
    for c in ASCII:
        out = garble(bytes([c]), S(host), S(device))
        assert out[:1] != bytes([c]), (host, device, chr(c), out)


def test_garble_faster_sender_collapses_and_slower_sender_multiplies() -> None:
    fast_host = garble(b"#ON\r", S(19200), S(9600))
    slow_host = garble(b"#ON\r", S(9600), S(19200))
    assert 0 < len(fast_host) < 4
    assert len(slow_host) > 4
    # Deterministic: a pure function of its arguments.
    assert garble(b"#ON\r", S(9600), S(19200)) == slow_host


def test_garble_a_break_reads_as_one_nul_however_long() -> None:
    """A line held low from the start bit through the stop bit sample is a break: one NUL (a
    16550 reports it once), then the character the line's rise cuts, as before.  Found by the
    soak over a real ``devsim run``: a host at 1 baud (RFC 2217 SET-BAUDRATE, or a pty's BOTHER
    rate) read by a 9600 Bd device came out as thousands of NULs per byte, and 256 bytes held the
    simulator's event loop 4 s; a host at 4294967295 Bd got 1.9 million bytes of a 7-byte answer."""
    assert garble(b"\x00", S(1), S(9600)) == b"\x00\xc0"  # start + 8 data bits low, then the stop bit
    assert garble(b"\x00" * 256, S(1), S(9600)) == b"\x00\xc0" * 256
    assert len(garble(b"#1P11?\r", S(9600), S(4_294_967_295))) < 50
    # shorter than two of the receiver's frames: read as it always was
    assert garble(b"#ON\r", S(1200), S(2400)) == b"\x1e\x86\xfe\x98\xf8\x98\xe6\x80"
    assert garble(b"\x10", S(9600), S(19200)) == b"\x00\xe0"


def test_garble_parity_error_reads_as_nul() -> None:
    # 8N1 ASCII read by a 7E1 UART: the 8th data bit (0) lands on the parity bit.
    out = garble(b"#", S(9600), S(9600, 7, "E"))  # '#' has three ones: even parity bit is 1
    assert out == b"\x00"
    assert garble(b"#ON\r", S(9600), S(9600, 7, "E")) != b"#ON\r"


def test_settings_match_ignores_int_float_stopbits() -> None:
    assert settings_match(S(9600, 8, "N", 1), S(9600, 8, "n", 1.0))
    assert not settings_match(S(9600), S(9600, 7, "E"))


# -- mismatch through the Line -----------------------------------------------------------------


def test_host_assumed_matching_until_reported() -> None:
    clock = VirtualClock()
    target = EchoTarget(S(19200))
    line = Line(target, clock)
    out = bytearray()
    line.attach(out.extend)
    line.feed(b"#ON\r")
    assert target.received == b"#ON\r"
    assert out == b"#ON\r"
    assert line.host is None and not line.mismatch


def test_mismatch_garbles_both_directions_and_status() -> None:
    clock = VirtualClock()
    target = EchoTarget(S(19200))
    line = Line(target, clock)
    out = bytearray()
    line.attach(out.extend)
    line.host_settings(S(9600))
    assert line.mismatch
    line.feed(b"#ON\r")
    seen = garble(b"#ON\r", S(9600), S(19200))
    assert bytes(target.received) == seen != b"#ON\r"
    assert bytes(out) == garble(seen, S(19200), S(9600))
    status = line.status()
    assert status["mismatch"] is True
    assert status["device"]["baudrate"] == 19200
    assert status["host"]["baudrate"] == 9600
    assert status["bytes_in"] == 4 and status["bytes_out"] == len(seen)

    line.host_settings(S(19200))
    target.received.clear()
    line.feed(b"#ON\r")
    assert target.received == b"#ON\r" and not line.mismatch


def test_host_disconnected_forwards_and_forgets_host() -> None:
    target = EchoTarget(S(19200))
    line = Line(target, VirtualClock())
    line.host_settings(S(9600))
    line.host_disconnected()
    assert target.disconnects == 1
    assert line.host is None and not line.mismatch


class _AddressedFace(Face):
    """Answers ``<addr>?`` with ``<addr>!``."""

    def feed(self, data: bytes) -> None:
        addr = self.model.config["addr"]
        if data == addr + b"?":
            self.send(addr + b"!")


class _Addressed(Device):
    kind = "test"
    face_classes: ClassVar[dict[str, Any]] = {"main": _AddressedFace}

    def __init__(self, addr: bytes, **kw: Any) -> None:
        super().__init__(config={"addr": addr}, **kw)


def test_line_in_front_of_a_bus() -> None:
    clock = VirtualClock()
    bus = Bus([_Addressed(b"1", clock=clock), _Addressed(b"2", clock=clock)])
    line = Line(bus, clock)
    out = bytearray()
    line.attach(out.extend)
    line.feed(b"2?")
    assert out == b"2!"


# -- pacing ------------------------------------------------------------------------------------


async def test_pacing_releases_output_no_earlier_than_char_time() -> None:
    clock = RealClock()
    settings = S(9600)
    target = EchoTarget(settings, echo=False)
    line = Line(target, clock, pacing=True)
    assert line.pacing
    arrivals: list[tuple[float, bytes]] = []
    done = asyncio.Event()
    message = b"0123456789AB"

    def write(data: bytes) -> None:
        arrivals.append((clock.now(), data))
        if sum(len(d) for _, d in arrivals) >= len(message):
            done.set()

    line.attach(write)
    t0 = clock.now()
    target.send(message)
    assert arrivals == []  # nothing is on the host side yet
    await asyncio.wait_for(done.wait(), 2.0)
    ct = settings.char_time()
    received = 0
    for when, data in arrivals:
        received += len(data)
        # the last byte of this chunk has been on the wire for `received` character times
        assert when - t0 >= received * ct - 1e-6
    assert b"".join(d for _, d in arrivals) == message
    assert arrivals[-1][0] - t0 >= len(message) * ct - 1e-6
    assert line.status()["pending_out"] == 0


async def test_pacing_queues_consecutive_telegrams_back_to_back() -> None:
    clock = RealClock()
    settings = S(19200)
    target = EchoTarget(settings, echo=False)
    line = Line(target, clock, pacing=True)
    arrivals: list[tuple[float, bytes]] = []
    done = asyncio.Event()

    def write(data: bytes) -> None:
        arrivals.append((clock.now(), data))
        if sum(len(d) for _, d in arrivals) >= 10:
            done.set()

    line.attach(write)
    t0 = clock.now()
    target.send(b"ABCDE")
    target.send(b"FGHIJ")
    await asyncio.wait_for(done.wait(), 2.0)
    assert arrivals[-1][0] - t0 >= 10 * settings.char_time() - 1e-6
    assert b"".join(d for _, d in arrivals) == b"ABCDEFGHIJ"


async def test_pacing_after_a_flood_holds_at_most_max_pending_and_answers_after_it() -> None:
    """A host on a pty sends faster than the wire carries, so an echoing device's paced output
    piles up: 1 MiB of garbage echoed at once.  The transmitter keeps the newest
    ``MAX_PENDING`` bytes (the oldest dropped, the rest moved up), so the echo of the host's next
    line leaves within ``MAX_PENDING`` character times, not behind the whole flood (before: every
    byte queued, the line's answer 1 MiB of character times later, at 9600 baud three hours)."""
    clock = RealClock()
    settings = S(4_000_000)  # (2.5 µs a character: MAX_PENDING leaves in 0.16 s, the flood in 2.6 s)
    target = EchoTarget(settings)
    line = Line(target, clock, pacing=True)
    arrived = bytearray()
    answered = asyncio.Event()

    def write(data: bytes) -> None:
        arrived.extend(data)
        if arrived.endswith(b"#1VER\r"):
            answered.set()

    line.attach(write)
    for _ in range(256):
        line.feed(bytes(4096))
    line.feed(b"#1VER\r")
    assert line.status()["pending_out"] <= MAX_PENDING
    await asyncio.wait_for(answered.wait(), 1.0)
    assert len(arrived) <= MAX_PENDING + 6
    assert line.status()["pending_out"] == 0


def test_pacing_is_off_on_a_virtual_clock() -> None:
    clock = VirtualClock()
    target = EchoTarget(S(300), echo=False)
    line = Line(target, clock, pacing=True)
    assert not line.pacing
    out = bytearray()
    line.attach(out.extend)
    target.send(b"hello")
    assert out == b"hello"


def test_output_dropped_when_nobody_listens() -> None:
    target = EchoTarget(S(9600))
    line = Line(target, VirtualClock())
    line.feed(b"x")  # echo with no transport attached: no error
    assert line.status()["bytes_out"] == 1
    line.close()
    target.send(b"y")  # detached from the target
    assert line.status()["bytes_out"] == 1


# -- trace -------------------------------------------------------------------------------------


def test_render_escapes() -> None:
    assert render(b"#ON\r") == '"#ON\\r"'
    assert render(b'\x00"\\\n\x7f') == '"\\x00\\"\\\\\\n\\x7f"'


def test_tracer_records_both_directions(tmp_path) -> None:
    clock = VirtualClock()
    path = tmp_path / "wire.trace"
    tracer = Tracer(path)
    target = EchoTarget(S(9600))
    line = Line(target, clock, tracer=tracer)
    line.attach(lambda data: None)
    clock.advance(1.5)
    line.feed(b"#ON\r")
    # flushed per line: readable before close
    lines = path.read_text().splitlines()
    assert lines == [
        '1.500000 H>D 23 4f 4e 0d "#ON\\r"',
        '1.500000 D>H 23 4f 4e 0d "#ON\\r"',
    ]
    line.host_settings(S(19200))
    clock.advance(0.25)
    line.feed(b"A")
    tracer.close()
    text = path.read_text().splitlines()
    assert text[2].startswith("1.500000 -- host settings 19200 8N1 (mismatch")
    assert text[3].startswith('1.750000 H>D 41 "A"  (device read "')
