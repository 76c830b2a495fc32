"""Command errors and their handling (spec pcd4h3.md §3.7, §6.6 E1–E12) on a running PCD,
driven over S-Bus on a real pty: three identical transfers, ComErS, the flag cleared, the chip
unchanged; halting the PCD when ComErS is the manual's commissioning one."""

from __future__ import annotations

from collections.abc import Callable

import pytest

from devsim.devices.pcd4h3.units import ffp_encode
from tests.pcd4h3.helpers import EXAMPLE, Station, flag, load, reg, run


def transfers(pcd: Station) -> list[str]:
    return [t for t in pcd.sim.read("axis.1.trace") if not t.startswith("C:1D D:FF FD")]


def fresh(pcd: Station) -> None:
    pcd.sim.set("axis.1.trace", [])


@pytest.mark.manual("§8", "Fehler-Beispiel: mit FLdVA wird eine negative Geschwindigkeit geladen")
@pytest.mark.manual("§8", "bei einem Fehler ignoriert der H3-Controller den gesendeten Befehl und setzt das "
                    "Befehls-Errorflag")
@pytest.mark.manual("§8", "der zuletzt gesendete Befehl wird maximal zweimal wiederholt; nach dem dritten "
                    "Fehler wird ComErS aufgerufen und danach mit dem nächsten Schritt weitergefahren")
@pytest.mark.manual("§8", "im Debugger mit Hilfe der Diagnoseregister feststellen, bei welchem Befehl der "
                    "Fehler ausgelöst wird")
def test_e1_negative_velocity_three_transfers_then_comers(pcd: Station) -> None:
    fresh(pcd)
    load(pcd, Veloc=-100)
    run(pcd, "FLdVA")
    assert transfers(pcd) == ["C:1F D:00 08 D:FF FC D:97 0A"] * 3
    assert pcd.read_flags(flag("FLdVA")) == [0]
    assert pcd.sim.read("axis.1.comers") == 1 and pcd.read_registers(4000 + 9) == [1]
    assert pcd.read_registers(4000 + 10) == [9]  # the offset of the function that called ComErS
    assert pcd.sim.device.model.drives[0].chip.buffer.velocity == 1_117_389  # unchanged
    assert pcd.call(0x1B, data_bytes=1) == b"R"


@pytest.mark.manual("§8", "für die Inbetriebnahme: ComErS provoziert mit einer Division durch Null XOB 13, "
                    "dort HALT")
def test_e1_with_the_commissioning_comers_halts_the_pcd(make: Callable[..., Station]) -> None:
    pcd = make({"comers_action": "halt"})
    load(pcd, Veloc=-100, DestP=500)
    run(pcd, "FLdVA", "FLdDA")  # FLdDA (offset 7) runs first, FLdVA (9) halts the PCD
    assert pcd.call(0x1B, data_bytes=1) == b"H"
    assert pcd.read_flags(flag("FLdVA")) == [0]
    fresh(pcd)
    pcd.write_flags(flag("FStart"), 1)
    pcd.sim.advance(0.1)
    assert pcd.read_flags(flag("FStart")) == [1] and transfers(pcd) == []  # flags no longer processed
    assert pcd.call(0x38) == b"\x00\x00"  # restart cold: AxInit loads Veloc again: halted again
    assert pcd.call(0x1B, data_bytes=1) == b"H"
    load(pcd, Veloc=500)
    assert pcd.call(0x38) == b"\x00\x00"
    assert pcd.call(0x1B, data_bytes=1) == b"R" and pcd.sim.read("axis.1.position") == 0
    assert pcd.read_flags(flag("FStart")) == [0]  # AxInit clears the command flags


@pytest.mark.manual("§8", "Fehler-Beispiel: ein Regelfaktor > 32767 soll ins H3-Modul geladen werden")
@pytest.mark.manual("§7.4 FLdRP", "wird ein Wert ausserhalb des erlaubten Wertebereichs in die Register "
                    "geladen, wird ein Befehls-Error erzeugt")
def test_e2_a_regulator_factor_beyond_32767(pcd: Station) -> None:
    fresh(pcd)
    load(pcd, KProp=40_000)
    run(pcd, "FLdRP")
    assert transfers(pcd) == ["C:1E D:0F 0F D:9C 40 D:00 32 D:00 32 D:01 F4"] * 3
    assert pcd.sim.device.model.drives[0].chip.filter.buffer.kp == 150


@pytest.mark.manual("§8", "Fehler-Beispiel: für die erste Bewegung (vor dem ersten Startbefehl) einen "
                    "Bewegungsparameter relativ laden (FLdDR, FLdVR, FLdAR, FLdBPR)")
