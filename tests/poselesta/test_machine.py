"""The POSELESTA's machine side through the control API of a served device (virtual time): the
M/S/T handshake on the data bus (spec §4.4, the timelines of §6.3, §6.4), the block cycle
(§4.3), exact positioning, NC-Stop, Not-Stop, block skip, single block, M06/M10 and the
direction keys (§5.4)."""

from __future__ import annotations

import json
import math
import re
from typing import Any

import pytest

from devsim.runtime import Runtime
from tests.support.memory import refused_memory

OUTPUTS = ("data_bus", "strobe_m", "strobe_s1", "strobe_s2", "strobe_t", "strobe_ba")
#: These tests check the control's logic on the levels it sees; the input delay of manual §2.3
#: has its own tests (test_manual_inputs.py), so here an input is seen as it is set.
NO_INPUT_DELAY = {"input_rise_ms": 0, "input_fall_ms": 0}


@pytest.fixture
def make(devsim_device):  # noqa: ANN001, ANN201
    def start(config: dict[str, Any] | None = None, program: str = "", mode: str = "AUTO_CONTINUOUS") -> Any:
        cnc = devsim_device("poselesta", {**NO_INPUT_DELAY, **(config or {})})
        cnc.advance(0.1)  # past the BA output after the boot
        if program:
            cnc.set("program.P20", program)
            cnc.set("panel.program", 20)
        cnc.set("panel.mode", mode)
        cnc.advance(0.1)
        return cnc

    return start


def bus(cnc: Any) -> tuple[Any, ...]:
    return tuple(cnc.read(f"output.{name}") for name in OUTPUTS)


