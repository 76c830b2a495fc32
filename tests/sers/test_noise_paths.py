"""Random noise with '#' (what ``benchmarks/noise.py --raw`` pours in), taken in chunks by the
face's one-step paths, must leave exactly the bytes and the state that byte-by-byte handling
leaves: the answers, every output change and every error the logs hear, in order and where
in the answers it happened, the parameters, errno and warnings, the drive's selection and the framing of the line in progress."""

from __future__ import annotations

import random

import hypothesis.strategies as hs
import pytest
from hypothesis import given, settings

from devsim.core.clock import VirtualClock
from devsim.core.nvram import NonVolatileMemory
from devsim.devices.sers import SersDevice
from tests.sers.lines import share_line

# Lines that change how the drive answers noise: echo modes, English messages, outputs that
# show errors and warnings, programming mode, selection, broadcast.
SETTINGS = [b"#P1017=0\r", b"#P1017=1\r", b"#P1017=2\r", b"#P265=1\r", b"#P265=0\r", b"#P1132=1\r",
            b"#P1131=-2\r", b"#P12=0\r", b"#PGM\r", b"#QUIT\r", b"#2\r", b"#1\r", b"#*\r", b"#Q\r"]
PIECES = [b"#", b"#1", b"#2", b"#*", b"#01", b"#001", b"#0", b"#12", b"#012", b"#5", b"#200", b"#1#", b"\r", b"\n", b"\r\n", b"\n\r",
          b"\x8f", b"Q", b" ", b"1", b"5", b"?", b"P11?", b"A" * 70, b"A" * 57, b" " * 58, b"X=1", b"E", b"IF"]


def _run(stream: bytes, cuts: list[int], address: int = 1, shared: bool = False,
         cycles: frozenset[int] = frozenset()) -> tuple[object, ...]:
    """What a fresh drive (DIP address ``address``, on a ``shared`` RS-485 line or not) sends
    and becomes when ``stream`` arrives cut at ``cuts`` (sizes, used in turn), its power
    cycled once the bytes up to each offset in ``cycles`` arrived (a chunk ends there)."""
    device = SersDevice(clock=VirtualClock(), config={"boot_time": 0, "address": address},
                        nvram=NonVolatileMemory(None))
    share_line(device, shared)
    model = device.model
    out = bytearray()
    device.attach(out.extend)
    changes: list[tuple[int, str, object]] = []  # (bytes sent before it, the output, its value)

    def changed(name: str, _old: object, new: object) -> None:
        changes.append((len(out) + sum(map(len, device.main._batch or ())), name, new))

    for name in model.signals.names("output"):
        model.signals.subscribe(name, changed)
    errors: list[tuple[str, bool]] = []  # (the code, whether it refused a host's line)
    model.listen("device_error", lambda code, refused=False: errors.append((code, refused)))
    # bytes fed -> bytes sent and errors heard by then (what the host and the logs have seen at
    # each chunk's end: a chunk's answers leave in one write, after it)
    sent = {}
    start, turn = 0, 0
    while start < len(stream):
        stop = min([start + cuts[turn % len(cuts)], len(stream), *(cycle for cycle in cycles if cycle > start)])
        device.feed(stream[start:stop])
        start, turn = stop, turn + 1
        if start in cycles:
            model.power_cycle()
        sent[start] = len(out), len(errors)
    face = device.face()
    line = face.line
    framer = vars(face.framer)
    if not framer["in_line"]:  # (what counted the last line means nothing once it ended)
        framer = {name: framer[name] for name in ("in_line", "_last_end")}
    return sent, (bytes(out), changes, errors, device.state(), dict(model.params.values), model.power_stage.errno, model.power_stage.warnings, model.addressed,
                  framer, face._last_replied,
                  None if line is None else (line.execute, line.reply, line.error, bytes(line.held),
                                             bytes(line.deferred)))


