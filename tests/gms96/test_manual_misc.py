"""Manual §1.3 (position range), §2.3 (the Langsatz), §2.3.1 immediate commands, §2.4 (PLC
resources), §4.3 (after power-on), §6 (stepper cards), §2.3.2 #1 K.0: driven through the card's pty."""

from __future__ import annotations

from typing import Any

import pytest

from devsim.devices.gms96.client import Gms96Client, Gms96Timeout
from devsim.devices.gms96.i2t import I_BASE
from tests.gms96.conftest import Plant
from tests.gms96.test_motion_reference import send

BUSY = 0x10
POSITION_MIN, POSITION_MAX = -8388352, 8388607  # manual §1.3, §2.3.1 A


def t0(c: Gms96Client) -> int:
    return int.from_bytes(c.read(0)[2], "little", signed=True)


@pytest.mark.manual("§1.3", "positions range from -8388352 to +8388607 increments (24 bits)")
@pytest.mark.manual("§2.3", "P1..P3 are 24-bit values of 3 bytes, the low byte sent first")
def test_the_whole_position_range(referenced: Plant) -> None:
    c = referenced.client()
    send(c, "M", 2000000)
    send(c, "B", 30000)
    send(c, "G", 0)  # rapid: the working speed is M
    send(c, "N", 3000, 10)  # a stiff loop and the widest following-error window for 2 MHz
    send(c, "N", 15000, 20)
    send(c, "A", POSITION_MAX)
    referenced.idle()
    assert t0(c) == POSITION_MAX
    send(c, "A", POSITION_MIN)
    referenced.idle()
    assert t0(c) == POSITION_MIN


@pytest.mark.manual("§2.3.1", "immediate commands (c, N, o2, p10/p11, q, T) are carried out at once, not in the "
                    "order of the queued commands")
def test_immediate_commands_overtake_the_queue(card: Plant) -> None:
    c = card.client()
    send(c, "p", 10, 14, 50)  # WAIT 5 s in the queue
    send(c, "N", 321, 10)
    send(c, "c", 77, 3)
    send(c, "p", 11, 40, 9)
    send(c, "q")
    assert c.read(3, 0)[0] & BUSY  # the WAIT still runs ...
    assert c.read(5, 10)[1] == 321  # ... and the immediate commands have acted
    assert c.read(1, 6, 12)[1] == 77
    assert c.read(1, 3, 40)[2][0] == 9
    assert c.read(1, 3, 3)[2][0] & 0x02


@pytest.mark.manual("§2.4", "the PLC works with 256 marker bytes and 128 data words")
@pytest.mark.manual("§2.4.2", "marker area MB0..MB255")
def test_marker_and_data_areas(card: Plant) -> None:
    c = card.client()
    send(c, "p", 11, 255, 0xA5)
    assert c.read(1, 3, 254)[2] == bytes([0, 0xA5])
    send(c, "d", 0x0102, 254)  # DW127
    assert c.read(1, 6, 254)[1] & 0xFFFF == 0x0102


@pytest.mark.manual("§4.3", "after switching on the motor is held in position (position controller active)")
@pytest.mark.manual("§2.4.1", "M0.5: position controller active")
def test_controller_active_after_power_on(card: Plant) -> None:
    c = card.client()
    assert c.read(1, 3, 0)[2][0] & 0x20
    card.runtime.power_cycle(card.name)
    card.advance(0.6)
    assert c.read(1, 3, 0)[2][0] & 0x20


@pytest.mark.manual("§6", "stepper cards (KS4/KS8) have no actual-value acquisition: the rotor is assumed to follow "
                    "the field, the internal actual position counts on")
def test_stepper_has_no_following_error(plant_factory: Any) -> None:
    plant = plant_factory({"variant": "KS4"})
    c = plant.client()
    send(c, "Q", 3)
    send(c, "A", 20000)
    plant.advance(1.0)
    assert c.read(3, 0)[0] & 0x02  # moving
    assert c.read(1, 4)[1] == 0  # no following error


@pytest.mark.manual("§2.3.2 #1", "K.0: I²t marker (latching)")
@pytest.mark.manual("§2.4.1", "M1.1: I²t marker, 1 = an I²t situation is or was present")
def test_k0_and_m1_1_latch_the_i2t_limitation(card: Plant) -> None:
    c = card.client()
    level = 84 / 255.0  # N15 default
    card.set("quantity.load_pct", (2 * level - I_BASE) * 100.0)
    card.advance(2.1)  # 2 s at a 100 % excess (manual §3.1)
    assert c.status()[0] & 0x01 and c.read(1, 3, 1)[2][0] & 0x02
    card.set("quantity.load_pct", 0.0)
    card.advance(10.0)  # the limitation ends, the marker stays
    assert c.read(3, 0)[0] & 0x20 == 0
    assert c.status()[0] & 0x01 and c.read(1, 3, 1)[2][0] & 0x02