def sample(cnc: Any, until_ms: int, step_ms: int = 20) -> list[tuple[Any, ...]]:
    """The bus and strobes in the middle of each ``step_ms`` window from now (t = 0 is now)."""
    cnc.advance(step_ms / 2000)
    seen = [bus(cnc)]
    for _ in range(until_ms // step_ms):
        cnc.advance(step_ms / 1000)
        seen.append(bus(cnc))
    return seen


@pytest.mark.manual("§2.4.5", "Nach Beendigung dieser Tests, nach ca. 2 Sekunden, schaltet die Steuerung auf Handbetrieb und der Ausgang wird auf H-Level gesetzt")
@pytest.mark.manual("§2.4.1", "Nach dem Netzeinschalten und Setzen des NC-Bereitschaftssignals wird die Betriebsart Handbetrieb über den Data-Bus ausgegeben")
@pytest.mark.manual("§2.4.8", "Der Uebernahmeimpuls Betriebsart hat einen festen Zeitablauf")
@pytest.mark.manual("§2.4.5", "Es wird durch anliegenden Not-Stop (V 19/2) nicht auf L-Level gesetzt")
def test_power_up_outputs_the_mode_code_with_the_ba_strobe(devsim_device) -> None:  # noqa: ANN001
    """§6.4: NC ready after about 2 s, then 0x08, strobe BA after t1, L after 2 t1, bus 00 after 3 t1."""
    cnc = devsim_device("poselesta", boot=False)
    assert cnc.read("output.nc_ready") is False and cnc.read("output.data_bus") == 0
    cnc.advance(1.99)
    assert cnc.read("output.nc_ready") is False
    cnc.advance(0.02)  # 2.01 s
    assert cnc.read("output.nc_ready") is True and bus(cnc) == (0x08, False, False, False, False, False)
    cnc.advance(0.02)  # 2.03
    assert bus(cnc) == (0x08, False, False, False, False, True)
    cnc.advance(0.02)  # 2.05
    assert bus(cnc) == (0x08, False, False, False, False, False)
    cnc.advance(0.02)  # 2.07
    assert bus(cnc) == (0x00, False, False, False, False, False)
    cnc.set("input.emergency_stop", False)  # Not-Stop does not drop NC ready
    cnc.advance(0.1)  # (seen after the input delay)
    assert cnc.read("output.nc_ready") is True


@pytest.mark.manual("§2.4.8", "Der Uebernahmeimpuls Betriebsart hat einen festen Zeitablauf, welcher durch die M-, S- und T-Quittierung nicht beeinflusst wird")
@pytest.mark.manual("§2.4.1", "Zu jeder Funktion wird ein separater Uebernahmeimpuls (STROBE) ausgegeben: M, S1, S2, T und Betriebsart")
def test_a_program_started_at_once_waits_for_the_mode_code(make) -> None:  # noqa: ANN001
    """NC-Start 5 ms after the switch to AUTO_CONTINUOUS: the mode code 0x0C still gets its strobe
    for t1 (20 ms), and M03 goes on the bus only after it (t2 after the bus went back to 00)."""
    cnc = make(program="N1 M03 X1", mode="MANUAL")
    cnc.set("panel.mode", "AUTO_CONTINUOUS")
    cnc.advance(0.005)
    cnc.set("panel.nc_start", True)
    seen = []
    for _ in range(150):
        cnc.advance(0.001)
        seen.append(bus(cnc))
    ba = [row for row in seen if row[5]]
    assert len(ba) == 20 and {row[0] for row in ba} == {0x0C}
    strobes = [(row[0], row[1], row[5]) for row in seen if row[1] or row[5]]
    assert strobes == [(0x0C, False, True)] * 20 + [(0x03, True, False)] * 20
    assert cnc.read("output.m03") is True


@pytest.mark.manual("§2.4.8", "Ausgabereihenfolge innerhalb eines Satzes: M, (M*), S1, S2, T")
@pytest.mark.manual("§2.4.1", "Zuerst erfolgt die Ausgabe der Einer- und Zehnerstellen (S 1) und danach die Ausgabe der Hunderter- und Tausenderstellen (S 2)")
@pytest.mark.manual("§2.4.8", "nach Ablauf der programmierten Zeit T1 wird der entsprechende Uebernahmepuls mitausgegeben; die Länge des Uebernahmeimpulses entspricht dann der Zeit T1")
@pytest.mark.manual("§2.4.7", "M 03 Spindel EIN wird dekodiert ausgegeben; selbsthaltende M-Funktionen werden durch eine löschende Funktion zurückgestellt")
@pytest.mark.manual("§2.4.2", "Die Fahrbefehle bleiben bis zum Ziel oder Bahnende aktiv")
@pytest.mark.manual("§2.4.6", "Sobald alle Achsen das Zielfenster einmal erreicht haben und keine Sollwerte vorgegeben werden, wird dieser Ausgang auf H-Level gesetzt")
def test_block_functions_follow_the_handshake_timeline_with_the_acknowledge_bridged(make) -> None:  # noqa: ANN001
    """§6.3, first table: N10 M03 S1250 T07 X100 with P72 = 20 ms."""
    cnc = make(program="N10 M03 S1250 T07 X100")
    cnc.set("panel.nc_start", True)
    assert cnc.read("output.m03") is True and cnc.read("program.state") == "MST_OUTPUT"
    seen = sample(cnc, 240)
    assert seen == [
        (0x03, False, False, False, False, False),  # 0–20: M03 on the bus
        (0x03, True, False, False, False, False),  # 20–40: strobe M
        (0x03, False, False, False, False, False),  # 40–60: t2
        (0x50, False, False, False, False, False),  # S1: units and tens first
        (0x50, False, True, False, False, False),
        (0x50, False, False, False, False, False),
        (0x12, False, False, False, False, False),  # S2: hundreds and thousands
        (0x12, False, False, True, False, False),
        (0x12, False, False, False, False, False),
        (0x07, False, False, False, False, False),  # T07
        (0x07, False, False, False, True, False),
        (0x07, False, False, False, False, False),
        (0x00, False, False, False, False, False),  # 240: bus 00, the motion
    ]
    assert cnc.read("output.travel_x") is True and cnc.read("output.machine_standstill") is False
    assert cnc.read("program.state") == "MOVING"
    # G00 at the rapid of P44 (6000 mm/min) with 500 mm/s² ramps: 100 mm take 1.2 s (240 ms → 1440 ms)
    cnc.advance(1.18)  # 1430 ms
    assert cnc.read("output.position_reached") is False and cnc.read("axis.x.position") < 100_000
    cnc.advance(0.02)
    assert cnc.read("axis.x.position") == pytest.approx(100_000)
    assert cnc.read("output.travel_x") is False and cnc.read("output.machine_standstill") is True
    assert cnc.read("program.state") == "END" and cnc.read("output.m03") is True  # self-holding
    assert cnc.read("output.start_stop_status") is False


@pytest.mark.manual("§2.4.8", "bleibt der Uebernahmepuls so lange stehen, bis die M-, S- oder T-Quittierung auf H-Level wechselt und T1 abgelaufen ist")
@pytest.mark.manual("§2.3.19", "Nach einem Uebergang der MST-Quittierung von H-Level auf L-Level wird die nächste Funktion ausgegeben")
def test_a_slow_plc_stretches_the_strobe_until_its_acknowledge(make) -> None:  # noqa: ANN001
    """§6.3, second variant: acknowledge H 35 ms after the strobe rises, L 15 ms after it falls:
    strobe M H at 20, L at 55, acknowledge L at 70, S1 on the bus at 90."""
    cnc = make({"plc": {"mst_ack": "delayed", "rise_ms": 35, "fall_ms": 15}}, program="N10 M03 S1250")
    cnc.set("panel.nc_start", True)
    seen = []
    for t in (10, 30, 50, 60, 65, 75, 85, 95):
        cnc.advance((t - (seen[-1][0] if seen else 0)) / 1000)
        seen.append((t, cnc.read("output.data_bus"), cnc.read("output.strobe_m"), cnc.read("input.mst_ack")))
    assert seen == [
        (10, 0x03, False, False), (30, 0x03, True, False), (50, 0x03, True, False), (60, 0x03, False, True),
        (65, 0x03, False, True), (75, 0x03, False, False), (85, 0x03, False, False), (95, 0x50, False, False),
    ]


@pytest.mark.manual("§2.3.19", "Die Uebernahme erfolgt nach einem Hand-shake-Verfahren: die nächste Funktion erst nach dem Uebergang H → L der Quittierung")
def test_an_acknowledge_stuck_high_holds_the_output(make) -> None:  # noqa: ANN001
    """§6.3 / S16: strobe M for t1, then the control waits for the acknowledge to go L."""
    cnc = make({"plc": {"mst_ack": "manual"}}, program="N10 M03 S1250")
    cnc.set("input.mst_ack", True)
    cnc.set("panel.nc_start", True)
    seen = sample(cnc, 200)
    assert seen[1] == (0x03, True, False, False, False, False)
    assert all(row == (0x03, False, False, False, False, False) for row in seen[2:])
    assert cnc.read("program.state") == "MST_OUTPUT"
    cnc.set("input.mst_ack", False)
    cnc.advance(0.03)
    assert cnc.read("output.data_bus") == 0x50  # t2 after the acknowledge fell


@pytest.mark.manual("§2.3.15", "Bei L-Level wird der Vorschub nicht freigegeben; die Steuerung ist in Wartestellung")
@pytest.mark.manual("§2.4.2", "Nach Ausgabe der Fahrbefehle wartet die Steuerung die Achsfreigabe ab, bevor in den Achsen verfahren wird")
@pytest.mark.manual("§2.3.16", "Steht der Eingang Programm fortsetzen auf L-Level, bleibt die Steuerung in Wartestellung, bis das Eingangssignal auf H-Level wechselt")
@pytest.mark.manual("§2.4.3", "Position erreicht wird ausgegeben, wenn ein genaues Positionieren programmiert ist und die bewegten Achsen das Zielfenster erreicht haben")
def test_axis_enable_and_program_continue_gate_the_block(make) -> None:  # noqa: ANN001
    """S19 (§2.3.15, §2.3.16): travel command, then wait for the axis enable; position reached,
    then wait for program continue."""
    cnc = make(program="N1 G00 X10\nN2 X20")
    cnc.set("input.axis_enable", False)
    cnc.set("input.program_continue", False)
    cnc.set("panel.nc_start", True)
    cnc.advance(1.0)
    assert cnc.read("program.state") == "WAIT_AXIS_ENABLE" and cnc.read("output.travel_x") is True
    assert cnc.read("axis.x.position") == 0
    cnc.set("input.axis_enable", True)
    cnc.advance(1.0)
    assert cnc.read("axis.x.position") == pytest.approx(10_000)
    assert cnc.read("program.state") == "WAIT_PROGRAM_CONTINUE"
    assert cnc.read("output.position_reached") is True and cnc.read("output.travel_x") is False
    cnc.set("input.program_continue", True)
    assert cnc.read("output.position_reached") is False and cnc.read("program.block") == 2
    cnc.set("input.program_continue", False)
    cnc.advance(1.0)
    assert cnc.read("program.state") == "WAIT_PROGRAM_CONTINUE" and cnc.read("axis.x.position") == pytest.approx(20_000)


@pytest.mark.manual("§2.3.1", "Ein NC-Stop bewirkt einen Halt der Achsbewegungen entlang der Bremsrampe. Durch Drücken der NC-Start-Taste wird die Positionierung fortgesetzt")
@pytest.mark.manual("§2.4.2", "Bei NC-Stop werden die Fahrbefehle nicht zurückgesetzt")
@pytest.mark.manual("§2.3.3", "Nach NC-Stop wird mittels NC-Start die unterbrochene Achsbewegung fortgesetzt")
def test_nc_stop_brakes_to_hold_and_nc_start_resumes_to_the_same_end_point(make) -> None:  # noqa: ANN001
    """S20 (§2.3.1): braking ramp, travel commands stay, HOLD; NC-Start continues."""
    cnc = make(program="N1 G01 X50 F3000")
    cnc.set("panel.nc_start", True)
    cnc.advance(0.5)
    moving_at = cnc.read("axis.x.velocity")
    assert moving_at == pytest.approx(50_000)  # 3000 mm/min = 50 mm/s = 50,000 increments/s
    cnc.set("input.nc_stop", False)
    assert cnc.read("program.state") == "HOLD" and cnc.read("output.start_stop_status") is False
    cnc.advance(0.05)
    assert 0 < cnc.read("axis.x.velocity") < moving_at  # along the ramp, not at once
    cnc.advance(0.5)
    held = cnc.read("axis.x.position")
    assert cnc.read("axis.x.velocity") == 0 and held < 50_000
    assert cnc.read("output.travel_x") is True and cnc.read("output.machine_standstill") is True
    cnc.set("panel.nc_start", True)  # still stopped: ignored
    assert cnc.read("program.state") == "HOLD"
    cnc.set("input.nc_stop", True)
    cnc.set("input.nc_start", True)  # the external button
    assert cnc.read("program.state") == "MOVING"
    cnc.advance(2.0)
    assert cnc.read("axis.x.position") == pytest.approx(50_000) and cnc.read("program.state") == "END"


@pytest.mark.manual("§2.3.2", "Ein Not-Stop bewirkt einen schlagartigen Halt der Achsbewegungen ohne Ausführung der Bremsrampe. Die Analogausgänge werden gleichzeitig auf Null gesetzt")
@pytest.mark.manual("§2.3.2", "Die Steuerung wechselt beim Aufheben des Not-Stops automatisch auf Handbetrieb")
@pytest.mark.manual("§2.4.1", "Dasselbe geschieht nach Not-Stop: Handbetrieb wird über den Data-Bus ausgegeben")
@pytest.mark.manual("§2.3.2", "Ist ein Schleppfehler vorhanden, der nicht abgearbeitet werden konnte, wird dieser durch "
                    "die Steuerung berücksichtigt und intern auf Null gesetzt, ohne die Istwerte zu verfälschen")
@pytest.mark.manual("§2.3.2", "Nach dem Aufheben des Not-Stops werden die Antriebe ruckfrei eingeschaltet und die "
                    "Lageregelkreise sind nun wieder aktiv")
def test_not_stop_stops_at_once_and_its_release_returns_to_manual(make) -> None:  # noqa: ANN001
    """S22 (§2.3.2): set-points 0 V at once, no ramp, the program aborted, the following error
    cleared with the actual value kept; release → MANUAL, 0x08, the drive holds where it stood."""
    cnc = make(program="N1 G01 X50 F3000")
    cnc.set("panel.nc_start", True)
    cnc.advance(0.5)
    assert cnc.read("axis.x.analog_out") > 0 and cnc.read("axis.x.following_error") > 0
    display = cnc.read("axis.x.display")
    cnc.set("input.emergency_stop", False)
    position = cnc.read("axis.x.position")
    assert cnc.read("axis.x.velocity") == 0 and cnc.read("axis.x.analog_out") == 0
    assert cnc.read("axis.x.following_error") == 0 and cnc.read("axis.x.display") == display
    cnc.advance(1.0)
    assert cnc.read("axis.x.position") == position and cnc.read("program.state") == "IDLE"
    assert cnc.read("output.nc_ready") is True and cnc.read("panel.mode") == "AUTO_CONTINUOUS"
    cnc.set("input.emergency_stop", True)
    assert cnc.read("panel.mode") == "MANUAL" and cnc.read("output.data_bus") == 0x08
    cnc.advance(0.5)  # the loop closed again on the actual value: no set-point jump, no motion
    assert cnc.read("axis.x.analog_out") == 0 and cnc.read("axis.x.position") == position


@pytest.mark.manual("§2.3.13", "Bei L-Level ist das Satzausblenden wirksam und der markierte Satz wird übersprungen; bei H-Level werden die markierten Sätze auch ausgeführt")
def test_blocks_marked_slash_are_skipped_while_the_input_is_low(make) -> None:  # noqa: ANN001
    """S23 (§2.3.13): a block marked ``#`` is sampled at its start."""
    cnc = make(program="N1 X10\nN2 X20 #\nN3 M02")
    cnc.set("panel.nc_start", True)
    cnc.advance(2.0)
    assert cnc.read("program.state") == "END" and cnc.read("axis.x.position") == pytest.approx(10_000)
    cnc.set("input.block_skip_cancel", True)
    cnc.set("panel.nc_start", True)
    cnc.advance(2.0)
    assert cnc.read("axis.x.position") == pytest.approx(20_000)


@pytest.mark.manual("§2.4.7", "die Rückstellung der nicht selbsthaltenden Funktionen (M 00) erfolgt durch NC-Start")
@pytest.mark.manual("§2.4.2", "In der Betriebsart Automatik-Einzelsatz werden die Fahrbefehle und Position erreicht gleich wie bei einem programmierten Stop ausgegeben")
def test_single_block_and_programmed_stop_wait_for_nc_start(make) -> None:  # noqa: ANN001
    """S30 and M00 (§2.4.7): every block stops like a programmed stop; M00's output until NC-Start."""
    cnc = make(program="N1 X1\nN2 X2 M00\nN3 X3", mode="AUTO_SINGLE_BLOCK")
    cnc.set("panel.nc_start", True)
    cnc.advance(1.0)
    assert cnc.read("program.state") == "STOPPED" and cnc.read("axis.x.position") == pytest.approx(1_000)
    cnc.set("panel.nc_start", True)
    cnc.advance(1.0)
    assert cnc.read("program.state") == "STOPPED" and cnc.read("output.m00") is True
    with pytest.raises(Exception, match="stop the program first|executes"):
        cnc.set("panel.nc_start", True)
        cnc.set("panel.mode", "MANUAL")  # N3 runs now: no mode change
    cnc.advance(1.0)
    assert cnc.read("output.m00") is False and cnc.read("axis.x.position") == pytest.approx(3_000)


@pytest.mark.manual("§2.3.17", "Wenn ein Werkzeugwechsel mit M 06 programmiert ist, muss dieser quittiert werden")
@pytest.mark.manual("§2.3.18", "Bei H-Level wird M 10 als eine nicht selbsthaltende Funktion behandelt: die Steuerung wartet, bis ein negativer Impuls die Löschung und die Programmfortsetzung bewirkt")
@pytest.mark.manual("§2.4.7", "M 10 wirkt am Satzanfang")
def test_tool_change_and_m10_wait_for_their_acknowledges(make) -> None:  # noqa: ANN001
    """S17, S18 (§2.3.17, §2.3.18)."""
    cnc = make(program="N20 M06 T05 X1\nN30 M10 X2\nN40 M11")
    cnc.set("panel.nc_start", True)
    cnc.advance(0.5)
    assert cnc.read("program.state") == "WAIT_TOOL_CHANGE" and cnc.read("output.m06") is True
    cnc.set("input.tool_change_ack", True)
    assert cnc.read("output.m06") is False
    cnc.set("input.tool_change_ack", False)
    cnc.set("input.m10_ack", True)  # H at output time: M10 waits for a negative pulse
    cnc.advance(1.0)
    assert cnc.read("program.state") == "WAIT_M10_PULSE" and cnc.read("output.m10") is True
    assert cnc.read("axis.x.position") == pytest.approx(1_000)  # M10 acts at the block start: X2 waits
    cnc.set("input.m10_ack", False)
    assert cnc.read("output.m10") is False
    cnc.advance(1.0)
    assert cnc.read("program.state") == "END" and cnc.read("axis.x.position") == pytest.approx(2_000)


@pytest.mark.manual("§2.3.6", "Die Richtungstasten bewirken eine Achsbewegung in die gewünschte Richtung, solange eine Taste gedrückt wird")
@pytest.mark.manual("§2.3.22", "Vorschubpotentiometer: Bereich 0...100 %, entsprechend 0...+10 V; 100 % = maximaler Vorschub P 48 - P 51")
@pytest.mark.manual("§2.3.8", "Eilgang: In den angewählten Achsen wird mit der maximal zulässigen Geschwindigkeit (Parameter 44-47) verfahren")
@pytest.mark.manual("§2.3.7", "Die Achsen können um den angewählten Jogging-Schritt verfahren werden")
@pytest.mark.manual("§2.4.3", "Im Handbetrieb wird das Signal Position erreicht nicht ausgegeben")
def test_direction_keys_jog_at_the_feed_pot_share_and_steps(make) -> None:  # noqa: ANN001
    """S26 (§2.3.6–§2.3.8): 5 V = 50 % of P48; rapid = P44; a 100-increment step per press."""
    cnc = make(mode="MANUAL")
    cnc.set("input.feed_pot_v", 5.0)
    cnc.set("input.jog_pos_x", True)
    assert cnc.read("output.travel_x") is True and cnc.read("output.machine_standstill") is False
    cnc.advance(1.0)
    assert cnc.read("axis.x.velocity") == pytest.approx(1000 / 60 * 1000)  # 50 % of 2000 mm/min
    cnc.set("input.rapid", True)
    cnc.advance(1.0)
    assert cnc.read("axis.x.velocity") == pytest.approx(100_000)  # P44 6000 mm/min
    cnc.set("input.jog_pos_x", False)
    cnc.advance(1.0)
    assert cnc.read("axis.x.velocity") == 0 and cnc.read("output.travel_x") is False
    assert cnc.read("output.position_reached") is False  # never in MANUAL
    start = cnc.read("axis.x.position")
    cnc.set("input.jog_step_100", True)
    for _ in range(3):
        cnc.set("input.jog_neg_x", True)
        cnc.set("input.jog_neg_x", False)
        cnc.advance(0.5)
    assert cnc.read("axis.x.position") == pytest.approx(start - 300)


@pytest.mark.manual("§2.3.22", "Override: 6,6 V = 100 % des programmierten Vorschubs, 10 V = 150 %")
def test_override_scales_the_feed_and_zero_stands_without_hold(make) -> None:  # noqa: ANN001
    """S29 (§2.3.22): 10 V = 150 %, 0 V stops the path (no HOLD), 6.667 V = 100 %."""
    cnc = make(program="N1 G01 X200 F1000")
    cnc.set("input.override_pot_v", 10.0)
    cnc.set("panel.nc_start", True)
    cnc.advance(0.5)
    assert cnc.read("axis.x.velocity") == pytest.approx(1500 / 60 * 1000)
    cnc.set("input.override_pot_v", 0.0)
    cnc.advance(0.5)
    assert cnc.read("axis.x.velocity") == 0 and cnc.read("program.state") == "MOVING"
    cnc.set("input.override_pot_v", 6.667)
    cnc.advance(0.5)
    assert cnc.read("axis.x.velocity") == pytest.approx(1000 / 60 * 1000, rel=1e-3)


@pytest.mark.manual("§2.3.25", "Ein Eingang auf H-Level wird auf dem Bildschirm mit 1 und ein Eingang auf L-Level mit 0 dargestellt (the port table)")
@pytest.mark.manual("§2.3.26", "Darstellung im Hexadezimal-Code: 00 entspricht 0 V, FF entspricht + 10 V")
def test_the_input_diagnostics_show_the_levels_of_section_6_11(make) -> None:  # noqa: ANN001
    """§6.11 (P79 N5) with the default levels; NC-Stop L changes port 4 B to 0x10; P79 N7."""
    cnc = make(mode="PROGRAM_ENTRY")
    cnc.set("panel.diagnostic", 5)
    assert cnc.read("diagnostics.inputs") == {
        "1A": 0x46, "1B": 0x00, "2A": 0xFF, "2B": 0x00, "3A": 0x00, "3B": 0x00, "4A": 0x60, "4B": 0x18,
    }
    assert cnc.read("diagnostics.input_screen").splitlines()[:2] == [
        "Port 1 EIN 01000110 00000000", "Port 2 EIN 11111111 00000000",
    ]
    cnc.set("input.nc_stop", False)
    assert cnc.read("diagnostics.inputs")["4B"] == 0x10
    cnc.set("panel.diagnostic", 7)
    assert cnc.read("diagnostics.pots") == ["FF", "AA"]  # 10 V, 6.667 V


def test_a_limit_switch_stops_at_once_and_lets_only_away(make) -> None:  # noqa: ANN001
    """S25 (spec §5.5): limit +X actuated while moving +: immediate stop, program aborted, alarm;
    in MANUAL + refused, − allowed."""
    cnc = make(program="N1 G01 X50 F3000")
    cnc.set("panel.nc_start", True)
    cnc.advance(0.5)
    cnc.set("input.limit_pos_x", False)
    stopped_at = cnc.read("axis.x.position")
    assert cnc.read("axis.x.velocity") == 0 and cnc.read("program.state") == "IDLE"
    assert cnc.read("panel.message") == "LIMIT_SWITCH" and cnc.read("output.nc_ready") is True
    cnc.set("panel.mode", "MANUAL")
    cnc.advance(0.1)
    cnc.set("input.jog_pos_x", True)
    cnc.advance(0.5)
    assert cnc.read("axis.x.position") == stopped_at and cnc.read("output.travel_x") is False
    cnc.set("input.jog_pos_x", False)
    cnc.set("input.jog_neg_x", True)
    cnc.advance(0.5)
    assert cnc.read("axis.x.position") < stopped_at


@pytest.mark.parametrize(("config", "passes"), [({}, 3), ({"g13_count_is_total": True}, 2)])
def test_subroutine_calls_and_repeats_follow_g12_g11_g13(make, config: dict[str, Any], passes: int) -> None:  # noqa: ANN001
    """Spec §4.12.1 (INFERRED from the manual's example §6.6): G12 L1.100 calls N100 once, G13
    L2.101 runs N101 two more times (two in all with g13_count_is_total, spec G-LOOP), G11
    returns after the call; each pass of N101 moves +1."""
    cnc = make(config, program="N1 G91\nN2 G12 L1.100\nN3 X10 M02\nN100 G10\nN101 X1\nN102 G13 L2.101\nN103 G11")
    cnc.set("panel.nc_start", True)
    cnc.advance(5.0)
    assert cnc.read("program.state") == "END"
    assert cnc.read("axis.x.position") == pytest.approx(passes * 1_000 + 10_000)  # the loop, then 10 mm


@pytest.mark.parametrize("program", [
    "\n".join(f"N{n} G91" for n in range(1, 400)) + "\nN400 X1",  # blocks of no motion and no function
    "N1 G91\nN2 G13 L99.001\nN3 X1",  # a repeat of such a block
])
def test_a_long_run_of_blocks_without_motion(make, program: str) -> None:  # noqa: ANN001
    """Blocks that end at once (no motion, no M, S or T) follow one another in the same instant;
    300 or 400 of them in a row ran out of Python's stack (RecursionError through NC-Start)."""
    cnc = make(program=program)
    cnc.set("panel.nc_start", True)
    cnc.advance(2.0)
    assert cnc.read("program.state") == "END" and cnc.read("axis.x.position") == pytest.approx(1_000)


def test_a_subroutine_that_calls_itself_without_motion_ends_the_program(make) -> None:  # noqa: ANN001
    """``N100 G12 L1.100`` never reaches its G11 and never moves: the program cannot go on (the
    manual has no alarm for it); it ends with the event ``endless_loop`` instead of a
    RecursionError or a control that never answers again."""
    cnc = make(program="N1 G12 L1.100\nN2 X1\nN100 G12 L1.100\nN101 G11")
    cnc.set("panel.nc_start", True)
    cnc.advance(1.0)
    assert cnc.read("program.state") == "END" and cnc.read("axis.x.position") == 0
    assert "endless_loop" in _events(cnc)


def test_dwell_and_unknown_g_functions(make) -> None:  # noqa: ANN001
    """G04 waits L seconds at the end of its block; an unknown G runs as a no-op (spec §4.12.1)."""
    cnc = make(program="N1 G04 L1.500\nN2 G77 X1")
    cnc.set("panel.nc_start", True)
    cnc.advance(1.4)
    assert cnc.read("program.block") == 1
    cnc.advance(1.0)
    assert cnc.read("program.state") == "END" and cnc.read("axis.x.position") == pytest.approx(1_000)


@pytest.mark.manual("§2.3.1", "Der NC-Stop wird jedoch intern abgespeichert, so dass eine nächste Achsbewegung erst nach "
                    "erneutem Auslösen eines NC-Starts ausgeführt wird")
@pytest.mark.manual("§2.3.22", "Der programmierte Vorschub kann mittels Override-Potentiometer erhöht bzw. verkleinert "
                    "werden")
def test_a_dwell_after_a_motion_keeps_nc_stop_and_its_time(make) -> None:  # noqa: ANN001
    """N1 moves X to 5 mm, then dwells 3 s (G04 L3).  NC-Stop during the dwell: the next block's
    motion waits for NC-Start; turning the override during the dwell neither restarts the dwell
    nor shows "Position erreicht" again."""
    cnc = make(program="N1 G01 X5 F6000 G04 L3\nN2 X6")
    cnc.set("panel.nc_start", True)
    cnc.advance(1.0)  # X arrived after 0.25 s; the dwell runs until 3.25 s
    assert cnc.read("axis.x.position") == pytest.approx(5_000) and cnc.read("program.block") == 1
    reached = _events(cnc).count("position_reached")
    for volts in (3.0, 4.0, 5.0):
        cnc.set("input.override_pot_v", volts)
        cnc.advance(0.5)  # 2.5 s
    assert _events(cnc).count("position_reached") == reached
    cnc.set("input.nc_stop", False)
    cnc.advance(4.0)  # the dwell is over; N2 has started and waits for NC-Start
    assert cnc.read("program.block") == 2 and cnc.read("program.state") == "HOLD"
    assert cnc.read("axis.x.position") == pytest.approx(5_000)
    cnc.set("input.nc_stop", True)
    cnc.advance(0.1)
    assert cnc.read("axis.x.position") == pytest.approx(5_000)  # still no NC-Start
    cnc.set("panel.nc_start", True)
    cnc.advance(1.0)
    assert cnc.read("program.state") == "END" and cnc.read("axis.x.position") == pytest.approx(6_000)


def test_the_override_during_a_dwell_does_not_restart_it(make) -> None:  # noqa: ANN001
    """G04 L3 after a motion: the block ends 3 s after the axis arrived, however the override is
    turned meanwhile (spec §5.3: L seconds)."""
    cnc = make(program="N1 G01 X5 F6000 G04 L3\nN2 G91 X1")
    cnc.set("panel.nc_start", True)
    cnc.advance(0.5)
    for volts in (3.0, 4.0, 5.0, 6.0, 6.667):
        cnc.set("input.override_pot_v", volts)
        cnc.advance(0.5)  # 3.0 s
    cnc.advance(1.0)  # 4.0 s: N2 ran (1 mm, 0.21 s)
    assert cnc.read("program.state") == "END" and cnc.read("axis.x.position") == pytest.approx(6_000)


@pytest.mark.manual("§2.3.21", "Satzabbruch: L-Level bewirkt, dass eine angefangene Positionierung abgebrochen wird; die Programmabarbeitung wird auf der Satznummer in P90 fortgesetzt")
def test_block_abort_brakes_and_goes_on_at_p90(make) -> None:  # noqa: ANN001
    """S31 (§2.3.21, POS III): P90 = 50; V22/10 H→L during N20's motion: the axis brakes, the
    program goes on at N50 by itself."""
    cnc = make(program="N10 X1\nN20 X100\nN30 X200\nN50 Y5")
    cnc.set("param.P90", 50)
    cnc.set("panel.nc_start", True)
    cnc.advance(0.8)
    assert cnc.read("program.block") == 20 and cnc.read("axis.x.velocity") > 0
    cnc.set("input.block_abort", False)
    cnc.advance(0.05)
    assert cnc.read("program.block") == 20 and cnc.read("axis.x.velocity") > 0  # braking along the ramp
    cnc.advance(1.0)
    assert cnc.read("program.state") == "END" and cnc.read("axis.y.position") == pytest.approx(5_000)
    assert 1_000 < cnc.read("axis.x.position") < 100_000


def _radius(cnc: Any, cx: float, cy: float) -> float:
    return math.hypot(cnc.read("axis.x.position") / 1000 - cx, cnc.read("axis.y.position") / 1000 - cy)


def test_g02_runs_the_quarter_circle_of_the_manuals_example(make) -> None:  # noqa: ANN001
    """Spec §5.3, §6.6 (N3 reconstructed): clockwise, radius 20 around the absolute centre
    I0 J-43.144, from (-20, -43.144) to (0, -23.144), at F3000 = 50 mm/s; NC-Stop brakes along
    the circle and NC-Start goes on to the end point."""
    cnc = make(program="N1 G00 X-20 Y-43.144\nN3 G02 X0 Y-23.144 I0 J-43.144 F3000")
    cnc.set("panel.nc_start", True)
    cnc.run_until(lambda d: d.model.executor.block_number == 3 and d.model.executor.state == "MOVING", 5.0)
    assert cnc.read("output.travel_x") is True and cnc.read("output.travel_y") is True
    cnc.advance(0.3)
    assert _radius(cnc, 0, -43.144) == pytest.approx(20.0, abs=1e-6)
    speed = math.hypot(cnc.read("axis.x.velocity"), cnc.read("axis.y.velocity"))
    assert speed == pytest.approx(50_000)
    assert cnc.read("axis.y.velocity") > 0 and cnc.read("axis.x.velocity") > 0  # climbing the left side
    cnc.set("input.nc_stop", False)
    cnc.advance(0.5)
    assert cnc.read("program.state") == "HOLD" and cnc.read("axis.x.velocity") == 0
    assert _radius(cnc, 0, -43.144) == pytest.approx(20.0, abs=1e-6)  # braked on the circle
    cnc.set("input.nc_stop", True)
    cnc.set("panel.nc_start", True)
    cnc.advance(2.0)
    assert cnc.read("program.state") == "END"
    assert (cnc.read("axis.x.position"), cnc.read("axis.y.position")) == pytest.approx((0, -23_144), abs=1e-6)


def test_an_arc_whose_end_is_off_the_circle_stops_the_program(make) -> None:  # noqa: ANN001
    """Spec §5.3: start and end radius differ by more than 0.01 mm: the block is not executed."""
    cnc = make(program="N1 G03 X10 Y10 I0 J0 F1000")
    cnc.set("panel.nc_start", True)
    cnc.advance(1.0)
    assert cnc.read("program.state") == "STOPPED" and cnc.read("axis.x.position") == 0


def test_a_full_circle_counter_clockwise_returns_to_its_start(make) -> None:  # noqa: ANN001
    cnc = make(program="N1 G00 X10\nN2 G03 X10 Y0 I0 J0 F6000")
    cnc.set("panel.nc_start", True)
    cnc.run_until(lambda d: d.model.executor.block_number == 2 and d.model.executor.state == "MOVING", 5.0)
    cnc.advance(0.3)
    assert cnc.read("axis.y.position") > 0  # counter-clockwise from (10, 0): up first
    assert _radius(cnc, 0, 0) == pytest.approx(10.0, abs=1e-6)
    cnc.advance(2.0)
    assert cnc.read("program.state") == "END"
    assert (cnc.read("axis.x.position"), cnc.read("axis.y.position")) == pytest.approx((10_000, 0), abs=1e-6)


@pytest.mark.parametrize(("config", "centre", "state"), [
    ({}, "I0 J0", "END"), ({}, "I0 J-10", "STOPPED"),
    ({"ijk_incremental": True}, "I0 J-10", "END"), ({"ijk_incremental": True}, "I0 J0", "STOPPED"),
])
def test_the_circle_centre_is_absolute_or_with_ijk_incremental_from_the_start(
        make, config: dict[str, Any], centre: str, state: str) -> None:  # noqa: ANN001
    """Spec G-IJK: I/J are absolute (the manual's example §6.6), or counted from the arc's start
    with ijk_incremental: from (0, 10) the centre (0, 0) is I0 J0 or I0 J-10; the other reading
    puts the end off the circle and the program stops."""
    cnc = make(config, program=f"N1 G00 Y10\nN2 G02 X10 Y0 {centre} F6000")
    cnc.set("panel.nc_start", True)
    cnc.advance(3.0)
    assert cnc.read("program.state") == state
    assert cnc.read("axis.x.position") == pytest.approx(10_000 if state == "END" else 0, abs=1e-6)


@pytest.mark.parametrize(("plane", "start", "end", "centre"), [(17, "Y10", "X10 Y0", "I0 J0"),
                                                          (18, "X10", "X0 Z10", "I0 K0"),
                                                          (19, "Z10", "Y10 Z0", "J0 K0")])
def test_g02_turns_clockwise_seen_from_the_positive_third_axis_in_every_plane(
        make, plane: int, start: str, end: str, centre: str) -> None:  # noqa: ANN001
    """Spec §5.3, DIN 66025 (the manual has no G17/G18/G19): G02 is clockwise seen from the
    positive third axis, that is in the right-handed plane XY (G17), ZX (G18), YZ (G19).  A
    quarter circle from the plane's second axis at 10 to its first axis at 10 stays in the
    quadrant where both are positive, not three quarters round the other way."""
    cnc = make(program=f"N1 G00 {start}\nN2 G{plane} G02 {end} {centre} F3000")
    cnc.set("panel.nc_start", True)
    cnc.run_until(lambda d: d.model.executor.block_number == 2 and d.model.executor.state == "MOVING", 5.0)
    cnc.advance(0.1)
    a, b = (axis for axis in "xyz" if f"{axis.upper()}" in end)
    assert cnc.read(f"axis.{a}.position") > 0 and cnc.read(f"axis.{b}.position") > 0
    cnc.advance(1.0)
    assert cnc.read("program.state") == "END"


@pytest.mark.manual("§2.3.23", "Bei offenem Kontakt (H-Level) ist die Referenzmarke für die Steuerung wirksam")
def test_homing_takes_the_first_mark_seen_with_its_activation_high(make) -> None:  # noqa: ANN001
    """S37 (§2.2.2, §2.3.23, spec §5.6): marks at −10 and −30 mm; with V24/1 L the first is
    ignored; set H after 20 mm, the second is taken: there the actual value becomes 0."""
    cnc = make({"axes": {"x": {"reference_marks": [-10.0, -30.0]}}}, mode="MANUAL")
    cnc.set("input.rm_enable_x", False)
    cnc.set("panel.reference", "x")
    cnc.advance(0.1)
    assert cnc.read("output.travel_x") is True and cnc.read("axis.x.velocity") < 0
    cnc.advance(7.0)  # 3.333 mm/s: past the mark at −10 mm, short of −30 mm
    assert -30_000 < cnc.read("axis.x.position") < -20_000 and cnc.read("referenced") == []
    cnc.set("input.rm_enable_x", True)
    cnc.run_until(lambda d: "x" in d.model.field.referenced, 60.0)
    # 10 % of P48 (2000 mm/min) = 3.333 mm/s; braking from it at 500 mm/s² takes 0.0111 mm
    assert cnc.read("axis.x.position") == pytest.approx(-(10 / 3) ** 2 / 2 / 500 * 1000, abs=1e-6)
    assert cnc.read("axis.x.velocity") == 0 and cnc.read("output.travel_x") is False


@pytest.mark.manual("§2.4.2", "Nach Ausgabe der Fahrbefehle wartet die Steuerung die Achsfreigabe ab, bevor in den Achsen verfahren wird")
def test_homing_waits_for_the_axis_enable_and_not_stop_ends_the_wait(make) -> None:  # noqa: ANN001
    """§2.4.2, §2.3.15 (spec §5.6 leaves the procedure open): the search's travel command goes out,
    X moves once V22/3 is H (machine standstill L then); Not-Stop ends a search still waiting, and
    one under way, so that a new one can start."""
    cnc = make({"axes": {"x": {"reference_marks": [-1.0]}}}, mode="MANUAL")
    cnc.set("input.axis_enable", False)
    cnc.set("panel.reference", "x")
    cnc.advance(0.5)
    assert cnc.read("output.travel_x") is True and cnc.read("axis.x.position") == 0
    assert cnc.read("output.machine_standstill") is True
    cnc.set("input.axis_enable", True)
    cnc.advance(0.1)
    assert cnc.read("axis.x.velocity") < 0 and cnc.read("output.machine_standstill") is False
    cnc.run_until(lambda d: "x" in d.model.field.referenced, 60.0)
    cnc.set("input.axis_enable", False)
    cnc.set("panel.reference", "x")
    cnc.set("input.emergency_stop", False)
    cnc.advance(0.1)
    assert cnc.read("output.travel_x") is False and cnc.device.model.field.homing is None
    cnc.set("input.emergency_stop", True)
    cnc.set("input.axis_enable", True)
    cnc.advance(0.5)
    assert cnc.read("axis.x.velocity") == 0
    cnc.set("panel.reference", "x")  # Not-Stop ends a moving search too: it can start again after
    cnc.advance(0.1)
    cnc.set("input.emergency_stop", False)
    cnc.advance(0.1)
    assert cnc.device.model.field.homing is None and cnc.read("axis.x.velocity") == 0
    cnc.set("input.emergency_stop", True)
    cnc.advance(0.1)
    cnc.set("panel.reference", "x")
    cnc.advance(0.1)
    assert cnc.read("axis.x.velocity") < 0


@pytest.mark.manual("§2.4.4", "Wird das programmierte Arbeitsfeld verlassen, werden alle Achsen entlang der Bremsrampen, wie bei NC-Stop, abgebremst; Fahren ist im Handbetrieb dann nur in Richtung Arbeitsfeld möglich")
@pytest.mark.manual("§2.4.4", "Die Werte für den Software-Endschalter beziehen sich immer auf die Referenzmarke der entsprechenden Achse")
def test_leaving_the_working_field_brakes_and_stops_the_program(make) -> None:  # noqa: ANN001
    """S24 (§2.4.4, spec §5.5): +limit X at 50 mm (P9) once referenced; G00 X80 brakes at the
    crossing and overshoots by the braking distance; V18/6 L; NC-Start ignored; in MANUAL + is
    refused, − brings it back and V18/6 goes H."""
    cnc = make({"axes": {"x": {"reference_marks": [-1.0]}}}, program="N1 G00 X80", mode="MANUAL")
    cnc.set("panel.reference", "x")
    cnc.run_until(lambda d: "x" in d.model.field.referenced, 60.0)
    cnc.set("param.P9", 50)
    cnc.set("panel.mode", "AUTO_CONTINUOUS")
    cnc.advance(0.1)
    cnc.set("panel.nc_start", True)
    cnc.run_until(lambda d: not d.model.signals.get("inside_working_field"), 5.0)
    assert cnc.read("axis.x.position") == pytest.approx(50_000, abs=1)
    assert cnc.read("program.state") == "LIMIT_STOP" and cnc.read("panel.message") == "OUTSIDE_WORKING_FIELD"
    cnc.advance(1.0)
    assert cnc.read("axis.x.position") == pytest.approx(60_000, abs=1)  # 100 mm/s braked at 500 mm/s²: 10 mm
    cnc.set("panel.nc_start", True)
    assert cnc.read("program.state") == "LIMIT_STOP"
    cnc.set("panel.mode", "MANUAL")
    cnc.advance(0.1)
    cnc.set("input.jog_pos_x", True)
    cnc.advance(0.2)
    assert cnc.read("axis.x.velocity") == 0
    cnc.set("input.jog_pos_x", False)
    cnc.set("input.jog_neg_x", True)
    cnc.run_until(lambda d: d.model.signals.get("inside_working_field"), 60.0)
    assert cnc.read("axis.x.position") == pytest.approx(50_000, abs=1)


@pytest.mark.manual("§2.4.4", "Die Werte für den Software-Endschalter (Arbeitsfeldbegrenzung) beziehen sich immer auf die "
                    "Referenzmarke der entsprechenden Achse")
def test_the_software_limits_count_from_the_reference_mark(make) -> None:  # noqa: ANN001
    """The actual value at X's mark is 5 mm (config reference_value): P9 = 20 and P13 = −3 put the
    field from 2 mm to 25 mm of the actual value, 20 mm and 3 mm either side of the mark."""
    cnc = make({"axes": {"x": {"reference_marks": [-1.0], "reference_value": 5.0}}, "params": {9: 20.0, 13: -3.0}},
               program="N1 G01 X24 F600\nN2 X30", mode="MANUAL")
    cnc.set("panel.reference", "x")
    cnc.run_until(lambda d: "x" in d.model.field.referenced, 60.0)
    assert cnc.read("output.inside_working_field") is True  # at about 5 mm: inside
    cnc.set("panel.mode", "AUTO_CONTINUOUS")
    cnc.advance(0.1)
    cnc.set("panel.nc_start", True)
    cnc.run_until(lambda d: d.model.executor.state in ("LIMIT_STOP", "END"), 10.0)
    assert cnc.read("program.state") == "LIMIT_STOP" and cnc.read("program.block") == 2
    cnc.advance(1.0)  # 10 mm/s braked at 500 mm/s²: 0.1 mm beyond the limit
    assert cnc.read("axis.x.position") == pytest.approx(25_100, abs=1)
    assert cnc.read("output.inside_working_field") is False


@pytest.mark.manual("§2.2.3", "Steht P 76 auf 4, ist ein Rasterschritt 4 x so gross")
@pytest.mark.manual("§2.4.6", "Maschinenstillstand: der Ausgang wird auf L-Level gesetzt, sobald eine Handradaktivierung erfolgt")
@pytest.mark.manual("§3.4", "Handradverfahren mit Impulsvervielfachung, Faktor 10: bei jedem Handradschritt werden 10 Schritte generiert")
def test_the_handwheel_moves_p76_increments_per_detent(make) -> None:  # noqa: ANN001
    """S27 (§2.2.3, §2.4.6): handwheel X active, P76 = 4, 25 detents: X moves 0.100 mm; the
    machine standstill output is L as soon as the handwheel is activated."""
    cnc = make(mode="MANUAL")
    cnc.set("param.P76", 4)
    with pytest.raises(Exception, match="not one of 1, 2, 4"):
        cnc.set("param.P76", 3)
    cnc.set("input.handwheel_x", True)
    assert cnc.read("output.machine_standstill") is False
    cnc.set("handwheel.turn", 25)
    cnc.advance(5.0)
    assert cnc.read("axis.x.position") == pytest.approx(100)
    cnc.set("handwheel.factor", 10)
    cnc.set("handwheel.turn", -1)
    cnc.advance(1.0)
    assert cnc.read("axis.x.position") == pytest.approx(60)
    cnc.set("input.handwheel_x", False)
    assert cnc.read("output.machine_standstill") is True


@pytest.mark.manual("§2.3.9", "In den mit P 77 bestimmten Achsen bleiben die Schleppfehler ständig auf Null; die Fahrbefehle werden auch bei aktiviertem Open-loop ausgegeben")
def test_open_loop_axes_follow_an_outside_force(make) -> None:  # noqa: ANN001
    """S28 (§2.3.9, spec §5.2): P77 = X, open loop at standstill; pushing X moves the display,
    following error and set-point stay 0, the travel command shows."""
    cnc = make(mode="MANUAL")
    with pytest.raises(Exception, match="not in open loop"):
        cnc.set("axis.x.push", 5.0)
    cnc.set("param.P77", 1)
    cnc.set("input.open_loop", True)
    cnc.set("axis.x.push", 5.0)
    cnc.advance(0.2)
    assert cnc.read("axis.x.velocity") != 0 and cnc.read("output.travel_x") is True
    assert cnc.read("axis.x.following_error") == 0 and cnc.read("axis.x.analog_out") == 0
    cnc.advance(1.0)
    assert cnc.read("axis.x.position") == pytest.approx(5_000)


@pytest.mark.manual("§2.3.14", "der Istwert 100.001 mm wird auf 3.93705 Inch umgerechnet und angezeigt")
def test_inch_shows_and_runs_inch_programs(make) -> None:  # noqa: ANN001
    """S33 (§2.3.14, spec §5.1): X at 100.001 mm shows 3.93705 inch with V22/2 H; an inch block
    moves inch and F is inch/min; D is not converted."""
    cnc = make(program="N1 G01 X1 D1 F10")
    cnc.set("input.inch", True)
    cnc.set("panel.nc_start", True)
    cnc.advance(0.5)
    assert math.hypot(cnc.read("axis.x.velocity"), cnc.read("axis.d.velocity")) == pytest.approx(10 * 25.4 / 60 * 1000,
                                                                                               rel=0.02)
    cnc.advance(10.0)
    assert cnc.read("axis.x.position") == pytest.approx(25_400) and cnc.read("axis.d.position") == pytest.approx(1_000)
    assert cnc.read("axis.x.display") == f"{25.4 / 25.4:.5f}" and cnc.read("axis.d.display") == "1.000"
    cnc.set("input.inch", False)
    cnc.set("program.P21", "N1 G00 X100.001")
    cnc.set("panel.program", 21)
    cnc.set("panel.nc_start", True)
    cnc.advance(3.0)
    assert cnc.read("axis.x.display") == "100.001"
    cnc.set("input.inch", True)
    assert cnc.read("axis.x.display") == "3.93705"


@pytest.mark.manual("§2.4.11", "Durch das Diagnose-Programm P 79, N 6 werden alle Ausgänge der Reihe nach im aufsteigenden Binär-Code betätigt; Dauer eines Durchlaufes: 1 Minute 4 Sekunden")
@pytest.mark.manual("§2.4.11", "Der Zyklus läuft unabhängig von der Stellung der Steuerungseingänge Not-Stop und NC-Stop ab")
@pytest.mark.manual("§2.4.11", "bis er durch die Taste C abgebrochen wird; Abschluss: Aus-/Einschalten des Gerätes")
def test_the_output_test_counts_through_every_output(make) -> None:  # noqa: ANN001
    """S40 (§2.4.11, spec §4.7 G-DIAG6): 250 ms per step, 64 s per pass, regardless of Not-Stop;
    C stops it with every output L, and only a power cycle brings the control back."""
    cnc = make(mode="PROGRAM_ENTRY")
    cnc.set("input.emergency_stop", False)
    cnc.set("panel.mode", "PROGRAM_ENTRY")  # (the Not-Stop release would switch to MANUAL)
    cnc.set("diagnostics.output_test", True)
    cnc.advance(0.25 * 5 + 0.1)  # n = 5: contacts 1 and 3
    assert cnc.read("output.m00") is True and cnc.read("output.m01") is False and cnc.read("output.m02") is True
    assert cnc.read("output.travel_x") is True and cnc.read("output.data_bus") == 5
    cnc.advance(64.0)
    assert cnc.read("diagnostics.output_cycles") == 1 and cnc.read("output.data_bus") == 5
    cnc.set("diagnostics.output_test", False)
    assert cnc.read("output.data_bus") == 0 and cnc.read("output.travel_x") is False
    assert cnc.read("output.nc_ready") is False
    with pytest.raises(Exception, match="switch the control off and on"):
        cnc.set("panel.mode", "MANUAL")
    cnc.set("input.emergency_stop", True)
    cnc.power_cycle()
    cnc.advance(0.1)
    assert cnc.read("output.nc_ready") is True and cnc.read("panel.mode") == "MANUAL"


@pytest.mark.manual("§2.4.11", "Der Zyklus läuft unabhängig von der Stellung der Steuerungseingänge Not-Stop und NC-Stop ab")
@pytest.mark.manual("§2.4.11", "bis er durch die Taste C abgebrochen wird; Abschluss: Aus-/Einschalten des Gerätes")
def test_not_stop_pressed_and_released_leaves_the_output_test_alone(make) -> None:  # noqa: ANN001
    """A Not-Stop pressed and released while P79 N6 runs neither clears its outputs (the bus, the
    strobes, the travel commands) nor switches to MANUAL with the mode code on the bus; after C,
    a Not-Stop released leaves every output L until the power cycle."""
    cnc = make(mode="PROGRAM_ENTRY")
    cnc.set("diagnostics.output_test", True)
    cnc.advance(0.25 * 20 + 0.1)  # n = 20 = 0b10100: contacts 3 and 5 of each group
    image = {name: cnc.read(f"output.{name}") for name in ("data_bus", "strobe_s2", "strobe_ba", "travel_z",
                                                            "inside_working_field", "machine_standstill")}
    assert image["data_bus"] == 20 and image["strobe_s2"] is True and image["travel_z"] is True
    seen = []
    cnc.set("input.emergency_stop", False)
    seen.append({name: cnc.read(f"output.{name}") for name in image})
    cnc.advance(0.01)
    cnc.set("input.emergency_stop", True)
    for _ in range(10):
        seen.append({name: cnc.read(f"output.{name}") for name in image})
        cnc.advance(0.005)
    assert seen == [image] * len(seen)
    assert cnc.read("panel.mode") == "PROGRAM_ENTRY" and cnc.read("diagnostics.output_test") is True
    cnc.set("diagnostics.output_test", False)  # C
    cnc.set("input.emergency_stop", False)
    cnc.set("input.emergency_stop", True)
    for _ in range(20):
        cnc.advance(0.005)
        assert cnc.read("output.data_bus") == 0 and cnc.read("output.strobe_ba") is False
        assert cnc.read("output.machine_standstill") is False
    assert cnc.read("panel.mode") == "PROGRAM_ENTRY"


@pytest.mark.manual("§2.4.5", "sofort, wenn ein Fehler festgestellt wird, wird der Ausgang auf L-Level gesetzt. Am Bildschirm erscheint eine Fehlermeldung")
def test_monitoring_alarms_drop_nc_ready_and_stop_the_axes(make) -> None:  # noqa: ANN001
    """S35, S36 (spec §4.10, §5.2, §5.7): an encoder loss or a following error beyond its limit
    drops NC ready, sets the set-points to 0 at once and gives the program up; reset_fault
    restores NC ready."""
    for fault, alarm in (("encoder_loss_y", "ENCODER_FAULT"), ("following_error", "FOLLOWING_ERROR_LIMIT")):
        cnc = make(program="N1 G01 Y50 F3000")
        cnc.set("panel.nc_start", True)
        cnc.advance(0.5)
        cnc.fault(fault)
        assert cnc.read("output.nc_ready") is False and cnc.read("panel.message") == alarm
        assert cnc.read("axis.y.velocity") == 0 and cnc.read("axis.y.analog_out") == 0
        assert cnc.read("program.state") == "IDLE"
        cnc.fault(fault, False)
        assert cnc.read("output.nc_ready") is True and cnc.read("panel.message") == ""


@pytest.mark.manual("§1.4", "Um die Relaisausgänge aktivieren zu können, muss an V 25 eine externe Spannungsquelle (24 V) angeschlossen werden")
def test_a_lost_relay_supply_shows_every_output_low(make) -> None:  # noqa: ANN001
    """S39 (§2.7): all outputs read L while the relay supply is lost; the logic goes on."""
    cnc = make(program="N1 M03 M08 X1")
    cnc.set("panel.nc_start", True)
    cnc.advance(1.0)
    assert cnc.read("output.m03") is True and cnc.read("output.machine_standstill") is True
    cnc.fault("relay_supply")
    assert cnc.read("output.m03") is False and cnc.read("output.nc_ready") is False
    assert cnc.read("output.data_bus") == 0
    cnc.fault("relay_supply", False)
    assert cnc.read("output.m03") is True and cnc.read("output.m08") is True and cnc.read("output.nc_ready") is True


@pytest.mark.manual("§2.3.15", "Beim Bahnfahren mit G 01, G 02 und G 03 wird durchgefahren, d. h. zwischen den einzelnen Sätzen nicht angehalten")
@pytest.mark.manual("§2.4.3", "Wenn in einer Bahn durchgefahren wird, wird das Signal Position erreicht erst am Ende der Bahn ausgegeben")
@pytest.mark.manual("§2.4.2", "bleiben die Fahrbefehle zwischen den einzelnen Sätzen bestehen")
def test_contouring_blocks_run_through_without_stopping(make) -> None:  # noqa: ANN001
    """Spec §4.3.3, §5.3 (manual §2.3.15, §2.4.2): G01 X10 then X20 pass the block boundary at
    the path speed, travel commands on, no position reached; the G00 block after the chain makes
    the end of the chain an exact stop."""
    cnc = make(program="N1 G01 X10 F3000\nN2 X20\nN3 G00 X0")
    cnc.set("panel.nc_start", True)
    cnc.run_until(lambda d: d.model.executor.block_number == 2, 5.0)
    assert cnc.read("axis.x.position") == pytest.approx(10_000)
    cnc.advance(0.001)
    assert cnc.read("axis.x.velocity") == pytest.approx(50_000)  # still 50 mm/s: no stop at N1's end
    assert cnc.read("output.travel_x") is True and cnc.read("output.position_reached") is False
    assert cnc.read("program.state") == "MOVING"
    cnc.run_until(lambda d: bool(d.model.signals.get("position_reached")), 5.0)
    assert cnc.read("axis.x.position") == pytest.approx(20_000) and cnc.read("program.block") == 2
    cnc.advance(3.0)
    assert cnc.read("program.state") == "END" and cnc.read("axis.x.position") == pytest.approx(0)


def test_a_chain_of_line_and_arc_keeps_its_speed(make) -> None:  # noqa: ANN001
    """A G01 into a G02 (spec §5.3: no look-ahead, the path speed is kept)."""
    cnc = make(program="N1 G01 X-20 F3000\nN2 G02 X0 Y20 I0 J0\nN3 G01 X10")
    cnc.set("panel.nc_start", True)
    cnc.run_until(lambda d: d.model.executor.block_number == 2, 5.0)
    cnc.advance(0.1)
    assert math.hypot(cnc.read("axis.x.velocity"), cnc.read("axis.y.velocity")) == pytest.approx(50_000)
    assert _radius(cnc, 0, 0) == pytest.approx(20.0, abs=1e-6)
    cnc.run_until(lambda d: d.model.executor.block_number == 3, 5.0)
    cnc.advance(0.01)
    assert cnc.read("axis.x.velocity") == pytest.approx(50_000) and cnc.read("output.position_reached") is False
    cnc.advance(2.0)
    assert cnc.read("program.state") == "END"
    assert (cnc.read("axis.x.position"), cnc.read("axis.y.position")) == pytest.approx((10_000, 20_000), abs=1e-6)


@pytest.mark.manual("§2.3.20", "Dieser Eingang (X/Y-Schreiber) wird nur beim Netzeinschalten registriert")
def test_an_xy_plotter_gets_its_position_as_the_set_point(devsim_device) -> None:  # noqa: ANN001
    """Spec §5.9 (manual §2.3.20): V22/8 H at power-on; the set-point is the position over the
    working field, −10 V … +10 V in 14 bits."""
    cnc = devsim_device("poselesta", NO_INPUT_DELAY)
    assert cnc.read("xy_plotter") is False
    cnc.set("input.xy_plotter", True)
    assert cnc.read("xy_plotter") is False  # sampled at power-on only
    cnc.set("param.P9", 100)
    cnc.set("param.P13", -100)
    cnc.power_cycle()
    assert cnc.read("xy_plotter") is True
    assert cnc.read("axis.x.analog_out") == pytest.approx(-10 + 20 * 8192 / 16383)  # 0 mm: the middle step
    assert cnc.read("axis.x.following_error") == 0


def test_panel_keys_blocks_and_diagnostics_as_operator_actions(make) -> None:  # noqa: ANN001
    """Spec §3.2.2: panel.key (by name or code, the V8 path: buzzer), panel.edit_block (one block
    by the read-in rules), panel.diagnostic (P79 N3 / N6 in PROGRAM_ENTRY)."""
    cnc = make({"v8_keymap": {"48": "P", "0x2D": "exit"}}, mode="PROGRAM_ENTRY")
    cnc.set("panel.key", "P")
    assert cnc.read("keyboard.last_key") == 0x48 and cnc.read("output.buzzer") is True
    with pytest.raises(Exception, match="not a key code"):
        cnc.set("panel.key", "01")
    cnc.set("panel.edit_block", "20: N5 X10")
    cnc.set("panel.edit_block", "20: N2 Y-3")
    cnc.set("panel.edit_block", "20: N5 X11")
    assert cnc.read("program.P20") == "N 2 Y- 3.000\nN 5 X 11.000"
    with pytest.raises(Exception, match="WERTBEREICHES-UEBERLAUF"):
        cnc.set("panel.edit_block", "20: N6 X12345.678")
    cnc.set("panel.diagnostic", 3)
    cnc.advance(0.2)
    cnc.set("panel.key", "P")
    assert cnc.read("diagnostics.keyboard_test") == "49"
    cnc.advance(0.2)
    cnc.set("panel.key", "exit")
    assert cnc.read("diagnostics.keyboard_test") == ""
    cnc.set("diagnostics.keyboard_test", "\u3000true")  # (an ideographic space: no true spelling)
    cnc.advance(0.2)
    cnc.set("panel.key", "P")
    assert cnc.read("diagnostics.keyboard_test") == ""


@pytest.mark.parametrize("name", ["program.P\u0662\u0660", "tool.T\u0660\u0661"])
def test_a_program_or_tool_name_s_number_is_ascii_digits(make, name: str) -> None:  # noqa: ANN001
    """'program.P٢٠' (Arabic-Indic digits, which \\d and int() take) is no name of P20, nor 'tool.T٠١' of T01."""
    from devsim.core.points import UnknownName

    cnc = make()
    with pytest.raises(UnknownName):
        cnc.read(name)


@pytest.mark.parametrize("key", ["٤٨", "0x48", "4_8", "+48", "ex\u0131t"])
def test_a_key_code_is_ascii_hex_digits(make, key: str) -> None:  # noqa: ANN001
    """panel.key's hex code is hex digits: int(key, 16) also took the Arabic-Indic '٤٨', '0x48',
    '4_8' and '+48' as the key 48 (P); a name is matched in ASCII case: str.upper made 'exıt' (the
    dotless ı, U+0131) the key named exit."""
    from devsim.core.points import BadValue

    cnc = make({"v8_keymap": {"48": "P", "0x2D": "exit"}}, mode="PROGRAM_ENTRY")
    with pytest.raises(BadValue, match="no key"):
        cnc.set("panel.key", key)
    assert cnc.read("keyboard.last_key") == -1  # (none yet)


@pytest.mark.parametrize("text", ["²0: N5 X10", "٢٠: N5 X10", "P²: N5 X10"])
def test_a_program_number_is_ascii_digits(make, text: str) -> None:  # noqa: ANN001
    """panel.edit_block's program number is digits as the keyboard types them: a superscript ²
    (which str.isdigit takes and int() does not: a ValueError, not a refusal) or digits of
    another script (which int() reads: '٢٠' stored P20) are refused."""
    from devsim.core.points import BadValue

    cnc = make(mode="PROGRAM_ENTRY")
    with pytest.raises(BadValue, match="expected 'program: block'"):
        cnc.set("panel.edit_block", text)
    assert cnc.read("programs") == []


def test_homing_turns_back_once_at_a_limit_switch(make) -> None:  # noqa: ANN001
    """Spec §5.6: the mark lies behind the start; the − limit switch turns the search back, the
    mark is then taken moving +; a second limit switch stops with the alarm."""
    cnc = make({"axes": {"x": {"reference_marks": [5.0]}}}, mode="MANUAL")
    cnc.set("panel.reference", "x")
    cnc.advance(1.0)
    assert cnc.read("axis.x.velocity") < 0
    cnc.set("input.limit_neg_x", False)
    cnc.advance(0.1)
    assert cnc.read("axis.x.velocity") > 0 and cnc.read("panel.message") == ""
    cnc.set("input.limit_neg_x", True)
    cnc.run_until(lambda d: "x" in d.model.field.referenced, 30.0)
    assert cnc.read("axis.x.position") == pytest.approx((10 / 3) ** 2 / 2 / 500 * 1000, abs=1e-6)  # braked +
    far = make({"axes": {"x": {"reference_marks": [500.0]}}}, mode="MANUAL")  # a mark beyond the + switch
    far.set("panel.reference", "x")
    far.advance(1.0)
    far.set("input.limit_neg_x", False)  # turns back
    far.advance(0.5)
    far.set("input.limit_neg_x", True)
    far.advance(0.5)
    far.set("input.limit_pos_x", False)  # and runs into the other switch: alarm
    assert far.read("panel.message") == "LIMIT_SWITCH" and far.read("axis.x.velocity") == 0
    assert far.read("referenced") == [] and far.read("output.travel_x") is False


def test_the_conversions_of_section_6_10(make) -> None:  # noqa: ANN001
    """Spec §6.10: pots in percent and as the diagnostic's hex, handwheel and jog step sizes."""
    cnc = make(mode="MANUAL")
    for volts, percent in ((6.6, 99.0), (10.0, 150.0), (0.0, 0.0), (6.667, 100.0)):
        cnc.set("input.override_pot_v", volts)
        assert cnc.read("panel.override") == percent
    for volts, percent in ((10.0, 100.0), (5.0, 50.0)):
        cnc.set("input.feed_pot_v", volts)
        assert cnc.read("panel.feed") == percent
    cnc.set("panel.mode", "PROGRAM_ENTRY")
    cnc.set("panel.diagnostic", 7)
    for feed, override, shown in ((0.0, 10.0, ["00", "FF"]), (10.0, 6.667, ["FF", "AA"])):
        cnc.set("input.feed_pot_v", feed)
        cnc.set("input.override_pot_v", override)
        assert cnc.read("diagnostics.pots") == shown
    cnc.set("panel.mode", "MANUAL")
    cnc.set("input.feed_pot_v", 10.0)
    cnc.set("param.P76", 4)
    cnc.set("handwheel.factor", 10)
    cnc.set("input.handwheel_x", True)
    cnc.set("handwheel.turn", 1)
    cnc.advance(1.0)
    assert cnc.read("axis.x.position") == pytest.approx(40)  # 0.040 mm
    cnc.set("input.handwheel_x", False)
    cnc.set("input.jog_step_1000", True)
    cnc.set("input.jog_pos_y", True)
    cnc.advance(1.0)
    assert cnc.read("axis.y.position") == pytest.approx(1_000)  # 1.000 mm


@pytest.mark.manual("§2.4.1", "Wertigkeiten des Data-Bus: 2 x BCD-Code; die S-Funktionen in 2 Teilen, S1 dann S2")
def test_the_data_bus_rows_of_section_6_2(make) -> None:  # noqa: ANN001
    """Spec §6.2: M 20 → 0x20; S 8 → S1 = 0x08, then S2 = 0x00 (S2 always goes out)."""
    cnc = make(program="N1 M20 S8")
    cnc.set("panel.nc_start", True)
    seen = sample(cnc, 180)
    assert [row[0] for row in seen[::3]] == [0x20, 0x08, 0x00, 0x00]
    assert seen[4][2] is True and seen[7][3] is True  # strobe S1, then strobe S2


def test_tools_and_compensation_are_recorded(make) -> None:  # noqa: ANN001
    """Spec §4.9, §5.8 phase 1: the tool catalogue keeps radius and length; G41/G42/G40 are
    recorded (an event each) without offsetting the path."""
    cnc = make(program="N1 G42 G01 X10 F3000 T05\nN2 G40 X0")
    cnc.set("tool.T05", {"radius": 4.0, "length": 120.5})
    assert cnc.read("tool.T05") == {"radius": 4.0, "length": 120.5}
    with pytest.raises(Exception, match="finite"):
        cnc.set("tool.T05", {"radius": float("nan")})
    cnc.set("panel.nc_start", True)
    cnc.run_until(lambda d: d.model.executor.state == "MOVING", 5.0)
    assert cnc.read("program.compensation") == "G42" and cnc.read("program.tool") == 5
    cnc.run_until(lambda d: d.model.executor.block_number == 2, 5.0)
    assert cnc.read("axis.x.position") == pytest.approx(10_000)  # the programmed path, no offset
    cnc.advance(2.0)
    assert cnc.read("program.compensation") == "G40"
    cnc.power_cycle()
    assert cnc.read("tool.T05") == {"radius": 4.0, "length": 120.5}


def _events(cnc: Any) -> list[str]:
    return [name for _, name in cnc.device.model.events]


def test_encoder_overspeed_rm_missing_and_the_g25_circle(make) -> None:  # noqa: ANN001
    """Spec §5.7: a 2-channel adapter (8 kHz) is too slow for the rapid of 100 mm/s at 0.001 mm
    (25 kHz): the event encoder_overspeed; a lost reference mark signal makes homing search on;
    with g25_full_circle a G25 block runs once round its centre (spec §4.12.1)."""
    cnc = make({"encoder_khz": 8.0, "g25_full_circle": True}, program="N1 G00 X10\nN2 G03 G25 I0 J0 F6000")
    cnc.set("panel.nc_start", True)
    cnc.advance(0.3)
    assert "encoder_overspeed" in _events(cnc)
    cnc.run_until(lambda d: d.model.executor.block_number == 2 and d.model.executor.state == "MOVING", 5.0)
    cnc.advance(0.5)
    assert _radius(cnc, 0, 0) == pytest.approx(10.0, abs=1e-6) and cnc.read("axis.y.position") != 0
    cnc.advance(3.0)
    assert cnc.read("program.state") == "END"
    assert (cnc.read("axis.x.position"), cnc.read("axis.y.position")) == pytest.approx((10_000, 0), abs=1e-6)
    quiet = make({"axes": {"x": {"reference_marks": [-1.0]}}}, mode="MANUAL")
    quiet.fault("rm_missing_x")
    quiet.set("panel.reference", "x")
    quiet.advance(5.0)
    assert quiet.read("referenced") == [] and quiet.read("axis.x.velocity") < 0 and "encoder_overspeed" not in _events(quiet)


@pytest.mark.manual("§2.3.14", "Es besteht die Möglichkeit, auch wenn der Parameter P1 auf 0 (metrisch) steht, NC-Programme in Inch einzugeben. Dazu muss der Eingang auf H-Level gesetzt werden")
def test_a_program_typed_in_inch_is_stored_as_typed(make) -> None:  # noqa: ANN001
    """Spec §5.1: entered or read in while V22/2 is H, X/Y/Z carry two more decimals
    (xx.xxxxx); run with V22/2 H they are inch."""
    cnc = make()
    cnc.set("input.inch", True)
    cnc.set("program.P22", "N1 G00 X3.93705 D1")
    assert cnc.read("program.P22") == "N 1 X 3.93705 D 1.000 G 00"
    with pytest.raises(Exception, match="beyond the format"):
        cnc.set("program.P23", "N1 X100.001")  # more than xx.xxxxx inch
    cnc.set("panel.program", 22)
    cnc.set("panel.nc_start", True)
    cnc.advance(3.0)
    assert cnc.read("axis.x.position") == pytest.approx(3.93705 * 25.4 * 1000)
    assert cnc.read("axis.d.position") == pytest.approx(1_000) and cnc.read("axis.x.display") == "3.93705"


def test_the_plc_helper_answers_tool_changes_and_releases_m10(make) -> None:  # noqa: ANN001
    """Spec Appendix A (plant helpers): M06 acknowledged 200 ms after it is output, a pulse-mode
    M10 released 300 ms after it is output; the program runs through without a hand."""
    cnc = make({"plc": {"tool_change_ms": 200, "m10_release_ms": 300}}, program="N1 M06 T02\nN2 M10 X1\nN3 M02")
    cnc.set("input.m10_ack", True)
    cnc.set("panel.nc_start", True)
    cnc.run_until(lambda d: d.model.executor.state == "WAIT_TOOL_CHANGE", 2.0)
    cnc.run_until(lambda d: d.model.executor.state != "WAIT_TOOL_CHANGE", 1.0)
    assert cnc.read("output.m06") is False
    cnc.run_until(lambda d: d.model.executor.state == "WAIT_M10_PULSE", 2.0)
    cnc.advance(2.0)
    assert cnc.read("program.state") == "END" and cnc.read("output.m10") is False
    assert cnc.read("input.m10_ack") is True and cnc.read("input.tool_change_ack") is False  # pulses over


def test_count_loss_shifts_the_actual_value_from_the_true_position(make) -> None:  # noqa: ANN001
    """Spec §5.7: an encoder drops counts: the actual value falls behind by that much (while
    the axis moves, from its next standstill); homing finds the mark where it physically is."""
    cnc = make({"count_loss_increments": 25, "axes": {"x": {"reference_marks": [-5.0]}}}, mode="MANUAL")
    cnc.fault("count_loss_x")
    assert cnc.read("axis.x.position") == -25 and "count_loss" in _events(cnc)
    cnc.fault("count_loss_x", False)
    cnc.set("input.jog_pos_x", True)
    cnc.advance(0.5)
    cnc.fault("count_loss_x")
    assert cnc.device.model.field.offset["x"] == -25  # not yet: X still moves
    cnc.set("input.jog_pos_x", False)
    cnc.advance(1.0)
    assert cnc.device.model.field.offset["x"] == -50
    cnc.set("panel.reference", "x")
    cnc.run_until(lambda d: "x" in d.model.field.referenced, 60.0)
    assert cnc.read("axis.x.position") == pytest.approx(-(10 / 3) ** 2 / 2 / 500 * 1000, abs=1e-6)


@pytest.mark.manual("§2.6.2.2", "Ausgabe auf Band --> Mode 2; Eingabe vom Band --> Mode 3; Vorlaufzeit von ca. 13 Sekunden")
def test_a_simulated_cassette_records_and_plays_back(make) -> None:  # noqa: ANN001
    """Spec §3.8, Appendix A (manual §2.6.2.2): with v6_peer: cassette, T2 records P20 after the
    13 s leader, T3 plays it into P21 after its leader; the tape survives a power cycle."""
    cnc = make({"v6_peer": "cassette"}, program="N1 X10\nN2 Y-2.5 M02", mode="EXTERNAL_MEDIUM")
    cnc.set("v6.transfer", "cassette_out")
    cnc.advance(20.0)
    assert cnc.read("v6.state") == "done" and cnc.read("cassette.tape").startswith("a5 8d 0a")  # ISO %
    cnc.power_cycle()
    cnc.advance(0.1)
    cnc.set("panel.mode", "EXTERNAL_MEDIUM")
    cnc.set("panel.program", 21)
    cnc.set("v6.transfer", "cassette_in")
    cnc.advance(12.9)
    assert cnc.read("program.P21") == ""
    cnc.advance(1.0)
    assert cnc.read("v6.state") == "done"
    assert cnc.read("program.P21") == "N 1 X 10.000\nN 2 Y- 2.500 M 02"


@pytest.mark.parametrize("key", ["\u0663", "+3", "1_0"])
def test_a_configured_parameter_number_is_ascii_digits(key: str) -> None:
    """A plant file's params key is a number in ASCII digits: int() also read the Arabic-Indic '٣'
    as P3, '+3' and '1_0' as P3 and P10."""
    from devsim.core.typed import Invalid
    from devsim.devices.poselesta.config import PoselestaConfig

    assert PoselestaConfig.parse({"params": {"3": 1.0, 13: -3.0}}).params[3] == 1.0
    with pytest.raises(Invalid, match="valid integer"):
        PoselestaConfig.parse({"params": {key: 1.0}})


@pytest.mark.parametrize("value", ['"nan"', '"1e999"', "true", '"12"'])
def test_a_stored_parameter_that_is_no_finite_number_refuses_the_memory(tmp_path, value: str) -> None:
    """A hand-edited state file (fuzzed): ``float()`` took "nan" and "1e999" as parameters, and
    the next save of the parameters (a write from the panel or the control API) raised
    PoisonedMemory out of the control.  Now the start stops naming the file, which stays as it
    was."""
    path = tmp_path / "poselesta.nvram.json"
    text = f'{{"params": {{"5": {value}}}}}'
    path.write_text(text)
    refused_memory(tmp_path, "poselesta", match="this memory image does not fit the kind 'poselesta'")
    assert path.read_text() == text


def test_a_stored_block_with_a_word_no_block_has_refuses_the_memory(tmp_path) -> None:
    """(Fuzzed: stored blocks with words 'W5', '%1' or '' loaded, and reading the program's text
    through the control API failed with KeyError in tape.block_words, which every output of a
    block goes through.)  A stored block of the letters a block has loads as before."""
    path = tmp_path / "poselesta.nvram.json"
    for letter in ("W", "%", ""):
        path.write_text(json.dumps({"programs": {"20": [{"N": 1, "words": [["X", 5], [letter, 5]], "skip": False}]}}))
        refused_memory(tmp_path, "poselesta", match=rf"\(ValueError: block N1: '{re.escape(letter)}' is no address letter")
    path.write_text(json.dumps({"programs": {"20": [{"N": 1, "words": [["X", 5000], ["M", 2]], "skip": False}]}}))
    runtime = Runtime(virtual=True, state_dir=tmp_path).start()
    try:
        runtime.add_device("poselesta")
        assert "X" in runtime.read("poselesta", "program.P20")
    finally:
        runtime.stop()


_BLOCK = [{"N": 1, "words": [["X", 5000], ["M", 2]], "skip": False}]


@pytest.mark.parametrize("sections", [
    {"tools": {"1": {"radius": "abc", "length": 1.0}}}, {"tools": {"1": {"radius": True, "length": 1.0}}},
    {"tools": {"1": {"radius": 2.5}}}, {"tools": {"1": {"radius": 2.5, "length": 1.0, "wear": 0.1}}},
    {"tools": {"150": {"radius": 2.5, "length": 1.0}}},
    {"protected": [-21]}, {"protected": [200]}, {"protected": [21.5]}, {"protected": ["21"]},
    {"inch_programs": [79]}, {"inch_programs": [-1]},
    {"programs": {"79": _BLOCK}}, {"programs": {"100": _BLOCK}}, {"programs": {"-1": _BLOCK}},
], ids=["tool-text", "tool-bool", "tool-no-length", "tool-extra-item", "tool-T150",
        "protected-negative", "protected-200", "protected-fraction", "protected-text", "inch-P79", "inch-negative",
        "program-P79", "program-P100", "program-negative"])
def test_a_stored_tool_or_program_number_the_control_never_stores_refuses_the_memory(tmp_path, sections) -> None:  # noqa: ANN001
    """(Fuzzed, /tmp/probe_images/mut.py: 306 damaged tool, protected and inch-program lists.)  A
    stored tool loaded as whatever the file held, and tool.Tnn served a text, true, a missing
    length or an extra item to the host; protected and inch programs outside P00 … P98 (or
    fractions, cut to whole numbers) and programs P79 or P100 loaded.  Now the start stops naming
    the file, which stays as it was; a tool, protection and program as the control stores them load."""
    path = tmp_path / "poselesta.nvram.json"
    text = json.dumps(sections)
    path.write_text(text)
    refused_memory(tmp_path, "poselesta", match="this memory image does not fit the kind 'poselesta'")
    assert path.read_text() == text


def test_stored_tools_protection_and_programs_load_as_saved(tmp_path) -> None:  # noqa: ANN001
    (tmp_path / "poselesta.nvram.json").write_text(json.dumps({
        "tools": {"1": {"radius": 2.5, "length": 10}, "99": {"radius": 0.5, "length": -3.25}},
        "protected": [0, 21, 98], "inch_programs": [22], "programs": {"0": _BLOCK, "98": _BLOCK}}))
    runtime = Runtime(virtual=True, state_dir=tmp_path).start()
    try:
        runtime.add_device("poselesta")
        assert runtime.read("poselesta", "tool.T01") == {"radius": 2.5, "length": 10.0}
        assert runtime.read("poselesta", "tool.T99") == {"radius": 0.5, "length": -3.25}
        assert runtime.read("poselesta", "protected") == [0, 21, 98]
        assert "X" in runtime.read("poselesta", "program.P98")
    finally:
        runtime.stop()


@pytest.mark.parametrize("block", [
    {"N": 1, "words": [["X", 10**8]]}, {"N": 1, "words": [["G", 150]]}, {"N": 1, "words": [["F", -5]]},
    {"N": 1, "words": [["X", 1], ["Y", 2], ["Z", 3]]}, {"N": 1, "words": [["T", 1], ["T", 2]]},
    {"N": 1, "words": [["M", 30]]}, {"N": 1, "words": [["P", 5]]}, {"N": 1000, "words": [["X", 1]]},
    {"N": -1, "words": [["X", 1]]}, {"N": 1, "words": [["X", 1.5]]}, {"N": 1, "words": [["X", "5"]]},
    {"N": 1, "words": [["X", 1]], "skip": "no"},
], ids=["X-8-digits", "G150", "F-signed", "three-coordinates", "T-twice", "M30", "P-word", "N1000", "N-1",
        "X-fraction", "X-text", "skip-text"])
def test_a_stored_block_no_read_in_stores_refuses_the_memory(tmp_path, block: dict) -> None:  # noqa: ANN001
    """(Fuzzed.)  Such a block loaded, and the control served it as a program it cannot read back:
    program.P20 read 'N 1 X 100000.000', 'G 150', 'F- 5', three coordinates, 'T 01 T 02' or an
    'M 30' that ends the tape, which entered again are WERTBEREICHES-UEBERLAUF or a cut program
    (a fraction or a text was cut to a whole number, any skip taken as yes).  Now the start stops
    naming the file, which stays as it was."""
    path = tmp_path / "poselesta.nvram.json"
    text = json.dumps({"programs": {"20": [block]}})
    path.write_text(text)
    refused_memory(tmp_path, "poselesta", match=r"\(ValueError: block N-?\d+: ")
    assert path.read_text() == text


def test_a_pos_iii_protection_in_the_memory_of_a_pos_ii_is_not_enforced(tmp_path) -> None:  # noqa: ANN001
    """A POS II has no program lock (spec §1.1, V22/9 POS III only).  A memory a POS III protected
    P21 in, started as a POS II, refused every change of P21 ('P21 is protected') and its release
    ('program protection is a POS III function'), so P21 could never change again.  [SIM-CHOICE]
    Now the POS II does not enforce it, and the file keeps it for the POS III."""
    path = tmp_path / "poselesta.nvram.json"
    path.write_text(json.dumps({"protected": [21], "programs": {"21": _BLOCK}}))
    runtime = Runtime(virtual=True, state_dir=tmp_path).start()
    try:
        runtime.add_device("poselesta", config={"variant": "II"})
        runtime.set("poselesta", "program.P21", "N1 X2")
        assert runtime.read("poselesta", "protected") == []
        assert runtime.read("poselesta", "program.P21") == "N 1 X 2.000"
    finally:
        runtime.stop()
    assert json.loads(path.read_text())["protected"] == [21]
