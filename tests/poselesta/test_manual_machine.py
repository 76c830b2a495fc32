"""Manual §2.3–§2.5 (the machine side: inputs, outputs, set-points) statement by statement, through
the control API of a served device on the virtual clock.  The inputs are seen as they are set
(config input_rise_ms / input_fall_ms 0): these tests are about what the control does with a
level; the input delay of §2.3 is in test_manual_inputs.py."""

from __future__ import annotations

from typing import Any

import pytest

NO_INPUT_DELAY = {"input_rise_ms": 0, "input_fall_ms": 0}


@pytest.fixture
def make(devsim_device):  # noqa: ANN001, ANN201
    def start(config: dict[str, Any] | None = None, program: str = "", mode: str = "AUTO_CONTINUOUS") -> Any:
        cnc = devsim_device("poselesta", {**NO_INPUT_DELAY, **(config or {})})
        cnc.advance(0.1)
        if program:
            cnc.set("program.P20", program)
            cnc.set("panel.program", 20)
        cnc.set("panel.mode", mode)
        cnc.advance(0.1)
        return cnc

    return start


def bus_codes(cnc: Any, until_s: float, step_s: float = 0.005) -> list[int]:
    """The codes on the data bus while a strobe is H, in order, over ``until_s`` seconds."""
    codes: list[int] = []
    strobes = ("strobe_m", "strobe_s1", "strobe_s2", "strobe_t")
    was = False
    for _ in range(round(until_s / step_s)):
        cnc.advance(step_s)
        now = any(cnc.read(f"output.{s}") for s in strobes)
        if now and not was:
            codes.append(cnc.read("output.data_bus"))
        was = now
    return codes


def strobe_rises(cnc: Any, until_s: float, step_s: float = 0.005) -> list[tuple[int, float]]:
    """(bus code, X position) each time the M strobe rises, over ``until_s`` seconds."""
    seen: list[tuple[int, float]] = []
    was = False
    for _ in range(round(until_s / step_s)):
        cnc.advance(step_s)
        now = cnc.read("output.strobe_m")
        if now and not was:
            seen.append((cnc.read("output.data_bus"), cnc.read("axis.x.position")))
        was = now
    return seen


# -- §2.3.1 NC-Stop, §2.3.3 NC-Start ----------------------------------------------------------------
@pytest.mark.manual("§2.3.1", "NC-Stop ist im Handbetrieb unwirksam")
def test_nc_stop_has_no_effect_in_manual(make) -> None:  # noqa: ANN001
    cnc = make(mode="MANUAL")
    cnc.set("input.nc_stop", False)
    cnc.set("input.jog_pos_x", True)
    cnc.advance(0.5)
    assert cnc.read("axis.x.velocity") > 0


@pytest.mark.manual("§2.3.1", "Ein NC-Stop bewirkt einen Halt der Achsbewegungen entlang der Bremsrampe. NC-Stop ist "
                    "im Handbetrieb unwirksam (so in Programmierung/Playback it stops the direction keys)")
def test_nc_stop_brakes_a_direction_key_in_program_entry(make) -> None:  # noqa: ANN001
    full = 2000 / 60 * 1000  # P48 at 100 % feed pot
    cnc = make(mode="PROGRAM_ENTRY")
    cnc.set("input.jog_pos_x", True)
    cnc.advance(0.5)
    assert cnc.read("axis.x.velocity") == pytest.approx(full)
    cnc.set("input.nc_stop", False)
    cnc.advance(0.02)
    assert 0 < cnc.read("axis.x.velocity") < full  # along the braking ramp
    cnc.advance(0.5)
    assert cnc.read("axis.x.velocity") == 0 and cnc.read("output.travel_x") is False
    held = cnc.read("axis.x.position")
    cnc.set("input.jog_pos_x", False)
    cnc.set("input.jog_pos_x", True)  # pressed again while NC-Stop is effective
    cnc.advance(0.5)
    assert cnc.read("axis.x.position") == held
    cnc.set("input.nc_stop", True)
    cnc.set("input.jog_pos_x", False)
    cnc.set("input.jog_pos_x", True)
    cnc.advance(0.5)
    assert cnc.read("axis.x.velocity") == pytest.approx(full)


@pytest.mark.manual("§2.3.1", "Falls ein NC-Stop während der Uebergabe der M-, S- oder T-Funktionen erfolgt, bleibt "
                    "dieser unwirksam, d. h. die Funktionen werden weiter ausgegeben. Der NC-Stop wird jedoch intern "
                    "abgespeichert, so dass eine nächste Achsbewegung erst nach erneutem NC-Start ausgeführt wird")
def test_nc_stop_during_the_functions_lets_them_out_and_holds_the_motion(make) -> None:  # noqa: ANN001
    cnc = make(program="N1 M03 S1250 T07 X10")
    cnc.set("panel.nc_start", True)
    cnc.advance(0.01)
    cnc.set("input.nc_stop", False)
    cnc.advance(0.01)
    cnc.set("input.nc_stop", True)  # a short press during the output of M03
    assert bus_codes(cnc, 0.3) == [0x03, 0x50, 0x12, 0x07]  # (strobe M seen from 20 ms on)
    cnc.advance(1.0)
    assert cnc.read("axis.x.position") == 0 and cnc.read("output.travel_x") is True
    cnc.set("panel.nc_start", True)
    cnc.advance(2.0)
    assert cnc.read("axis.x.position") == pytest.approx(10_000)


@pytest.mark.manual("§2.3.3", "Über den Parameter P 75 kann vorgewählt werden, ob die Steuerung den NC-Start-Impuls "
                    "von der Steuerungsfrontplatte, von einem externen Taster oder von beiden akzeptieren soll")
@pytest.mark.parametrize(("p75", "panel", "external"), [(0, True, True), (1, True, False), (2, False, True)])
def test_p75_selects_where_nc_start_comes_from(make, p75: int, panel: bool, external: bool) -> None:  # noqa: ANN001
    for source, counts in (("panel", panel), ("external", external)):
        cnc = make({"params": {75: p75}}, program="N1 X10")
        if source == "panel":
            cnc.set("panel.nc_start", True)
        else:
            cnc.set("input.nc_start", True)
        cnc.advance(0.5)
        assert (cnc.read("program.state") != "IDLE") is counts, source


