"""Manual §7.4 (the library's functions) statement by statement, driven by a host over S-Bus on
a real pty: the registers written, the command flags set, the read functions' registers read back."""

from __future__ import annotations

from collections.abc import Callable

import pytest

from devsim.devices.pcd4h3.units import CHIP_SAMPLE, ffp_encode
from tests.pcd4h3.helpers import Station, flag, load, reg, run

VELOCITY_MODE, FORWARD = 1 << 11, 1 << 12  # MCW and RSigB bits 11, 12 (§7.4 FSelOM, FRdSR)


def signal_register(pcd: Station) -> int:
    run(pcd, "FRdSR")
    return pcd.read_registers(reg("RSigB"))[0]


@pytest.mark.manual("§7.4 FSelOM", "die neu definierte Betriebsart ist erst nach Ausführen des nächsten "
                    "Startbefehls FStart gültig")
@pytest.mark.manual("§7.4 FRdSR", "RSigB Bit 11 (Betriebsart) und Bit 12 (Drehrichtung): Setzen und Rücksetzen "
                    "des Bit erfolgt jeweils erst beim nächsten Startbefehl")
def test_fselom_changes_the_mode_bits_only_with_the_next_start(pcd: Station) -> None:
    assert signal_register(pcd) & (VELOCITY_MODE | FORWARD) == 0  # AxInit with MCW 41Bh: position mode
    load(pcd, MCW=0x041B | VELOCITY_MODE | FORWARD, Veloc=100)
    run(pcd, "FSelOM", "FLdVA")
    assert signal_register(pcd) & (VELOCITY_MODE | FORWARD) == 0  # selected, not yet valid
    assert pcd.sim.read("axis.1.velocity") == 0  # and the axis does not run in velocity mode either
    run(pcd, "FStart")
    assert signal_register(pcd) & (VELOCITY_MODE | FORWARD) == VELOCITY_MODE | FORWARD
    load(pcd, MCW=0x041B)  # back to position mode: still velocity mode until the next start
    run(pcd, "FSelOM")
    assert signal_register(pcd) & (VELOCITY_MODE | FORWARD) == VELOCITY_MODE | FORWARD


def settled(pcd: Station, timeout: float = 30.0) -> None:
    assert pcd.sim.run_until(lambda d: d.read("axis.1.OnDest"), timeout)
    pcd.sim.advance(0.5)


def read(pcd: Station, function: str, register: str) -> int:
    run(pcd, function)
    return pcd.read_registers(reg(register))[0]


@pytest.mark.manual("§7.4 FSelOM", "die Funktion liest nur Bit 11 und 12 des Registers MCW")
def test_fselom_reads_only_the_mode_bits(pcd: Station) -> None:
    load(pcd, DestP=1000)
    run(pcd, "FLdDA", "FStart")
    pcd.sim.advance(2.0)
    load(pcd, MCW=0x0300)  # stop bits 8 and 9 and no position error reaction: not FSelOM's business
    run(pcd, "FSelOM")
    pcd.sim.advance(1.0)
    assert pcd.sim.read("axis.1.motor_off") is False and read(pcd, "FRdSV", "RSetV") > 0  # still moving
    assert pcd.sim.read("axis.1.comers") == 0


@pytest.mark.manual("§7.4 FLdDA", "die neue geladene Position wird vom H3-Modul erst beim nächsten Startbefehl FStart ins "
                    "Arbeitsregister übernommen")
@pytest.mark.manual("§7.4 FLdDA", "Beispiel: Spindel 3 mm, 1000 Imp./Umdr., k = 4 · 1000 / 3000 µm = 1,33333 Imp./µm: "
                    "DestP = 60000 µm fährt 60 mm an")
@pytest.mark.manual("§7.4 FStart", "mit dieser Funktion kann eine Bewegung gestartet werden")
def test_fldda_loads_and_fstart_takes_it_over(pcd: Station) -> None:
    load(pcd, MCFac=ffp_encode(4 * 1000 / 3000), DestP=60_000, Veloc=50_000, Accel=100_000)
    run(pcd, "FLdVA", "FLdAA", "FLdDA")
    pcd.sim.advance(1.0)
    assert pcd.sim.read("axis.1.position") == 0 and pcd.sim.read("axis.1.set_position") == 0
    run(pcd, "FStart")
    settled(pcd)
    assert pcd.sim.read("axis.1.position") == pytest.approx(80_000, abs=3)  # 60 mm · 1.3333 counts/µm
    assert read(pcd, "FRdAP", "RActP") == pytest.approx(60_000, abs=3)


@pytest.mark.manual("§7.4 FLdDA", "Beispiel in 1/10 mm: k = 4 · 1000 / 30 = 133,333 Imp. pro 1/10 mm; DestP "
                    "= 600")
def test_fldda_in_tenths_of_a_millimetre(pcd: Station) -> None:
    load(pcd, MCFac=ffp_encode(4 * 1000 / 30), DestP=600)
    run(pcd, "FLdVA", "FLdAA", "FLdDA", "FStart")
    settled(pcd)
    assert pcd.sim.read("axis.1.position") == pytest.approx(80_000, abs=3)


@pytest.mark.manual("§7.4 FLdDR", "relativ laden heisst, der Wert ist bezogen auf die momentane Zielposition; übernommen "
                    "beim nächsten FStart")
