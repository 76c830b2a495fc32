"""Random noise with '#' (what ``benchmarks/noise.py --raw`` pours in), taken in chunks by the
face's one-step paths, must leave exactly the bytes and the state that byte-by-byte handling
leaves: the answers, every output change in order and where in the answers it happened, the
parameters, errno and warnings, the drive's selection and the framing of the line in progress."""

from __future__ import annotations

import random

import hypothesis.strategies as hs
import pytest
from hypothesis import given, settings

from devsim.core.clock import VirtualClock
from devsim.core.nvram import NonVolatileMemory
from devsim.devices.sers import SersDevice

# Lines that change how the drive answers noise: echo modes, English messages, outputs that
# show errors and warnings, programming mode, selection, broadcast.
SETTINGS = [b"#P1017=0\r", b"#P1017=1\r", b"#P1017=2\r", b"#P265=1\r", b"#P265=0\r", b"#P1132=1\r",
            b"#P1131=-2\r", b"#P12=0\r", b"#PGM\r", b"#QUIT\r", b"#2\r", b"#1\r", b"#*\r", b"#Q\r"]
PIECES = [b"#", b"#1", b"#2", b"#*", b"#01", b"#001", b"#0", b"#12", b"#012", b"#5", b"#200", b"#1#", b"\r", b"\n", b"\r\n", b"\n\r",
          b"\x8f", b"Q", b" ", b"1", b"5", b"?", b"P11?", b"A" * 70, b"A" * 57, b" " * 58, b"X=1", b"E", b"IF"]


def _run(stream: bytes, cuts: list[int], address: int = 1, shared: bool = False) -> tuple[object, ...]:
    """What a fresh drive (DIP address ``address``, on a ``shared`` RS-485 line or not) sends
    and becomes when ``stream`` arrives cut at ``cuts`` (sizes, used in turn)."""
    device = SersDevice(clock=VirtualClock(), config={"boot_time": 0, "address": address},
                        nvram=NonVolatileMemory(None))
    device.main.shared_line = shared
    model = device.model
    out = bytearray()
    device.attach(out.extend)
    changes: list[tuple[int, str, object]] = []  # (bytes sent before it, the output, its value)

    def changed(name: str, _old: object, new: object) -> None:
        changes.append((len(out) + sum(map(len, device.main._batch or ())), name, new))

    for name in model.signals.names("output"):
        model.signals.subscribe(name, changed)
    sent = {}  # bytes fed -> bytes sent by then (what the host has seen at each chunk's end)
    start, turn = 0, 0
    while start < len(stream):
        size = cuts[turn % len(cuts)]
        device.feed(stream[start : start + size])
        start, turn = start + size, turn + 1
        sent[min(start, len(stream))] = len(out)
    face = device.face()
    line = face.line
    framer = vars(face.framer)
    if not framer["in_line"]:  # (what counted the last line means nothing once it ended)
        framer = {name: framer[name] for name in ("in_line", "_last_end")}
    return sent, (bytes(out), changes, device.state(), dict(model.params.values), model.power_stage.errno, model.power_stage.warnings, model.addressed,
                  framer, face._last_replied,
                  None if line is None else (line.execute, line.reply, line.error, bytes(line.held),
                                             bytes(line.deferred)))


def _check(stream: bytes, cuts: list[int], address: int = 1, shared: bool = False) -> tuple[object, ...]:
    """``stream`` in chunks leaves what it leaves byte by byte, and at each chunk's end the
    same bytes have been sent; returns what it leaves."""
    sent_bytewise, bytewise = _run(stream, [1], address, shared)
    sent, chunked = _run(stream, cuts, address, shared)
    assert chunked == bytewise
    assert sent == {fed: sent_bytewise[fed] for fed in sent}
    return bytewise


