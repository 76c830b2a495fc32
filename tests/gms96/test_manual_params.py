"""Manual §2.3.1 N (standard parameters, read back with T5), r (software reset), s (saving),
G53..G57 (zero offsets), O: driven through the card's pty with the :class:`Gms96Client`."""

from __future__ import annotations

from typing import Any

import pytest

from devsim.devices.gms96.client import Gms96Client
from tests.gms96.conftest import Plant
from tests.gms96.test_motion_reference import send, velocity

BUSY = 0x10

#: (N, default, range) as manual §2.3.1 N gives them: "[range] (default)".
N_DEFAULTS = [
    (10, 200, (1, 3000)),
    (11, 200, (50, 255)),
    (12, 0, (0, 15)),
    (13, 0, (0, 9999)),
    (15, 84, (0, 255)),
    (16, 3, (2, 6)),
    (17, 0, (0, 1)),
    (20, 1000, (10, 15000)),
    (21, 1, (0, 1)),
    (23, 1, (1, 8)),
    (24, 1, (0, 1)),
    (25, 0, (0, 1)),
    (26, 0, (0, 1)),
    (27, 0, (-255, 255)),
    (34, 1200, (None, 32000)),
    (35, 0, (0, None)),
    (41, 0, (0, 255)),
    (50, 6, (None, None)),
]


def n(c: Gms96Client, index: int) -> int:
    """T5;index: the N parameter as a signed 24-bit value (manual §2.3.1 T, P1=5)."""
    ident, _value, raw = c.read(5, index)
    assert ident == ord("N")
    return int.from_bytes(raw, "little", signed=True)


@pytest.mark.manual("§2.3.1 N", "the N parameters' defaults (round brackets), e.g. N10 (200), N15 (84), N20 (1000), "
                    "N24 (1), N34 (1200), N50 (6)")
@pytest.mark.manual("§2.3.1 T", "T5;P2: identifier 'N', the stored value of N parameter P2")
def test_n_defaults_after_power_on(card: Plant) -> None:
    c = card.client()
    for index, default, _range in N_DEFAULTS:
        assert n(c, index) == default, f"N{index}"


@pytest.mark.manual("§2.3.1 N", "the N parameters' ranges (square brackets), e.g. N10 [1..3000], N11 [50..255], "
                    "N20 [10..15000], N23 [1..8]")
@pytest.mark.manual("§2.3.1 N", "N P1;P2 is answered with the single character E5h")
def test_n_values_within_their_ranges(card: Plant) -> None:
    c = card.client()
    for index, _default, (low, high) in N_DEFAULTS:
        for value in (low, high):
            if value is None:
                continue
            assert c.send_letter("N", value, index) is not None
            assert n(c, index) == value, f"N{index} = {value}"
    send(c, "N", 5000, 10)  # above the range: not taken as it is
    assert 1 <= n(c, 10) <= 3000


@pytest.mark.manual("§2.3.1 r", "r with P3 = 0 sets all defaults of position controller and indexer")
@pytest.mark.manual("§2.3.1 G", "G94: speeds in inc per second = Hz (Grundeinstellung)")
@pytest.mark.parametrize("working", [[("M", 6000)], [("M", 6000), ("f", 500)], [("G", 95), ("f", 500)]])
def test_r0_restores_the_defaults(referenced: Plant, working: list[tuple[str, int]]) -> None:
    c = referenced.client()
    send(c, "N", 300, 10)
    send(c, "N", 500, 20)
    for command in working:
        send(c, *command)
    send(c, "r", 0, 0, 0)
    assert n(c, 10) == 200 and n(c, 20) == 1000
    send(c, "A", 20000)
    referenced.advance(1.0)
    assert velocity(referenced) == pytest.approx(2000)  # M back to 2000, f = M (the G0 state), G94


@pytest.mark.manual("§2.3.1 r", "r with P3 = 1 erases the EEPROM: the next start uses the defaults")
@pytest.mark.manual("§2.3.1 s", "s85;170: the data entered during operation are kept in the EEPROM and active at "
                    "the start; other P1/P2 do not save")