def _check(stream: bytes, cuts: list[int], address: int = 1, shared: bool = False,
           cycles: frozenset[int] = frozenset()) -> tuple[object, ...]:
    """``stream`` in chunks leaves what it leaves byte by byte, and at each chunk's end the
    same bytes have been sent and the same errors heard; returns what it leaves."""
    sent_bytewise, bytewise = _run(stream, [1], address, shared, cycles)
    sent, chunked = _run(stream, cuts, address, shared, cycles)
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


# Lines of noise as they come one after the other: the first character of the text (most fail
# at once, some do not; an address, a restart), the text with restarts, the line end, noise.
FIRSTS = [b"\x00", b"!", b"\xff", b"K", b"A", b"P", b"H", b"s", b"*H", b"1S", b" ", b"1", b"*", b"#", b"\r", b"",
          b"1\x00", b"01!", b"*\x00", b"1A"]
RESTARTS = [b"#", b"#\x00", b"#1", b"#2", b"#*", b"##", b"#01", b"#1#"]
ENDS = [b"\r", b"\n", b"\r\n", b"\n\r", b"\r\r", b"\n\n", b""]
TEXT = hs.binary(max_size=12).map(lambda text: text.replace(b"#", b"").replace(b"\r", b"").replace(b"\n", b""))
NOISE = hs.binary(max_size=12).map(lambda noise: noise.replace(b"#", b""))
LINE = hs.tuples(hs.sampled_from(FIRSTS), hs.lists(hs.one_of(TEXT, hs.sampled_from(RESTARTS)), max_size=4),
                 hs.sampled_from(ENDS), NOISE).map(lambda parts: b"#" + parts[0] + b"".join(parts[1]) + parts[2] + parts[3])


@settings(max_examples=400, deadline=None)
@given(lines=hs.lists(hs.one_of(LINE, LINE, LINE, hs.sampled_from([*SETTINGS, b"#ON\r", b"#OFF\r"])), max_size=30),
       cuts=hs.lists(hs.integers(min_value=1, max_value=120), min_size=1, max_size=8),
       address=hs.sampled_from([1, 1, 0]), shared=hs.booleans())
def test_lines_of_noise_in_chunks_leave_what_bytes_leave(lines: list[bytes], cuts: list[int], address: int,
                                                         shared: bool) -> None:
    """Lines of noise one after the other (most failing at their first character, some running
    a statement first (``H``, ``S``: refused, or run once ``ON``), with restarts with and
    without addresses, CR/LF pairs and noise with line ends between them), echo modes, English
    messages, programming mode and selections among them, cut anywhere."""
    _check(b"".join(lines), cuts, address, shared)


@settings(max_examples=150, deadline=None)
@given(lines=hs.lists(hs.one_of(LINE, LINE, hs.sampled_from([*SETTINGS, b"#ON\r"])), min_size=1, max_size=20),
       cuts=hs.lists(hs.integers(min_value=1, max_value=120), min_size=1, max_size=4),
       cycles=hs.frozensets(hs.integers(min_value=1, max_value=400), max_size=3), shared=hs.booleans())
