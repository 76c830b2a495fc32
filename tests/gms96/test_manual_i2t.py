"""Manual §3.1 (I²t protection), §2.3.1 N15, T3;0 I.5/I.6, §2.3.2 #1 K.0, §2.4.1 M1.1: driven
through the card's pty; the load is the machine side (``quantity.load_pct``: the current the motor
asks for beyond what it needs at rest, :data:`~devsim.devices.gms96.i2t.I_BASE`)."""

from __future__ import annotations

import pytest

from devsim.devices.gms96.client import Gms96Client
from devsim.devices.gms96.i2t import A_REF, I_BASE, K_ACC
from tests.gms96.conftest import Plant
from tests.gms96.test_motion_reference import last, send

I2T_NOW, I2T_LATCHED = 0x20, 0x40  # T3;0 I.5, I.6 (manual §2.3.1 T)
K_I2T = 0x01  # #1 K.0 (manual §2.3.2)
N15_DEFAULT = 84  # manual §2.3.1 N: P2=15 (84, entspricht 33%)
ALLOWED_AT_100_PCT = 2.0  # manual §3.1: "bei einer 100%-igen Überschreitung ... 2 Sekunden"
BOOT = 0.6


def load_for(current: float) -> float:
    """The load (in %) that makes the motor ask for ``current`` (fraction of Imax)."""
    return (current - I_BASE) * 100.0


def status(c: Gms96Client) -> int:
    return c.read(3, 0)[0]


@pytest.mark.manual("§3.1", "at a 100 % excess of the I²t limit the current is allowed for 2 seconds, then limited")
@pytest.mark.manual("§2.3.1 T", "T3;0 I.5: I²t limitation active; I.6: I²t limitation active (latching)")
def test_double_the_n15_current_is_allowed_for_two_seconds(card: Plant) -> None:
    c = card.client()
    level = N15_DEFAULT / 255.0  # manual §3.1: 255 = 100 % of the maximum current
    card.set("quantity.load_pct", load_for(2 * level))
    card.advance(ALLOWED_AT_100_PCT - 0.05)
    assert status(c) & (I2T_NOW | I2T_LATCHED) == 0
    card.advance(0.1)
    assert status(c) & (I2T_NOW | I2T_LATCHED) == I2T_NOW | I2T_LATCHED


@pytest.mark.manual("§3.1", "I²t: the 2 s allowed at a 100 % excess count from power-on; "
                    "nothing of the time before a power cycle is carried over")
