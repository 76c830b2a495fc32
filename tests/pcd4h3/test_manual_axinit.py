"""Manual §7.2: the main function blocks AxInit (run at the cold start, XOB 16; S-Bus 'restart
cold' 38h runs it again) and AxHndlg (every PLC cycle), seen by a host over S-Bus on a real pty."""

from __future__ import annotations

import pytest

from tests.pcd4h3.helpers import Station, flag, load, reg, run

RESTART_COLD, STOP = 0x38, 0x43
ACK = b"\x00\x00"


def finished(pcd: Station, timeout: float = 20.0) -> None:
    assert pcd.sim.run_until(lambda d: d.read("axis.1.OnDest"), timeout)
    pcd.sim.advance(0.5)


@pytest.mark.manual("§7.2 AxInit", "1. Reset des Controllers: alle Bewegungs- und PID-Parameter (inkl. Stellgrösse) auf "
                    "Null; die Istposition wird als Nullposition definiert")
@pytest.mark.manual("§7.2 AxInit", "nach der Ausführung des FB AxInit ist die Achse betriebsbereit")
def test_axinit_makes_the_actual_position_zero_and_the_axis_ready(pcd: Station) -> None:
    load(pcd, DestP=500)
    run(pcd, "FLdDA", "FStart")
    finished(pcd)
    mechanical = pcd.sim.read("axis.1.mechanical_position")
    assert pcd.call(RESTART_COLD) == ACK
    run(pcd, "FRdAP", "FRdSP")
    assert pcd.read_registers(reg("RActP"), 2) == [0, 0]  # RActP, RSetP: here is zero now
    assert pcd.sim.read("axis.1.output_volts") == 0.0 and pcd.sim.read("axis.1.motor_off") is True
    pcd.sim.advance(1.0)
    assert pcd.sim.read("axis.1.mechanical_position") == pytest.approx(mechanical, abs=1)  # nothing moved
    load(pcd, DestP=-100)  # ready: the next move runs from the new zero
    run(pcd, "FLdDA", "FStart")
    finished(pcd)
    assert pcd.sim.read("axis.1.mechanical_position") == pytest.approx(mechanical - 10_000, abs=3)


@pytest.mark.manual("§7.2 AxInit", "3.–8.: Betriebsart (FSelOM), Positionsfehler (FSetPE), Regelparameter (FLdRP, "
                    "FUpDRP), Beschleunigung (FLdAA) und Geschwindigkeit (FLdVA) aus den Registern laden")
def test_axinit_loads_the_registers_it_reads(pcd: Station) -> None:
    load(pcd, Veloc=200, Accel=50, MCW=0x041A, PosEr=1000)
    assert pcd.call(RESTART_COLD) == ACK
    run(pcd, "FRdSR")
    signals = pcd.read_registers(reg("RSigB"))[0]
    assert signals & 0x4280 == 0x4280  # acceleration loaded (14), stop on position error (9: MCW 1Ah), off (7)
    load(pcd, DestP=1000)
    run(pcd, "FLdDA", "FStart")
    pcd.sim.advance(4.5)  # 200 at 50 per s²: full speed from 4 s to 5 s (400 + 200 + 400 = 1000)
    run(pcd, "FRdSV")
    assert pcd.read_registers(reg("RSetV")) == [200]
    pcd.sim.fault("blocked_1", True)
    assert pcd.sim.run_until(lambda d: d.read("axis.1.ExcPEr"), 2.0)
    pcd.sim.advance(0.05)
    assert pcd.sim.read("axis.1.motor_off") is True  # MCW 41Ah: the control switched off
    assert pcd.sim.read("axis.1.set_position") - pcd.sim.read("axis.1.position") <= 1_001 + 100


@pytest.mark.manual("§7.2 AxHndlg", "damit nach dem Aufstarten keine unbeabsichtigten Funktionen ausgeführt werden, werden "
                    "die Befehlsflag mit AxInit automatisch zurückgesetzt")
@pytest.mark.manual("§7.2 AxInit", "9. Reset aller Funktions-Befehlsflag")
def test_a_command_flag_left_set_does_not_run_after_the_cold_start(pcd: Station) -> None:
    assert pcd.call(STOP) == ACK  # AxHndlg no longer runs: the flags stay as the host set them
    load(pcd, DestP=1000)
    pcd.write_flags(flag("FLdDA"), 1)
    pcd.write_flags(flag("FStart"), 1)
    pcd.sim.advance(0.1)
    assert pcd.read_flags(flag("FStart")) == [1]
    assert pcd.call(RESTART_COLD) == ACK
    assert pcd.read_flags(flag("FLdDA")) == [0] and pcd.read_flags(flag("FStart")) == [0]
    pcd.sim.advance(2.0)
    assert pcd.sim.read("axis.1.position") == 0


@pytest.mark.manual("§7.2 AxHndlg", "ist ein Befehlsflag gesetzt, führt der FB die Funktion aus; danach wird das Flag "
                    "wieder zurückgesetzt; ist kein Flag gesetzt, wird der FB verlassen, ohne dass eine Funktion "
                    "ausgeführt wurde")
def test_axhndlg_runs_a_set_flag_once_and_resets_it(pcd: Station) -> None:
    pcd.sim.set("axis.1.trace", [])
    pcd.write_flags(flag("FSetZP"), 1)
    pcd.sim.advance(0.1)  # ten PLC cycles
    assert pcd.read_flags(flag("FSetZP")) == [0]
    assert pcd.sim.read("axis.1.trace") == ["C:02"]  # DFH once, nothing in the other cycles


@pytest.mark.manual("§7.2 AxHndlg", "bei jeder Abarbeitung des FB werden automatisch die Statusflag der Achse gelesen und "
                    "in diese Flag kopiert")
def test_the_status_flags_are_copied_from_the_module_every_call(pcd: Station) -> None:
    assert pcd.read_flags(flag("OnDest")) == [1]  # after AxInit: the control is off
    pcd.write_flags(flag("OnDest"), 0)  # a host's write does not stick: the next call copies the module's
    pcd.sim.advance(0.05)
    assert pcd.read_flags(flag("OnDest")) == [1]
    load(pcd, DestP=300)
    run(pcd, "FLdDA", "FStart")
    assert pcd.read_flags(flag("OnDest")) == [0]
    finished(pcd)
    assert pcd.read_flags(flag("OnDest")) == [1]


@pytest.mark.manual("§7.2 AxInit", "beim Reset werden die Bewegungsparameter (Beschleunigung, Geschwindigkeit, Zielposition "
                    "und Breakposition) auf Null gesetzt")
def test_axinit_forgets_the_break_position(pcd: Station) -> None:
    load(pcd, BrkP=300, StaFRR=0)
    run(pcd, "FLdBPA", "FResSF")
    assert pcd.call(RESTART_COLD) == ACK
    load(pcd, DestP=600)
    run(pcd, "FLdDA", "FStart")
    finished(pcd)
    assert pcd.read_flags(flag("BrkPos")) == [0]  # passed 300 without a break position
