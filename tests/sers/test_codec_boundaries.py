"""The SERS framer's fast paths at the limits of §4.1/§4.2, by property.

The device takes noise, text, whole lines and other drives' lines in one step each
(``skip_noise``, ``skip_text``, ``begin_line``, ``take_line``, ``whole_line``, ``end_line``,
``text_run``/``take_text``, ``skip_unaddressed``); each must leave the framer where the manual's
byte-by-byte rule leaves it.  Streams are generated around every limit (lines of 55 to 65
characters, addresses with leading zeros, ``*``, a ``#`` at a chunk's end, CR/LF pairs), and the
framer's events after the fast path are compared with the oracle of ``framer_oracle`` (written
from the manual, not from the codec), for every byte that follows.
"""

from __future__ import annotations

import re

import hypothesis.strategies as hs
import pytest
from hypothesis import assume, example, given, settings

from devsim.devices.sers import codec
from tests.sers.framer_oracle import LIMIT, framer_events, line_state

TOKENS = [b"#", b"*", b"\r", b"\n", b"\r\n", b"0", b"1", b"2", b"9", b"12", b"A", b"?", b" ", b"\xb2", b"#1", b"#2",
          b"#*", b"#01", b"#12", b"#9", b"#90"]
ADDRESSES = [b"", b"1", b"2", b"12", b"*", b"01", b"007", b"3", b"9", b"09"]  # the digits 0 to 9


@hs.composite
def _line(draw: hs.DrawFn) -> bytes:
    """A line of 55 to 65 characters (``#``, an address, text) and perhaps its end."""
    length = draw(hs.integers(min_value=55, max_value=65))
    address = draw(hs.sampled_from(ADDRESSES))
    text = bytes(0x41 + x % 26 for x in draw(hs.binary(min_size=70, max_size=70)))
    end = draw(hs.sampled_from([b"\r", b"\n", b"\r\n", b"\n\r", b""]))
    return b"#" + address + text[: max(0, length - 1 - len(address))] + end


STREAM = hs.lists(hs.one_of(hs.sampled_from(TOKENS), hs.binary(max_size=12), _line()), max_size=8).map(b"".join)
#: Bytes before the place a fast path starts at (a chunk is taken from the middle): every one
#: that matters to the framer, none of which may be looked at again.
#: What ends a run of a line's text (§3.2): its end or a ``#`` (a restart); the oracle of codec.text_end.
TEXT_END = re.compile(rb"[\r\n#]")
LEAD = b"#1 A\r\n#2\r#*"
NOT_DIGITS = bytes(range(256)).translate(None, b"0123456789")
TEXT = hs.binary(max_size=70).map(lambda b: bytes(0x41 + x % 26 for x in b))  # no '#', CR, LF, digit


def _fed(data: bytes) -> codec.Framer:
    framer = codec.Framer()
    for byte in data:
        framer.feed(byte)
    return framer


def _continues(framer: codec.Framer, before: bytes, rest: bytes, address_taken: bool = False) -> None:
    """``framer`` has taken ``before`` (by whatever path): every byte of ``rest`` fed one by one
    gives the oracle's events for it.  ``address_taken``: the fast path took a complete address
    (the oracle announces it with the first byte after it; the framer already has)."""
    oracle = framer_events(before + rest)[len(before):]
    got = [framer.feed(byte) for byte in rest]
    if address_taken and oracle and oracle[0] and isinstance(oracle[0][0], codec.Address):
        oracle[0] = oracle[0][1:]
    assert got == oracle


def _first(data: bytes, chars: bytes, start: int = 0) -> int:
    return next((i for i in range(start, len(data)) if data[i] in chars), len(data))


@settings(max_examples=300, deadline=None)
@given(STREAM, STREAM)
def test_the_line_length_counts_hash_address_and_text(before: bytes, after: bytes) -> None:
    framer = _fed(before)
    in_line, count = line_state(before)
    assert framer.in_line == in_line
    if in_line:
        assert framer.length == count
    _continues(framer, before, after)