@pytest.mark.manual("§7.4 FLdDR", "nach der Initialisierung darf für die erste Bewegung nur eine absolute "
                    "Zielposition geladen werden; relativ erzeugt einen Command Error")
@pytest.mark.manual("§7.4 FLdVR", "für die erste Bewegung nur eine absolute Geschwindigkeit; relativ: "
                    "Command Error")
@pytest.mark.manual("§7.4 FLdAR", "für die erste Bewegung nur eine absolute Beschleunigung; relativ: Command "
                    "Error")
def test_e3_e4_relative_loads_before_the_first_movement(pcd: Station) -> None:
    load(pcd, DestP=100)
    for function in ("FLdDR", "FLdVR", "FLdAR", "FLdBPR"):
        before = pcd.sim.read("axis.1.comers")
        run(pcd, function)
        assert pcd.sim.read("axis.1.comers") == before + 1, function
    run(pcd, "FLdDA", "FStart")  # after a first start a relative load is accepted
    before = pcd.sim.read("axis.1.comers")
    run(pcd, "FLdDR")
    assert pcd.sim.read("axis.1.comers") == before


@pytest.mark.manual("§8", "Fehler-Beispiel: der Maschinenfaktor k wurde nicht im Fliesspunkt-Format in MCFac "
                    "geladen")
def test_e5_an_integer_machine_factor(pcd: Station) -> None:
    """k = 0 (00000064h decodes to 0): the target is 0 counts without an error; FRdAP divides by
    zero: ComErS, RActP unchanged."""
    load(pcd, MCFac=0x64, DestP=1000, RActP=4711)
    fresh(pcd)
    run(pcd, "FLdDA", "FStart")
    assert transfers(pcd) == ["C:1F D:00 02 D:00 00 D:00 00", "C:01"]
    run(pcd, "FRdAP")
    assert pcd.read_registers(reg("RActP")) == [4711] and pcd.sim.read("axis.1.comers") == 1


@pytest.mark.manual("§8", "Fehler-Beispiel: eine Störung auf dem PCD4-Bus; der Befehl wird wiederholt")
def test_e6_one_disturbed_transfer_is_repeated(pcd: Station) -> None:
    pcd.sim.set("axis.1.bus_errors", 1)
    load(pcd, DestP=1000)
    fresh(pcd)
    run(pcd, "FLdDA")
    assert transfers(pcd) == ["C:1F D:00 02 D:00 01 D:86 A0"] * 2
    assert pcd.sim.read("axis.1.comers") == 0
    assert pcd.sim.device.model.drives[0].chip.buffer.position == 100_000


@pytest.mark.manual("§7.4 FLdAA", "FLdAA darf während einer Bewegung ausgeführt werden; beim Aufruf wird "
                    "FMotOff ausgeführt: die Regelung ist danach aus und wird mit FStart wieder "
                    "eingeschaltet")
def test_e7_acceleration_during_a_move_switches_the_motor_off(pcd: Station) -> None:
    load(pcd, DestP=1000)
    run(pcd, "FLdDA", "FStart")
    pcd.sim.advance(2.0)
    run(pcd, "FLdAA")
    run(pcd, "FRdSR")
    assert pcd.read_flags(flag("OnDest")) == [1]
    assert pcd.read_registers(reg("RSigB"))[0] & 0x4080 == 0x4080
    assert pcd.sim.read("axis.1.output_volts") == 0.0
    run(pcd, "FStart")  # re-enables with the new acceleration towards the target
    assert pcd.sim.run_until(lambda d: d.read("axis.1.OnDest"), 20.0)
    assert abs(pcd.sim.read("axis.1.position") - 100_000) <= 3


@pytest.mark.manual("§7.4 FLdRP", "KProp, KInt, KDer, IntL: Integer 0.. 32'767; ausserhalb ein Befehls-Error")
@pytest.mark.manual("§7.4 FSetPE", "PosEr: Integer 0.. 32'767 Imp.")
@pytest.mark.parametrize(("registers", "function"), [
    ({"KProp": 65_636}, "FLdRP"), ({"KProp": -65_536}, "FLdRP"), ({"IntL": 98_303}, "FLdRP"),
    ({"MCW": 0x041B, "PosEr": 65_546}, "FSetPE"),
])
def test_a_register_beyond_16_bits_is_a_command_error_not_its_low_word(pcd: Station, registers: dict[str, int],
                                                                       function: str) -> None:
    """The library took the low 16 bits (65 636 loaded a KProp of 100, 65 546 a following-error
    limit of 10): only a value whose low word is above 7FFFh was refused."""
    fresh(pcd)
    chip = pcd.sim.device.model.drives[0].chip
    loaded = (chip.filter.buffer.kp, chip.filter.buffer.il, chip.error_threshold)
    load(pcd, **registers)
    before = pcd.sim.read("axis.1.comers")
    run(pcd, function)
    assert pcd.sim.read("axis.1.comers") == before + 1 and transfers(pcd) == []  # refused by the FB itself
    assert (chip.filter.buffer.kp, chip.filter.buffer.il, chip.error_threshold) == loaded


