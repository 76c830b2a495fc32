"""The GMS96 FT1.2 codec at its limits, by property (spec §3.2, §3.5, §3.6, §3.7; Appendix B).

Each test generates values at and around one declared limit (the inter-character timeout, the
Langsatz length octets, a start byte right after a broken frame, the number of AE octets, the
24-bit parameter range, the letter's parameter count) in both directions, and compares the codec
with the rule written here as a small oracle.
"""

from __future__ import annotations

import re

import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from devsim.devices.gms96.codec import (
    FrameDecoder,
    FrameError,
    LongFrame,
    ShortFrame,
    SingleChar,
    encode,
    from_s24,
    k_frame,
    letter,
    parse_letter,
    short_command,
    short_extension_device,
    t_reply,
    to_s24,
    wrap24,
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


# -- what a caller is told about a field that does not fit -----------------------------------------
@pytest.mark.parametrize(("make", "field"), [
    (lambda: encode(SingleChar(256)), "single character must be an octet 0..255, not 256"),
    (lambda: encode(ShortFrame(0x100, 3)), "control must be an octet 0..255, not 256"),
    (lambda: encode(ShortFrame(1.5, 3)), "control must be an octet 0..255, not 1.5"),  # type: ignore[arg-type]
    (lambda: encode(ShortFrame(-1, 3)), "control must be an octet 0..255, not -1"),
    (lambda: encode(ShortFrame(0x53, 0x100)), "address must be an octet 0..255, not 256"),
    (lambda: encode(ShortFrame(0x53, 1.5)), "address must be an octet 0..255, not 1.5"),  # type: ignore[arg-type]
    (lambda: encode(LongFrame(0x100, 3, b"")), "control must be an octet 0..255, not 256"),
    (lambda: encode(LongFrame(0x53, 256, b"")), "address must be an octet 0..255, not 256"),
    (lambda: short_command(256, 3), "command number must be an octet 0..255, not 256"),
    (lambda: k_frame(0x10, 3, 256), "MB4 must be an octet 0..255, not 256"),
    (lambda: t_reply(3, 256, b""), "identifier must be an octet 0..255, not 256"),
    (lambda: to_s24(1 << 24), "parameter 16777216 does not fit in 24 bits"),
    (lambda: from_s24(b"\x00\x00"), "a 24-bit parameter has 3 octets, not 2"),
    (lambda: letter("\u0100"), "a command character is one latin-1 character, not 'Ā'"),
    (lambda: letter("AB"), "a command character is one latin-1 character, not 'AB'"),
    (lambda: letter("A", 1, 2, 3, 4), "at most 3 parameters, got 4"),
])
def test_a_field_that_does_not_fit_is_named(make: object, field: str) -> None:
    with pytest.raises(ValueError, match=f"^{re.escape(field)}$"):
        make()  # type: ignore[operator]


@pytest.mark.parametrize("char", ["\x00", "A", "\xfe", "\xff"])
def test_every_latin_1_character_is_a_command(char: str) -> None:
    assert letter(char, 1) == char.encode("latin-1") + b"\x01\x00\x00"


@settings(max_examples=200, deadline=None)
@given(st.one_of(st.integers(-(1 << 25), 1 << 25), st.sampled_from([(1 << 23) - 1, 1 << 23, -(1 << 23),
                                                                    -(1 << 23) - 1, (1 << 24) - 1, 1 << 24])))
def test_positions_wrap_as_24_bit_twos_complement(value: int) -> None:
    """Spec §5.1: positions travel as 24-bit two's complement and wrap around."""
    low = value % (1 << 24)
    assert wrap24(value) == (low - (1 << 24) if low >= 1 << 23 else low)


def test_encode_names_what_is_no_frame() -> None:
    with pytest.raises(TypeError, match="not a GMS96 frame: 'E5'"):
        encode("E5")  # type: ignore[arg-type]


@pytest.mark.parametrize(("header", "reason"), [(b"\x68\x01", "length"), (b"\x68\x05\x06", "length_mismatch"),
                                              (b"\x68\x05\x05\x69", "start_byte")])
def test_a_broken_langsatz_header_is_reported_at_the_octet_that_breaks_it(header: bytes, reason: str) -> None:
    """The header 68h L L 68h is checked octet by octet as it arrives (spec §3.2): the error
    comes with the octet that makes it, not with the next one."""
    decoder = _decoder()
    assert decoder.feed(header[:-1], 0.0) == [] and decoder.pending == len(header) - 1
    assert decoder.feed(header[-1:], 0.0) == [FrameError(reason, header)]
    assert decoder.pending == 0


def test_single_characters_are_frames_only_on_the_host_side() -> None:
    assert FrameDecoder().accept_single is False
    assert FrameDecoder(accept_single=True).accept_single is True


@pytest.mark.parametrize("kind", [bytearray, memoryview])
def test_what_is_discarded_is_bytes_whatever_was_fed(kind: type) -> None:
    out = _decoder().feed(kind(b"\x01\x02" + encode(GOOD)), 0.0)
    assert out == [FrameError("garbage", b"\x01\x02"), GOOD]
    assert type(out[0].discarded) is bytes


def test_a_start_byte_right_after_the_start_of_a_broken_frame() -> None:
    """§3.2 R6: a frame found broken is discarded up to the next start byte after its own, which
    may be the very next octet (here a Kurzsatz whose control field is 10h, with no 16h at its
    end, and the frame that begins one octet later)."""
    good = encode(ShortFrame(0x01, 3))
    assert _decoder().feed(b"\x10" + good, 0.0) == [FrameError("end_byte", b"\x10"), ShortFrame(0x01, 3)]
