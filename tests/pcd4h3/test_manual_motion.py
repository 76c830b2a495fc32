"""Manual §6.1 … §6.3: the operating modes, the profile generator and the PID regulator as a host
sees them over S-Bus on a real pty (registers written, command flags set, the read functions'
registers read back) and the machine side shows them (the motor's position and the output)."""

from __future__ import annotations

from collections.abc import Callable

import pytest

from tests.pcd4h3.helpers import Station, load, reg, run

K1 = 0x80000041  # MCFac 1.0 (FFP): user units are counts


def settled(pcd: Station, timeout: float = 30.0) -> None:
    assert pcd.sim.run_until(lambda d: d.read("axis.1.OnDest"), timeout)
    pcd.sim.advance(0.5)


def set_velocity(pcd: Station) -> int:
    run(pcd, "FRdSV")
    return pcd.read_registers(reg("RSetV"))[0]


@pytest.mark.manual("§6.1", "Positionierbetrieb: Position und Parameter eingeben, Positionierung starten, Signal "
                    "'Zielposition erreicht' abwarten; die Zielposition wird geregelt angefahren")
def test_position_mode_reaches_the_target_and_signals_it(pcd: Station) -> None:
    load(pcd, DestP=700)
    run(pcd, "FLdDA", "FStart")
    assert pcd.read_flags(200) == [0]  # OnDest: on the way
    settled(pcd)
    assert pcd.sim.read("axis.1.position") == pytest.approx(70_000, abs=3)
    assert pcd.read_flags(200) == [1]


@pytest.mark.manual("§6.1", "drehzahlgeregelter Betrieb: mit der definierten Beschleunigung bis zur Sollgeschwindigkeit "
                    "beschleunigen, geregelt mit dieser Geschwindigkeit fahren bis ein Stopbefehl erfolgt; die "
                    "Sollgeschwindigkeit kann während der Bewegung verändert werden")
@pytest.mark.manual("§6.2", "im drehzahlregulierten Betrieb beschleunigt der Controller bis zur Sollgeschwindigkeit und "
                    "fährt mit konstanter Geschwindigkeit bis ein Stopbefehl erfolgt")
def test_velocity_mode_runs_until_a_stop(pcd: Station) -> None:
    load(pcd, MCW=0x041B | 0x1800, Veloc=300)  # velocity mode, forward; smooth stop
    run(pcd, "FSelOM", "FLdVA", "FStart")
    pcd.sim.advance(2.0)
    assert set_velocity(pcd) == 200  # Accel 100 per s²
    pcd.sim.advance(8.0)
    assert set_velocity(pcd) == 300
    assert pcd.sim.read("axis.1.velocity") == pytest.approx(30_000 * 0.999, rel=0.01)
    assert pcd.read_flags(200) == [0]  # no target to reach
    load(pcd, Veloc=100)
    run(pcd, "FLdVA", "FStart")  # changed while running
    pcd.sim.advance(3.0)
    assert set_velocity(pcd) == 100
    run(pcd, "FStop")
    settled(pcd)
    assert set_velocity(pcd) == 0 and pcd.read_flags(200) == [1]
    standing = pcd.sim.read("axis.1.set_position")
    pcd.sim.advance(2.0)
    assert pcd.sim.read("axis.1.position") == pytest.approx(standing, abs=1)


@pytest.mark.manual("§6.2", "die Geschwindigkeit und die Zielposition können an einer beliebigen Position während der "
                    "Bewegung verändert werden; der Controller beschleunigt oder bremst mit der definierten "
                    "Beschleunigung")
@pytest.mark.manual("§1", "Geschwindigkeit, Zielposition und PID-Parameter können während der Bewegung "
                    "verändert werden")
def test_target_velocity_and_regulator_change_during_the_move(pcd: Station) -> None:
    load(pcd, DestP=2000)
    run(pcd, "FLdDA", "FStart")
    pcd.sim.advance(6.0)  # at 500, beyond 1250
    load(pcd, DestP=1000, Veloc=300, KProp=200)
    run(pcd, "FLdDA", "FLdVA", "FStart", "FLdRP", "FUpDRP")  # a target already passed: brake, come back
    settled(pcd)
    assert pcd.sim.read("axis.1.position") == pytest.approx(100_000, abs=3)
    assert pcd.sim.read("axis.1.comers") == 0


