"""Fuzzing the GMS96 card behind its link layer: any bytes, at any time, never crash it and
never change what `s85;170` saved (design principle 4)."""

from __future__ import annotations

import signal

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from devsim.core.clock import VirtualClock
from devsim.core.nvram import NonVolatileMemory
from devsim.devices.gms96 import Gms96Device
from devsim.devices.gms96.codec import LongFrame, ShortFrame, control_host, encode, letter

SAVE = encode(LongFrame(control_host(0), 3, letter("s", 85, 170)))
SET_N10 = encode(LongFrame(control_host(1), 3, letter("N", 300, 10)))
FRAMES = [
    encode(LongFrame(control_host(0), 3, letter("A", 10000))),
    encode(LongFrame(control_host(1), 3, letter("T", 3, 0))),
    encode(LongFrame(control_host(0), 3, letter("Q", 3))),
    encode(LongFrame(control_host(1), 3, letter("+", -500))),
    encode(ShortFrame(0x01, 3)),
    encode(ShortFrame(0x00, 3)),
    encode(ShortFrame(0x0B, 3, bytes([80]))),
]


def _card() -> tuple[Gms96Device, VirtualClock, NonVolatileMemory, bytearray]:
    clock = VirtualClock()
    nvram = NonVolatileMemory(None)
    card = Gms96Device(clock=clock, config={"boot_time": 0}, nvram=nvram)
    out = bytearray()
    card.attach(out.extend)
    card.feed(SET_N10)
    clock.advance(0.01)
    card.feed(SAVE)
    clock.advance(0.5)
    return card, clock, nvram, out


@settings(max_examples=150, deadline=None)
@given(
    st.lists(st.one_of(st.binary(max_size=40), st.sampled_from(FRAMES)), max_size=30),
    st.lists(st.floats(min_value=0, max_value=0.2), max_size=30),
)
def test_card_survives_any_input_and_keeps_saved_parameters(chunks: list[bytes], pauses: list[float]) -> None:
    card, clock, nvram, out = _card()
    image = {section: nvram.get(section) for section in nvram.sections()}
    for i, chunk in enumerate(chunks):
        card.feed(chunk)
        clock.advance(pauses[i] if i < len(pauses) else 0.001)
    clock.advance(1.0)
    # still answering: #1 after the line has been idle
    out.clear()
    card.feed(encode(ShortFrame(0x01, 3)))
    clock.advance(0.01)
    assert bytes(out[:1]) == b"\x10" and bytes(out[-1:]) == b"\x16"
    if not any(letter_ in chunk for chunk in chunks for letter_ in (b"s", b"r", b"N", b"p", b"a")):
        # nothing here could save, reset or download: the stored image is untouched and the
        # saved N10 comes back after a power cycle
        assert {section: nvram.get(section) for section in nvram.sections()} == image
        card.power_cycle()
        clock.advance(1.0)
        assert card.read("param.N10") == 300


def test_an_i2t_crossing_closer_than_the_clock_resolves_is_reached_at_once() -> None:
    """After 39,175 s of device time the clock resolves about 7 ps.  With the I²t integral 1.7e-9
    below its threshold and rising at 536/s (N15 = 11, full load) the crossing is 3 ps away: its
    timer fired at the same instant, integrated nothing and was set again, and ``advance`` never
    returned (found by a fuzz run).  Such a crossing is reached at once."""
    clock = VirtualClock()
    device = Gms96Device(clock=clock, config={"boot_time": 0}, nvram=NonVolatileMemory(None))
    clock.advance(39_175.374685741655)
    device.set("param.N15", 11)
    device.set("quantity.load_pct", 100)
    card = device.model
    threshold = 3.0 * card.cfg.axis.i2t_t_allow_s
    card.i2t.q, card.i2t.t = threshold - 1.72e-9, clock.now()
    previous = signal.signal(signal.SIGALRM, _too_long)
    signal.alarm(10)
    try:
        card.i2t.update()
        clock.advance(0.1)
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, previous)
    assert device.read("i2t_active") is True