@pytest.mark.manual("§7.4 FLdDR", "Beispiel: relativ eine Strecke von −60 mm (DestP = −60000 µm)")
def test_flddr_is_relative_to_the_current_target(pcd: Station) -> None:
    load(pcd, DestP=1000)
    run(pcd, "FLdDA", "FStart")
    pcd.sim.advance(2.0)  # about 200 on the way to 1000
    load(pcd, DestP=-600)
    run(pcd, "FLdDR")
    pcd.sim.advance(0.5)
    assert read(pcd, "FRdSV", "RSetV") > 0  # not yet taken over: still on the way up
    run(pcd, "FStart")
    settled(pcd)
    assert pcd.sim.read("axis.1.position") == pytest.approx(40_000, abs=3)  # 1000 − 600, not 200 − 600
    load(pcd, MCFac=ffp_encode(4 * 1000 / 3000), DestP=-60_000, Veloc=50_000, Accel=100_000)
    run(pcd, "FLdVA", "FLdAA", "FStart")  # the acceleration needs a start while standing
    settled(pcd)
    run(pcd, "FLdDR", "FStart")
    settled(pcd)
    assert pcd.sim.read("axis.1.position") == pytest.approx(40_000 - 80_000, abs=3)


def test_flddr_after_a_pending_fldda_adds_to_it(pcd: Station) -> None:
    """Spec G-30 (the manual's „momentane Zielposition“ does not say): a relative load adds to a
    value loaded and not yet started.  1000, then 2000 loaded and +500 relative: 2500 (was 1500)."""
    load(pcd, DestP=1000)
    run(pcd, "FLdDA", "FStart")
    settled(pcd)
    load(pcd, DestP=2000)
    run(pcd, "FLdDA")
    load(pcd, DestP=500)
    run(pcd, "FLdDR", "FStart")
    settled(pcd)
    assert read(pcd, "FRdAP", "RActP") == pytest.approx(2500, abs=1)


@pytest.mark.manual("§7.4 FLdVR", "Relativ laden heisst, der Wert ist bezogen auf die momentane "
                    "Sollgeschwindigkeit")
def test_fldvr_at_rest_adds_to_the_momentary_set_velocity(pcd: Station) -> None:
    """At rest the set velocity (FRdSV) is 0, so +100 cruises at 100, not at the last loaded
    Veloc (500) + 100."""
    load(pcd, DestP=1000)
    run(pcd, "FLdDA", "FStart")
    settled(pcd)
    assert read(pcd, "FRdSV", "RSetV") == 0
    load(pcd, Veloc=100, DestP=3000)
    run(pcd, "FLdVR", "FLdDA", "FStart")
    pcd.sim.advance(3.0)  # well into the cruise
    assert read(pcd, "FRdSV", "RSetV") == pytest.approx(100, abs=1)


@pytest.mark.manual("§7.4 FLdVA", "die neue geladene Geschwindigkeit wird erst beim nächsten Startbefehl ins "
                    "Arbeitsregister übernommen")
@pytest.mark.manual("§7.4 FStart", "mit dieser Funktion kann der Controller veranlasst werden, mit einem neu geladenen "
                    "Bewegungsparameter (z.B. einer Geschwindigkeit) zu arbeiten")
def test_fldva_acts_at_the_next_start(pcd: Station) -> None:
    load(pcd, DestP=10_000)
    run(pcd, "FLdDA", "FStart")
    pcd.sim.advance(6.0)
    assert read(pcd, "FRdSV", "RSetV") == 500
    load(pcd, Veloc=200)
    run(pcd, "FLdVA")
    pcd.sim.advance(2.0)
    assert read(pcd, "FRdSV", "RSetV") == 500
    run(pcd, "FStart")
    pcd.sim.advance(4.0)
    assert read(pcd, "FRdSV", "RSetV") == 200
    run(pcd, "FStop")
    settled(pcd)


@pytest.mark.manual("§7.4 FLdVA", "Beispiel: k = 1333,3 Imp./mm, Veloc = 100 mm/s fährt mit 0,1 m/s")
def test_fldva_example_in_millimetres_per_second(make: Callable[..., Station]) -> None:
    pcd = make({"axes": {1: {"kv": 20_000}}})  # a motor fast enough for 133 333 counts/s
    load(pcd, MCFac=ffp_encode(4 * 1000 / 3), Veloc=100, Accel=1000, MCW=0x141B | 0x0800)  # mm, velocity mode
    run(pcd, "FSelOM", "FLdVA", "FLdAA", "FStart")
    pcd.sim.advance(1.0)
    assert pcd.sim.read("axis.1.velocity") == pytest.approx(133_333 * 0.999, rel=0.002)  # 0.1 m/s


@pytest.mark.manual("§7.4 FLdVR", "relativ laden heisst, der Wert ist bezogen auf die momentane "
                    "Sollgeschwindigkeit")
@pytest.mark.manual("§7.4 FLdVR", "Beispiel: eine Geschwindigkeit relativ von −0,1 m/s (Veloc = −100 mm/s)")
def test_fldvr_is_relative_to_the_set_velocity(pcd: Station) -> None:
    load(pcd, MCW=0x141B | 0x0800)  # velocity mode, forward
    run(pcd, "FSelOM", "FStart")
    pcd.sim.advance(6.0)
    assert read(pcd, "FRdSV", "RSetV") == 500
    load(pcd, Veloc=-200)
    run(pcd, "FLdVR", "FStart")
    pcd.sim.advance(3.0)
    assert read(pcd, "FRdSV", "RSetV") == 300
    load(pcd, MCFac=ffp_encode(4 * 1000 / 3), Veloc=-100)  # k in counts per mm: 300 · 100 / 1333.3 = 22.5 mm/s
    run(pcd, "FLdVR")
    assert pcd.sim.read("axis.1.comers") == 1  # 22.5 − 100 mm/s is negative: a command error (§8)


@pytest.mark.manual("§7.4 FLdAA", "die neue Beschleunigung wird erst beim nächsten Startbefehl übernommen; beim Aufruf wird "
                    "FMotOff ausgeführt, die Regelung ist danach aus und wird mit FStart wieder eingeschaltet")
