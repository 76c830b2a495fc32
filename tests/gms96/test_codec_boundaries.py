"""The GMS96 FT1.2 codec at its limits, by property (spec §3.2, §3.5, §3.6, §3.7; Appendix B).

Each test generates values at and around one declared limit (the inter-character timeout, the
Langsatz length octets, a start byte right after a broken frame, the number of AE octets, the
24-bit parameter range, the letter's parameter count) in both directions, and compares the codec
with the rule written here as a small oracle.
"""

from __future__ import annotations

import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from devsim.devices.gms96.codec import (
    FrameDecoder,
    FrameError,
    LongFrame,
    ShortFrame,
    encode,
    from_s24,
    parse_letter,
    short_extension_device,
    to_s24,
)

STARTS = {0x10, 0x68, 0xE5, 0xA2}
NON_START = bytes(b for b in range(256) if b not in STARTS)
GOOD = LongFrame(0x53, 3, b"A\x10\x27\x00")  # A 10000 to drive 3


def _decoder(timeout: float = 0.05) -> FrameDecoder:
    return FrameDecoder(short_extension=short_extension_device, char_timeout=timeout)


# -- the inter-character timeout (§3.7) ----------------------------------------------------------
@settings(max_examples=200, deadline=None)
@given(st.integers(min_value=1, max_value=64), st.integers(min_value=-3, max_value=3), st.integers(1, 11))
@example(4, 0, 6)  # a gap of exactly the timeout
def test_a_partial_frame_is_dropped_only_after_more_than_the_timeout(sixteenths: int, delta: int, cut: int) -> None:
    """A partial frame is discarded when the next byte comes more than the character timeout
    after the last one; a gap of exactly the timeout keeps it (times are exact binary fractions)."""
    timeout = sixteenths / 64
    gap = timeout + delta / 1024
    wire = encode(GOOD)
    decoder = _decoder(timeout)
    assert decoder.feed(wire[:cut], 10.0) == []
    out = decoder.feed(wire[cut:], 10.0 + gap)
    if gap > timeout:  # the oracle: stale head, then the tail is garbage up to its end
        assert out[0] == FrameError("timeout", wire[:cut])
        assert GOOD not in out
    else:
        assert out == [GOOD]
    decoder.feed(wire[:cut], 20.0)
    assert decoder.expire(20.0 + gap) == ([FrameError("timeout", wire[:cut])] if gap > timeout else [])
    assert decoder.pending == (0 if gap > timeout else cut)


# -- resynchronisation (§3.2 R6) -------------------------------------------------------------------
@settings(max_examples=300, deadline=None)
@given(st.integers(0, 255), st.integers(0, 255), st.integers(0, 255), st.binary(max_size=6))
@example(1, 1, 0x68, b"")  # L = 1: below the Langsatz minimum of 2
@example(2, 3, 0x68, b"")  # the two length octets differ
@example(2, 2, 0x69, b"")  # no second 68h
def test_a_start_byte_right_after_a_broken_header(length: int, again: int, second: int, junk: bytes) -> None:
    """A Langsatz header broken at its length or its second start byte is discarded up to the
    next start byte, and a frame starting right there decodes."""
    junk = bytes(NON_START[b % len(NON_START)] for b in junk)
    header = bytes((0x68, length, again, second))
    if length < 2:
        broken, reason = header[:2], "length"
    elif again != length:
        broken, reason = header[:3], "length_mismatch"
    elif second != 0x68:
        broken, reason = header, "start_byte"
    else:
        return  # a good header: not this rule
    if any(b in STARTS for b in broken[1:]):
        return  # a start byte inside the broken header: the next frame starts there
    out = _decoder().feed(broken + junk + encode(GOOD), 0.0)
    assert out == [FrameError(reason, broken + junk), GOOD]


@settings(max_examples=300, deadline=None)
@given(st.binary(min_size=1, max_size=20), st.integers(1, 255), st.booleans())
def test_a_start_byte_right_after_a_frame_with_a_bad_checksum_or_end(data: bytes, error: int, at_end: bool) -> None:
    """A complete frame with a wrong checksum or end byte is discarded up to the next start
    byte after its own; the frame after it decodes."""
    data = bytes(NON_START[b % len(NON_START)] for b in data)
    wire = bytearray(encode(LongFrame(0x53, 3, data)))
    if at_end:
        wire[-1] = NON_START[(wire[-1] + error) % len(NON_START)]
        if wire[-1] == 0x16:
            wire[-1] = 0x17
    else:
        wire[-2] = (wire[-2] + error) & 0xFF
    broken = bytes(wire)
    first_start = next((i for i in range(1, len(broken)) if broken[i] in STARTS), len(broken))
    out = _decoder().feed(broken + encode(GOOD), 0.0)
    reason = "end_byte" if at_end else "checksum"
    if first_start == 3:  # (68 L L 68: the second 68h is a start byte)
        assert out[0] == FrameError(reason, broken[:3])
    assert out[-1] == GOOD
    assert b"".join(e.discarded for e in out if isinstance(e, FrameError)) + encode(GOOD) == broken + encode(GOOD)