@pytest.mark.manual("§6", "KS4/KS8: the maximum step frequency is 500 kHz")
def test_stepper_never_steps_faster_than_500_khz(plant_factory: Any) -> None:
    plant = plant_factory({"variant": "KS4"})
    c = plant.client()
    send(c, "Q", 3)
    send(c, "M", 2000000)
    send(c, "G", 0)
    send(c, "B", 30000)
    send(c, "A", 8000000)
    plant.advance(1.0)
    assert plant.read("axis.velocity") == pytest.approx(500000)


@pytest.mark.manual("§2.3.1 Q", "Q8 with P3 >= 0x3F0000: the speed comes from the pulses on the reference track of the "
                    "counter input, each pulse worth the distance in the low word of P3")
def test_q8_speed_from_reference_track_pulses(card: Plant) -> None:
    c = card.client()
    card.set("quantity.ref_pulse_hz", 10.0)
    send(c, "Q", 8, 3, 0x3F0000 | 50)  # 10 pulses/s x 50 inc = 500 Hz
    card.advance(1.0)
    assert card.read("axis.velocity") == pytest.approx(500)
    card.set("quantity.ref_pulse_hz", 20.0)
    card.advance(1.0)
    assert card.read("axis.velocity") == pytest.approx(1000)


@pytest.mark.manual("§2.3.1 N", "stepper software: N10 is the corner frequency in kHz [10..500]")
def test_stepper_n10_range(plant_factory: Any) -> None:
    plant = plant_factory({"variant": "KS4"})
    c = plant.client()
    send(c, "N", 10, 10)
    assert c.read(5, 10)[1] == 10
    send(c, "N", 500, 10)
    assert c.read(5, 10)[1] == 500
    send(c, "N", 3000, 10)  # a servo value: not taken as it is
    assert 10 <= c.read(5, 10)[1] <= 500


@pytest.mark.manual("§2.3.1 N", "in-position (N27/N28) cannot be evaluated on a stepper: A0.1 follows the set-point")
def test_stepper_in_position_is_the_set_point(plant_factory: Any) -> None:
    plant = plant_factory({"variant": "KS4"})
    c = plant.client()
    send(c, "Q", 3)
    send(c, "N", 10, 27)
    send(c, "N", 200, 28)
    send(c, "A", 1000)
    plant.idle()
    plant.advance(0.001)
    assert c.read(1, 2, 0)[2][0] & 0x02  # not N28 = 200 ms later


@pytest.mark.manual("§2.2", "switch 5 on: address offset 16 (addresses 16..31)")
@pytest.mark.manual("§2.3.1 T", "the answer carries the card's address")
def test_address_above_15(plant_factory: Any) -> None:
    plant = plant_factory({"dil": {"address": 29}})
    c = plant.client(address=29)
    assert c.read(1, 0)[0] == ord("V")
    assert c.last_reply is not None and c.last_reply.address == 29  # type: ignore[union-attr]
    other = plant.client(address=13)  # switches 1..4 alone: not this card
    other.timeout = 0.2
    with pytest.raises(Gms96Timeout):
        other.read(1, 0)


@pytest.mark.manual("§2.3.1 S", "S P1: the search speed in Hz for the index mark of the Q command [20..5000]")
def test_s_sets_the_index_mark_search_speed(plant_factory: Any) -> None:
    plant = plant_factory({"axis": {"index_offset": 100}})
    c = plant.client()
    send(c, "S", 500)
    send(c, "Q", 1)
    plant.advance(1.0)
    assert plant.read("axis.velocity") == pytest.approx(-500)


@pytest.mark.manual("§2.3.1 N", "N33: the drive-off position after the reference run (used only by the command Q-1)")
def test_n33_drive_off_only_with_q_minus_1(card: Plant) -> None:
    c = card.client()
    send(c, "N", 3000, 33)
    send(c, "Q", 0)
    card.idle()
    assert t0(c) == 0  # Q0 ends on the index mark
    send(c, "N", 0, 19)  # reference type Q0
    send(c, "Q", -1)
    card.idle()
    assert t0(c) == 3000
