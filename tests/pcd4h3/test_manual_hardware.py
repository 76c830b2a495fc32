"""Manual §1, §2, §5.2, §6.1 … §6.6: what the module's hardware shows a host (over S-Bus on a real
pty: the bus inputs, the registers after the library's functions) and the machine side (the LEDs,
the set-point output, the motor)."""

from __future__ import annotations

from collections.abc import Callable

import pytest

from devsim.core.typed import Invalid
from tests.pcd4h3.helpers import Station, flag, load, reg, run

FMAH3 = 48  # the manual's example installation (§9.1 a)


def inputs(pcd: Station, first: int, count: int) -> list[int]:
    return pcd.read_flags(first, count, command=0x03)


def moved_to(pcd: Station, destination: int, axis: int = 1, timeout: float = 20.0) -> None:
    load(pcd, axis, DestP=destination)
    run(pcd, "FLdDA", "FStart", axis=axis)
    assert pcd.sim.run_until(lambda d: d.read(f"axis.{axis}.OnDest"), timeout)
    pcd.sim.advance(0.5)  # OnDest is the generator's end; the motor settles after it


@pytest.mark.manual("§1", "ein Modul belegt 16 Adressen am Bus; an einem PCD4 können 16 Positioniermodule (32 Achsen) "
                    "angeschlossen werden")
@pytest.mark.manual("§5.2", "Eingänge relativ zur Modul-Basisadresse: 9 LS1x, 10 LS2x, 11 In/Ref X, 13 LS1y, 14 LS2y, "
                    "15 In/Ref Y; Absolutadresse = Modul-Basisadresse + Relativadresse")
def test_each_module_takes_16_addresses_with_its_switch_inputs(make: Callable[..., Station]) -> None:
    pcd = make({"modules": 2, "h3def": {"fmah3": FMAH3, "bar": 200, "baf": 200, "mna": 4},
                "axes": {3: {"ls1": 10}, 4: {"ls2": -10, "ref_switch": [-5, 5]}}})
    second = FMAH3 + 16  # the second module
    assert inputs(pcd, second + 9, 7) == [0, 1, 0, 0, 1, 0, 1]  # LS1x open (axis 3); LS2y open, Ref y closed (4)
    assert inputs(pcd, FMAH3 + 9, 7) == [1, 1, 0, 0, 1, 1, 0]  # the first module's switches: healthy, no ref
    big = {"modules": 16, "h3def": {"fmah3": 0, "bar": 200, "baf": 200, "mna": 32}}
    assert make(big).read_registers(reg("KProp", 32)) == [150]  # axis 32's block, initialised
    with pytest.raises(Invalid):
        make({"h3def": {"mna": 33}})


@pytest.mark.manual("§1", "die Achsen werden unabhängig voneinander gesteuert")
def test_the_axes_move_independently(make: Callable[..., Station]) -> None:
    pcd = make({"h3def": {"fmah3": FMAH3, "bar": 200, "baf": 200, "mna": 2}})
    moved_to(pcd, 300, axis=2)
    assert pcd.sim.read("axis.2.position") == pytest.approx(30_000, abs=3)
    assert pcd.sim.read("axis.1.position") == 0 and pcd.read_flags(flag("OnDest", 1)) == [1]
    moved_to(pcd, -200, axis=1)
    assert pcd.sim.read("axis.1.position") == pytest.approx(-20_000, abs=3)
    assert pcd.sim.read("axis.2.position") == pytest.approx(30_000, abs=3)


@pytest.mark.manual("§1", "Typenübersicht: PCD4.H310/H311/H316/H317 haben eine Achse (X), H320/H321/H326/H327 zwei "
                    "(X, Y)")
def test_a_one_axis_module_has_no_y_axis(make: Callable[..., Station]) -> None:
    two = {"h3def": {"fmah3": FMAH3, "bar": 200, "baf": 200, "mna": 2}}
    pcd = make({**two, "variant": "H310"})
    assert pcd.sim.read("axis.2.comers") >= 1  # AxInit of axis 2 already found no chip
    before = pcd.sim.read("axis.2.comers")
    load(pcd, 2, DestP=100)
    run(pcd, "FLdDA", axis=2)
    assert pcd.sim.read("axis.2.comers") == before + 1
    pcd = make({**two, "variant": "H320"})
    run(pcd, "FLdDA", axis=2)
    assert pcd.sim.read("axis.2.comers") == 0


@pytest.mark.manual("§2", "Positioniervorgaben Position: Bereich [−2^30 … +(2^30 − 1)] Impulse (durch k geteilt in "
                    "der Einheit des Anwenders)")