@pytest.mark.manual("§2.3.3", "In den Betriebsarten Automatik-Folgesatz, Automatik-Einzelsatz und Hand-Einzelsatz wird "
                    "damit das Programm gestartet (and in no other)")
@pytest.mark.parametrize(("mode", "starts"), [("AUTO_CONTINUOUS", True), ("AUTO_SINGLE_BLOCK", True),
                                              ("MANUAL_SINGLE_BLOCK", True), ("MANUAL", False),
                                              ("PROGRAM_ENTRY", False), ("EXTERNAL_OPERATION", False)])
def test_nc_start_starts_a_program_in_the_program_modes_only(make, mode: str, starts: bool) -> None:  # noqa: ANN001
    cnc = make(program="N1 G01 X10 F3000", mode=mode)
    if mode == "MANUAL_SINGLE_BLOCK":
        cnc.set("panel.mdi", "N1 G01 X10 F3000")
    cnc.set("input.nc_start", True)
    cnc.advance(1.0)
    assert (cnc.read("axis.x.position") == pytest.approx(10_000)) is starts


# -- §2.3.6–§2.3.9 manual motion ----------------------------------------------------------------------
@pytest.mark.manual("§2.3.6", "Es kann jederzeit eine zweite Richtungstaste gedrückt werden. Beide Achsen werden "
                    "entlang einer eigenen Anfahrrampe gestartet")
def test_two_direction_keys_move_two_axes(make) -> None:  # noqa: ANN001
    cnc = make(mode="MANUAL")
    cnc.set("input.jog_pos_x", True)
    cnc.advance(0.3)
    cnc.set("input.jog_neg_y", True)
    cnc.advance(0.01)
    assert 0 > cnc.read("axis.y.velocity") > -cnc.read("axis.x.velocity")  # y on its own ramp
    cnc.advance(0.5)
    assert cnc.read("axis.x.velocity") > 0 and cnc.read("axis.y.velocity") == -cnc.read("axis.x.velocity")


@pytest.mark.manual("§2.3.6", "Die Richtungstasten sind in den Betriebsarten Handbetrieb und Programmierung wirksam")
@pytest.mark.parametrize(("mode", "moves"), [("MANUAL", True), ("PROGRAM_ENTRY", True), ("AUTO_CONTINUOUS", False),
                                             ("EXTERNAL_OPERATION", False), ("AUTO_SINGLE_BLOCK", False),
                                             ("MANUAL_SINGLE_BLOCK", False), ("EXTERNAL_MEDIUM", False)])
def test_direction_keys_act_in_manual_and_program_entry_only(make, mode: str, moves: bool) -> None:  # noqa: ANN001
    cnc = make(mode=mode)
    cnc.set("input.jog_pos_x", True)
    cnc.advance(0.5)
    assert (cnc.read("axis.x.velocity") > 0) is moves


@pytest.mark.manual("§2.4.2", "Nach Ausgabe der Fahrbefehle wartet die Steuerung die Achsfreigabe ab, bevor in den "
                    "Achsen verfahren wird (a direction key in Handbetrieb and Programmierung as well)")
@pytest.mark.manual("§2.3.15", "Bei L-Level wird der Vorschub nicht freigegeben; die Steuerung ist in Wartestellung. "
                    "Steht die Achsfreigabe auf H-Level, wird der Vorschub derjenigen Achsen freigegeben, deren "
                    "Fahrbefehle anstehen")
@pytest.mark.manual("§2.3.15", "Nach Freigabe der Vorschübe ist es nicht mehr möglich, durch Aenderung der "
                    "Achsfreigabe von H-Level auf L-Level die Bewegung zu stoppen")
@pytest.mark.manual("§2.4.6", "Durch die nächste Achsfreigabe wird der Ausgang (Maschinenstillstand) wieder auf "
                    "L-Level gesetzt")
@pytest.mark.parametrize("mode", ["MANUAL", "PROGRAM_ENTRY"])
def test_a_direction_key_waits_for_the_axis_enable(make, mode: str) -> None:  # noqa: ANN001
    cnc = make(mode=mode)
    cnc.set("input.axis_enable", False)
    cnc.set("input.jog_pos_x", True)
    cnc.advance(0.5)
    assert cnc.read("output.travel_x") is True and cnc.read("axis.x.position") == 0
    assert cnc.read("output.machine_standstill") is True
    cnc.set("input.axis_enable", True)
    assert cnc.read("output.machine_standstill") is False
    cnc.advance(0.5)
    assert cnc.read("axis.x.velocity") == pytest.approx(2000 / 60 * 1000)  # P48 along the ramp
    cnc.set("input.axis_enable", False)  # released: L no longer stops it
    cnc.advance(0.5)
    assert cnc.read("axis.x.velocity") == pytest.approx(2000 / 60 * 1000)


@pytest.mark.manual("§2.3.15", "Bei L-Level wird der Vorschub nicht freigegeben; die Steuerung ist in Wartestellung "
                    "(die Wartestellung kann durch Not-Stop abgebrochen werden)")
def test_a_jog_step_waits_for_the_axis_enable_and_not_stop_ends_the_wait(make) -> None:  # noqa: ANN001
    cnc = make(mode="MANUAL")
    cnc.set("input.axis_enable", False)
    cnc.set("input.jog_pos_y", True)
    cnc.set("input.jog_pos_y", False)  # a key let go before the feed is released: nothing to wait for
    assert cnc.read("output.travel_y") is False
    cnc.set("input.jog_step_100", True)
    cnc.set("input.jog_pos_x", True)
    cnc.set("input.jog_pos_x", False)
    cnc.advance(0.5)
    assert cnc.read("output.travel_x") is True and cnc.read("axis.x.position") == 0
    cnc.set("input.axis_enable", True)
    cnc.advance(0.5)
    assert cnc.read("axis.x.position") == pytest.approx(100) and cnc.read("output.travel_x") is False
    assert cnc.read("axis.y.position") == 0
    cnc.set("input.axis_enable", False)
    cnc.set("input.jog_neg_x", True)
    assert cnc.read("output.travel_x") is True
    cnc.set("input.emergency_stop", False)  # ends the wait
    assert cnc.read("output.travel_x") is False
    cnc.set("input.emergency_stop", True)
    cnc.set("input.jog_neg_x", False)
    cnc.set("input.axis_enable", True)
    cnc.advance(0.5)
    assert cnc.read("axis.x.position") == pytest.approx(100)


