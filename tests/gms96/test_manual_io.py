"""Manual §2.4.2 (inputs, outputs, data area), §2.4.3 (direct commands on inputs and outputs), §4.2
(24 V outputs), §4.4 and §5.2 (inputs OR-ed for the interpolation card, K1): driven through the
card's pty; inputs are the machine side (the card's ``input.*`` points), read back with ``T1;1``."""

from __future__ import annotations

from typing import Any

import pytest

from devsim.devices.gms96.client import Gms96Client
from tests.gms96.conftest import Plant
from tests.gms96.test_motion_reference import send

BUSY = 0x10
WOSI, WORI, WOSO, WORO, SETO, RESO, INVO, CLAO, SNDF, STVO = 2, 3, 6, 7, 16, 17, 24, 26, 28, 31


def eb(c: Gms96Client, byte: int) -> int:
    """EB(byte) as ``T1;1;byte`` shows it (manual §2.3.1 T)."""
    return c.read(1, 1, byte)[2][0]


def ab(c: Gms96Client, byte: int) -> int:
    return c.read(1, 2, byte)[2][0]


def busy(c: Gms96Client) -> bool:
    return bool(c.read(3, 0)[0] & BUSY)


@pytest.mark.manual("§2.4.2", "KSA: E1.6/E1.7 are OR-ed with E2.0/E2.1")
def test_ksa_ors_e1_6_e1_7_with_e2_0_e2_1(card: Plant) -> None:  # the default card is a KSA15-2R
    c = card.client()
    card.set("input.E2.1", False)
    card.set("input.E1.6", True)
    card.advance(0.01)
    assert eb(c, 1) & 0x40 and eb(c, 2) & 0x01
    card.set("input.E1.6", False)
    card.set("input.E2.1", True)
    card.advance(0.01)
    assert eb(c, 1) & 0x80 and eb(c, 2) & 0x02


@pytest.mark.manual("§4.4", "under an interpolation card E2.0/E2.1 are OR-ed with E1.6/E1.7")
@pytest.mark.manual("§5.2", "in an interpolation system E2.1 and E1.7, E2.0 and E1.6 are OR-ed")
def test_interpolation_ors_the_reference_inputs(plant_factory: Any) -> None:
    plant = plant_factory({"variant": "KD8", "dil": {"interpolation": True}})
    c = plant.client()
    plant.set("input.E2.0", True)
    plant.advance(0.01)
    assert eb(c, 1) & 0x40


@pytest.mark.manual("§5.2", "K1: only 6 inputs; E0.4 and E0.5 are shown at E2.0 and E2.1")
def test_k1_shows_e0_4_e0_5_at_e2_0_e2_1(plant_factory: Any) -> None:
    plant = plant_factory({"variant": "K1", "axis": {"cam": None}})
    c = plant.client()
    assert eb(c, 2) & 0x03 == 0
    plant.set("input.E0.4", True)
    plant.advance(0.01)
    assert eb(c, 2) & 0x03 == 0x01
    plant.set("input.E0.5", True)
    plant.advance(0.01)
    assert eb(c, 2) & 0x03 == 0x03


@pytest.mark.manual("§2.4.2", "digital outputs A0.0 .. A1.7; hardware fitted up to A0.5 on the K/K1")
@pytest.mark.manual("§6", "G96-K1: 6 outputs (KSA and the others: 11)")
@pytest.mark.parametrize(("variant", "fitted"), [("K1", 6), ("KSA15-2R", 11)])
def test_only_the_fitted_outputs_switch(plant_factory: Any, variant: str, fitted: int) -> None:
    plant = plant_factory({"variant": variant})
    c = plant.client()
    for n in range(2, 16):
        send(c, "p", 10, SETO, n)
    assert ab(c, 0) & 0xFC == 0xFC  # the process image holds them all (T1;2)
    for n in range(2, 16):
        assert plant.read(f"output.A{n // 8}.{n % 8}") is (n < fitted), f"A{n // 8}.{n % 8}"


@pytest.mark.manual("§2.4.3", "WOSI (2): wait until input Operand (0..17) is set; WORI (3): until it is reset")
def test_wosi_wori(card: Plant) -> None:
    c = card.client()
    send(c, "p", 10, WOSI, 17)  # operand 17 = E2.1
    card.set("input.E2.1", False)
    card.advance(0.1)
    assert busy(c)
    card.set("input.E2.1", True)
    card.advance(0.001)
    assert not busy(c)
    card.set("input.E0.3", True)
    send(c, "p", 10, WORI, 3)  # E0.3
    card.advance(0.1)
    assert busy(c)
    card.set("input.E0.3", False)
    card.advance(0.001)
    assert not busy(c)


@pytest.mark.manual("§2.4.3", "WOSO (6) / WORO (7): wait until output Operand (0..10) is set / reset")
@pytest.mark.manual("§2.4.3", "SETO (16) / RESO (17) / INVO (24): output Operand on / off / inverted")
def test_output_commands_and_waits(card: Plant) -> None:
    c = card.client()
    send(c, "p", 10, SETO, 10)  # A1.2
    assert ab(c, 1) & 0x04
    send(c, "p", 10, INVO, 10)
    assert ab(c, 1) & 0x04 == 0
    send(c, "p", 10, WOSO, 3)
    card.advance(0.1)
    assert busy(c)
    c.abort()
    card.advance(0.01)
    send(c, "p", 10, SETO, 3)
    send(c, "p", 10, WOSO, 3)  # already set: goes on at once
    card.advance(0.001)
    assert not busy(c)
    send(c, "p", 10, RESO, 3)
    send(c, "p", 10, WORO, 3)
    card.advance(0.001)
    assert not busy(c) and ab(c, 0) & 0x08 == 0