def test_s_saves_only_with_85_170_and_r1_erases(card: Plant) -> None:
    c = card.client()
    send(c, "N", 300, 10)
    send(c, "s", 85, 171)
    card.idle()
    card.runtime.power_cycle(card.name)
    card.advance(0.6)
    assert n(c, 10) == 200
    send(c, "N", 300, 10)
    send(c, "s", 85, 170)
    card.idle()
    card.runtime.power_cycle(card.name)
    card.advance(0.6)
    assert n(c, 10) == 300
    send(c, "r", 0, 0, 1)
    card.idle()
    card.runtime.power_cycle(card.name)
    card.advance(0.6)
    assert n(c, 10) == 200


@pytest.mark.manual("§2.3.1 s", "s85;170 saves the activity of the override potentiometer (o command)")
def test_s_saves_the_override_activity(referenced: Plant) -> None:
    c = referenced.client()
    send(c, "o", 0)
    send(c, "s", 85, 170)
    referenced.idle()
    referenced.runtime.power_cycle(referenced.name)
    referenced.advance(0.6)
    referenced.set("quantity.override_pot", 50)
    send(c, "Q", 3)
    send(c, "A", 20000)
    referenced.advance(1.0)
    assert velocity(referenced) == pytest.approx(2000)  # o0 came back: the pot is ignored


@pytest.mark.manual("§2.3.1 N", "N51 = 1: E0.0 is an enable of the indexer; at 0 V all moves are blocked")
def test_n51_e0_0_enables_the_moves(referenced: Plant) -> None:
    c = referenced.client()
    send(c, "N", 1, 51)
    referenced.set("input.E0.0", False)
    send(c, "A", 3000)
    referenced.advance(1.0)
    assert velocity(referenced) == 0.0 and c.read(3, 0)[0] & BUSY
    referenced.set("input.E0.0", True)
    referenced.idle()
    assert c.read(0)[1] == 3000


@pytest.mark.manual("§2.3.1 N", "N51 = 1: at 0 V on E0.0 alle Fahrten are blocked, the spindle simulation too")
@pytest.mark.manual("§2.3.1 Q", "Q8: during the spindle simulation the status shows 'Fahrt läuft' = 1")
def test_n51_e0_0_blocks_the_spindle_simulation(referenced: Plant) -> None:
    c = referenced.client()
    send(c, "N", 1, 51)
    referenced.set("input.E0.0", False)
    send(c, "Q", 8, 3, 1000)
    referenced.advance(1.0)
    assert velocity(referenced) == 0.0 and c.read(3, 0)[0] & 0x02  # blocked, 'Fahrt läuft'
    referenced.set("input.E0.0", True)
    referenced.advance(1.0)
    assert velocity(referenced) == pytest.approx(1000)
    referenced.set("input.E0.0", False)  # taken away while the spindle turns: it brakes and waits
    referenced.advance(1.0)
    assert velocity(referenced) == 0.0
    referenced.set("input.E0.0", True)
    referenced.advance(1.0)
    assert velocity(referenced) == pytest.approx(1000)


@pytest.mark.manual("§2.3.1 N", "N27 negative: A0.1 stays a free output")
def test_n27_negative_leaves_a0_1_free(referenced: Plant) -> None:
    c = referenced.client()
    send(c, "N", -5, 27)
    send(c, "A", 100)
    referenced.idle()
    referenced.advance(0.5)
    assert c.read(1, 2, 0)[2][0] & 0x02 == 0
    send(c, "p", 10, 16, 1)  # SETO A0.1
    assert c.read(1, 2, 0)[2][0] & 0x02


@pytest.mark.manual("§2.3.1 N", "N21: A0.0 brake output (1) or normal output (0); the change acts after the next start")
def test_n21_acts_after_the_next_start(plant_factory: Any, tmp_path: Any) -> None:
    plant = plant_factory({}, state_dir=tmp_path)
    c = plant.client()
    send(c, "N", 0, 21)
    send(c, "p", 10, 17, 0)  # RESO A0.0: still the brake output (released)
    assert c.read(1, 2, 0)[2][0] & 0x01
    send(c, "s", 85, 170)
    plant.idle()
    plant.runtime.power_cycle(plant.name)
    plant.advance(0.6)
    send(c, "p", 10, 17, 0)
    assert c.read(1, 2, 0)[2][0] & 0x01 == 0  # now a normal output