def test_fldaa_sets_the_ramp_of_the_next_start(pcd: Station) -> None:
    load(pcd, Accel=200, DestP=3000)
    run(pcd, "FLdAA")
    assert pcd.sim.read("axis.1.motor_off") is True
    run(pcd, "FLdDA", "FStart")
    pcd.sim.advance(1.25)
    assert read(pcd, "FRdSV", "RSetV") == pytest.approx(250, abs=3)  # 200 per s²


@pytest.mark.manual("§7.4 FLdAR", "relativ laden heisst, der Wert ist bezogen auf die momentane "
                    "Sollbeschleunigung")
def test_fldar_is_relative_to_the_acceleration(pcd: Station) -> None:
    load(pcd, DestP=10)
    run(pcd, "FLdDA", "FStart")  # the first start: relative loads allowed from now on
    settled(pcd)
    load(pcd, Accel=300, DestP=3000)
    run(pcd, "FLdAR", "FLdDA", "FStart")
    pcd.sim.advance(1.0)
    assert read(pcd, "FRdSV", "RSetV") == pytest.approx(400, abs=3)  # 100 + 300 per s²


@pytest.mark.manual("§7.4 FStop", "Bit 10: bei einem Stopbefehl wird mit der definierten Verzögerung gebremst; das "
                    "Statusflag OnDest wird nach einem ausgeführten Stop gesetzt")
def test_fstop_smooth_brakes_with_the_acceleration(pcd: Station) -> None:
    load(pcd, Veloc=500)
    run(pcd, "FLdVA", "FForw")
    pcd.sim.advance(6.0)
    run(pcd, "FRdSP", "FStop", cycles=0)  # in one AxHndlg call: RSetP read just before the stop (41Bh: bit 10)
    at = pcd.read_registers(reg("RSetP"))[0]
    assert pcd.read_flags(200) == [0]
    started = pcd.sim.now()
    assert pcd.sim.run_until(lambda d: d.read("axis.1.OnDest"), 10.0)
    assert pcd.sim.now() - started == pytest.approx(5.0, abs=0.1)  # 500 at 100 per s²
    assert read(pcd, "FRdSP", "RSetP") - at == pytest.approx(1250, abs=5)  # v² / 2a


@pytest.mark.manual("§7.4 FStop", "Bit 9: mit der maximalen Verzögerung gebremst, indem die Sollposition gleich der "
                    "Istposition gesetzt wird")
def test_fstop_abrupt_holds_the_set_position(pcd: Station) -> None:
    load(pcd, Veloc=500, MCW=0x021B)
    run(pcd, "FLdVA", "FForw")
    pcd.sim.advance(6.0)
    assert pcd.sim.read("axis.1.following_error") > 50  # at 50 000 counts/s the set position runs ahead
    pcd.write_flags(flag("FStop"), 1)
    assert pcd.sim.run_until(lambda d: not d.read("axis.1.FStop"), 1.0)  # the cycle that ran FStop, no later
    assert pcd.sim.read("axis.1.set_position") == pytest.approx(pcd.sim.read("axis.1.position"), abs=1)
    pcd.sim.advance(0.01)
    assert pcd.read_flags(200) == [1]
    held = pcd.sim.read("axis.1.set_position")
    pcd.sim.advance(1.0)
    assert pcd.sim.read("axis.1.set_position") == held
    assert pcd.sim.read("axis.1.position") == pytest.approx(held, abs=2)
    assert pcd.sim.read("axis.1.motor_off") is False


@pytest.mark.manual("§7.4 FStop", "Bit 8: bei einem Stopbefehl wird die Regelung ausgeschaltet, die "
                    "Stellgrösse auf Null")
@pytest.mark.manual("§7.4 FMotOff", "FMotOff schaltet die Regelung aus (Stellgrösse Null), wie FStop mit Bit "
                    "8 im MCW")
@pytest.mark.manual("§7.4 FResSF", "OnDest wird '1' gesetzt, wenn die Regelung ausgeschaltet ist (z.B. nach "
                    "FMotOff)")
def test_fstop_bit_8_and_fmotoff_switch_the_control_off(make: Callable[..., Station]) -> None:
    for function, mcw in (("FStop", 0x011B), ("FMotOff", 0x041B)):
        pcd = make()
        load(pcd, Veloc=500, MCW=mcw)
        run(pcd, "FLdVA", "FForw")
        pcd.sim.advance(6.0)
        run(pcd, function)
        assert pcd.sim.read("axis.1.motor_off") is True and pcd.sim.read("axis.1.output_volts") == 0.0
        assert pcd.read_flags(200) == [1]
        assert read(pcd, "FRdSR", "RSigB") & 0x80
        pcd.sim.advance(0.2)
        assert pcd.sim.read("axis.1.velocity") < 40_000  # coasting down, not driven


@pytest.mark.manual("§7.4 FStop", "das Statusflag OnDest wird nach einem ausgeführten Stop gesetzt (Stopart Bit 10, "
                    "mit der definierten Verzögerung)")
@pytest.mark.manual("§7.4 FResSF", "OnDest wird '1' gesetzt ... nach einem manuellen Stop (Funktion FStop)")
@pytest.mark.manual("§7.4 FRdSR", "Bit 10: '1' wenn der Generator das errechnete Geschwindigkeitsprofil beendet hat")
def test_a_smooth_stop_of_a_standing_axis_sets_ondest(pcd: Station) -> None:
    """A smooth stop (MCW 41Bh) when the generator already stands: nothing to brake, the stop is
    done at once and OnDest rises, as it does for the abrupt and the motor-off stop (it stayed 0:
    in velocity mode at Veloc 0 a host waiting for OnDest after FStop waited for ever)."""
    load(pcd, MCW=0x041B | VELOCITY_MODE | FORWARD, Veloc=0, StaFRR=0)
    run(pcd, "FSelOM", "FLdVA", "FStart")  # velocity mode at 0: running, never on target by itself
    pcd.sim.advance(1.0)
    assert pcd.read_flags(200) == [0] and signal_register(pcd) & 0x0404 == 0
    load(pcd, MCW=0x041B)
    run(pcd, "FStop")
    assert pcd.read_flags(200) == [1]
    assert signal_register(pcd) & 0x0404 == 0x0404
    load(pcd, DestP=100, Veloc=500)  # position mode, at rest on the target, OnDest reset by FResSF
    run(pcd, "FSelOM", "FLdVA", "FLdDA", "FStart")
    settled(pcd)
    run(pcd, "FResSF")
    assert pcd.read_flags(200) == [0]
    run(pcd, "FStop")
    assert pcd.read_flags(200) == [1]


