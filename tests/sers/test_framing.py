"""The SERS port's framing (devsim.devices.sers.framing), what record, replay and the telegram tap
cut a line with: a host's line ends after CR or LF, the drive's answer after CR (§4.1); a line
that never ends is shown as it is once it passes ``MAX_PARTIAL`` bytes.  By property, against the
rule written as an oracle, with the stream cut anywhere."""

from __future__ import annotations

import hypothesis.strategies as hs
import pytest
from hypothesis import example, given

from devsim.core.framing import MAX_PARTIAL
from devsim.devices.sers.device import SersDevice
from devsim.devices.sers.framing import LINES

TOKENS = [b"#1P11?", b"#V=1000", b"\r", b"\n", b"\r\n", b"\n\r", b"\nok1\n\r", b"A", b"\xb2"]


def _oracle(stream: bytes, ends: bytes) -> tuple[list[str], bytes]:
    """Lines as the manual cuts them, byte by byte; a rest longer than MAX_PARTIAL bytes is shown
    as it is and forgotten."""
    lines: list[str] = []
    current = bytearray()
    for byte in stream:
        current.append(byte)
        if byte in ends or len(current) > MAX_PARTIAL:
            lines.append(current.decode("latin-1"))
            current.clear()
    return lines, bytes(current)


def _fed(direction: str, chunks: list[bytes]) -> list[str]:
    decoder = LINES.decoder(direction)
    out: list[str] = []
    for chunk in chunks:
        got = decoder.feed(chunk)
        assert got is not None
        out += got
    return out


def test_the_port_declares_the_line_framing() -> None:
    assert SersDevice.ports[0].framing is LINES
    assert LINES.tolerances == () and LINES.label is None  # the answer echoes the line as typed


@pytest.mark.manual("§4.1", "a line ends with CR or LF; the drive answers <LF>ok1<LF><CR>")
def test_host_lines_end_after_cr_or_lf_and_answers_after_cr() -> None:
    assert LINES.split is not None
    assert LINES.split(b"#1P11?\r\n#V") == ([b"#1P11?\r", b"\n"], b"#V")
    assert _fed("host", [b"#1P11?\r\n#V=1", b"0\n"]) == ["#1P11?\r", "\n", "#V=10\n"]
    assert _fed("device", [b"#1P11?\rP11=5\n\r\nok1\n\r\n"]) == ["#1P11?\r", "P11=5\n\r", "\nok1\n\r"]
    assert LINES.decoder("host").direction == "host" and LINES.decoder("device").direction == "device"


@given(hs.lists(hs.sampled_from(TOKENS), max_size=10).map(b"".join), hs.integers(min_value=0, max_value=80),
       hs.sampled_from(["host", "device"]))
def test_a_stream_cut_anywhere_gives_the_oracles_lines(stream: bytes, cut: int, direction: str) -> None:
    ends = b"\r\n" if direction == "host" else b"\r"
    lines, _rest = _oracle(stream, ends)
    assert _fed(direction, [stream[:cut], stream[cut:]]) == lines


@pytest.mark.parametrize("direction", ["host", "device"])
@given(length=hs.integers(min_value=MAX_PARTIAL - 2, max_value=MAX_PARTIAL + 2), cut=hs.integers(min_value=1, max_value=600))
@example(length=MAX_PARTIAL, cut=MAX_PARTIAL)
@example(length=MAX_PARTIAL + 1, cut=MAX_PARTIAL + 1)
def test_a_line_without_an_end_is_kept_up_to_max_partial_bytes(direction: str, length: int, cut: int) -> None:
    garbage = bytes(0x41 + i % 26 for i in range(length))
    decoder = LINES.decoder(direction)
    got = decoder.feed(garbage[:cut]) + decoder.feed(garbage[cut:])
    if length <= MAX_PARTIAL:  # kept: the line it starts ends with the next CR
        assert got == []
        assert decoder.feed(b"\r") == [garbage.decode("latin-1") + "\r"]
    else:  # the first MAX_PARTIAL + 1 bytes shown as they are, and forgotten; the rest starts a line
        assert got == [garbage[: MAX_PARTIAL + 1].decode("latin-1")]
        assert decoder.feed(b"#1\r") == [garbage[MAX_PARTIAL + 1 :].decode("latin-1") + "#1\r"]


@given(hs.binary(max_size=1800).map(lambda noise: noise.replace(b"\r", b"").replace(b"\n", b"")),
       hs.lists(hs.sampled_from([b"\r", b"\n", b"\r\n", b"#1P11?\r"]), max_size=4), hs.integers(0, 2000),
       hs.sampled_from(["host", "device"]))
@example(b"A" * 1100, [b"\r"], 513, "host")
@example(b"A" * 514, [], 513, "host")
@example(b"A" * 513, [b"\r"], 2000, "device")  # one byte more than the limit, then its end: two pieces
def test_a_long_line_cut_anywhere_gives_what_bytes_give(noise: bytes, tail: list[bytes], cut: int, direction: str) -> None:
    """Lines longer than MAX_PARTIAL, ended or not, give the pieces byte by byte gives (the
    oracle), whatever the chunks."""
    stream = noise + b"".join(tail)
    ends = b"\r\n" if direction == "host" else b"\r"
    lines, _rest = _oracle(stream, ends)
    assert _fed(direction, [stream[:cut], stream[cut:]]) == lines