@pytest.mark.manual("§6.3", "der Motor wird in der Zielposition gehalten, da der Regler aktiv ist bis ein Stopbefehl "
                    "erfolgt")
def test_the_regulator_holds_the_target_against_a_load(pcd: Station) -> None:
    load(pcd, DestP=100)
    run(pcd, "FLdDA", "FStart")
    settled(pcd)
    pcd.sim.set("axis.1.load", 0.1)  # a load torque pushing the axis back
    pcd.sim.advance(3.0)
    assert pcd.sim.read("axis.1.position") == pytest.approx(10_000, abs=1)  # the integral holds it there


@pytest.mark.manual("§6.3", "Integrationsgrenze IL: begrenzt wird der Betrag von ki · Σ e(n)")
@pytest.mark.manual("§7.4 FRdITS", "RIntTS: der Wert liegt im Bereich der mit FLdRP definierten Integrationsgrenze "
                    "(Reg. IntL)")
def test_the_integration_term_is_limited_by_intl(pcd: Station) -> None:
    pcd.sim.fault("blocked_1", True)
    load(pcd, DestP=100, IntL=300)
    run(pcd, "FLdRP", "FUpDRP", "FLdDA", "FStart")
    pcd.sim.advance(5.0)
    run(pcd, "FRdITS")
    assert pcd.read_registers(reg("RIntTS")) == [300]


@pytest.mark.manual("§7.4 FLdRP", "der Regler übernimmt die Werte in die Arbeitsregister erst nachdem die Funktion "
                    "FUpDRP ausgeführt wurde")
@pytest.mark.manual("§7.4 FUpDRP", "der Regler übernimmt die mit FLdRP geladenen Parameter von den Zwischenregistern in "
                    "die Arbeitsregister")
def test_regulator_parameters_act_after_fupdrp(pcd: Station) -> None:
    pcd.sim.fault("blocked_1", True)
    load(pcd, DestP=100)
    run(pcd, "FLdDA", "FStart")
    pcd.sim.advance(5.0)
    run(pcd, "FRdITS")
    assert pcd.read_registers(reg("RIntTS")) == [500]  # KInt 50 up to IntL 500
    load(pcd, KInt=0)
    run(pcd, "FLdRP")
    pcd.sim.advance(0.5)
    run(pcd, "FRdITS")
    assert pcd.read_registers(reg("RIntTS")) == [500]  # loaded, not active
    run(pcd, "FUpDRP")
    run(pcd, "FRdITS")
    assert pcd.read_registers(reg("RIntTS")) == [0]


@pytest.mark.manual("§6.3", "die Abtastzeit vom Differentialteil kann in Schritten von 341 µs eingestellt "
                    "werden")
@pytest.mark.manual("§7.4 FLdRP", "Abtastzeit des D-Anteils = (n + 1) · 341,33 µs, n im Register SampI")
def test_the_derivative_sample_time_is_n_plus_1_samples(make: Callable[..., Station]) -> None:
    """Only the D term (KProp = KInt = 0), the rotor blocked, the set position running away at a
    constant speed: the error grows by the same step each sample, so the D term's difference over
    (n + 1) samples, and the output, doubles from n = 1 to n = 3."""
    outputs = []
    for n in (1, 3):
        pcd = make({"init": {1: {"MCFac": 1.0, "KProp": 0, "KInt": 0, "KDer": 100, "SampI": n,
                                 "Accel": 1_000_000, "MCW": 0x041B | 0x1800}}})
        pcd.sim.fault("blocked_1", True)
        load(pcd, Veloc=29_297)  # 10 counts per 341.33 µs sample
        run(pcd, "FLdVA", "FStart")
        pcd.sim.advance(0.2)
        outputs.append(pcd.sim.read("axis.1.output_volts"))
    assert outputs[0] > 0.3
    assert outputs[1] / outputs[0] == pytest.approx(2.0, rel=0.1)
