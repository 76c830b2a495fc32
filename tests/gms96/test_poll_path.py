"""The fast path of a status poll (issue 31) changes nothing: a decoder that remembers whole-frame
chunks finds what one that does not finds, chunk by chunk; the K answer's bytes are
``encode(k_frame(...))``; a card answers a poll to its address only."""

from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from devsim.devices.gms96 import codec
from devsim.devices.gms96.codec import FrameDecoder, encode, k_bytes, k_frame, short_command

POLL = encode(short_command(1, 3))
READ_BACK = encode(codec.LongFrame(codec.control_host(0), 3, codec.letter("T", 3, 0, 0)))
CHUNKS = [
    POLL, encode(short_command(1, 4)), encode(short_command(0, 3)), encode(short_command(9, 3, b"\x50")),
    encode(short_command(8, 3, b"\x10\x27")), POLL[:2], POLL[2:], POLL[:1], POLL + POLL, b"\x00", b"\xe5",
    POLL[:-1] + b"\x17", POLL[:-2] + b"\x00\x16",
    READ_BACK, READ_BACK[:7], b"\x68\x03\x03\x68", b"\x10", b"",
]


def decoded(chunks: list[tuple[bytes, float]], remember: bool, monkeypatch: pytest.MonkeyPatch,
            **options: object) -> list[list[object]]:
    with monkeypatch.context() as patch:
        if not remember:
            patch.setattr(codec, "_WHOLE_FRAMES", 0)
        decoder = FrameDecoder(short_extension=codec.short_extension_device, **options)  # type: ignore[arg-type]
        out = []
        for data, now in chunks:
            out.append([*decoder.feed(data, now), decoder.pending, *decoder.expire(now + 0.01)])
        return out


@settings(max_examples=300, deadline=None)
@given(st.lists(st.tuples(st.sampled_from(CHUNKS), st.sampled_from([0.0, 0.001, 0.2])), max_size=12),
       st.booleans())
def test_remembering_whole_frames_finds_the_same_frames_and_errors(
        chunks: list[tuple[bytes, float]], single: bool) -> None:
    timed, now = [], 0.0
    for data, step in chunks:
        now += step
        timed.append((data, now))
    with pytest.MonkeyPatch.context() as monkeypatch:
        assert (decoded(timed, True, monkeypatch, accept_single=single)
                == decoded(timed, False, monkeypatch, accept_single=single))


def test_a_decoder_remembers_a_bounded_number_of_chunks() -> None:
    decoder = FrameDecoder(short_extension=codec.short_extension_device)
    for address in range(200):
        assert decoder.feed(encode(short_command(1, address)), 0.0) == [codec.ShortFrame(1, address)]
    assert len(decoder._whole) == codec._WHOLE_FRAMES


@pytest.mark.parametrize("mb4", [None, 0, 7, 255])
def test_the_k_answer_bytes_are_the_encoded_k_frame(mb4: int | None, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(codec, "_K_ANSWERS", {})  # (answers kept by an earlier test are not this one's)
    for _kept in (False, True):  # made, then as kept
        for address in range(256):
            for k in range(256):
                assert k_bytes(k, address, mb4) == encode(k_frame(k, address, mb4))


@pytest.mark.parametrize("address", [-1, 256])
def test_a_k_answer_to_an_impossible_address_fails_as_encode_does(address: int) -> None:
    with pytest.raises(ValueError, match="address"):
        k_bytes(0, address, None)
    with pytest.raises(ValueError, match="address"):
        encode(k_frame(0, address, None))