@settings(max_examples=200, deadline=None)
@given(STREAM, STREAM)
def test_reset_forgets_the_line(before: bytes, after: bytes) -> None:
    framer = _fed(before)
    framer.reset()
    assert not framer.in_line and framer.idle
    _continues(framer, b"", after)


@settings(max_examples=300, deadline=None)
@given(STREAM, STREAM, STREAM)
@example(b"#1\r", b"\nAB#", b"")
@example(b"", b"AB#", b"")
@example(b"#1\r", b"#", b"")
def test_skip_noise_stops_at_the_next_hash(before: bytes, chunk: bytes, after: bytes) -> None:
    framer = _fed(before)
    assume(not framer.in_line and (framer.idle or (chunk and chunk[0] not in b"\r\n")))
    stop = framer.skip_noise(LEAD + chunk, len(LEAD)) - len(LEAD)
    assert stop == _first(chunk, b"#")
    assert all(events == [codec.Ignored()] for events in framer_events(before + chunk)[len(before):][:stop])
    _continues(framer, before + chunk[:stop], chunk[stop:] + after)


@pytest.mark.manual("§4.1", "at most 60 characters in a line")
@settings(max_examples=300, deadline=None)
@given(hs.sampled_from(ADDRESSES), TEXT, STREAM, STREAM)
@example(b"1", b"A" * 56, b"BB\r", b"")  # '#1 ' and 56: the 60th character kept, the 61st dropped
@example(b"", b"A" * 57, b"B\r", b"")  # '# ', 57 and one skipped: exactly 60, no overflow
@example(b"", b"A" * 57, b"BB\r", b"")  # 61: overflow
def test_skip_text_counts_to_the_line_end(address: bytes, text: bytes, chunk: bytes, after: bytes) -> None:
    before = b"#" + address + b" " + text
    framer = _fed(before)
    assert framer.in_text
    stop = framer.skip_text(LEAD + chunk, len(LEAD)) - len(LEAD)
    assert stop == _first(chunk, b"\r\n#")
    _continues(framer, before + chunk[:stop], chunk[stop:] + after)


@settings(max_examples=300, deadline=None)
@given(STREAM, hs.sampled_from(ADDRESSES), STREAM, STREAM)
@example(b"", b"12", b"", b"A\r")  # the address cut off by the chunk's end
@example(b"", b"12", b"#", b"")  # a '#' right after the digits
@example(b"#1 AB", b"*", b"A", b"\r")
@example(b"", b"", b"\r", b"")
@example(b"", b"", b"*", b"")  # '#*' at the chunk's end
@example(b"", b"1", b"*2", b"")  # '*' after digits is text
def test_begin_line_takes_the_hash_and_address(before: bytes, address: bytes, tail: bytes, after: bytes) -> None:
    framer = _fed(before)
    assume(not framer.in_line or framer.in_text)
    chunk = b"#" + address + tail
    complete, value, stop = framer.begin_line(LEAD + chunk, len(LEAD))
    stop -= len(LEAD)
    # the address: one '*' right after the '#', or the run of digits there
    run = 2 if chunk[1:2] == b"*" else _first(chunk, NOT_DIGITS, 1)
    assert stop == run
    assert complete == (stop < len(chunk) and chunk[stop] != ord("#"))
    if complete:
        announced = framer_events(before + chunk + b"\r")[len(before) + stop][0]
        assert announced == codec.Address(value)
    else:
        assert value is None
    _continues(framer, before + chunk[:stop], chunk[stop:] + after, address_taken=complete)