@pytest.mark.manual("§2.3.1 G", "G54..G57;P2;1 enters a zero point, G54..G57 selects it, G53 deselects it")
@pytest.mark.manual("§2.3.1 G", "G 0x000n36: extended zero point n = 0..15 (zero points 54..69)")
@pytest.mark.manual("§2.3.1 G", "G54..57 with P2 = 1: reselect the zero point active before G53")
def test_zero_offsets(referenced: Plant) -> None:
    c = referenced.client()

    def t0() -> int:
        return int.from_bytes(c.read(0)[2], "little", signed=True)

    send(c, "G", 54, 500, 1)
    send(c, "G", 54)
    assert t0() == -500
    send(c, "G", 53)
    assert t0() == 0
    send(c, "G", 54, 1)
    assert t0() == -500
    send(c, "G", 0x000236, 700, 1)  # zero point 56 (n = 2)
    send(c, "G", 0x000236)
    assert t0() == -700


@pytest.mark.manual("§2.3.1 G", "G53 (P2=0) deselects the zero point; G53;1 the zero point and the tool correction")
@pytest.mark.manual("§2.3.1 G", "G54..57;1: reselect the zero point and, where it was active, the tool correction")
@pytest.mark.manual("§2.3.1 G", "G53;P2;1: input of the machine zero, not used internally")
def test_g53_1_deselects_the_tool_correction_too(referenced: Plant) -> None:
    c = referenced.client()

    def t0() -> int:
        return int.from_bytes(c.read(0)[2], "little", signed=True)

    referenced.set("tool_offset", 100)  # (no command sets it: the host's tool memory, spec §5.9)
    send(c, "G", 55, 1000, 1)
    send(c, "G", 55)
    assert t0() == -1100
    send(c, "G", 53)
    assert t0() == -100  # the tool correction stays
    send(c, "G", 55, 1)
    assert t0() == -1100
    send(c, "G", 53, 1)
    assert t0() == 0
    send(c, "G", 53, 5000, 1)  # the machine zero entered: not used internally
    assert t0() == 0
    send(c, "G", 55, 1)
    assert t0() == -1100


@pytest.mark.manual("§2.3.1 O", "O P1: the actual position := P1, no move; active zero offsets are taken into account")
def test_o_sets_the_position_counter(referenced: Plant) -> None:
    c = referenced.client()
    before = referenced.read("axis.physical")
    send(c, "G", 54, 500, 1)
    send(c, "G", 54)
    send(c, "O", 100)
    assert int.from_bytes(c.read(0)[2], "little", signed=True) == 100
    send(c, "G", 53)
    assert int.from_bytes(c.read(0)[2], "little", signed=True) == 600
    assert referenced.read("axis.physical") == before  # no move


@pytest.mark.manual("§2.3.1 N", "N39: peak current [0..100 %], lowers the fixed maximum current of the power stage")
def test_n39_lowers_the_peak_current(card: Plant) -> None:
    c = card.client()
    card.set("quantity.load_pct", 200)  # asks for more than the stage gives
    card.advance(0.01)
    assert c.read(1, 5)[1] == 252
    send(c, "N", 50, 39)
    card.advance(0.01)
    assert c.read(1, 5)[1] == pytest.approx(126, abs=1)


@pytest.mark.manual("§2.3.1 N", "N34 [*..32000] (1200), N35 [0..*] (0): the P part of the current controller can be "
                    "lowered to at least 150 % of the I part (and the other way round)")
def test_n34_n35_couple(card: Plant) -> None:
    c = card.client()
    send(c, "N", 1000, 35)  # above N34 / 1.5 = 800
    assert n(c, 35) == 800
    send(c, "N", 100, 34)  # below 1.5 · N35 = 1200
    assert n(c, 34) == 1200
    send(c, "N", 200, 35)
    send(c, "N", 100, 34)  # below 1.5 · 200: the value stops at 300
    assert (n(c, 34), n(c, 35)) == (300, 200)


@pytest.mark.manual("§2.3.1 N", "N28: time for in-position [1..255 ms]; N27: window [+/-1..255 inc]")
def test_n27_n28_ranges(card: Plant) -> None:
    c = card.client()
    for index, value in ((28, 1), (28, 255), (27, 255), (27, -255)):
        send(c, "N", value, index)
        assert n(c, index) == value
