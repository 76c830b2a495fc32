"""The FT1.2 Langsatz length limits through the real pty (spec gms96.md §3.2 (c): L counts C, A and
the user data, one octet sent twice, so at most 255; the frame at most 261 octets on the wire; L
must hold C and A): a frame of L = 255 is taken and acknowledged, L = 1 is a framing error the card
keeps silent about, and it answers the next frame."""

from __future__ import annotations

from devsim.devices.gms96 import codec
from tests.gms96.conftest import Plant

STATUS = "10 01 03 04 16"


def _download(octets: int) -> str:
    """An ``a`` download frame (opaque data, spec §3.8.24) of ``octets`` user data after the ``a``."""
    return codec.encode(codec.LongFrame(0x53, 3, b"a" + bytes(range(octets)))).hex(" ").upper()


def test_a_frame_of_the_longest_length_is_taken(card: Plant) -> None:
    frame = _download(255 - 3)  # C, A, "a" and 252 octets: L = 255
    assert frame.split()[1:3] == ["FF", "FF"] and len(frame.split()) == 261
    assert card.host.ask(frame) == "E5"


def test_a_length_too_short_for_c_and_a_gets_silence_and_the_next_frame_an_answer(card: Plant) -> None:
    assert card.host.silent("68 01 01 68 53 53 16")
    card.advance(0.01)  # the line idle after an error (R4: about 33 bit times) before the next frame
    assert card.host.ask(STATUS) != ""


def test_the_card_never_builds_a_frame_over_the_limit() -> None:
    codec.encode(codec.LongFrame(0x08, 3, bytes(253)))  # L = 255: fine
    try:
        codec.encode(codec.LongFrame(0x08, 3, bytes(254)))
    except ValueError as exc:
        assert "L = 256" in str(exc)
    else:
        raise AssertionError("a Langsatz of L = 256 was built")