@pytest.mark.manual("§2.3.8", "Der Eilgang wirkt nur bei gleichzeitiger Betätigung mit den Richtungstasten")
@pytest.mark.manual("§2.3.8", "Die Eilgangaufschaltung erfolgt nicht schlagartig, sondern entlang der Anfahrrampe")
def test_rapid_acts_with_a_direction_key_along_the_ramp(make) -> None:  # noqa: ANN001
    cnc = make(mode="MANUAL")
    cnc.set("input.rapid", True)
    cnc.advance(0.5)
    assert cnc.read("axis.x.velocity") == 0
    cnc.set("input.rapid", False)
    cnc.set("input.jog_pos_x", True)
    cnc.advance(0.5)
    feed = cnc.read("axis.x.velocity")
    cnc.set("input.rapid", True)
    cnc.advance(0.01)
    assert feed < cnc.read("axis.x.velocity") < 100_000  # on its way to P44 along the ramp
    cnc.advance(0.5)
    assert cnc.read("axis.x.velocity") == pytest.approx(100_000)


@pytest.mark.manual("§2.3.7", "Jogging: Eine Ueberlagerung mit der Eilgang-Funktion ist nicht möglich")
@pytest.mark.manual("§2.3.7", "Die Verfahrgeschwindigkeit wird am Vorschubpotentiometer eingestellt")
def test_a_jog_step_runs_at_the_feed_pot_even_with_rapid(make) -> None:  # noqa: ANN001
    cnc = make(mode="MANUAL")
    cnc.set("input.feed_pot_v", 5.0)
    cnc.set("input.jog_step_10000", True)
    cnc.set("input.rapid", True)
    cnc.set("input.jog_pos_x", True)
    cnc.set("input.jog_pos_x", False)
    cnc.advance(0.3)
    assert cnc.read("axis.x.velocity") == pytest.approx(1000 / 60 * 1000)  # 50 % of P48, not P44
    cnc.advance(2.0)
    assert cnc.read("axis.x.position") == pytest.approx(10_000)


@pytest.mark.manual("§2.3.22", "Vorschubpotentiometer: aktiv in den Betriebsarten Handbetrieb und Programmierung; "
                    "Override-Potentiometer: aktiv in den Betriebsarten Automatik und Hand-Einzelsatz")
def test_the_feed_pot_acts_on_manual_motion_only_and_the_override_on_programs_only(make) -> None:  # noqa: ANN001
    cnc = make(mode="MANUAL")
    cnc.set("input.override_pot_v", 3.333)  # 50 %
    cnc.set("input.jog_pos_x", True)
    cnc.advance(0.5)
    assert cnc.read("axis.x.velocity") == pytest.approx(2000 / 60 * 1000)  # P48 at 100 % feed pot
    cnc.set("input.jog_pos_x", False)
    cnc.advance(0.5)
    cnc.set("input.override_pot_v", 6.667)
    cnc.set("input.feed_pot_v", 5.0)
    cnc.set("program.P20", "N1 G01 X100 F1200")
    cnc.set("panel.program", 20)
    cnc.set("panel.mode", "AUTO_CONTINUOUS")
    cnc.set("panel.nc_start", True)
    cnc.advance(0.5)
    assert cnc.read("axis.x.velocity") == pytest.approx(20_000, rel=1e-3)  # F1200 whatever the feed pot


@pytest.mark.manual("§2.3.22", "Es besteht die Möglichkeit, den Eilgang ebenfalls mit dem Override-Potentiometer zu "
                    "beeinflussen, siehe Maschinenparameter P 64")
@pytest.mark.parametrize(("p64", "speed"), [(0, 100_000), (1, 50_000)])
def test_p64_lets_the_override_act_on_rapid(make, p64: int, speed: float) -> None:  # noqa: ANN001
    cnc = make({"params": {64: p64}}, program="N1 G00 X200")
    cnc.set("input.override_pot_v", 3.3335)  # 50 %
    cnc.set("panel.nc_start", True)
    cnc.advance(0.6)
    assert cnc.read("axis.x.velocity") == pytest.approx(speed, rel=1e-3)


@pytest.mark.manual("§2.3.9", "Der Open-loop-Betrieb darf nur bei Stillstand ein- oder ausgeschaltet werden")
def test_open_loop_is_not_taken_while_an_axis_moves(make) -> None:  # noqa: ANN001
    """Spec §5.4: a change while not at standstill "is ignored until standstill": once the key is
    let go and X stands, open loop takes effect; switched off during the push, it ends after it."""
    cnc = make({"params": {77: 1}}, mode="MANUAL")
    cnc.set("input.jog_pos_x", True)
    cnc.advance(0.5)
    cnc.set("input.open_loop", True)
    cnc.advance(0.1)
    assert cnc.read("axis.x.following_error") > 0  # still closed loop
    with pytest.raises(ValueError, match="not in open loop"):
        cnc.set("axis.x.push", 1.0)
    cnc.set("input.jog_pos_x", False)
    cnc.advance(1.0)
    assert cnc.read("output.machine_standstill") is True
    cnc.set("axis.x.push", 1.0)  # open loop now
    cnc.advance(0.05)
    assert cnc.read("axis.x.following_error") == 0 and cnc.read("output.travel_x") is True
    cnc.set("input.open_loop", False)  # during the push: deferred again
    cnc.advance(0.05)
    assert cnc.read("axis.x.following_error") == 0
    cnc.advance(0.5)
    assert cnc.read("output.travel_x") is False
    with pytest.raises(ValueError, match="not in open loop"):
        cnc.set("axis.x.push", 1.0)


@pytest.mark.manual("§2.3.7", "Nach einem ausgeführten Jogging-Schritt wird in einer Achse erst weiterverfahren, wenn "
                    "der nächste Impuls erfolgt")