def test_the_position_range_is_plus_minus_2_to_the_30_counts(pcd: Station) -> None:
    load(pcd, DestP=10_737_418)  # k = 100: 1 073 741 800 counts, inside
    run(pcd, "FLdDA")
    assert pcd.sim.read("axis.1.comers") == 0
    load(pcd, DestP=10_737_419)  # 1 073 741 900 counts: beyond 2^30 − 1
    run(pcd, "FLdDA")
    assert pcd.sim.read("axis.1.comers") == 1
    load(pcd, DestP=-10_737_418)
    run(pcd, "FLdDA")
    assert pcd.sim.read("axis.1.comers") == 1


@pytest.mark.manual("§2", "Analoger Ausgang ±10 V, Auflösung 12 Bit (plus Vorzeichen)")
@pytest.mark.manual("§6.5", "pro Achse ist ein 12 Bit D/A-Wandler eingesetzt")
def test_the_analog_output_has_12_bit_steps_up_to_10_volts(pcd: Station) -> None:
    load(pcd, DestP=1000)
    run(pcd, "FLdDA", "FStart")
    seen = set()
    for _ in range(40):
        pcd.sim.advance(0.05)
        volts = pcd.sim.read("axis.1.output_volts")
        assert -10.0 <= volts <= 10.0
        assert volts * 2048 / 10 == pytest.approx(round(volts * 2048 / 10), abs=1e-6)  # 10 V / 2048 steps
        seen.add(volts)
    assert len(seen) > 5
    pcd.sim.fault("blocked_1", True)
    pcd.sim.advance(2.0)
    assert abs(pcd.sim.read("axis.1.output_volts")) >= 9.99  # saturated at the end of the range


@pytest.mark.manual("§2", "PWM Ausgang: Puls-Weiten-Moduliert, Auflösung 8 Bit")
@pytest.mark.manual("§6.6", "die Auflösung des PWM-Signals beträgt 8 Bit, Bereich −128 … +127")
def test_the_pwm_output_has_8_bit_steps(make: Callable[..., Station]) -> None:
    pcd = make({"variant": "H326"})
    load(pcd, DestP=1000)
    run(pcd, "FLdDA", "FStart")
    seen = set()
    for _ in range(40):
        pcd.sim.advance(0.05)
        duty = pcd.sim.read("axis.1.output_volts") * 128 / 10  # the duty as −128 … +127
        assert duty == pytest.approx(round(duty), abs=1e-6) and -128 <= round(duty) <= 127
        seen.add(round(duty))
    assert len(seen) > 3


@pytest.mark.manual("§6.4", "auf jeden Zustandswechsel der Signale A und B wird das Positionsregister um 1 erhöht oder "
                    "erniedrigt: die vierfache Auflösung der Encoderteilung (4 × 500 Impulse pro Umdrehung)")
@pytest.mark.manual("§6.4", "jedesmal wenn alle 3 Encodersignale Null sind und vorher SetIP aufgerufen wurde, wird die "
                    "Motorposition in das Indexpositionsregister geschrieben")
def test_one_revolution_is_four_times_the_lines_and_the_index_is_captured(make: Callable[..., Station]) -> None:
    pcd = make({"axes": {1: {"encoder_lines": 500, "index_offset": 0}}})
    moved_to(pcd, 5)  # 500 counts: a quarter revolution, away from the mark at 0
    load(pcd, Veloc=20)
    run(pcd, "FSetIP", "FLdVA", "FForw")
    assert pcd.sim.run_until(lambda d: d.read("axis.1.IPuls"), 10.0)
    load(pcd, MCFac=0x80000041)  # k = 1.0: RIndP in counts
    run(pcd, "FRdIP")
    assert pcd.read_registers(reg("RIndP")) == [2000]  # the next mark: one revolution = 4 · 500 counts


@pytest.mark.manual("§6.4", "Eingang IN als Referenzpunkteingang (Jumper IN/RP in Position RP): der Eingang ist nicht "
                    "mehr aktiv für den Positionsdecoder")
@pytest.mark.manual("§6.4", "bei H311, H321, H317, H327 kann sowohl ein Referenzschalter (Klemmen) als auch das "
                    "Indexsignal (Sub-D) angeschlossen werden")
def test_with_jumper_rp_the_24v_decoder_sees_no_index(make: Callable[..., Station]) -> None:
    for variant, captured in (("H320", False), ("H321", True)):
        pcd = make({"variant": variant, "axes": {1: {"in_rp": "ref", "ref_switch": [500, 1500]}}})
        load(pcd, Veloc=50)
        run(pcd, "FSetIP", "FLdVA", "FForw")
        pcd.sim.advance(1.5)  # 7500 counts: past three marks and through the reference switch
        assert bool(pcd.read_flags(flag("IPuls"))[0]) is captured, variant
        assert pcd.sim.read("input.REF_1") is False  # left the switch behind


@pytest.mark.manual("§6.4", "die Signale der End- und Referenzschalter werden direkt auf den PCD4-Bus geführt; sie "
                    "müssen vom Anwenderprogramm überwacht werden")