@settings(max_examples=400, deadline=None)
@given(data=hs.lists(hs.one_of(hs.binary(max_size=16), hs.sampled_from(PIECES + SETTINGS)), max_size=50),
       cuts=hs.lists(hs.integers(min_value=1, max_value=300), min_size=1, max_size=8),
       address=hs.sampled_from([1, 1, 1, 0, 12]), shared=hs.booleans())
def test_noise_in_chunks_leaves_what_bytes_leave(data: list[bytes], cuts: list[int], address: int,
                                                 shared: bool) -> None:
    """(Address 0 is the master, answering to #200; on a shared line a drive starts
    unselected.)"""
    _check(b"".join(data), cuts, address, shared)


@pytest.mark.parametrize("seed", [1, 2, 3, 4])
def test_the_benchmarks_noise_in_pty_reads_leaves_what_bytes_leave(seed: int) -> None:
    """The benchmark's own noise (seeds 1–3 of ``benchmarks/noise.py --raw``), in 4 KiB reads
    as from a pty and in uneven ones."""
    stream = random.Random(seed).randbytes(1 << 13)
    _check(stream, [4095])
    _check(stream, [1000, 7, 333])


@pytest.mark.parametrize(
    "stream",
    [
        # a line for another drive ends and the next begins within one skip: the new line is
        # not the old one (a failed line's error does not carry over to it)
        b"#\x00#0\r#\x00#1P11?\r",
        b"#\x00#0\r#\x00#2\r#\x00\r#1P11?\r",
        # lines failing at once, one after the other, with restarts, pairs and noise between
        b"#\x00\r\n\x8f#Q\n\r#\x01#\x02#*\x03\r#1\x04\r#P11?\r",
        b"#P1017=2\r#\x00#\x01\r#P1017=1\r#P265=1\r#\x00\r#P265=0\r#P11?\r",
        # outputs showing warnings and errors change at the first error, after its echo
        b"#P1132=1\r#P1131=-2\r#\x00\r#P12=0\r#\x01#\x02\r#P12=0\r#Q\r#1P11?\r",
        # a broadcast's failed line, then the drive's own address: it is selected from then on
        b"#*\x00#1\x01\r#\x02\r#P11?\r",
        # echo mode 2: an error's message waits for the line end, even in a later chunk
        b"#P1017=2\r#\x00" + b"X" * 20 + b"#\x01\r#" + b"\x02" * 30 + b"\r#P1017=1\r#P11?\r",
        # beyond 60 characters a line's text is dropped, only echoed (and an overflow)
        b"#1" + b" " * 70 + b"P11?\r#" + b" " * 57 + b"X=1\x00\r# " + b"1" * 65 + b"\r#1P11?\r",
        # not selected: other drives' addresses are skipped too; beyond 60 characters their
        # digits, like a '#', are no overflow, text is
        b"#2\r#" + b"A" * 58 + b"#5#1\r#1P11?\r",
        b"#2\r#" + b"A" * 57 + b"#55#1\r#1P11?\r",
        b"#2\r#" + b"A" * 58 + b"#5X#1\r#1P11?\r",
        b"#2\r#" + b"A" * 59 + b"5#1\r#1P11?\r",
        b"#2\r#12 X\r#0\r#001\r#P11?\r",
        b"#2\r#5 P11?\r#*P265=1\r#1\x00\r#P265=0\r#1P11?\r",  # (a broadcast is executed)
    ],
)
@pytest.mark.parametrize("shared", [False, True])
def test_noise_lines_in_one_chunk_answer_as_bytes_do(stream: bytes, shared: bool) -> None:
    """On a shared line the drive starts unselected: the same lines, then after ``#1``."""
    for lines in ([stream, b"#1\r" + stream] if shared else [stream]):
        for cuts in ([len(lines)], [len(lines) // 2 + 1], [5, 11]):
            answers = _check(lines, cuts, shared=shared)[0]
    assert answers[-13:-3] == b"P11=0\n\r\nok"  # (the last line is answered)