@pytest.mark.manual("§2.3.7", "Die Anfahr- und Bremsrampen werden ausgeführt")
def test_a_jog_step_waits_for_the_next_press_and_runs_its_ramps(make) -> None:  # noqa: ANN001
    cnc = make(mode="MANUAL")
    cnc.set("input.jog_step_10000", True)
    cnc.set("input.jog_pos_x", True)  # and held
    cnc.advance(0.02)
    assert 0 < cnc.read("axis.x.velocity") < 2000 / 60 * 1000  # on its way to P48 along the ramp
    cnc.advance(3.0)
    assert cnc.read("axis.x.position") == pytest.approx(10_000) and cnc.read("axis.x.velocity") == 0
    cnc.advance(1.0)
    assert cnc.read("axis.x.position") == pytest.approx(10_000)  # held: still one step
    cnc.set("input.jog_pos_x", False)
    cnc.set("input.jog_pos_x", True)
    cnc.advance(3.0)
    assert cnc.read("axis.x.position") == pytest.approx(20_000)


@pytest.mark.manual("§2.3.6", "Die Verfahrgeschwindigkeit der einzelnen Achsen ist von der Stellung des "
                    "Vorschubpotentiometers und des pro Achse programmierten Vorschubs (P 44 - 51) abhängig")
def test_each_axis_jogs_at_its_own_parameters(make) -> None:  # noqa: ANN001
    cnc = make({"params": {48: 1200, 49: 600, 44: 6000, 45: 3000}}, mode="MANUAL")
    cnc.set("input.feed_pot_v", 5.0)
    cnc.set("input.jog_pos_x", True)
    cnc.set("input.jog_pos_y", True)
    cnc.advance(1.0)
    assert cnc.read("axis.x.velocity") == pytest.approx(10_000)  # 50 % of 1200 mm/min
    assert cnc.read("axis.y.velocity") == pytest.approx(5_000)  # 50 % of 600 mm/min
    cnc.set("input.rapid", True)
    cnc.advance(1.0)
    assert cnc.read("axis.x.velocity") == pytest.approx(100_000) and cnc.read("axis.y.velocity") == pytest.approx(50_000)


@pytest.mark.manual("§2.2.3", "Steht der Maschinenparameter P 76 auf 1 (Einflanken-Auswertung), ist ein Rasterschritt "
                    "so gross wie die gewählte Auflösung. Steht er auf 2, ist ein Rasterschritt doppelt so gross")
@pytest.mark.parametrize(("p76", "increments"), [(1, 1), (2, 2), (4, 4)])
def test_a_handwheel_detent_is_p76_increments(make, p76: int, increments: int) -> None:  # noqa: ANN001
    cnc = make({"params": {76: p76}}, mode="MANUAL")
    cnc.set("handwheel.factor", 1)
    cnc.set("input.handwheel_x", True)
    cnc.set("handwheel.turn", 25)
    cnc.advance(5.0)
    assert cnc.read("axis.x.position") == pytest.approx(25 * increments)


@pytest.mark.manual("§2.3.22", "Override-Potentiometer: Aktiv in den Betriebsarten Automatik-Folgesatz, "
                    "- Einzelsatz und Hand-Einzelsatz")
@pytest.mark.parametrize("mode", ["AUTO_CONTINUOUS", "AUTO_SINGLE_BLOCK", "MANUAL_SINGLE_BLOCK"])
def test_the_override_acts_in_every_program_mode(make, mode: str) -> None:  # noqa: ANN001
    cnc = make(program="N1 G01 X100 F1200", mode=mode)
    if mode == "MANUAL_SINGLE_BLOCK":
        cnc.set("panel.mdi", "N1 G01 X100 F1200")
    cnc.set("input.override_pot_v", 10.0 / 3)  # 50 %
    cnc.set("input.feed_pot_v", 2.0)
    cnc.set("panel.nc_start", True)
    cnc.advance(0.5)
    assert cnc.read("axis.x.velocity") == pytest.approx(10_000, rel=1e-3)


# -- §2.3.12 M01 -------------------------------------------------------------------------------------
@pytest.mark.manual("§2.3", "V 21/10: M 01 wahlweisen Halt aktivieren")
@pytest.mark.parametrize(("invert", "optional_stop", "stops"), [
    (False, True, True), (False, False, False),
    (True, True, False), (True, False, True),  # invert_optional_stop (spec G-M01): L stops
])
def test_m01_stops_only_while_v21_10_is_high(make, invert: bool, optional_stop: bool, stops: bool) -> None:  # noqa: ANN001
    cnc = make({"invert_optional_stop": True} if invert else None, program="N1 X1 M01\nN2 X2")
    cnc.set("input.optional_stop", optional_stop)
    cnc.set("panel.nc_start", True)
    cnc.advance(2.0)
    assert (cnc.read("axis.x.position") == pytest.approx(1_000)) is stops
    assert (cnc.read("program.state") == "STOPPED") is stops


# §2.3.2
# -- §2.3.15, §2.3.16 the waits of a block, §2.3.25 the input page -------------------------------------
@pytest.mark.manual("§2.3.15", "Bei L-Level wird der Vorschub nicht freigegeben; die Steuerung ist in Wartestellung "
                    "(die Wartestellung kann durch Not-Stop abgebrochen werden)")
def test_not_stop_ends_the_wait_for_the_axis_enable(make) -> None:  # noqa: ANN001
    cnc = make(program="N1 X10\nN2 X20")
    cnc.set("input.axis_enable", False)
    cnc.set("panel.nc_start", True)
    cnc.advance(0.3)
    assert cnc.read("program.state") == "WAIT_AXIS_ENABLE" and cnc.read("output.travel_x") is True
    cnc.set("input.emergency_stop", False)
    assert cnc.read("program.state") == "IDLE" and cnc.read("output.travel_x") is False
    cnc.set("input.emergency_stop", True)
    cnc.set("input.axis_enable", True)  # the wait is over: the enable now releases nothing
    cnc.advance(1.0)
    assert cnc.read("panel.mode") == "MANUAL" and cnc.read("axis.x.position") == 0


@pytest.mark.manual("§2.3.16", "Anschliessend wird der Eingang Programm fortsetzen abgefragt. Steht dieser auf H-Level, "
                    "wird die nächste Funktion im zu bearbeitenden Satz oder der nächste Satz ausgeführt")