@pytest.mark.manual("§7.4 FStop", "nach einem Stop verliert der Controller die zuletzt geladene Zielposition nicht; bevor "
                    "die Bewegung ohne neuen Parameter fortgesetzt werden kann, muss zuerst FSelOM neu geladen werden")
@pytest.mark.manual("§7.4 FMotOff", "der Befehl FMotOff hat die gleiche Funktion wie der Befehl FStop, wenn das Bit 8 "
                    "im Register MCW gesetzt ist")
@pytest.mark.parametrize(("function", "mcw"), [("FStop", 0x041B), ("FStop", 0x011B), ("FMotOff", 0x041B)])
def test_resuming_after_a_stop_needs_fselom(pcd: Station, function: str, mcw: int) -> None:
    """Also after a motor-off stop and FMotOff: FStart alone repeats the stop, the control stays
    off (RSigB bit 7) until FSelOM (docs/devices/pcd4h3.md, Deviations §7.4 FRdSR bit 7)."""
    load(pcd, DestP=1000, MCW=mcw)
    run(pcd, "FLdDA", "FStart")
    pcd.sim.advance(2.0)
    run(pcd, function)
    settled(pcd)
    stopped = pcd.sim.read("axis.1.position")
    assert stopped < 50_000  # 200 · 2 s, braking as long: about 400
    run(pcd, "FStart")  # the stop is still in the loaded control word: nothing
    pcd.sim.advance(2.0)
    assert pcd.sim.read("axis.1.position") == pytest.approx(stopped, abs=2)
    assert signal_register(pcd) & 0x80 == (0 if mcw == 0x041B and function == "FStop" else 0x80)
    run(pcd, "FSelOM", "FStart")
    assert signal_register(pcd) & 0x80 == 0
    settled(pcd)
    assert pcd.sim.read("axis.1.position") == pytest.approx(100_000, abs=3)


@pytest.mark.manual("§7.4 FSStepF", "ein Einzelimpuls in positive Richtung: relativ +1 Impuls geladen und gestartet "
                    "(1 Impuls = 1/4 Encoderteilung)")
@pytest.mark.manual("§7.4 FSStepB", "ein Einzelimpuls in negative Richtung: relativ −1 Impuls")
def test_single_steps(pcd: Station) -> None:
    load(pcd, DestP=10)
    run(pcd, "FLdDA", "FStart")
    settled(pcd)
    for function, expected in (("FSStepF", 1001), ("FSStepF", 1002), ("FSStepB", 1001)):
        run(pcd, function)
        settled(pcd)
        assert pcd.sim.read("axis.1.position") == expected, function


@pytest.mark.manual("§7.4 FForw", "mit der zuletzt geladenen Geschwindigkeit in positive Richtung fahren, bis ein "
                    "manueller Stopbefehl ausgeführt wird")
@pytest.mark.manual("§7.4 FBackw", "mit der zuletzt geladenen Geschwindigkeit in negative Richtung fahren, "
                    "bis ein Stop")
def test_forward_and_backward_run_until_a_stop(pcd: Station) -> None:
    load(pcd, Veloc=200)
    run(pcd, "FLdVA", "FBackw")
    pcd.sim.advance(30.0)
    assert read(pcd, "FRdSV", "RSetV") == -200  # signed (spec G-11)
    assert pcd.sim.read("axis.1.velocity") == pytest.approx(-20_000 * 0.999, rel=0.01)
    run(pcd, "FForw")
    pcd.sim.advance(30.0)
    assert read(pcd, "FRdSV", "RSetV") == 200
    run(pcd, "FStop")
    settled(pcd)
    assert read(pcd, "FRdSV", "RSetV") == 0


@pytest.mark.manual("§7.4 FRdAP", "die Funktion liest die Istposition und kopiert sie in das Register RActP (mit k "
                    "umgerechnet)")
@pytest.mark.manual("§7.4 FRdSP", "die Funktion liest die momentane Sollposition am Ausgang des "
                    "Profilgenerators in RSetP")
def test_read_actual_and_set_position(pcd: Station) -> None:
    load(pcd, DestP=1000)
    run(pcd, "FLdDA", "FStart")
    pcd.sim.advance(3.0)
    run(pcd, "FRdAP", "FRdSP")
    actual, setpoint = pcd.read_registers(reg("RActP"), 2)
    # the machine now, one PLC cycle (10 ms at 300 per s) after the functions read it
    assert setpoint == pytest.approx(pcd.sim.read("axis.1.set_position") / 100, abs=4)
    assert actual == pytest.approx(pcd.sim.read("axis.1.position") / 100, abs=4)
    assert 0 < actual < setpoint  # the actual position follows the set position
    settled(pcd)
    run(pcd, "FRdAP", "FRdSP")
    assert pcd.read_registers(reg("RActP"), 2) == [1000, 1000]