def test_lines_of_noise_across_power_cycles_leave_what_bytes_leave(lines: list[bytes], cuts: list[int],
                                                                   cycles: frozenset[int], shared: bool) -> None:
    """A power cycle in the middle of lines of noise (mid-line, between lines, in a run of
    failed lines): what the drive sends and becomes after it, in chunks as byte by byte."""
    _check(b"".join(lines), cuts, 1, shared, cycles)


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
        # a line that failed at once, noise after its end, the chunk's end, a line end in the
        # next chunk: noise, not the other half of a pair
        b"#\x00\rxy\n#\x00\r\n#1P11?\r",
        b"#\x00\rx\r#\x00\n\r\n#1P11?\r",
        # lines whose first character runs a statement (refused while the drive is off; run
        # once it is on) and whose next one fails; one cut by the chunk, one that goes on
        b"#H\x9bxx\r#s\x01#\x02\r\n#Sx#1y\r#ON\r#H\x9bxx\r#sx\n\r#Hxx#2\r#1S\r#1P11?\r",
        b"#ON\r#PGM\r#H\x00\r#S\r#QUIT\r#H" + b"S" * 70 + b"\r#P11?\r",
        # ... a broadcast's (executed, not answered), in echo mode 2 (the message at the end)
        b"#*H\x9bx\r#*Sx#1\r#P1017=2\r#Hxx\r#S\x00\r\n#P1017=1\r#P11?\r",
        # ... run while the drive is on, and the text up to the 60th character kept, or not
        b"#ON\r#H" + b" " * 57 + b"S\r#S" + b" " * 58 + b"H\r#P11?\r",
        # ... run, and the statements after it in the same text run (echoed with it, in mode 2 not)
        b"#ON\r#HSP11?\r#1H P1017=2\r#Sx\r#HP11?\r#P1017=1\r#P11?\r",
        # while selected, lines the noise path begins for the face: another drive's (it is
        # selected then; ended, or cut by a restart or the chunk), and this one's whose
        # statement completes before anything fails (left to the text run), or that is quiet
        b"#\x00\r#7ab\r#1\r#7x#1\x00\r#X=1\x00\r#P1\x00\r#P11?\r#\x00\n#12\r#1P11?\r",
        # a failed line that a chunk cuts in its text, taken on in the next chunk: its restarts
        # (another drive's address, this one's), its end, a pair, the lines after it
        b"#\x00abcdefgh#\x00ij\r\n#\x00kl#7mn\r#1\x00opqrst#1uv\r\nw#\x00\r#P11?\r",
        # lines failing at once, one after the other, with restarts, pairs and noise between
        b"#\x00\r\n\x8f#Q\n\r#\x01#\x02#*\x03\r#1\x04\r#P11?\r",
        b"#P1017=2\r#\x00#\x01\r#P1017=1\r#P265=1\r#\x00\r#P265=0\r#P11?\r",
        # outputs showing warnings and errors change at the first error, after its echo
        b"#P1132=1\r#P1131=-2\r#\x00\r#P12=0\r#\x01#\x02\r#P12=0\r#Q\r#1P11?\r",
        # a broadcast's failed line, then the drive's own address: it is selected from then on
        b"#*\x00#1\x01\r#\x02\r#P11?\r",
        # echo mode 2: an error's message waits for the line end, even in a later chunk
        b"#P1017=2\r#\x00" + b"X" * 20 + b"#\x01\r#" + b"\x02" * 30 + b"\r#P1017=1\r#P11?\r",
        # a run of failed lines whose last one goes on: at a restart for another drive, at one
        # for this drive, at the chunk's end (beyond 60 characters), in echo modes 1 and 2
        b"#\x00a\r#\x01b#7c\r#1\r#\x02d#\x00#1e\r#\x03e" + b"f" * 70 + b"#\r#1P11?\r",
        b"#P1017=2\r#\x00a\r#\x01b#7c\r#1\r#\x02d#1\x00\r#\x03" + b"f" * 70 + b"\r#P1017=1\r#1P11?\r",
        # lines with this drive's address or the broadcast one that fail (taken one at a time),
        # in echo modes 2 and 1, with restarts, pairs and noise after them
        b"#P1017=2\r#1\x00a\r#1\x01b#2c\r#1\r#01\x02\n\r#1A\x00b#\x00c\r#1" + b"x" * 70 + b"\r#P1017=1\r#1P11?\r",
        b"#*\x00a\r#*H\x00\r#1\x00#*b\r#1\x00\r\nxx\r#1\x00\n\n#1\x00\r\r\n#1\x00#1\r\n#P11?\r",
        # a text that fails at its 60th character, and one whose failing character is the
        # 61st, dropped: no error but the overflow's at the line end
        b"#" + b" " * 58 + b"\x00x\r#" + b" " * 59 + b"\x00x\r#A" + b"1" * 57 + b"\x00\r#A" + b"1" * 58 + b"\x00\r#P11?\r",
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