def test_the_block_end_functions_wait_for_program_continue(make) -> None:  # noqa: ANN001
    cnc = make(program="N1 X1 M05\nN2 X2")
    cnc.set("input.program_continue", False)
    cnc.set("panel.nc_start", True)
    cnc.advance(1.0)
    assert cnc.read("output.position_reached") is True and cnc.read("program.state") == "WAIT_PROGRAM_CONTINUE"
    assert strobe_rises(cnc, 0.5) == []  # M05 waits as well
    cnc.set("input.program_continue", True)
    assert strobe_rises(cnc, 0.1) == [(0x05, pytest.approx(1_000))]
    cnc.advance(1.0)
    assert cnc.read("axis.x.position") == pytest.approx(2_000)


#: §2.3.25: port and half → the terminal of bit 7 … bit 0 (None: "nicht verwendet" / "leer").
INPUT_PAGE = {
    "1A": ("open_loop", "key_switch", "keyboard_external", "optional_stop", "xy_plotter", "program_lock_open",
           "block_abort", None),
    "1B": ("jog_step_10000", "jog_step_1000", "jog_step_100", "jog_step_10", "jog_step_1", "m10_ack", "rapid",
           "mst_ack"),
    "2A": ("limit_pos_d", "limit_pos_z", "limit_pos_y", "limit_pos_x", "limit_neg_d", "limit_neg_z", "limit_neg_y",
           "limit_neg_x"),
    "2B": ("jog_pos_d", "jog_pos_z", "jog_pos_y", "jog_pos_x", "jog_neg_d", "jog_neg_z", "jog_neg_y", "jog_neg_x"),
    "3A": (None, None, None, None, "handwheel_d", "handwheel_z", "handwheel_y", "handwheel_x"),
    "4A": ("tool_change_ack", "program_continue", "axis_enable", "inch", None, "block_skip_cancel", None, None),
    "4B": (None, None, "nc_start", "emergency_stop", "nc_stop", None, None, None),
}


@pytest.mark.manual("§2.3.25", "Bildschirm/Klemme/Belegung: the table of ports 1 … 4, A and B, bit 7 … 0")
def test_each_input_shows_on_its_own_bit_of_the_input_page(make) -> None:  # noqa: ANN001
    cnc = make({"plc": {"mst_ack": "manual"}}, mode="PROGRAM_ENTRY")
    cnc.set("panel.diagnostic", 5)
    for port, names in INPUT_PAGE.items():
        for bit, name in zip(range(7, -1, -1), names, strict=True):
            if name is None:
                continue
            if cnc.read("panel.mode") != "PROGRAM_ENTRY":  # Not-Stop's release switched to MANUAL
                cnc.set("panel.mode", "PROGRAM_ENTRY")
                cnc.set("panel.diagnostic", 5)
            before = cnc.read("diagnostics.inputs")
            level = cnc.read(f"input.{name}")
            cnc.set(f"input.{name}", not level)
            after = cnc.read("diagnostics.inputs")
            cnc.set(f"input.{name}", level)
            changed = {p: before[p] ^ after[p] for p in before if before[p] != after[p]}
            assert changed == {port: 1 << bit}, name


# -- §2.4 outputs --------------------------------------------------------------------------------------
@pytest.mark.manual("§2.4.1", "Die Betriebsarten werden über den Data-Bus ausgegeben: Handbetrieb 08, Externer Betrieb "
                    "0A, Externer Datenträger 0B, Programm-Eingabe 09, Hand-Einzelsatz 0E, Automatik-Einzelsatz 0D, "
                    "Automatik-Folgesatz 0C (10⁰: 1 2 4 8)")
@pytest.mark.manual("§2.4.1", "Bit 8, 10⁰ dient als Uebertragungsabsicherung")
@pytest.mark.manual("§2.4.1", "nur Hand-Einzelsatz, Automatik-Einzelsatz und Automatik-Folgesatz erkannt werden müssen, "
                    "kann dies mit Bit 4, 10⁰ erfolgen")
@pytest.mark.parametrize(("mode", "code"), [("MANUAL", 0b1000), ("EXTERNAL_OPERATION", 0b1010),
                                            ("EXTERNAL_MEDIUM", 0b1011), ("PROGRAM_ENTRY", 0b1001),
                                            ("MANUAL_SINGLE_BLOCK", 0b1110), ("AUTO_SINGLE_BLOCK", 0b1101),
                                            ("AUTO_CONTINUOUS", 0b1100)])
def test_each_mode_goes_out_with_its_code_and_the_ba_strobe(make, mode: str, code: int) -> None:  # noqa: ANN001
    cnc = make(mode="AUTO_CONTINUOUS" if mode == "MANUAL" else "MANUAL")
    cnc.set("panel.mode", mode)
    assert cnc.read("output.data_bus") == code
    assert bool(code & 0x04) is (mode in ("MANUAL_SINGLE_BLOCK", "AUTO_SINGLE_BLOCK", "AUTO_CONTINUOUS"))
    cnc.advance(0.03)
    assert cnc.read("output.strobe_ba") is True and cnc.read("output.data_bus") == code


@pytest.mark.manual("§2.4.2", "Ausser im Handbetrieb werden die beiden Fahrbefehle der gewählten Interpolationsebene "
                    "bereits am Anfang ausgegeben, obwohl die erste Bahnbewegung nur in einer Achse erfolgt")
@pytest.mark.manual("§2.4.2", "In den Betriebsarten Handbetrieb und Programmierung werden die Fahrbefehle nur für die "
                    "zu verfahrende(n) Achse(n) ausgegeben")
def test_travel_commands_of_the_plane_in_a_program_of_the_axis_by_hand(make) -> None:  # noqa: ANN001
    cnc = make(program="N1 G01 X10 F3000\nN2 Y10")
    cnc.set("panel.nc_start", True)
    cnc.advance(0.1)
    assert cnc.read("output.travel_x") is True and cnc.read("output.travel_y") is True
    cnc.advance(2.0)
    cnc.set("panel.mode", "MANUAL")
    cnc.set("input.jog_pos_x", True)
    cnc.advance(0.1)
    assert cnc.read("output.travel_x") is True and cnc.read("output.travel_y") is False


@pytest.mark.manual("§2.4.2", "Ausser im Handbetrieb werden die beiden Fahrbefehle der gewählten Interpolationsebene "
                    "bereits am Anfang ausgegeben, obwohl die erste Bahnbewegung gegebenenfalls nur in einer Achse "
                    "(achsparallel) erfolgt")