@pytest.mark.manual("§7.4 FRdAV", "nur die 14 höherwertigen Bit der Istgeschwindigkeit können gelesen werden; für kleine "
                    "Geschwindigkeiten kann kein vernünftiger Wert gelesen werden, die Sollgeschwindigkeit empfiehlt sich")
@pytest.mark.manual("§7.4 FRdSV", "die Funktion liest die momentane Sollgeschwindigkeit vom Profilgenerator "
                    "in RSetV")
def test_read_actual_velocity_is_coarse(pcd: Station) -> None:
    load(pcd, Veloc=500)
    run(pcd, "FLdVA", "FForw")
    pcd.sim.advance(8.0)
    assert read(pcd, "FRdSV", "RSetV") == 500
    assert read(pcd, "FRdAV", "RActV") == pytest.approx(500, rel=0.05)  # whole counts per sample: coarse
    load(pcd, Veloc=1)  # 100 counts/s: 0.03 counts per sample
    run(pcd, "FLdVA", "FStart")
    pcd.sim.advance(8.0)
    assert read(pcd, "FRdSV", "RSetV") == 1
    assert read(pcd, "FRdAV", "RActV") == 0


@pytest.mark.manual("§7.4 FRdIP", "die Funktion liest die Indexposition in das Register RIndP")
@pytest.mark.manual("§7.4 FSetIP", "nach FSetIP wird beim nächsten Mal, wenn A, B und der Indexeingang Null sind, die "
                    "Istposition ins Indexpositionsregister geschrieben und das Statusflag IPuls gesetzt")
@pytest.mark.manual("§7.4 FRdSR", "Bit 0: '1' nach FSetIP; zurückgesetzt, nachdem die nächste Indexposition "
                    "erfasst wurde")
@pytest.mark.manual("§7.4 FResSF", "IPuls wird '1' gesetzt, wenn ein Indeximpuls erfasst wurde")
def test_index_capture(make: Callable[..., Station]) -> None:
    pcd = make({"axes": {1: {"index_offset": 700}}})
    run(pcd, "FSetIP")
    assert read(pcd, "FRdSR", "RSigB") & 1 == 1 and pcd.read_flags(201) == [0]
    load(pcd, Veloc=20)
    run(pcd, "FLdVA", "FForw")
    assert pcd.sim.run_until(lambda d: d.read("axis.1.IPuls"), 5.0)
    assert read(pcd, "FRdSR", "RSigB") & 1 == 0
    assert read(pcd, "FRdIP", "RIndP") == 7  # 700 counts, k = 100


@pytest.mark.manual("§7.4 FRdSR", "Bit 7: '1' wenn die Regelung ausgeschaltet ist (Einschalten, nach AxInit, FMotOff, "
                    "...); zurückgesetzt mit dem nächsten FStart")
@pytest.mark.manual("§7.4 FRdSR", "Bit 10: '1' wenn der Generator das Profil beendet hat; zurückgesetzt beim nächsten "
                    "FStart")
@pytest.mark.manual("§7.4 FRdSR", "Bit 14: eine neue Beschleunigung wurde mit FLdAA/R geladen; zurückgesetzt beim "
                    "nächsten Startbefehl")
@pytest.mark.manual("§7.4 FRdSR", "Bit 2 bis 6: der Zustand der Statusflag")
@pytest.mark.manual("§7.4 FResSF", "OnDest: das Flag wird bei einem Startbefehl (Funktion FStart) automatisch "
                    "zurückgesetzt")
def test_signal_register_bits(pcd: Station) -> None:
    after_axinit = read(pcd, "FRdSR", "RSigB")
    assert after_axinit & 0x4080 == 0x4080 and pcd.read_flags(200) == [1]  # off, acceleration loaded; OnDest
    load(pcd, DestP=300)
    run(pcd, "FLdDA", "FStart")
    moving = read(pcd, "FRdSR", "RSigB")
    assert moving & 0x4480 == 0 and moving & 0x04 == 0  # on, not finished, taken over; OnDest 0
    assert pcd.read_flags(200) == [0]
    settled(pcd)
    done = read(pcd, "FRdSR", "RSigB")
    assert done & 0x0404 == 0x0404 and pcd.read_flags(200) == [1]
    load(pcd, Accel=10)
    run(pcd, "FLdAR")  # the relative load sets bit 14 as the absolute one does (and switches the control off)
    assert read(pcd, "FRdSR", "RSigB") & 0x4080 == 0x4080
    run(pcd, "FStart")
    assert read(pcd, "FRdSR", "RSigB") & 0x4080 == 0


@pytest.mark.manual("§7.4 FRdSR", "Bit 9: die Massnahme bei Positionsfehler: 0 nur Statusflag, 1 Statusflag und Regelung "
                    "aus")
@pytest.mark.manual("§7.4 FSetPE", "im Register MCW wird angegeben ob im Fehlerfall nur das Statusflag gesetzt oder "
                    "zusätzlich die Regelung ausgeschaltet wird")
def test_signal_register_bit_9_shows_the_reaction(pcd: Station) -> None:
    assert read(pcd, "FRdSR", "RSigB") & 0x200 == 0  # 41Bh: flag only
    load(pcd, MCW=0x041A)
    run(pcd, "FSetPE")
    assert read(pcd, "FRdSR", "RSigB") & 0x200 == 0x200


@pytest.mark.manual("§7.4 FSetPE", "die Differenz zwischen Soll- und Istposition wird direkt in Impulsen (nach der "
                    "Vervierfachung) eingegeben: PosEr ist ein Grenzwert in Zählschritten")
@pytest.mark.manual("§7.4 FResSF", "ExcPEr wird '1' gesetzt, wenn der Betrag des Positionsfehlers den mit FSetPE "
                    "definierten Wert überschreitet")