@pytest.mark.manual("§2.4.3", "CLAO (26): all outputs reset")
@pytest.mark.manual("§2.4.2", "A0.0 is normally configured as the brake output (N21)")
def test_clao_resets_the_outputs_but_not_the_brake(card: Plant) -> None:
    c = card.client()
    for n in (2, 5, 9):
        send(c, "p", 10, SETO, n)
    assert ab(c, 0) == 0x01 | 0x04 | 0x20 and ab(c, 1) == 0x02  # A0.0: the brake, released
    send(c, "p", 10, CLAO, 0)
    assert ab(c, 0) == 0x01 and ab(c, 1) == 0


@pytest.mark.manual("§2.4.3", "SNDF (28): Operand into MB5 (error byte)")
def test_sndf(card: Plant) -> None:
    c = card.client()
    send(c, "p", 10, SNDF, 99)
    assert c.read(1, 3, 5)[2][0] == 99


@pytest.mark.manual("§2.4.3", "STVO (31): wait for a 0-1 edge on input E0.1")
def test_stvo_waits_for_a_rising_edge(card: Plant) -> None:
    c = card.client()
    card.set("input.E0.1", True)
    send(c, "p", 10, STVO, 0)
    card.advance(0.1)
    assert busy(c)  # a level that is already there is no edge
    card.set("input.E0.1", False)
    card.advance(0.01)
    assert busy(c)
    card.set("input.E0.1", True)
    card.advance(0.001)
    assert not busy(c)


@pytest.mark.manual("§2.4.3", "WAIT (14): wait Operand tenths of a second")
def test_wait_tenths(card: Plant) -> None:
    c = card.client()
    send(c, "p", 10, 14, 7)
    card.advance(0.69)
    assert busy(c)
    card.advance(0.02)
    assert not busy(c)


@pytest.mark.manual("§2.4.2", "E2.2 = 24 V short circuit")
@pytest.mark.manual("§4.2", "the short-circuit protection switches all outputs off at about 2.5 A total")
def test_output_overload_switches_all_outputs_off(card: Plant) -> None:
    c = card.client()
    send(c, "p", 10, SETO, 4)
    assert ab(c, 0) & 0x10
    card.set("quantity.output_overload", True)
    card.advance(0.01)
    assert ab(c, 0) == 0 and ab(c, 1) == 0
    assert eb(c, 2) & 0x04


@pytest.mark.manual("§2.3.1 p", "p12;P2: the analog output voltage := P2 [0..255]")
@pytest.mark.manual("§2.4.2", "analog output AB2")
def test_analog_output_in_ab2(card: Plant) -> None:
    c = card.client()
    send(c, "p", 12, 200)
    card.advance(0.001)
    assert ab(c, 2) == 200


@pytest.mark.manual("§2.3.1 d", "d P1;P2: the word P1 at data byte offset P2 [0..254]; DW0..DW79 (offset 0..158) "
                    "are restored at every power-on")
@pytest.mark.manual("§2.4.2", "data area DW0..127, DW0..79 static")
def test_data_words_and_their_static_part(card: Plant) -> None:
    c = card.client()
    send(c, "d", 0x1111, 158)  # DW79
    send(c, "d", 0x2222, 160)  # DW80
    send(c, "d", 0x3333, 254)  # DW127
    assert c.read(1, 6, 158)[1] & 0xFFFF == 0x1111
    assert c.read(1, 6, 254)[1] & 0xFFFF == 0x3333
    card.runtime.power_cycle(card.name)
    card.advance(0.6)
    assert c.read(1, 6, 158)[1] & 0xFFFF == 0x1111
    assert c.read(1, 6, 160)[1] & 0xFFFF == 0


@pytest.mark.manual("§2.4.2", "E2.3 = resolver failure (if a resolver is fitted)")
@pytest.mark.manual("§3.1", "the power stage is switched off when the resolver signals fail")
def test_e2_3_shows_a_resolver_failure(card: Plant) -> None:  # KSA15-2R: a resolver card
    c = card.client()
    assert eb(c, 2) & 0x08 == 0
    card.set("quantity.monitoring", "resolver_loss")
    card.advance(0.01)
    assert eb(c, 2) & 0x08
    assert c.read(3, 0)[0] & 0x04  # monitoring
    assert c.read(1, 3, 0)[2][0] & 0x20 == 0  # position controller off


@pytest.mark.manual("§3.1", "KSA LEDs: red overvoltage, yellow undervoltage, green temperature protection")
@pytest.mark.parametrize(("cause", "led"), [("dc_overvoltage", "red"), ("dc_undervoltage", "yellow"),
                                            ("overtemperature", "green")])
def test_ksa_leds(card: Plant, cause: str, led: str) -> None:
    c = card.client()
    card.set("quantity.monitoring", cause)
    card.advance(0.01)
    assert c.read(3, 0)[0] & 0x04  # the interface says only "monitoring" ...
    leds = card.read("leds")
    assert leds[led] and sum(leds.values()) == 1  # ... the LED tells which