def _too_long(*_: object) -> None:
    raise AssertionError("advance did not return within 10 s")


def test_a_level_change_while_i2t_limits_at_the_level() -> None:
    """While I²t limits the current to the level, the integral stands still (rate 0); a change of
    N15 then must not divide by that rate (a fuzz run found a ZeroDivisionError here)."""
    clock = VirtualClock()
    device = Gms96Device(clock=clock, config={"boot_time": 0}, nvram=NonVolatileMemory(None))
    device.set("param.N15", 127)
    device.set("quantity.load_pct", 100)
    clock.advance(2.5)
    assert device.read("i2t_active") is True
    device.set("param.N15", 127)
    device.set("param.N15", 100)
    clock.advance(1.0)
    assert device.read("i2t_active") is True


@pytest.mark.manual("§2.4.3", "WOSO (6) / WORO (7): Operand 0..10 -- an operand beyond them waits for no output")
@pytest.mark.parametrize("operand", [15363, 24, 11, -1])
def test_woso_and_woro_with_an_operand_beyond_the_outputs_do_not_wait(operand: int) -> None:
    """Found by fuzzing: ``p10;6;15363`` (WOSO, ``68 0C 0C 68 73 03 70 0A 00 00 06 00 00 03 3C 00 35 16``)
    raised IndexError out of the port's feed.  Like WOSI/WORI beyond E2.1 and SETO beyond A1.2, the
    command is done at once: the card acknowledges it and the next command runs."""
    card, clock, _nvram, out = _card()
    if operand == 15363:
        frame = bytes.fromhex("68 0C 0C 68 73 03 70 0A 00 00 06 00 00 03 3C 00 35 16")
        assert frame == encode(LongFrame(control_host(1), 3, letter("p", 10, 6, operand)))
    for opcode, fcb in ((6, 1), (7, 0)):  # WOSO, WORO
        out.clear()
        card.feed(encode(LongFrame(control_host(fcb), 3, letter("p", 10, opcode, operand))))
        clock.advance(0.01)
        assert bytes(out) == b"\xe5"
        assert card.read("busy") is False
    card.feed(encode(LongFrame(control_host(1), 3, letter("p", 10, 16, 3))))  # SETO A0.3 runs next
    clock.advance(0.01)
    assert card.read("output.A0.3") is True


@pytest.mark.manual("§2.3.1 T", "T1;2;P3: 16 bits of the output process image from byte P3 -- bytes outside it read 0")
@pytest.mark.parametrize("p3", [-65535, -1, 3])
def test_t1_2_from_a_byte_outside_the_output_image_reads_0(p3: int) -> None:
    """Found by fuzzing: ``T1;2;-65535`` (``68 0C 0C 68 73 03 54 01 00 00 02 00 00 01 00 FF CD 16``)
    raised IndexError out of the port's feed; ``T1;2;-1`` read the analog byte AB2 as if it were the
    byte before AB0.  As for T1;1 (inputs) and T1;3 (markers), bytes beyond the image read 0."""
    card, clock, _nvram, out = _card()
    if p3 == -65535:
        frame = bytes.fromhex("68 0C 0C 68 73 03 54 01 00 00 02 00 00 01 00 FF CD 16")
        assert frame == encode(LongFrame(control_host(1), 3, letter("T", 1, 2, p3)))
    card.feed(encode(LongFrame(control_host(0), 3, letter("p", 12, 200))))  # AB2 := 200
    clock.advance(0.01)
    out.clear()
    card.feed(encode(LongFrame(control_host(1), 3, letter("T", 1, 2, p3))))
    clock.advance(0.01)
    assert bytes(out[:7]) == bytes.fromhex("68 05 05 68 08 03 49") and out[7] == 0  # not AB2 = 200
    if p3 != -1:
        assert out[8] == 0  # (after T1;2;-1: AB0)