@pytest.mark.manual("§7.4 FLdRP", "SampI 0 … 255: ein Wert ausserhalb erzeugt einen Befehls-Error")
def test_e8_e9_mcw_reaction_and_sample_interval_out_of_range(pcd: Station) -> None:
    fresh(pcd)
    load(pcd, MCW=0)
    run(pcd, "FSetPE")
    load(pcd, SampI=300)
    run(pcd, "FLdRP")
    assert pcd.sim.read("axis.1.comers") == 2 and transfers(pcd) == []  # refused by the FB itself


@pytest.mark.manual("§10.1", "FSStepF und FSStepB sind während einer Bewegung nicht ausführbar (die FB "
                    "führen sie trotzdem aus)")
def test_e10_a_single_step_while_moving_is_executed_with_a_warning(pcd: Station) -> None:
    load(pcd, DestP=1000)
    run(pcd, "FLdDA", "FStart")
    assert pcd.read_flags(8000 + 3) == [0]
    fresh(pcd)
    run(pcd, "FSStepF")
    assert transfers(pcd)[:2] == ["C:1F D:00 03 D:00 00 D:00 01", "C:01"]
    assert pcd.read_flags(8000 + 3) == [1]


@pytest.mark.manual("§6.2", "erreicht der Motor die Sollgeschwindigkeit nicht (blockierter Rotor), wird die "
                    "Differenz Soll − Ist sehr gross: eine Positionsfehlermeldung, die einen automatischen "
                    "Stop des Motors auslösen kann")
@pytest.mark.manual("§7.4 FSetPE", "im Fehlerfall wird nur das Statusflag gesetzt (1Bh) oder zusätzlich die "
                    "Regelung ausgeschaltet (1Ah)")
def test_e11_e12_a_blocked_rotor_trips_the_position_error(make: Callable[..., Station]) -> None:
    for reaction, off in ((0x41A, True), (0x41B, False)):
        pcd = make()
        load(pcd, MCW=reaction, DestP=1000)
        run(pcd, "FSetPE", "FLdDA", "FStart")
        pcd.sim.advance(1.0)
        pcd.sim.fault("blocked_1", True)
        assert pcd.sim.run_until(lambda d: d.read("axis.1.ExcPEr"), 5.0)
        pcd.sim.advance(0.05)
        assert pcd.sim.read("axis.1.motor_off") is off
        if off:
            assert pcd.read_flags(flag("OnDest")) == [1] and pcd.sim.read("axis.1.output_volts") == 0.0
        else:
            assert abs(pcd.sim.read("axis.1.output_volts")) > 9.9  # saturated, the trajectory goes on
            assert pcd.sim.read("axis.1.set_position") > pcd.sim.read("axis.1.position") + 2000


@pytest.mark.manual("§7.4 FSetPE", "die Differenz (Betrag) zwischen Soll- und Istposition wird überwacht: ExcPEr "
                    "auch hinter einer Bewegung in negativer Richtung")
@pytest.mark.manual("§7.4 FRdSR", "Bit 7: die Regelung wird bei einer Positionsfehlerüberschreitung (falls so "
                    "definiert) ausgeschaltet; das Bit wird mit dem nächsten Startbefehl zurückgesetzt")
def test_a_position_error_behind_a_backward_move_switches_off_until_the_next_start(pcd: Station) -> None:
    """The error's magnitude counts (the set position leads a backward move below the actual
    one); with 1Ah the control goes off, and FStart alone switches it on again towards the target
    (the trip loads no stop into the trajectory).  ExcPEr stays until FResSF, a start does not reset it."""
    load(pcd, MCW=0x041A, PosEr=500, DestP=-1000)
    run(pcd, "FSetPE", "FLdDA", "FStart")
    pcd.sim.advance(1.0)
    pcd.sim.fault("blocked_1", True)
    assert pcd.sim.run_until(lambda d: d.read("axis.1.ExcPEr"), 5.0)
    run(pcd, "FRdSR")
    assert pcd.read_registers(reg("RSigB"))[0] & 0x02A4 == 0x02A4  # OnDest, ExcPEr, control off, reaction
    pcd.sim.fault("blocked_1", False)
    run(pcd, "FStart")
    run(pcd, "FRdSR")  # (in a call of its own: FRdSR's flag comes before FStart's)
    assert pcd.read_registers(reg("RSigB"))[0] & 0x00A4 == 0x0020 and pcd.read_flags(flag("ExcPEr")) == [1]
    assert pcd.sim.run_until(lambda d: d.read("axis.1.OnDest"), 20.0)
    pcd.sim.advance(0.5)
    assert pcd.sim.read("axis.1.position") == pytest.approx(-100_000, abs=3)


