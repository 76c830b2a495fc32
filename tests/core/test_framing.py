"""The kit's framing (devsim.core.framing): ``split_at`` against the rule written as an oracle, by
property, and the decoder of a port that declares no framing."""

from __future__ import annotations

import hypothesis.strategies as hs
from hypothesis import example, given

from devsim.core.framing import PLAIN, PlainDecoder, split_at

ENDS = (0x0D, 0x0A)


def _oracle(buffer: bytes, ends: tuple[int, ...]) -> tuple[list[bytes], bytes]:
    """The rule, byte by byte: a message is everything up to and including an end byte."""
    messages: list[bytes] = []
    current = bytearray()
    for byte in buffer:
        current.append(byte)
        if byte in ends:
            messages.append(bytes(current))
            current.clear()
    return messages, bytes(current)


#: bytes dense in ends: several in a row, one first, one last
STREAM = hs.lists(hs.sampled_from([b"\r", b"\n", b"\r\n", b"\n\r", b"#1", b"A", b"\x00", b"\xff"]),
                  max_size=12).map(b"".join)


@given(STREAM)
@example(b"")
@example(b"\r")
@example(b"\r\r")
@example(b"AB\r\nC")
@example(b"A\r\rB")
def test_split_at_cuts_after_every_end_byte(buffer: bytes) -> None:
    messages, rest = split_at(buffer, ENDS)
    assert (messages, rest) == _oracle(buffer, ENDS)
    assert b"".join(messages) + rest == buffer


def test_split_at_examples() -> None:
    assert split_at(b"#1A\r\n#2", ENDS) == ([b"#1A\r", b"\n"], b"#2")
    assert split_at(b"\r\r", ENDS) == ([b"\r", b"\r"], b"")
    assert split_at(b"ab", ENDS) == ([], b"ab")
    assert split_at(b"a\nb\r", (0x0D,)) == ([b"a\nb\r"], b"")  # only the ends named


def test_a_port_without_framing_decodes_nothing() -> None:
    assert PLAIN.split is None and PLAIN.tolerances == () and PLAIN.label is None
    host, device = PLAIN.decoder("host"), PLAIN.decoder("device")
    assert (host.direction, device.direction) == ("host", "device")
    assert PlainDecoder().direction == "host"  # what the device receives, when not told
    assert host.feed(b"#1\r") is None and device.feed(b"") is None