def test_the_module_does_not_stop_at_an_open_limit_switch(make: Callable[..., Station]) -> None:
    pcd = make({"axes": {1: {"ls2": 50_000}}})
    assert inputs(pcd, FMAH3 + 10, 1) == [1]
    moved_to(pcd, 1000)
    assert pcd.sim.read("axis.1.position") == pytest.approx(100_000, abs=3)  # through LS2 at 50 000
    assert inputs(pcd, FMAH3 + 10, 1) == [0]  # the open switch, for the user program to see


@pytest.mark.manual("§6.4", "Zustandstabelle der LEDs: LS1 offen → LED LS1 hell; LS2 offen → LED LS2 hell; beide offen "
                    "→ STOP hell; beide 24 V → alle dunkel")
def test_the_led_table(pcd: Station) -> None:
    for ls1, ls2, leds in ((True, True, (False, False, False)), (False, True, (True, False, False)),
                           (True, False, (False, True, False)), (False, False, (False, False, True))):
        pcd.sim.set("input.LS1_1", ls1)
        pcd.sim.set("input.LS2_1", ls2)
        assert tuple(pcd.sim.read(f"output.LED_{led}_1") for led in ("LS1", "LS2", "STOP")) == leds
        assert inputs(pcd, FMAH3 + 9, 2) == [int(ls1), int(ls2)]


@pytest.mark.manual("§6.4", "liefert der Encoder andere Signale, müssen diese mittels Jumper invertiert werden: eine "
                    "falsch invertierte Phase lässt den Decoder rückwärts zählen")
def test_both_phases_inverted_together_keep_the_direction(make: Callable[..., Station]) -> None:
    pcd = make({"jumpers": {"invert_a": False, "invert_b": False}})
    moved_to(pcd, 100)
    assert pcd.sim.read("axis.1.position") == pytest.approx(10_000, abs=3)
    assert pcd.sim.read("axis.1.mechanical_position") == pytest.approx(10_000, abs=3)


@pytest.mark.manual("§6.4", "die Invertierung der Encodersignale erfolgt mit je 1 Jumper für A, B und IN gemeinsam für "
                    "beide Achsen; der Jumper IN/RP ist für jede Achse getrennt wählbar")
def test_the_inversion_jumpers_are_common_to_both_axes(make: Callable[..., Station]) -> None:
    pcd = make({"h3def": {"fmah3": FMAH3, "bar": 200, "baf": 200, "mna": 2}, "jumpers": {"invert_b": False},
                "init": {1: {"MCW": 0x41A}, 2: {"MCW": 0x41A}}})
    for axis in (1, 2):
        load(pcd, axis, DestP=10)
        run(pcd, "FLdDA", "FStart", axis=axis)
    assert pcd.sim.run_until(lambda d: d.read("axis.1.ExcPEr") and d.read("axis.2.ExcPEr"), 2.0)  # both run away


@pytest.mark.manual("§6.4", "wird bei 24 V-Encodern mit Referenzschaltern gearbeitet (Jumper IN/RP in RP), so muss der "
                    "Jumper IN/ĪN in Pos. IN stecken: das Indexsignal darf am Decoder nicht dauernd Null sein "
                    "(Fehlfunktion)")
def test_rp_with_the_index_inverted_is_a_malfunction(make: Callable[..., Station]) -> None:
    for inverted, captured in ((False, False), (True, True)):
        pcd = make({"jumpers": {"index_invert": inverted}, "axes": {1: {"in_rp": "ref", "index_offset": 1000}}})
        load(pcd, Veloc=20)
        run(pcd, "FSetIP", "FLdVA", "FForw")
        pcd.sim.advance(2.0)
        assert bool(pcd.read_flags(flag("IPuls"))[0]) is captured, inverted
        if captured:
            load(pcd, MCFac=0x80000041)
            run(pcd, "FRdIP")
            assert pcd.read_registers(reg("RIndP")) == [4]  # the next line, not a mark of the encoder


@pytest.mark.manual("§2", "Geschwindigkeit und Beschleunigung: Bereich bis 2^30 − 1 im Register des Controllers (durch "
                    "k und die Abtastzeit geteilt in der Einheit des Anwenders)")
def test_the_velocity_and_acceleration_ranges(pcd: Station) -> None:
    # k = 100: Veloc · 100 · 65536 · 341 µs ≤ 3FFFFFFFh up to Veloc 480 468; Accel · 100 · 65536 · (341 µs)² up to
    # 1.409 · 10^9
    for register, function, inside, beyond in (("Veloc", "FLdVA", 480_000, 481_000),
                                                ("Accel", "FLdAA", 1_400_000_000, 1_420_000_000)):
        before = pcd.sim.read("axis.1.comers")
        load(pcd, **{register: inside})
        run(pcd, function)
        assert pcd.sim.read("axis.1.comers") == before, register
        load(pcd, **{register: beyond})
        run(pcd, function)
        assert pcd.sim.read("axis.1.comers") == before + 1, register