def test_the_position_error_limit_in_counts(pcd: Station) -> None:
    pcd.sim.fault("blocked_1", True)
    load(pcd, PosEr=500, DestP=1000)
    run(pcd, "FSetPE", "FLdDA", "FStart")
    # in steps of one PLC cycle (the PLC runs no timer while the chip only moves: no event to jump to)
    for _ in range(500):
        if pcd.sim.read("axis.1.following_error") >= 400:
            break
        pcd.sim.advance(0.010)
    assert 400 <= pcd.sim.read("axis.1.following_error") <= 500
    assert pcd.read_flags(203) == [0]
    assert pcd.sim.run_until(lambda d: d.read("axis.1.ExcPEr"), 5.0)
    assert 500 <= pcd.sim.read("axis.1.following_error") <= 520


@pytest.mark.manual("§7.4 FResSF", "das Flag wird zurückgesetzt, wenn das entsprechende Bit im Register "
                    "StaFRR Null ist")
@pytest.mark.manual("§7.4 FLdBPA", "die Breakposition wird sofort in das Arbeitsregister übernommen; wird sie erreicht, "
                    "wird BrkPos gesetzt; das Flag kann mit ResSF zurückgesetzt werden")
@pytest.mark.manual("§7.4 FResSF", "BrkPos wird '1' gesetzt, sobald die Istposition die Breakposition über- oder "
                    "unterschreitet")
def test_break_position_and_reset_of_single_status_flags(pcd: Station) -> None:
    load(pcd, DestP=1000, BrkP=300)
    run(pcd, "FLdDA", "FStart")
    pcd.sim.advance(0.5)
    run(pcd, "FLdBPA")  # during the move, no start
    assert pcd.sim.run_until(lambda d: d.read("axis.1.BrkPos"), 10.0)
    assert read(pcd, "FRdAP", "RActP") == pytest.approx(300, abs=5)
    settled(pcd)
    assert pcd.read_flags(200, 5) == [1, 0, 0, 0, 1]
    load(pcd, StaFRR=0xFFFF & ~(1 << 6))  # only BrkPos's bit is 0
    run(pcd, "FResSF")
    assert pcd.read_flags(200, 5) == [1, 0, 0, 0, 0]
    load(pcd, DestP=0)
    run(pcd, "FLdDA", "FStart")  # back through 300: under it this time
    assert pcd.sim.run_until(lambda d: d.read("axis.1.BrkPos"), 10.0)
    assert read(pcd, "FRdAP", "RActP") == pytest.approx(300, abs=5)


@pytest.mark.manual("§7.4 FLdBPR", "relativ laden heisst, der Wert ist bezogen auf die momentane "
                    "Zielposition")
def test_fldbpr_is_relative_to_the_target(pcd: Station) -> None:
    load(pcd, DestP=1000, BrkP=-300, StaFRR=0)
    run(pcd, "FLdDA", "FStart")
    run(pcd, "FLdBPR", "FResSF")
    assert pcd.sim.run_until(lambda d: d.read("axis.1.BrkPos"), 10.0)
    assert read(pcd, "FRdAP", "RActP") == pytest.approx(700, abs=5)


@pytest.mark.manual("§7.4 FResSF", "WrapOc wird '1' gesetzt, wenn es einen Überlauf des Positionsregisters gibt (im "
                    "drehzahlgeregelten Betrieb)")
def test_wraparound_in_velocity_mode(pcd: Station) -> None:
    pcd.sim.set("axis.1.position", (1 << 30) - 20_000)
    load(pcd, MCW=0x041B | 0x1800)
    run(pcd, "FSelOM", "FStart")
    assert pcd.sim.run_until(lambda d: d.read("axis.1.WrapOc"), 10.0)
    assert pcd.sim.read("axis.1.position") < 0  # counted over to −2^30


@pytest.mark.manual("§7.4 FLdDA", "absolut laden heisst, der Wert ist bezogen auf die Nullposition")
@pytest.mark.manual("§7.4 FLdDR", "relativ laden heisst, der Wert ist bezogen auf die momentane Zielposition")
@pytest.mark.manual("§7.4 FResSF", "WrapOc: einen Überlauf kann es im drehzahlgeregelten Betrieb geben")
def test_after_a_wraparound_moves_count_from_the_wrapped_position(pcd: Station) -> None:
    pcd.sim.set("axis.1.position", (1 << 30) - 20_000)
    load(pcd, MCW=0x041B | 0x1800)
    run(pcd, "FSelOM", "FStart")
    assert pcd.sim.run_until(lambda d: d.read("axis.1.WrapOc"), 10.0)
    load(pcd, MCW=0x041B, StaFRR=0)
    run(pcd, "FStop")
    settled(pcd)
    run(pcd, "FResSF")
    here = read(pcd, "FRdAP", "RActP")
    assert here < -10_737_000  # just past −2^30 counts (k = 100)
    load(pcd, DestP=here + 5)  # 500 counts forward
    run(pcd, "FSelOM", "FLdDA", "FStart")
    settled(pcd, 10.0)
    assert read(pcd, "FRdAP", "RActP") == here + 5
    load(pcd, DestP=3, BrkP=2)
    run(pcd, "FLdBPR")  # 2 past the target reached
    run(pcd, "FLdDR", "FStart")
    settled(pcd, 10.0)
    assert read(pcd, "FRdAP", "RActP") == here + 8
    assert pcd.sim.read("axis.1.comers") == 0
    assert pcd.read_flags(flag("OnDest"), 5) == [1, 0, 0, 0, 1]  # no second overflow; the break position passed


@pytest.mark.manual("§7.4 FSetZP", "die Istposition wird als Nullposition definiert")
@pytest.mark.manual("§7.4 FSetZP", "während einer Bewegung wird die momentane Zielposition nicht beeinflusst, wenn kein "
                    "FStart ausgeführt wird")
