"""Manual §8 (what the host sees of a command error), §9.1 (Example 1's initialisation values) and
§10.1 (the functions' execution times), over S-Bus on a real pty."""

from __future__ import annotations

from collections.abc import Callable

import pytest

from devsim.devices.pcd4h3.units import ffp_encode
from tests.pcd4h3.helpers import Station, flag, load, reg, run

TWO_AXES = {"h3def": {"fmah3": 48, "bar": 200, "baf": 200, "mna": 2}}


@pytest.mark.manual("§8", "der Anwender hat keinen direkten Zugriff auf das Errorflag: die FB überwachen es "
                    "selbständig")
def test_the_command_error_flag_is_not_left_for_the_user(pcd: Station) -> None:
    load(pcd, Veloc=-5)
    run(pcd, "FLdVA")
    assert pcd.sim.read("axis.1.comers") == 1
    run(pcd, "FRdSR")
    assert pcd.read_registers(reg("RSigB"))[0] & 0x02 == 0  # bit 1: the chip's command error, cleared by the FB


@pytest.mark.manual("§9.1", "Initialisierungsregister von Beispiel 1: MCW 41BH, PosEr 2000, KProp 150, KInt 50, KDer 50, "
                    "IntL 500, SampI 15, MCFac 100.0 (Fliesspunkt), Veloc 500, Accel 100")
def test_example_1_initialisation_registers(make: Callable[..., Station]) -> None:
    pcd = make({"user_program": "example1"})
    values = pcd.read_registers(reg("KProp"), 13)
    assert values[:7] == [150, 50, 50, 500, 15, ffp_encode(100.0) - (1 << 32), 2000]
    assert values[9:11] == [500, 100] and values[12] == 0x41B


@pytest.mark.manual("§10.1", "Abarbeitungszeiten der Funktionen in AxHndlg: FLdDA 4,1 ms, FStart 1 ms (was ein Aufruf "
                    "abarbeitet, verzögert den Aufruf der nächsten Achse)")
@pytest.mark.manual("§1", "eine Verkettung mehrerer Achsen (Punkt-Punkt) im quasi Synchronbetrieb ist "
                    "programmierbar")
def test_the_execution_times_delay_the_next_axis(make: Callable[..., Station]) -> None:
    pcd = make(TWO_AXES)
    for axis in (1, 2):
        load(pcd, axis, DestP=1000)
    pcd.write_flags(flag("FLdDA", 1), 1)  # both axes' flags before one PLC cycle (axis 2's field follows axis 1's)
    pcd.write_flags(flag("FStart", 1), 1)
    pcd.write_flags(flag("FLdDA", 2), 1)
    pcd.write_flags(flag("FStart", 2), 1)
    assert pcd.sim.run_until(lambda d: not d.read("axis.2.FStart"), 1.0)
    pcd.sim.advance(1.0)
    lead = pcd.sim.read("axis.1.set_position") - pcd.sim.read("axis.2.set_position")
    # both ramp at 10 000 counts/s²: after 1 s, a start later by Δt is Δt · 10 000 counts behind
    assert lead / 10_000 == pytest.approx((4.1 + 1.0 + 0.5) / 1000, abs=0.0007)  # axis 1's call: its two functions


#: §10.1, column "Abarbeitungszeit", as the manual prints it (ms).
EXECUTION_MS = {
    "FSelOM": 1.9, "FSetPE": 1.9, "FStart": 1.0, "FStop": 2.7, "FMotOff": 1.8, "FSStepF": 4.5, "FSStepB": 4.5,
    "FForw": 4.5, "FBackw": 4.5, "FLdDR": 4.1, "FLdDA": 4.1, "FLdVR": 4.5, "FLdVA": 4.5, "FLdAR": 7.2, "FLdAA": 7.2,
    "FLdRP": 5.2, "FUpDRP": 0.9, "FRdAP": 4.3, "FRdSP": 4.3, "FRdAV": 2.8, "FRdSV": 3.7, "FRdITS": 1.9, "FRdIP": 4.3,
    "FRdSR": 1.8, "FResSF": 1.8, "FLdBPR": 3.3, "FLdBPA": 3.3, "FSetIP": 0.9, "FSetZP": 0.9,
}


def axis_2_start_lag(make: Callable[..., Station], function: str | None) -> float:
    """Axis 1 runs ``function`` (or nothing) in the PLC cycle in which axis 2 starts a move; how
    far axis 2's set position is behind after 1 s, as time at its speed then (about 1 s · 100 · k)."""
    pcd = make(TWO_AXES)
    load(pcd, 1, DestP=10)
    run(pcd, "FLdDA", "FStart", axis=1)  # a first start: relative loads are allowed, nothing is refused
    pcd.sim.advance(2.0)
    load(pcd, 2, DestP=1000)
    if function is not None:
        pcd.write_flags(flag(function, 1), 1)
    pcd.write_flags(flag("FLdDA", 2), 1)
    pcd.write_flags(flag("FStart", 2), 1)
    pcd.sim.advance(1.0)
    return -pcd.sim.read("axis.2.set_position") / 10_000  # s behind, against the same run without lag


@pytest.mark.manual("§10.1", "Abarbeitungszeit jeder Funktion (FSelOM 1,9 ms … FSetZP 0,9 ms): so lange dauert ihr "
                    "Aufruf in AxHndlg")
def test_each_function_takes_its_execution_time(make: Callable[..., Station]) -> None:
    baseline = axis_2_start_lag(make, None)
    for function, ms in EXECUTION_MS.items():
        lag = axis_2_start_lag(make, function) - baseline
        assert lag * 1000 == pytest.approx(ms, abs=0.4), function  # the chip acts on its 341 µs sample grid


@pytest.mark.manual("§10.1", "ausführbar während Bewegung: ja für die Lade-, Lese- und Hilfsfunktionen (FLdAA/FLdAR nur "
                    "bedingt, FSStepF/FSStepB nein)")
def test_the_functions_allowed_during_a_move(pcd: Station) -> None:
    load(pcd, DestP=5000, BrkP=4000, StaFRR=0xFFFF, Veloc=400)
    run(pcd, "FLdDA", "FStart")
    pcd.sim.advance(3.0)
    allowed = ("FSelOM", "FSetPE", "FLdDR", "FLdDA", "FLdVR", "FLdVA", "FLdRP", "FUpDRP", "FRdAP", "FRdSP", "FRdAV",
               "FRdSV", "FRdITS", "FRdIP", "FRdSR", "FResSF", "FLdBPR", "FLdBPA", "FSetIP")
    for function in allowed:
        run(pcd, function)
        assert pcd.sim.read("axis.1.comers") == 0, function
        assert pcd.sim.read("axis.1.motor_off") is False and pcd.read_flags(flag("OnDest")) == [0], function