@pytest.mark.parametrize(("plane", "word", "expected"), [(17, "X10", "xy"), (18, "X10", "xz"), (18, "Z10", "xz"),
                                                         (19, "Y10", "yz")])
def test_the_travel_commands_of_the_chosen_plane_go_out_at_the_start(make, plane: int, word: str,
                                                                     expected: str) -> None:  # noqa: ANN001
    """A G01 block moving one axis of the plane G17 (XY), G18 (XZ) or G19 (YZ): the travel commands
    of both axes of that plane, and of no other axis."""
    cnc = make(program=f"N1 G{plane} G01 {word} F3000")
    cnc.set("panel.nc_start", True)
    cnc.advance(0.1)
    assert cnc.read("program.state") == "MOVING"
    assert {a for a in "xyzd" if cnc.read(f"output.travel_{a}")} == set(expected)


@pytest.mark.manual("§2.4.3", "Das Signal wird auch dann ausgegeben, wenn der nächste zu verfahrende Weg so klein oder "
                    "Null ist, dass das Zielfenster nicht verlassen wird")
@pytest.mark.manual("§2.4.6", "Im Automatikbetrieb wird der Ausgang (Maschinenstillstand) gleichzeitig mit Position "
                    "erreicht gesetzt")
def test_a_block_without_travel_still_reaches_its_position(make) -> None:  # noqa: ANN001
    cnc = make(program="N1 G00 X0\nN2 X1")
    cnc.set("input.program_continue", False)
    cnc.set("panel.nc_start", True)
    cnc.advance(0.2)
    assert cnc.read("program.state") == "WAIT_PROGRAM_CONTINUE" and cnc.read("program.block") == 1
    assert cnc.read("output.position_reached") is True and cnc.read("output.machine_standstill") is True


@pytest.mark.manual("§2.4.6", "Durch die nächste Achsfreigabe wird der Ausgang (Maschinenstillstand) wieder auf L-Level "
                    "gesetzt")
def test_the_next_axis_enable_drops_machine_standstill(make) -> None:  # noqa: ANN001
    cnc = make(program="N1 G00 X10")
    cnc.set("input.axis_enable", False)
    cnc.set("panel.nc_start", True)
    cnc.advance(0.2)
    assert cnc.read("output.travel_x") is True and cnc.read("output.machine_standstill") is True
    cnc.set("input.axis_enable", True)
    cnc.advance(0.01)
    assert cnc.read("output.machine_standstill") is False


@pytest.mark.manual("§2.3.15", "Nach Freigabe der Vorschübe ist es nicht mehr möglich, durch Aenderung der Achsfreigabe "
                    "von H-Level auf L-Level die Bewegung zu stoppen")
@pytest.mark.manual("§2.3.15", "Beim Bahnfahren mit G 01, G 02 und G 03 … wird die Achsfreigabe ignoriert")
def test_the_axis_enable_does_not_stop_a_released_motion_or_a_contour(make) -> None:  # noqa: ANN001
    cnc = make(program="N1 G01 X10 F3000\nN2 X20")
    cnc.set("panel.nc_start", True)
    cnc.advance(0.1)
    cnc.set("input.axis_enable", False)
    cnc.advance(1.0)
    assert cnc.read("program.state") != "WAIT_AXIS_ENABLE"
    assert cnc.read("axis.x.position") == pytest.approx(20_000)


@pytest.mark.manual("§2.4.7", "Die Rückstellung der selbsthaltenden M-Funktionen erfolgt durch eine löschende Funktion "
                    "(Beispiel M 03 / M 05)")
@pytest.mark.manual("§2.4.7", "M 10 ist selbsthaltend, wenn zur Ausgabezeit die M 10-Quittierung auf L-Level steht. "
                    "Rückstellen durch M 11")
def test_self_holding_m_functions_end_with_their_cancelling_function(make) -> None:  # noqa: ANN001
    cnc = make(program="N1 M03 M10\nN2 X1\nN3 M05 M11")
    cnc.set("panel.nc_start", True)
    cnc.run_until(lambda d: d.model.executor.block_number == 2, 5.0)
    assert cnc.read("output.m03") is True and cnc.read("output.m10") is True
    cnc.advance(3.0)
    assert cnc.read("program.state") == "END"
    assert cnc.read("output.m03") is False and cnc.read("output.m10") is False


@pytest.mark.manual("§2.4.8", "Wenn zwei M-Funktionen in einem Satz stehen, wird die Ausgabereihenfolge durch den "
                    "aufsteigenden M-Code definiert")
@pytest.mark.manual("§2.4.8", "M 00, M 01, M 02, M 05, M 09, M 11 … werden am Satzende ausgeführt, dafür werden die "
                    "Funktionen M 00, M 01, M 02 immer zuletzt (z. B. nach M 05) ausgeführt")
def test_m_functions_go_out_in_the_manuals_order(make) -> None:  # noqa: ANN001
    cnc = make(program="N1 M08 M03 X1\nN2 M02 M05 Y1")
    cnc.set("panel.nc_start", True)
    first = bus_codes(cnc, 0.2)
    assert first[:2] == [0x03, 0x08]
    cnc.run_until(lambda d: d.model.executor.block_number == 2, 5.0)
    cnc.run_until(lambda d: bool(d.model.signals.get("position_reached")), 5.0)
    assert bus_codes(cnc, 0.3) == [0x05, 0x02]


@pytest.mark.manual("§2.4.10", "Start/Stop-Status: Dieser Ausgang schaltet mit dem Start/Stop-Symbol auf dem Bildschirm "
                    "(H-Level: Symbol Start)")
def test_the_start_stop_status_is_high_while_the_program_runs(make) -> None:  # noqa: ANN001
    cnc = make(program="N1 G01 X50 F3000")
    assert cnc.read("output.start_stop_status") is False
    cnc.set("panel.nc_start", True)
    cnc.advance(0.3)
    assert cnc.read("output.start_stop_status") is True
    cnc.set("input.nc_stop", False)
    assert cnc.read("output.start_stop_status") is False


DECODED = (0, 1, 2, 3, 4, 6, 8, 10)


@pytest.mark.manual("§2.4.7", "Folgende 8 M-Funktionen werden zusätzlich dekodiert ausgegeben: M 00, M 01, M 02, M 03, "
                    "M 04, M 06, M 08, M 10 (V 15/1-8)")