def test_fsetzp_standing_and_moving(pcd: Station) -> None:
    load(pcd, DestP=200)
    run(pcd, "FLdDA", "FStart")
    settled(pcd)
    run(pcd, "FSetZP")
    assert read(pcd, "FRdAP", "RActP") == 0
    load(pcd, DestP=1000)
    run(pcd, "FLdDA", "FStart")
    pcd.sim.advance(3.0)
    mechanical_start = 20_000
    run(pcd, "FSetZP")
    settled(pcd)
    assert pcd.sim.read("axis.1.mechanical_position") == pytest.approx(mechanical_start + 100_000, abs=3)


@pytest.mark.manual("§7.4 FResSF", "OnDest: infolge falsch eingestellter Parameter oder mechanischer Probleme kann der "
                    "Motor noch nicht in der Zielposition sein und das Flag trotzdem gesetzt werden, da der Generator "
                    "das Sollprofil bereits beendet hat")
def test_ondest_follows_the_generator_not_the_motor(pcd: Station) -> None:
    pcd.sim.fault("blocked_1", True)
    load(pcd, DestP=50)
    run(pcd, "FLdDA", "FStart")
    assert pcd.sim.run_until(lambda d: d.read("axis.1.OnDest"), 10.0)
    assert read(pcd, "FRdSP", "RSetP") == 50 and read(pcd, "FRdAP", "RActP") == 0


@pytest.mark.manual("§7.4 FSStepF", "die Funktion darf nicht ausgeführt werden, wenn die absolute Zielposition die positive "
                    "Grenze des Wertebereichs erreicht hat")
@pytest.mark.manual("§7.4 FSStepB", "die Funktion darf nicht ausgeführt werden, wenn die absolute Zielposition die negative "
                    "Grenze des Wertebereichs erreicht hat")
@pytest.mark.parametrize(("function", "end"), [("FSStepF", (1 << 30) - 1), ("FSStepB", -(1 << 30))])
def test_a_step_beyond_the_range_is_a_command_error(pcd: Station, function: str, end: int) -> None:
    load(pcd, MCFac=0x80000041, DestP=end)  # k = 1: the last count of the range
    run(pcd, "FLdDA", "FStart")
    assert pcd.sim.read("axis.1.comers") == 0
    run(pcd, function)
    assert pcd.sim.read("axis.1.comers") == 1  # the chip refuses the target 2^30 / −2^30 − 1: ComErS


@pytest.mark.manual("§7.2 AxHndlg", "Laderegister: soll ein Parameter geladen werden, muss die Funktion aktiviert werden, "
                    "welche den Wert vom Laderegister ins H3-Modul kopiert")
def test_a_load_register_alone_changes_nothing(pcd: Station) -> None:
    load(pcd, DestP=100)
    run(pcd, "FLdDA", "FStart")
    settled(pcd)
    load(pcd, DestP=900)  # written, never loaded
    run(pcd, "FStart")
    settled(pcd)
    assert pcd.sim.read("axis.1.position") == pytest.approx(10_000, abs=3)


@pytest.mark.manual("§6.2", "Funktionsprinzip der Drehzahlregelung: die Sollposition wird kontinuierlich (entsprechend "
                    "der verlangten Geschwindigkeit) vergrössert")
def test_in_velocity_mode_the_set_position_keeps_growing(pcd: Station) -> None:
    load(pcd, MCW=0x041B | 0x1800, Veloc=200)
    run(pcd, "FSelOM", "FLdVA", "FStart")
    pcd.sim.advance(3.0)
    first, then = read(pcd, "FRdSP", "RSetP"), pcd.sim.now()
    pcd.sim.advance(1.0)
    second, now = read(pcd, "FRdSP", "RSetP"), pcd.sim.now()
    assert second - first == pytest.approx(200 * (now - then), abs=2)  # 200 per second


@pytest.mark.manual("§1", "auf dem Modul befindet sich für jede Achse ein Prozessor, welcher eine Bewegung entsprechend "
                    "den geladenen Parametern selbständig ausführt")
def test_the_chip_finishes_a_move_while_the_plc_stands(pcd: Station) -> None:
    load(pcd, DestP=400)
    run(pcd, "FLdDA", "FStart")
    assert pcd.call(0x43) == b"\x00\x00"  # S-Bus stop: AxHndlg no longer runs
    pcd.sim.advance(10.0)
    assert pcd.sim.read("axis.1.position") == pytest.approx(40_000, abs=3)
    assert pcd.read_flags(200) == [0]  # nobody copies the status while the PLC stands
    assert pcd.call(0x2F) == b"\x00\x00"  # run
    pcd.sim.advance(0.05)
    assert pcd.read_flags(200) == [1]


@pytest.mark.manual("§7.4 FRdSR", "Bit 7: die Regelung wird ausgeschaltet beim Einschalten der Speisung")
def test_power_on_switches_the_control_off(pcd: Station) -> None:
    load(pcd, DestP=100)
    run(pcd, "FLdDA", "FStart")
    settled(pcd)
    assert pcd.sim.read("axis.1.motor_off") is False
    pcd.sim.power_cycle()
    assert read(pcd, "FRdSR", "RSigB") & 0x80 and pcd.sim.read("axis.1.output_volts") == 0.0


@pytest.mark.manual("§7.4 FSetZP", "die Zielposition wird nicht beeinflusst, wenn kein FStart ausgeführt wird: mit "
                    "FStart gilt die geladene Zielposition ab der neuen Nullposition")