@settings(max_examples=300, deadline=None)
@given(STREAM, hs.sampled_from([b"#", b"#1", b"#12", b"#*", b"#007"]), TEXT, STREAM)
@example(b"", b"#1", b"A" * 58, b"B\r")  # the line's 61st character is text: overflow
@example(b"", b"#1", b"A" * 57, b"\r")  # exactly 60 characters: no overflow
@example(b"", b"#1", b"A" * 57, b"B\r")
@example(b"#2 " + b"A" * 50, b"#1", b"A" * 20, b"\r")  # a restart goes on counting
def test_take_line_counts_a_hash_its_address_and_text(before: bytes, head: bytes, text: bytes, after: bytes) -> None:
    framer = _fed(before)
    assume(not framer.in_line or framer.in_text)
    taken = head + b" " + text
    framer.take_line(len(head), len(taken) - len(head))
    _continues(framer, before + taken, after)


@settings(max_examples=300, deadline=None)
@given(STREAM, hs.sampled_from([b"#", b"#1", b"#12", b"#*"]), TEXT, hs.sampled_from([b"\r", b"\n"]), STREAM)
@example(b"", b"#1", b"P" * 58, b"\r", b"\n#1\r")  # 60 characters and the pair's second half
def test_whole_line_is_a_line_taken_at_once(before: bytes, head: bytes, text: bytes, end: bytes,
                                            after: bytes) -> None:
    framer = _fed(before)
    assume(not framer.in_line)
    line = (head + b" " + text)[:LIMIT]
    framer.whole_line(len(line), end[0])
    _continues(framer, before + line + end, after)


@settings(max_examples=300, deadline=None)
@given(hs.sampled_from(ADDRESSES), TEXT, TEXT, hs.sampled_from([b"\r", b"\n"]), STREAM)
@example(b"", b"A" * 58, b"", b"\r", b"\n")  # exactly 60 characters
@example(b"", b"A" * 58, b"B", b"\n", b"\r")  # 61
def test_end_line_reports_the_overflow(address: bytes, text: bytes, more: bytes, end: bytes, after: bytes) -> None:
    before = b"#" + address + b" " + text + more
    framer = _fed(before)
    overflow = framer.end_line(end[0])
    assert overflow == (len(before) > LIMIT)
    assert framer_events(before + end)[-1] == [codec.LineEnd(overflow)]
    _continues(framer, before + end, after)


@pytest.mark.manual("§4.1", "at most 60 characters in a line")
@settings(max_examples=300, deadline=None)
@given(hs.sampled_from(ADDRESSES), TEXT, STREAM, STREAM)
@example(b"", b"A" * 57, b"BCD\r", b"")  # '# ' and 57: one character left before the limit
@example(b"", b"A" * 58, b"BCD\r", b"")  # none left
@example(b"", b"A" * 70, b"BCD\r", b"")  # beyond it
def test_text_run_ends_at_the_60th_character(address: bytes, text: bytes, chunk: bytes, after: bytes) -> None:
    before = b"#" + address + b" " + text
    framer = _fed(before)
    run = framer.text_run(LEAD + chunk, len(LEAD)) - len(LEAD)
    assert run == min(_first(chunk, b"\r\n#"), max(0, LIMIT - len(before)))
    assert framer.length == len(before)  # (text_run changes nothing)
    framer.take_text(run)
    _continues(framer, before + chunk[:run], chunk[run:] + after)


def _concerning(data: bytes, mine: int) -> int:
    """Where the next ``#`` is that can concern drive ``mine``: followed by ``*``, by its address
    (leading zeros allowed) and no further digit, or by digits (or nothing) up to the end."""
    for at in range(len(data)):
        if data[at] != ord("#"):
            continue
        digits_end = _first(data, NOT_DIGITS, at + 1)
        digits = data[at + 1 : digits_end]
        if data[at + 1 : at + 2] == b"*" or digits_end == len(data):
            return at
        if digits and int(digits) == mine:
            return at
    return len(data)