def test_i2t_after_power_on_counts_afresh(card: Plant) -> None:
    c = card.client()
    send(c, "N", N15_DEFAULT // 2, 15)  # not saved: power-on brings back 84
    card.set("quantity.load_pct", load_for(2 * N15_DEFAULT / 255.0))  # 4x the level now, 2x after power-on
    card.advance(0.2)  # at 4x (a 300 % excess) the limit would trip after 0.4 s
    assert status(c) & I2T_LATCHED == 0
    card.runtime.power_cycle(card.name)
    card.advance(BOOT)
    assert c.read(5, 15)[1] == N15_DEFAULT
    card.advance(ALLOWED_AT_100_PCT - BOOT - 0.05)
    assert status(c) & (I2T_NOW | I2T_LATCHED) == 0
    card.advance(0.1)
    assert status(c) & (I2T_NOW | I2T_LATCHED) == I2T_NOW | I2T_LATCHED


def test_no_i2t_while_the_power_is_off(card: Plant) -> None:
    c = card.client()
    card.set("quantity.load_pct", load_for(2 * N15_DEFAULT / 255.0))
    card.advance(1.0)
    card.runtime.fault(card.name, "power", True)
    card.advance(5.0)
    card.runtime.fault(card.name, "power", False)
    card.advance(BOOT)
    assert status(c) & I2T_LATCHED == 0


@pytest.mark.manual("§3.1", "after the allowed time the motor current is set to the programmed limit (N15)")
@pytest.mark.manual("§2.3.1 T", "T1;5: the motor current [0..252], 252 = the maximum current")
def test_the_current_is_held_at_the_n15_level(card: Plant) -> None:
    c = card.client()
    card.set("quantity.load_pct", 80)
    card.advance(5.0)
    assert status(c) & I2T_NOW
    assert c.read(1, 5)[1] == pytest.approx(252 * N15_DEFAULT / 255, abs=1)


@pytest.mark.manual("§3.1", "I²t: the card checks the magnitude of the motor current all the time; at a 100 % "
                    "excess (here the current that accelerates the axis) 2 seconds are allowed, then it is limited")
def test_the_accelerating_current_counts_for_i2t(referenced: Plant) -> None:
    c = referenced.client()
    level = N15_DEFAULT / 255.0
    b = 100  # linear ramp of 100 Hz/ms: the acceleration current K_ACC·1e5/A_REF = 60 % of Imax (spec §5.7)
    accelerating = K_ACC * b * 1000.0 / A_REF
    # a small load makes the current on the ramp exactly twice the N15 level (and leaves it far below at rest)
    referenced.set("quantity.load_pct", load_for(2 * level - accelerating))
    for command, *params in (("N", 15000, 20), ("N", 0, 24), ("M", 500000), ("G", 0), ("B", b)):
        send(c, command, *params)
    referenced.advance(5.0)
    assert status(c) & (I2T_NOW | I2T_LATCHED) == 0
    send(c, "A", 8000000)  # a 5 s ramp to 500 kHz
    referenced.advance(0.5)
    assert c.read(1, 5)[1] == round(252 * 2 * level)  # T1;5 shows the current that is integrated
    referenced.advance(ALLOWED_AT_100_PCT - 0.5 - 0.01)
    assert status(c) & (I2T_NOW | I2T_LATCHED) == 0
    referenced.advance(0.02)
    assert status(c) & (I2T_NOW | I2T_LATCHED) == I2T_NOW | I2T_LATCHED
    assert c.read(1, 5)[1] == round(252 * level)  # held at the N15 level


@pytest.mark.manual("§3.1", "I²t evaluates the motor current; the limitation usually brings a following error, "
                    "after which the position and current control are off: no current flows, the I²t runs back")
@pytest.mark.manual("§2.3.1 T", "T3;0 I.5: I²t limitation active (now); I.6 latched; T1;5 the motor current")
def test_no_current_no_i2t_after_the_following_error(referenced: Plant) -> None:
    c = referenced.client()
    level = N15_DEFAULT / 255.0
    referenced.set("quantity.load_pct", load_for(2 * level))  # the load stays on all the time
    send(c, "A", 100000)
    referenced.advance(ALLOWED_AT_100_PCT + 0.01)
    assert status(c) & (I2T_NOW | I2T_LATCHED) == I2T_NOW | I2T_LATCHED
    dev = referenced.device()
    referenced.run_until(lambda d: d.stage.idxoff, 5.0)  # the limited current cannot carry the load
    t_fe = last(dev, "following_error")
    referenced.advance(0.1)
    assert c.read(1, 5)[1] == 0  # controller off: no motor current
    # the integral stood at its threshold 3·2 s while limited; with no current it runs back at 1 per second
    referenced.advance(t_fe + 3 * ALLOWED_AT_100_PCT - 0.05 - referenced.now())
    assert status(c) & I2T_NOW
    referenced.advance(0.1)
    assert status(c) & (I2T_NOW | I2T_LATCHED) == I2T_LATCHED


@pytest.mark.manual("§3.1", "I²t: the current of an axis pressed against a blockage counts like any other; "
                    "above the limit it is allowed for the I²t time, then held at the N15 level")
def test_a_blocked_axis_trips_the_i2t(referenced: Plant) -> None:
    c = referenced.client()
    level = N15_DEFAULT / 255.0
    send(c, "f", 100)  # slow: the following error (N20 = 1000) would take 10 s
    send(c, "A", 100000)
    referenced.advance(1.0)
    referenced.set("quantity.blocked", True)
    assert c.read(1, 5)[1] == 252  # the peak current (N39 = 100 %)
    allowed = 3 * ALLOWED_AT_100_PCT / (1.0 / level**2 - 1.0)  # the integral's threshold at (i² - L²)/L²
    referenced.advance(allowed - 0.01)
    assert status(c) & (I2T_NOW | I2T_LATCHED) == 0
    referenced.advance(0.02)
    assert status(c) & (I2T_NOW | I2T_LATCHED) == I2T_NOW | I2T_LATCHED
    assert c.read(1, 5)[1] == round(252 * level)