def test_fsetzp_then_fstart_takes_the_target_from_the_new_zero(pcd: Station) -> None:
    load(pcd, DestP=1000)
    run(pcd, "FLdDA", "FStart")
    pcd.sim.advance(3.0)
    run(pcd, "FSetZP", "FStart")
    # the encoder counts at the chip's last sample, the motor (the shared axis) moves on between
    # samples (§5.1, 341 µs): the zero is known within one sample's travel
    zero = pcd.sim.read("axis.1.mechanical_position") - pcd.sim.read("axis.1.position")
    between_samples = abs(pcd.sim.read("axis.1.velocity")) * CHIP_SAMPLE
    settled(pcd)
    assert read(pcd, "FRdAP", "RActP") == pytest.approx(1000, abs=1)
    assert pcd.sim.read("axis.1.mechanical_position") == pytest.approx(zero + 100_000, abs=3 + between_samples)
    assert zero > 30_000  # the new zero lies where the axis was, well past the old one


@pytest.mark.manual("§7.4 FResSF", "OnDest wird durch folgende Ereignisse '1' gesetzt: ... die Regelung ist "
                    "ausgeschaltet (z.B. nach der Funktion FMotOff)")
@pytest.mark.manual("§7.4 FResSF", "das Flag wird zurückgesetzt, wenn das entsprechende Bit im Register "
                    "StaFRR Null ist")
def test_fressf_resets_ondest_also_while_the_control_is_off(pcd: Station) -> None:
    """Switching the control off is an event that sets OnDest (LM628 status bit 2, "trajectory
    complete" is an interrupt flag); FResSF resets it like any status flag, also while the motor
    stays off: the chip's status byte reads 84h after the reset and 80h after RSTI 0000h (spec
    §3.5.2, the AN-693 initialisation check), not 84h for as long as the motor is off."""
    assert pcd.read_flags(flag("OnDest")) == [1]  # AxInit leaves the control off
    assert pcd.read_registers(4000)[0] == 0x84  # the diagnostics' chip status byte (spec §9.6.3)
    load(pcd, StaFRR=0)
    run(pcd, "FResSF")
    assert pcd.read_flags(flag("OnDest")) == [0]
    assert pcd.read_registers(4000)[0] == 0x80
    assert signal_register(pcd) & 0x84 == 0x80  # RSigB: control off (bit 7), OnDest (bit 2) reset
    run(pcd, "FMotOff")  # the event again
    assert pcd.read_flags(flag("OnDest")) == [1] and pcd.read_registers(4000)[0] == 0x84


@pytest.mark.manual("§7.4 FStop", "die Funktion liest nur Bit 8 bis 10 vom Register MCW")
def test_fstop_reads_only_the_stop_bits(pcd: Station) -> None:
    """At FStop the MCW also asks for velocity mode and for the control to go off at a position
    error (1Ah): FStop takes only its smooth stop (bit 10) from it; the reaction stays the one
    FSetPE loaded (RSigB bit 9), and the next load and start still run in position mode."""
    load(pcd, DestP=1000)
    run(pcd, "FLdDA", "FStart")
    pcd.sim.advance(2.0)
    load(pcd, MCW=0x041A | VELOCITY_MODE | FORWARD)
    run(pcd, "FStop")
    settled(pcd)
    assert pcd.sim.read("axis.1.position") < 50_000  # stopped on the way (about 400 at 200 per s)
    assert signal_register(pcd) & (0x0080 | 0x0200 | VELOCITY_MODE) == 0  # control on, flag only, position mode
    load(pcd, DestP=500)
    run(pcd, "FLdDA", "FStart")
    settled(pcd)
    assert pcd.sim.read("axis.1.position") == pytest.approx(50_000, abs=3)
    assert pcd.sim.read("axis.1.comers") == 0


@pytest.mark.manual("§7.4 FLdBPR", "die negative Breakposition addiert mit der Zielposition darf den gültigen "
                    "Wertebereich für die Zielposition nicht überschreiten")
@pytest.mark.manual("§8", "ein Wert ausserhalb seines erlaubten Wertebereiches: der H3-Controller ignoriert den "
                    "Befehl und setzt das Befehls-Errorflag")
@pytest.mark.parametrize(("function", "break_position"), [("FLdBPR", -100), ("FLdBPA", -(1 << 30) - 1)])
def test_a_break_position_beyond_the_range_is_a_command_error(pcd: Station, function: str,
                                                               break_position: int) -> None:
    chip = pcd.sim.device.model.drives[0].chip
    load(pcd, MCFac=0x80000041, DestP=-(1 << 30) + 10, BrkP=-5)  # k = 1; a target 10 counts inside the range
    run(pcd, "FLdDA", "FStart", "FLdBPA")
    assert pcd.sim.read("axis.1.comers") == 0 and chip.breakpoint == -5
    load(pcd, BrkP=break_position)
    run(pcd, function)
    assert pcd.sim.read("axis.1.comers") == 1 and chip.breakpoint == -5  # ignored: ComErS


@pytest.mark.manual("§7.4 FSetIP", "nachdem diese Funktion ausgeführt ist, wird beim nächsten Mal, wenn A, B und der "
                    "Indexeingang Null sind, die Istposition ins Indexpositionsregister geschrieben: nur beim nächsten Mal")
def test_fsetip_captures_only_the_next_index_mark(make: Callable[..., Station]) -> None:
    """A move over three marks (every 2000 counts) after one FSetIP: RIndP keeps the first."""
    pcd = make({"axes": {1: {"encoder_lines": 500, "index_offset": 0}}})
    load(pcd, MCFac=0x80000041, DestP=500)  # k = 1: positions in counts
    run(pcd, "FLdDA", "FStart")
    settled(pcd)
    load(pcd, Veloc=2000, DestP=7000)
    run(pcd, "FSetIP", "FLdVA", "FLdDA", "FStart")
    settled(pcd)
    assert read(pcd, "FRdAP", "RActP") == pytest.approx(7000, abs=2)
    assert read(pcd, "FRdIP", "RIndP") == 2000 and pcd.read_flags(flag("IPuls")) == [1]

