"""The fast path of a status poll (issue 31) changes nothing: a decoder that remembers whole-frame
chunks finds what one that does not finds, chunk by chunk; the K answer's bytes are
``encode(k_frame(...))``; a card answers a poll to its address only; a link that answers a
remembered poll in one step answers, counts and holds what one that does not would."""

from __future__ import annotations

import msgspec
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from devsim.core.clock import VirtualClock
from devsim.devices.gms96 import codec, tables
from devsim.devices.gms96 import link as link_module
from devsim.devices.gms96.codec import FrameDecoder, encode, k_bytes, k_frame, short_command
from devsim.devices.gms96.device import Gms96Device
from devsim.devices.gms96.face import status_answers

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


def test_a_kept_answer_without_mb4_is_not_taken_for_one_with_it(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(codec, "_K_ANSWERS", {})
    for address in (0, 1, 0x10, 255):
        for k in (0, 0x40, 0x7F, 0xFF):
            assert k_bytes(k, address, None) == encode(k_frame(k, address, None))  # (now kept)
            for mb4 in (0, 7, 255):
                assert k_bytes(k, address, mb4) == encode(k_frame(k, address, mb4))


@pytest.mark.parametrize("address", [-1, 256])
def test_a_k_answer_to_an_impossible_address_fails_as_encode_does(address: int) -> None:
    with pytest.raises(ValueError, match="address"):
        k_bytes(0, address, None)
    with pytest.raises(ValueError, match="address"):
        encode(k_frame(0, address, None))


# -- the link's remembered polls (a whole Kurzsatz to the card answered in one step) -----------
def _long(letter: str, *params: int, address: int = 3, fcb: int = 0) -> bytes:
    return encode(codec.LongFrame(codec.control_host(fcb), address, codec.letter(letter, *params)))


LINK_CHUNKS = [
    POLL, POLL, encode(short_command(1, 4)), encode(short_command(0, 3)), encode(short_command(9, 3, b"\x50")),
    encode(short_command(8, 3, b"\x10\x27")), encode(codec.ShortFrame(0x21, 3)), encode(short_command(5, 3)),
    POLL[:2], POLL[2:], POLL + POLL, b"\x00", POLL[:-1] + b"\x17", READ_BACK, READ_BACK[:7], b"",
    _long("p", 3, 100, 1), _long("p", 3, 101), _long("T", 1, 3, 4), _long("T", 1, 3, 4, fcb=1),
    bytearray(POLL), POLL + POLL[:2],
]
LINK_STEPS = st.one_of(
    st.tuples(st.just("chunk"), st.integers(0, len(LINK_CHUNKS) - 1)),
    st.tuples(st.just("advance"), st.sampled_from([0.0, 0.0005, 0.004, 0.06, 0.3, 1.5])),
    st.tuples(st.just("power"), st.sampled_from([3, 4])),  # the DIL address read at the next power-on
    st.tuples(st.just("message"), st.integers(1, 40)),  # a code in MB4 (the #1 answer carries it)
    st.tuples(st.just("off"), st.just(0)),
)


def link_run(steps: list[tuple[str, int | float]], protocol: str, remember: bool) -> list[object]:
    with pytest.MonkeyPatch.context() as patch:
        if not remember:
            patch.setattr(link_module, "_POLLS", 0)
        clock = VirtualClock()
        device = Gms96Device(clock=clock, config={"dil": {"protocol": protocol}})
        out: list[object] = []
        device.main.attach(lambda data: out.append((clock.now(), bytes(data))))
        model, link = device.model, device.face().link
        for kind, value in steps:
            if kind == "chunk":
                device.feed(LINK_CHUNKS[int(value)])
            elif kind == "advance":
                clock.advance(float(value))
            elif kind == "power":
                device.set("dil.address", int(value))
                model.power_cycle()
            elif kind == "message":
                model.image.post_message(int(value))
            else:
                model.power(False)  # (the supply off: the card hears nothing)
            out.append((link.frames, dict(link.errors), link.error_hold, link.last_fcb, link.decoder.pending))
        return out


_UP, _POLL, _GARBAGE, _PART = ("advance", 1.5), ("chunk", 0), ("chunk", 11), ("chunk", 8)
_ABORT, _T0, _ERASE = ("chunk", 3), ("chunk", 18), ("chunk", 16)
#: what a remembered poll must not jump over: an error held (R4), a partial frame, a card that
#: does not listen (flash erase, power off), another address, a message in MB4, #0 and the FCB
HAZARDS = {
    "error held": [_UP, _POLL, _GARBAGE, _POLL, ("advance", 0.01), _POLL],
    "partial frame": [_UP, _POLL, _PART, _POLL, ("advance", 0.06), _POLL],
    "the rest of a frame": [_UP, _PART, ("chunk", 9), ("chunk", 9)],
    "a frame and a part": [_UP, ("chunk", 21), ("advance", 0.06), ("chunk", 21), _POLL],
    "flash erase": [_UP, _POLL, _ERASE, _POLL, ("advance", 4.0), _POLL],
    "power off": [_UP, _POLL, ("off", 0), _POLL],
    "address": [_UP, _POLL, ("power", 4), _UP, _POLL, ("power", 3), _UP, _POLL],
    "message": [_UP, _POLL, ("message", 7), _POLL, _POLL],
    "abort and FCB": [_UP, _T0, _ABORT, _T0, _ABORT, _T0],
}


@pytest.mark.parametrize("protocol", ["S", "E"])
@pytest.mark.parametrize("hazard", HAZARDS)
def test_a_remembered_poll_jumps_over_nothing(hazard: str, protocol: str) -> None:
    assert link_run(HAZARDS[hazard], protocol, remember=True) == link_run(HAZARDS[hazard], protocol, remember=False)


@settings(max_examples=300, deadline=None)
@given(st.lists(LINK_STEPS, max_size=30), st.sampled_from(["S", "E"]))
def test_a_link_that_remembers_polls_answers_as_one_that_does_not(
        steps: list[tuple[str, int | float]], protocol: str) -> None:
    assert link_run(steps, protocol, remember=True) == link_run(steps, protocol, remember=False)


def test_a_remembered_poll_is_answered_without_the_decoder_and_forgotten_at_power_on() -> None:
    clock = VirtualClock()
    device = Gms96Device(clock=clock, config={"boot_time": 0})
    out: list[bytes] = []
    device.main.attach(out.append)
    link = device.face().link
    device.feed(POLL)
    assert POLL in link._polls and out == [encode(k_frame(0x40, 3, None))]
    link.decoder.feed = None  # type: ignore[method-assign]  # (not asked again for a remembered poll)
    device.feed(POLL)
    assert out[-1] == out[0] and link.frames == 2
    del link.decoder.feed
    device.set("dil.address", 4)
    device.model.power_cycle()
    assert link._polls == {}
    device.feed(POLL)  # card 3 is card 4 now: no answer
    assert len(out) == 2 and link.frames == 2
    device.feed(encode(short_command(1, 4)))
    assert out[-1] == encode(k_frame(0x40, 4, None))


@pytest.mark.parametrize("address", range(32))
def test_the_answers_by_status_byte_are_the_k_answers(address: int) -> None:
    assert status_answers(address) == tuple(encode(k_frame(tables.k_from_status(status, False), address, None))
                                            for status in range(256))


def test_the_line_settings_follow_the_dil_rate_at_power_on_and_stay_the_same_object() -> None:
    device = Gms96Device(clock=VirtualClock(), config={"boot_time": 0})
    settings = device.serial_settings
    assert (settings.baudrate, settings.bytesize, settings.parity, settings.stopbits) == (9600, 8, "E", 1)
    device.model.power_cycle()
    assert device.serial_settings is settings  # (the line compares a host's settings with it once)
    device.set("dil.baud", 38400)
    assert device.serial_settings is settings  # read at the next power-on (manual §2.2)
    device.model.power_cycle()
    assert device.serial_settings == msgspec.structs.replace(settings, baudrate=38400)