@settings(max_examples=500, deadline=None)
@given(STREAM, STREAM, STREAM, hs.sampled_from([1, 2, 12]), hs.sampled_from([b"", LEAD]))
@example(b"", b"#2 " + b"A" * 60 + b"\r\n#1\r", b"", 1, LEAD)
@example(b"#2 AB", b"C" * 60 + b"#01 X\r", b"", 1, LEAD)
@example(b"", b"#2 AB\r", b"\n", 1, LEAD)  # the pair's second half in the next chunk
@example(b"", b"#2 AB\r#", b"1\r", 1, LEAD)  # a '#' at the chunk's end: more digits may follow
@example(b"", b"#2 " + b"A" * 57 + b"#3", b"\r", 1, LEAD)  # digits after '#' beyond the limit set nothing
# The last line end before the stop: the end of a line (a CR/LF after it is a pair's second
# half) or noise between lines (it is not), decided by the line ends before it:
@example(b"", b"#2 X\rnoise\r", b"\n", 1, LEAD)  # noise after a line: no pair
@example(b"", b"#2 X\r#2 Y\rnoise\r", b"\n", 1, LEAD)  # the line end right before it decides
@example(b"", b"#2 X\n#2 Y\nnoise\n", b"\r", 1, LEAD)
@example(b"", b"#2 X\r\n#2 Y\r", b"\n", 1, LEAD)  # a line's end: a pair
@example(b"", b"#2 X\n#2 Y\n\rZ\r", b"\n", 1, LEAD)
@example(b"", b"#2\rA\n#2 B\r", b"\n", 1, LEAD)
@example(b"#2 AB", b"\r", b"\n", 1, LEAD)  # the line was open before the chunk
@example(b"#2 AB", b"\r", b"\n", 1, b"")
@example(b"", b"#2 X\n", b"\r", 1, LEAD)  # the only line end, an LF: a pair follows
@example(b"", b"#2 X\r", b"\n", 1, LEAD)
@example(b"", b"noise\r", b"\n", 1, LEAD)  # noise only
@example(b"", b"noise\n", b"\r", 1, LEAD)
@example(b"#2 AB", b"\r X\r", b"\n", 1, b"")  # a line end at the very start of the data
@example(b"#2 AB", b"\n X\n", b"\r", 1, b"")
@example(b"", b"#2 A\r\r", b"\n", 1, LEAD)
@example(b"", b"#2 X#\rnoise\r", b"\n", 1, LEAD)  # a '#' right before the line end that decides
# Beyond the 60th character: digits of text set the overflow, digits of an address do not
@example(b"", b"#2 " + b"A" * 55 + b"12345", b"\r", 1, LEAD)
@example(b"", b"#2 " + b"A" * 56 + b"#34#", b"\r", 1, LEAD)
@example(b"#2 " + b"A" * 50, b"B" * 5 + b"12345", b"\r", 1, b"")
def test_skip_unaddressed_frames_other_drives_lines(before: bytes, chunk: bytes, after: bytes, mine: int,
                                                    lead: bytes) -> None:
    framer = _fed(before)
    assume(not framer.in_line or framer.in_text)
    stop = framer.skip_unaddressed(lead + chunk, len(lead), mine) - len(lead)
    assert stop == _concerning(chunk, mine)
    _continues(framer, before + chunk[:stop], chunk[stop:] + after)


@pytest.mark.parametrize(("digits", "value"), [("", None), ("*", "*"), ("0", 0), ("007", 7), ("255", 255)])
def test_address_values(digits: str, value: int | str | None) -> None:
    assert codec.address_value(digits) == value


@settings(max_examples=300, deadline=None)
@given(STREAM, hs.integers(min_value=0, max_value=200))
@example(b"", 0)
@example(b"AB", 2)
@example(b"A#B\rC\nD", 0)
@example(b"A\nB\rC#D", 0)
@example(b"#\r\n", 1)
def test_text_end_finds_what_the_text_end_pattern_finds(data: bytes, start: int) -> None:
    """``codec.text_end`` (three finds) stops where the pattern of a text's end (CR, LF or ``#``)
    would, or at the end."""
    start = min(start, len(data))
    found = TEXT_END.search(data, start)
    assert codec.text_end(data, start) == (len(data) if found is None else found.start())