# -- the Langsatz length (§3.2: L = 2 + user data, at most 255) --------------------------------------
@pytest.mark.parametrize("size", [0, 1, 2, 252, 253])
def test_langsatz_user_data_at_the_length_limits(size: int) -> None:
    frame = LongFrame(0x53, 3, bytes(range(size)))
    wire = encode(frame)
    assert wire[1] == wire[2] == size + 2 and len(wire) == size + 8
    assert _decoder().feed(wire, 0.0) == [frame]


def test_langsatz_longer_than_255_is_refused() -> None:
    with pytest.raises(ValueError):
        encode(LongFrame(0x53, 3, bytes(254)))


@pytest.mark.parametrize("length", [0, 1])
def test_langsatz_length_below_2_is_a_length_error(length: int) -> None:
    assert _decoder().feed(bytes((0x68, length)), 0.0) == [FrameError("length", bytes((0x68, length)))]


# -- Kurzsatz AE octets (§3.6) -----------------------------------------------------------------------
@settings(max_examples=100, deadline=None)
@given(st.integers(-5, 300))
@example(250)
@example(251)
@example(0)
@example(-1)
def test_the_ae_count_of_a_table_is_held_to_0_to_250(count: int) -> None:
    held = max(0, min(count, 250))
    extension = bytes(held)
    body = bytes((0x0A, 3)) + extension
    wire = bytes((0x10,)) + body + bytes((sum(body) & 0xFF, 0x16))
    decoder = FrameDecoder(short_extension=lambda control: count)
    assert decoder.feed(wire, 0.0) == [ShortFrame(0x0A, 3, extension)]


@pytest.mark.parametrize(("control", "octets"), [(0x08, 2), (0x0A, 2), (0x09, 1), (0x0B, 1), (0x01, 0), (0x00, 0),
                                                 (0x0C, 0), (0x0D, 0), (0x48, 2), (0x4B, 1)])
def test_the_card_counts_ae_octets_by_command_number(control: int, octets: int) -> None:
    """Spec §3.6 rule 2: #8 carries two AE octets, #9 one, by the command number F & 0Dh."""
    assert short_extension_device(control) == octets


# -- 24-bit parameters (Appendix B) ------------------------------------------------------------------
@settings(max_examples=200, deadline=None)
@given(st.one_of(st.integers(-(1 << 23) - 3, -(1 << 23) + 3), st.integers((1 << 23) - 3, (1 << 23) + 3),
                 st.integers((1 << 24) - 3, (1 << 24) + 3), st.integers(-3, 3)))
def test_parameters_at_the_24_bit_limits(value: int) -> None:
    fits = -(1 << 23) <= value <= (1 << 24) - 1
    if not fits:
        with pytest.raises(ValueError):
            to_s24(value)
        return
    pattern = value % (1 << 24)
    assert to_s24(value) == bytes((pattern & 0xFF, pattern >> 8 & 0xFF, pattern >> 16))
    assert from_s24(to_s24(value)) == (pattern - (1 << 24) if pattern >= 1 << 23 else pattern)


@settings(max_examples=200, deadline=None)
@given(st.sampled_from("ANTqa"), st.binary(max_size=14))
def test_a_letter_carries_0_to_3_whole_parameters(command: str, rest: bytes) -> None:
    """§3.5: a letter's parameters are whole 3-octet triples, at most three; anything else is
    not executed (None).  The PLC download ``a`` takes any length (§3.8.24)."""
    parsed = parse_letter(command.encode() + rest)
    if command != "a" and (len(rest) % 3 or len(rest) > 9):
        assert parsed is None
        return
    count = min(len(rest) // 3, 3)
    values = [from_s24(rest[3 * k : 3 * k + 3]) for k in range(count)] + [0] * (3 - count)
    assert parsed == (command, tuple(values), count)