@pytest.mark.manual("§8", "MCFac nicht im Fliesspunkt-Format kann bei der Umrechnung einen Überlauf des "
                    "Wertebereiches bewirken")
def test_a_machine_factor_that_overflows_the_range(pcd: Station) -> None:
    """§3.7: integer 1000 as MCFac gives k = −196 608: DestP 10 000 is beyond −2^30 counts."""
    load(pcd, MCFac=1000, DestP=10_000)
    fresh(pcd)
    run(pcd, "FLdDA")
    assert pcd.sim.read("axis.1.comers") == 1 and len(transfers(pcd)) == 3


@pytest.mark.manual("§7.4 FLdDA", "k = 4 · In / s; Beispiel: 1,33333 Imp./µm, DestP = 60000 µm")
def test_the_machine_factor_as_float_gives_the_example_counts(pcd: Station) -> None:
    load(pcd, MCFac=ffp_encode(4000 / 3000), DestP=60_000)  # U1: k = 1.33333 counts/µm
    fresh(pcd)
    run(pcd, "FLdDA")
    assert transfers(pcd) == ["C:1F D:00 02 D:00 01 D:38 80"]  # 80 000 counts


@pytest.mark.manual("§6.4", "für den Positionsdecoder müssen die Signale genau die Folge aufweisen; eine "
                    "Phase falsch invertiert zählt rückwärts")
def test_a_phase_jumper_the_wrong_way_reverses_the_count(make: Callable[..., Station]) -> None:
    """Jumper A/Ā changed alone (§2.5): the decoder counts backwards, the loop runs away; with
    LPES (MCW 41Ah) the control switches off at the position error."""
    pcd = make({"jumpers": {"invert_a": False}, "init": {1: {"MCW": 0x41A}}})
    load(pcd, DestP=10)
    run(pcd, "FLdDA", "FStart")
    assert pcd.sim.run_until(lambda d: d.read("axis.1.ExcPEr"), 2.0)
    pcd.sim.advance(0.05)
    assert pcd.sim.read("axis.1.motor_off") and pcd.sim.read("axis.1.mechanical_position") > 1000


@pytest.mark.manual("§6.4", "das Indexsignal darf am Eingang des Positionsdecoders nicht dauernd Null sein, "
                    "da dies zu einer Fehlfunktion des Controllers führen kann")
def test_an_inverted_index_jumper_captures_at_the_next_line(make: Callable[..., Station]) -> None:
    """IN/ĪN wrong: the decoder sees A = B = IN = 0 at every line and captures there, not at the
    index mark (the manual's malfunction, §6.4)."""
    for inverted, near in ((False, 1000), (True, 4)):
        pcd = make({"jumpers": {"index_invert": inverted}, "axes": {1: {"index_offset": 1000}}})
        load(pcd, Veloc=20)
        run(pcd, "FSetIP", "FLdVA", "FForw")
        assert pcd.sim.run_until(lambda d: d.read("axis.1.IPuls"), 5.0)
        assert pcd.sim.device.model.drives[0].chip.index_position == near


@pytest.mark.manual("§7.1.3", "IMode: Module H310, 311, 320 u. 321: IMode = 6; Module H316, 317, 326 u. 327: IMode = 5")
def test_g26_imode_5_on_an_analog_module_is_taken_with_a_warning(make: Callable[..., Station]) -> None:
    """Spec G-26: IMode 5 in H3DEF on a ±10 V module (LM628) is accepted: AxInit sends PORT8, the
    12-bit DAC gets the top 8 bits only (RSigB bit 8 = 1), no command error; the diagnostics flag
    "warning pending" (F 8000 + 3, spec §9.6.3) says so.  The module's own IMode 6 gives none."""
    analog = make({"variant": "H320"})
    assert analog.read_flags(8000 + 3) == [0]
    coarse = make({"variant": "H320", "h3def": {**EXAMPLE["h3def"], "imode": 5}})
    assert coarse.read_flags(8000 + 3) == [1]
    assert coarse.sim.read("axis.1.comers") == 0
    run(coarse, "FRdSR")
    assert coarse.read_registers(reg("RSigB"))[0] >> 8 & 1 == 1  # the 8-bit port