@pytest.mark.parametrize("m", DECODED)
def test_each_decoded_m_function_sets_its_own_output(make, m: int) -> None:  # noqa: ANN001
    cnc = make(program=f"N1 M{m:02d} X1")
    cnc.set("input.optional_stop", True)
    cnc.set("panel.nc_start", True)
    seen: set[int] = set()
    for _ in range(100):
        cnc.advance(0.01)
        seen |= {n for n in DECODED if cnc.read(f"output.m{n:02d}")}
    assert seen == {m}


@pytest.mark.manual("§2.4.8", "M 00, M 01, M 02, M 05, M 09, M 11, M 15 sowie die ungeraden, frei programmierbaren "
                    "M-Funktionen werden am Satzende ausgeführt")
@pytest.mark.parametrize(("m", "at_end"), [(9, True), (11, True), (15, True), (21, True), (8, False), (20, False)])
def test_an_m_function_goes_out_at_the_start_or_the_end_of_its_block(make, m: int, at_end: bool) -> None:  # noqa: ANN001
    cnc = make(program=f"N1 M{m:02d} X1")
    cnc.set("panel.nc_start", True)
    code = m // 10 << 4 | m % 10
    assert strobe_rises(cnc, 1.0) == [(code, pytest.approx(1_000) if at_end else 0)]


@pytest.mark.manual("§2.4.4", "Wird das programmierte Arbeitsfeld verlassen, werden alle Achsen jeder Betriebsart "
                    "entlang der Bremsrampen, wie bei NC-Stop, abgebremst (a direction key in Handbetrieb)")
def test_a_direction_key_that_leaves_the_working_field_brakes_along_the_ramp(make) -> None:  # noqa: ANN001
    cnc = make({"axes": {"x": {"reference_marks": [-1.0]}}, "params": {9: 5}}, mode="MANUAL")
    cnc.set("panel.reference", "x")
    cnc.run_until(lambda d: "x" in d.model.field.referenced, 60.0)
    cnc.set("input.jog_pos_x", True)  # 2000 mm/min, 33.3 mm/s: 1.1 mm to brake at 500 mm/s²
    cnc.run_until(lambda d: not d.model.signals.get("inside_working_field"), 10.0)
    assert cnc.read("axis.x.position") == pytest.approx(5_000, abs=1)
    cnc.advance(0.02)
    assert 0 < cnc.read("axis.x.velocity") < 2000 / 60 * 1000  # braking, not stopped at once
    cnc.advance(1.0)
    assert cnc.read("axis.x.velocity") == 0
    assert cnc.read("axis.x.position") == pytest.approx(5_000 + 1_111, abs=2)
    assert cnc.read("output.inside_working_field") is False


@pytest.mark.manual("§2.4.6", "Ausnahme: Betriebsarten Handbetrieb und Programm-Eingabe bei Anwahl eines Handrades: "
                    "der Ausgang wird auf L-Level gesetzt, sobald eine Handradaktivierung erfolgt")
@pytest.mark.parametrize("mode", ["MANUAL", "PROGRAM_ENTRY"])
def test_a_handwheel_activation_drops_machine_standstill(make, mode: str) -> None:  # noqa: ANN001
    cnc = make(mode=mode)
    assert cnc.read("output.machine_standstill") is True
    cnc.set("input.handwheel_y", True)
    assert cnc.read("output.machine_standstill") is False and cnc.read("axis.y.velocity") == 0


# -- §2.5 set-points ---------------------------------------------------------------------------------------
@pytest.mark.manual("§2.5", "Je höher die Verstärkung, desto kleiner ist der Schleppfehler (P 30 - P 33 achsweise)")
@pytest.mark.manual("§2.5", "Analog Sollwert max. +/- 10 V")
def test_a_higher_gain_gives_a_smaller_following_error(make) -> None:  # noqa: ANN001
    errors = []
    for gain in (10, 20):
        cnc = make({"params": {30: gain}}, program="N1 G01 X-100 F3000")
        cnc.set("panel.nc_start", True)
        cnc.advance(0.5)
        errors.append(abs(cnc.read("axis.x.following_error")))
        assert -10.0 <= cnc.read("axis.x.analog_out") < 0
    assert errors[1] == pytest.approx(errors[0] / 2) and errors[1] > 0


@pytest.mark.manual("§2.4.2", "Position erreicht erscheint nur während ca. 60 us, falls Programm-Fortschaltung schon "
                    "anliegt")
def test_position_reached_is_a_60_us_pulse_when_program_continue_is_high(make) -> None:  # noqa: ANN001
    cnc = make(program="N1 G00 X1\nN2 G00 X2")
    cnc.set("panel.nc_start", True)
    cnc.run_until(lambda d: bool(d.model.signals.get("position_reached")), 5.0)
    assert cnc.read("output.position_reached") is True and cnc.read("program.block") == 1
    cnc.advance(70e-6)
    assert cnc.read("output.position_reached") is False


@pytest.mark.manual("§2.4.7", "In der Betriebsart Hand-Einzelsatz wirken alle dekodierten M-Funktionen satzweise")
def test_decoded_m_functions_act_block_by_block_in_manual_single_block(make) -> None:  # noqa: ANN001
    cnc = make(mode="MANUAL_SINGLE_BLOCK")
    cnc.set("panel.mdi", "N1 M03 G01 X10 F3000")
    cnc.set("panel.nc_start", True)
    cnc.advance(0.3)
    assert cnc.read("output.m03") is True and cnc.read("axis.x.velocity") > 0
    cnc.advance(2.0)
    assert cnc.read("axis.x.position") == pytest.approx(10_000)
    assert cnc.read("output.m03") is False  # the block is over: M03 was for this block only



def _program_end_in_the_block(cnc: Any) -> None:
    cnc.advance(3.0)  # M02 at the block end: the program end


def _mode_key_while_held(cnc: Any) -> None:
    cnc.set("input.nc_stop", False)  # HOLD, then the mode key gives the block up
    cnc.advance(0.5)
    assert cnc.read("program.state") == "HOLD" and cnc.read("output.m03") is True
    cnc.set("panel.mode", "MANUAL")


def _not_stop(cnc: Any) -> None:
    cnc.set("input.emergency_stop", False)
    cnc.advance(0.1)
    cnc.set("input.emergency_stop", True)


@pytest.mark.manual("§2.4.7", "In der Betriebsart Hand-Einzelsatz wirken alle dekodierten M-Funktionen satzweise")
@pytest.mark.parametrize(("mdi", "end"), [("N1 M03 M02 G01 X10 F3000", _program_end_in_the_block),
                                          ("N1 M03 M08 G01 X100 F1000", _mode_key_while_held),
                                          ("N1 M03 M08 G01 X100 F1000", _not_stop)])
def test_a_manual_single_block_ended_otherwise_ends_its_decoded_m_functions(make, mdi: str, end: Any) -> None:  # noqa: ANN001
    """The block is over also when it ends the program (M02) or is given up (a mode key in HOLD,
    Not-Stop): what it set on V15 was for this block only."""
    cnc = make(mode="MANUAL_SINGLE_BLOCK")
    cnc.set("panel.mdi", mdi)
    cnc.set("panel.nc_start", True)
    cnc.advance(0.3)
    assert cnc.read("output.m03") is True
    end(cnc)
    cnc.advance(0.1)
    assert cnc.read("program.state") in ("END", "IDLE")
    assert [cnc.read(f"output.m{m:02d}") for m in (0, 1, 2, 3, 4, 6, 8, 10)] == [False] * 8

@pytest.mark.manual("§2.3.17", "Damit eine Werkzeugwechsel-Quittierung akzeptiert werden kann, müssen zuvor alle im "
                    "gleichen Satz programmierten S- und T-Funktionen übernommen und quittiert sein")
def test_a_tool_change_acknowledge_before_s_and_t_are_taken_does_not_count(make) -> None:  # noqa: ANN001
    cnc = make(program="N1 M06 S100 T05 X1")
    cnc.set("panel.nc_start", True)
    cnc.advance(0.01)
    assert cnc.read("output.m06") is True and cnc.read("output.data_bus") == 0x06
    cnc.set("input.tool_change_ack", True)  # a pulse while M06 is still on the bus
    cnc.advance(0.05)
    cnc.set("input.tool_change_ack", False)
    cnc.advance(1.0)
    assert cnc.read("program.state") == "WAIT_TOOL_CHANGE" and cnc.read("output.m06") is True
    assert cnc.read("axis.x.position") == 0


@pytest.mark.manual("§2.3.17", "Die Werkzeugwechsel-Quittierung kann impulsförmig oder statisch erfolgen")
def test_a_static_tool_change_acknowledge_counts(make) -> None:  # noqa: ANN001
    cnc = make(program="N1 M06 T05 X1")
    cnc.set("panel.nc_start", True)
    cnc.run_until(lambda d: d.model.executor.state == "WAIT_TOOL_CHANGE", 2.0)
    cnc.set("input.tool_change_ack", True)  # and left H
    cnc.advance(1.0)
    assert cnc.read("output.m06") is False and cnc.read("axis.x.position") == pytest.approx(1_000)


@pytest.mark.manual("§2.4.10", "Start/Stop-Status (nur POS III)")
@pytest.mark.manual("§2.3.21", "Programmverriegelung (nur POS III); Satzabbruch (nur POS III)")
def test_a_pos_ii_has_no_start_stop_status_program_lock_or_block_abort(make) -> None:  # noqa: ANN001
    cnc = make({"variant": "II"}, program="N1 G01 X50 F3000\nN2 Y1")
    cnc.set("param.P90", 2)
    cnc.set("panel.nc_start", True)
    cnc.advance(0.3)
    assert cnc.read("program.state") == "MOVING" and cnc.read("output.start_stop_status") is False
    cnc.set("input.block_abort", False)
    cnc.advance(0.3)
    assert cnc.read("program.block") == 1 and cnc.read("axis.x.velocity") > 0  # no block abort
    with pytest.raises(ValueError, match="POS III"):
        cnc.set("panel.protect", 20)


@pytest.mark.manual("§2.4.1", "Beispiel: Code 37: Data-Bits 01, 02, 04, 10, 20 sind auf H-Level")
def test_code_37_sets_the_data_bits_of_the_manuals_example(make) -> None:  # noqa: ANN001
    cnc = make(program="N1 M37")
    cnc.set("panel.nc_start", True)
    assert bus_codes(cnc, 0.3) == [0x01 | 0x02 | 0x04 | 0x10 | 0x20]


@pytest.mark.manual("§3.4", "Handradverfahren: Es können mehrere Handradaktivierungen gleichzeitig wirksam sein")
@pytest.mark.manual("§3.4", "Handradverfahren direkt, Faktor 1: bei jedem Handradschritt wird 1 Schritt generiert. "
                    "1 Schritt = Auflösung")
def test_several_handwheel_activations_move_their_axes_together(make) -> None:  # noqa: ANN001
    cnc = make(mode="MANUAL")
    cnc.set("handwheel.factor", 1)
    cnc.set("input.handwheel_x", True)
    cnc.set("input.handwheel_z", True)
    cnc.set("handwheel.turn", 7)
    cnc.advance(2.0)
    assert cnc.read("axis.x.position") == pytest.approx(7) and cnc.read("axis.z.position") == pytest.approx(7)
    assert cnc.read("axis.y.position") == 0


@pytest.mark.manual("§2.3", "V 19/4 … 11: Endschalter ±X, ±Y, ±Z, ±D (L = actuated: the axis stops)")
@pytest.mark.parametrize(("switch", "key", "axis"), [("limit_pos_y", "jog_pos_y", "y"), ("limit_neg_d", "jog_neg_d", "d")])
def test_a_limit_switch_stops_its_axis_in_its_direction(make, switch: str, key: str, axis: str) -> None:  # noqa: ANN001
    cnc = make(mode="MANUAL")
    cnc.set(f"input.{key}", True)
    cnc.advance(0.5)
    assert cnc.read(f"axis.{axis}.velocity") != 0
    cnc.set(f"input.{switch}", False)
    assert cnc.read(f"axis.{axis}.velocity") == 0
    held = cnc.read(f"axis.{axis}.position")
    cnc.advance(0.5)
    assert cnc.read(f"axis.{axis}.position") == held
