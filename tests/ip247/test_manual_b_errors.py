"""The manual's error chapter walked (manual §7.2 Fehlerbehandlung, §7.2.2 Baugruppenfehler und
mögliche Ursachen): each module error and the situation the manual names as its cause, driven
through the PG port (AS511 on a real pty) or the PLC endpoint (TCP), in virtual time."""

from __future__ import annotations

import struct
from typing import Any

import pytest

from devsim.devices.ip247 import program as lang
from devsim.devices.ip247.client import AgClient
from tests.ip247.helpers import BACKWARD, FORWARD, START, STOP, TAKE_OVER, Make, Module, record
from tests.ip247.test_machine_data import COM247, words

PROGRAM_5 = "%  5\nN1 X1 F100\nN2 M02\n"


def length(text: str) -> int:
    """A program's record length in words (manual §6.3.8.2): 5 header words and the text."""
    return len(lang.record_words(0, text))


def filler(number: int) -> str:
    """A valid program of 994 … 1023 characters (the most one program may have, §2.6.1)."""
    text, k = f"%{number:3d} FILLER\n", 1
    while len(text) < 990:
        text += f"N{k} X{k} F100\n"
        k += 1
    text = text[: text.rfind("\n", 0, 1010) + 1] if len(text) > 1010 else text
    text += f"N{k} M02\n"
    assert 994 <= len(text) <= 1023
    return text


def observe(mod: Module, page: int = 1) -> tuple[int, int, bytes]:
    """OBSERVE: actual value, residual distance and the four pages' errors."""
    answer = mod.call(0x62, bytes((page,)))
    position, residual = struct.unpack(">ii", answer[8:16])
    return position, residual, answer[16:20]


@pytest.mark.manual("§7.2.2", "Fehler 1 \"Auftragsliste PG ist voll\": the module cannot process the jobs as fast "
                    "as they are entered; the job last entered from the PG is lost and must be repeated")
def test_error_1_the_job_that_overflows_the_pg_list_is_lost(mod: Module) -> None:
    mod.ready()
    mod.operate(1, 1, FORWARD, w=6000)
    mod.clock.advance(3)
    mod.operate(1, 1, STOP)  # the axis brakes: jobs wait in the PG's job list
    acks = [mod.operate(1, 12, START, dd=1_000 * k)[0] for k in range(1, 10)]
    assert acks[-1] == 0x81 and mod.device.read("axis.1.error") == 1
    mod.clock.advance(10)
    assert observe(mod)[0] == 8_000  # the eighth job ran last; the ninth (9 mm) is lost
    assert mod.operate(1, 12, START, dd=9_000)[4] == 0  # repeated, it runs
    assert observe(mod)[0] == 9_000


@pytest.mark.manual("§7.2.2", "Fehler 5 \"Auftragsliste AG ist voll\": as error 1, from the AG; the last job "
                    "must be repeated")
def test_error_5_the_plc_job_list_overflows(devsim_device: Any) -> None:
    module = devsim_device("ip247", {}, transport="tcp")
    module.set("input.ANF1", True)
    module.set("input.END1", True)
    md = words(COM247)
    md[3], md[47] = 0x0001, 0  # module 0 (the SYS-ID's), axis 1; binary values
    host, port = module.port_url("ag").removeprefix("socket://").rsplit(":", 1)
    with AgClient(host, int(port)) as plc:
        assert plc.write_record(0, 20, 1, md)[8] == 0
        plc.operate(0, 5, "Start", b=1)
        plc.operate(0, 1, "Vorwärts", w=6000)
        module.advance(3)
        plc.operate(0, 1, "Stopp")
        acks = [plc.operate(0, 12, "Start", dd=1_000 * k)[0] for k in range(1, 10)]
        assert acks == [0x01] * 8 + [0x81] and module.read("axis.1.error") == 5
        module.advance(10)
        assert module.read("axis.1.position") == 8_000


@pytest.mark.manual("§7.2.2", "Fehler 2 \"Nicht erlaubter Auftrag\": a job with an undefined mode, or one "
                    "senseless here (starting an axis that already runs): the running mode is aborted and "
                    "the error shown")
def test_error_2_starting_a_running_axis_aborts_it(mod: Module) -> None:
    mod.ready()
    mod.operate(1, 6, START, w=1000, dd=400_000)
    mod.clock.advance(2)
    assert mod.operate(1, 6, START, w=1000, dd=400_000)[4] == 2
    mod.clock.advance(60)
    position, _, errors = observe(mod)
    assert mod.device.read("axis.1.running") is False and position < 100_000 and errors[0] == 2
    assert mod.operate(1, 40, START)[4] == 2  # mode 40 does not exist


@pytest.mark.manual("§7.2.2", "Fehler 6 \"Motor wartet auf externen Start\": signal 1 at the digital input "
                    "'externer Start/Stop' holds the selected mode")
def test_error_6_the_external_start_input_holds_the_job(mod: Module) -> None:
    mod.ready()
    mod.device.set("input.START1", True)
    assert mod.operate(1, 7, FORWARD, w=1000, dd=5_000)[4] == 6
    mod.clock.advance(10)
    assert observe(mod)[0] == 1_000  # still at the reference coordinate x_ref = 1 mm
    mod.device.set("input.START1", False)
    mod.clock.advance(10)
    assert observe(mod)[0] == 6_000


@pytest.mark.manual("§7.2.2", "Fehler 7: a jog or incremental velocity whose frequency lies outside 1 Hz … "
                    "maximum frequency: the frequency is set to the limit and this message given")
def test_error_7_a_too_fast_jog_runs_at_the_maximum_frequency(mod: Module) -> None:
    mod.ready()  # COM247's MD: 1.1 µm per pulse, f_max 100 kHz: 6600 mm/min at most
    assert mod.operate(1, 1, FORWARD, w=30_000)[4] == 7
    mod.clock.advance(5)
    assert mod.device.read("axis.1.running") is True
    assert mod.device.read("axis.1.velocity") == pytest.approx(100_000 * 1.1)  # base units per second


@pytest.mark.manual("§7.2.2", "Fehler 10 \"Referenzpunkt fehlt\": after switching on, and after machine data "
                    "are loaded for the first time, the reference point is missing; BA5 sets it")
def test_error_10_after_power_up_and_after_the_first_machine_data(mod: Module) -> None:
    assert mod.load_md()[8] == 0
    assert mod.operate(1, 6, START, w=1000, dd=5_000)[4] == 10
    assert mod.operate(1, 5, START, b=1)[4] == 0
    assert mod.operate(1, 6, START, w=1000, dd=5_000)[4] == 0
    mod.clock.advance(10)
    mod.device.fault("power", True)
    mod.device.fault("power", False)
    mod.clock.advance(2)
    assert mod.operate(1, 6, START, w=1000, dd=0)[4] == 10


@pytest.mark.manual("§7.2.2", "Fehler 12: once at least one correct machine-data set is on the module, its "
                    "module number can no longer be changed")
def test_error_12_the_module_number_is_frozen_by_correct_machine_data(mod: Module) -> None:
    assert mod.write(4, 24, 0, [11, 2, 0])[4] == 0  # without MD: a SYS-ID may change
    assert mod.load_md()[8] == 0
    assert mod.write(4, 24, 0, [12, 2, 0])[4] == 12
    assert mod.call(0x64, bytes((4, 70, 0, 0)))[8 + 12:8 + 18] == bytes((0, 11, 0, 2, 0, 0))


@pytest.mark.manual("§7.2.2", "Fehler 22: while an axis is in teach-in no program can be changed or transferred "
                    "over the data channel, and teach-in cannot be switched on on more than one axis")
def test_error_22_programs_are_locked_while_an_axis_teaches(mod: Module) -> None:
    mod.ready()
    mod.ready(axis=2)
    assert mod.store(5, PROGRAM_5)[4] == 0
    assert mod.operate(1, 10, START, b=7)[4] == 0
    assert mod.store(6, "%  6\nN1 X1 F100\nN2 M02\n")[4] == 22
    assert mod.write(4, 22, 5, lang.record_words(5, "%  5\nN1 X2 F100\nN2 M02\n"), flags=1)[4] == 22
    assert mod.operate(2, 10, START, b=8)[4] == 22
    assert mod.call(0x64, bytes((4, 65, 0, 0)))[8:] == struct.pack(">2H", 5, length(PROGRAM_5))  # program 5 only


@pytest.mark.manual("§7.2.2", "Fehler 30: with teach-in on only the jog and incremental modes are allowed")
def test_error_30_only_jog_and_incremental_moves_in_teach_in(mod: Module) -> None:
    mod.ready()
    mod.store(5, "%  5\nN1 X1 F100\nN2 M02\n")
    assert mod.operate(1, 10, START, b=7)[4] == 0
    for ba, cmd, b in ((5, START, 1), (8, START, 5), (9, START, 5), (12, START, 0), (13, FORWARD, 0),
                       (14, START, 0), (15, FORWARD, 0), (16, START, 0)):
        assert mod.operate(1, ba, cmd, b=b)[4] == 30, ba
    assert mod.operate(1, 7, FORWARD, w=1000, dd=1_000)[4] == 0
    mod.clock.advance(5)
    assert mod.operate(1, 1, FORWARD, w=1000)[4] == 0


@pytest.mark.manual("§7.2.2", "Fehler 46: entering or deleting a program on axes 1 … 3, entering or deleting "
                    "machine data on the data channel (axis 4), or any of the operator modes 1 … 17 there "
                    "except 17")
def test_error_46_modes_on_the_wrong_page(mod: Module) -> None:
    text = PROGRAM_5
    for page in (1, 2, 3):
        answer = mod.write(page, 22, 5, lang.record_words(5, text))
        assert (answer[0], answer[4]) == (0x80, 46)
    mod.store(5, text)
    answer = mod.call(0x65, bytes((2, 23, 5)))
    assert (answer[0], answer[4]) == (0x80, 46) and mod.device.read("programs") == [[5, length(text)]]
    answer = mod.write(4, 20, 101, words(COM247))
    assert (answer[0], answer[4]) == (0x80, 46) and mod.device.read("axis.1.md_error") == -1
    assert mod.call(0x65, bytes((4, 21, 101)))[4] == 46
    for ba, cmd in ((1, FORWARD), (2, BACKWARD), (4, START), (5, START), (6, START), (7, FORWARD), (8, START),
                    (9, START), (10, START), (11, START), (12, START), (13, FORWARD), (14, START),
                    (15, FORWARD), (16, START)):
        answer = mod.operate(4, ba, cmd)
        assert (answer[0], answer[4]) == (0x80, 46), ba
    assert mod.operate(4, 17, START)[:5] == bytes((0, 4, 17, 1, 0))


@pytest.mark.manual("§7.2.2", "Fehler 51 \"Verfahrprogramm ist aktiv\": a program that is being executed may "
                    "not be changed or deleted")
def test_error_51_a_running_program_is_neither_changed_nor_deleted(mod: Module) -> None:
    mod.ready()
    text = "%  5\nN1 X100 F1000\nN2 M02\n"
    mod.store(5, text)
    mod.operate(1, 8, START, b=5)
    mod.clock.advance(1)
    assert mod.call(0x65, bytes((4, 23, 5)))[4] == 51
    assert mod.write(4, 22, 5, lang.record_words(5, "%  5\nN1 X1 F100\nN2 M02\n"), flags=1)[4] == 51
    assert mod.device.read("program.5") == text and mod.device.read("axis.1.running") is True


@pytest.mark.manual("§7.2.2", "Fehler 61: the program left the directory only: a program with the same number "
                    "may be transferred again, but deleting freed no room in the program memory")
def test_error_61_delete_while_another_program_runs(mod: Module) -> None:
    mod.ready()
    running = "%  5\nN1 X100 F1000\nN2 M02\n"
    mod.store(5, running)
    for number in range(6, 11):  # five programs of about 1000 characters: 6000 - 5027 characters left
        assert mod.store(number, filler(number))[4] == 0
    mod.operate(1, 8, START, b=5)
    mod.clock.advance(1)
    assert mod.call(0x65, bytes((4, 23, 6)))[4] == 61
    directory = struct.unpack(">10H", mod.call(0x64, bytes((4, 65, 0, 0)))[8:])
    assert directory[::2] == (5, 7, 8, 9, 10)
    assert mod.store(6, "%  6\nN1 M02\n")[4] == 0  # the number is free again
    assert mod.store(11, filler(11))[4] == 24  # the room is not: it would fit after a compacting delete
    mod.operate(1, 8, STOP)
    mod.operate(1, 8, STOP)  # the program context ends: nothing executes
    mod.clock.advance(5)
    assert mod.call(0x65, bytes((4, 23, 6)))[4] == 0
    assert mod.store(11, filler(11))[4] == 0


@pytest.mark.manual("§7.2.2", "Fehler 53 \"Leistungsteil einschalten\": the power unit's ready input must be high "
                    "while the power unit is on")
def test_error_53_without_the_power_units_ready_signal(mod: Module) -> None:
    mod.ready()
    mod.device.set("input.BB1", False)
    assert mod.operate(1, 7, FORWARD, w=1000, dd=1_000)[4] == 53
    mod.clock.advance(5)
    assert observe(mod)[0] == 1_000  # still at the reference coordinate x_ref = 1 mm
    mod.device.set("input.BB1", True)
    assert mod.operate(1, 7, FORWARD, w=1000, dd=1_000)[4] == 0


@pytest.mark.manual("§7.2.2", "Fehler 55 \"AG ist ausgefallen\": with X21 at 2-3 the module sees the CPU's BASP; "
                    "the traverse motions of all three axes are aborted")
def test_error_55_basp_aborts_all_three_axes(mod: Module) -> None:
    for axis in (1, 2, 3):
        mod.ready(axis)
        mod.operate(axis, 1, FORWARD, w=1000)
    mod.clock.advance(1)
    mod.device.set("input.BASP", True)
    mod.clock.advance(5)
    assert [mod.device.read(f"axis.{n}.running") for n in (1, 2, 3)] == [False] * 3
    assert observe(mod)[2][:3] == bytes((55, 55, 55))


@pytest.mark.manual("§7.2", "4 \"Achse in Betrieb ==> Eingabe nicht möglich\": machine data cannot be entered "
                    "while the axis runs")
@pytest.mark.manual("§7.2", "17 \"Maschinendaten überschreiben ?\"; 13 \"Datenbaustein nicht vorhanden\"")
def test_errors_4_13_and_17_of_the_machine_data_records(mod: Module) -> None:
    mod.ready()
    mod.operate(1, 1, FORWARD)
    assert mod.write(1, 20, 101, words(COM247), flags=1)[4] == 4
    assert mod.call(0x65, bytes((1, 21, 101)))[4] == 4
    mod.operate(1, 1, STOP)
    mod.clock.advance(5)
    assert mod.write(1, 20, 101, words(COM247))[4] == 17
    assert mod.call(0x64, bytes((1, 67, 55, 0)))[4] == 13
    assert mod.call(0x65, bytes((1, 21, 55)))[4] == 13 and mod.device.read("axis.1.md_error") == 0


@pytest.mark.manual("§7.2", "18 \"Max. Programmzahl erreicht\"; 19 \"Datenbaustein nicht vorhanden\"; "
                    "20 \"Verfahrprogramm überschreiben ?\"; 49 \"Verfahrprogramm bereits vorhanden ! Prog-Nr. "
                    "ändern\"; 24 \"Zu wenig Platz für Verfahrprogramm\"; 48 \"Verfahrprogramm fehlerhaft\"")
def test_the_program_memory_errors(mod: Module, devsim_device: Any) -> None:
    for number in range(255):
        assert mod.store(number, f"%{number:3d}\nN1 M02\n")[4] == 0
    assert mod.store(255, "%255\nN1 M02\n")[4] == 18
    assert mod.call(0x65, bytes((4, 23, 0)))[4] == 0
    assert mod.call(0x64, bytes((4, 69, 0, 0)))[4] == 19
    assert mod.store(1, "%  1\nN1 M02\n")[4] == 20
    for number in range(1, 255):
        mod.call(0x65, bytes((4, 23, number)))
    assert [mod.store(number, filler(number))[4] for number in range(1, 7)] == [0] * 5 + [24]  # 6000 characters
    answer = mod.store(0, "%  0\nN1 X1\nN2 M02\n")
    assert answer[4] == 48 and struct.unpack(">2H", answer[8:12]) == (6, 1)  # X without F
    plc = devsim_device("ip247", {}, transport="tcp")
    host, port = plc.port_url("ag").removeprefix("socket://").rsplit(":", 1)
    with AgClient(host, int(port)) as ag:
        ag.write_record(3, 22, 1, lang.record_words(1, "%  1\nN1 M02\n"))
        assert ag.write_record(3, 22, 1, lang.record_words(1, "%  1\nN1 M02\n"), overwrite=True)[4] == 49


@pytest.mark.manual("§7.2", "23 \"Verfahrbereichsüberschreitung\"; 28/29 \"Software-Endschalter Anfang/Ende "
                    "überfahren\"")
def test_errors_23_28_and_29_at_the_software_limits(mod: Module) -> None:
    mod.ready()  # COM247's MD: software limits −10 mm … +500 mm
    assert mod.operate(1, 6, START, w=1000, dd=600_000)[4] == 23
    assert mod.operate(1, 7, BACKWARD, w=1000, dd=20_000)[4] == 23
    mod.operate(1, 1, BACKWARD, w=1000)
    mod.clock.advance(30)
    assert mod.device.read("axis.1.error") == 28 and mod.device.read("axis.1.running") is False
    mod.operate(1, 6, START, w=6000, dd=499_000)
    mod.clock.advance(120)
    mod.operate(1, 1, FORWARD, w=1000)
    mod.clock.advance(30)
    assert mod.device.read("axis.1.error") == 29 and mod.device.read("axis.1.running") is False


@pytest.mark.manual("§7.2", "25/26 \"Endschalter Anfang/Ende überfahren\"; 27 \"externer STOP aufgetreten\"")
def test_errors_25_26_and_27_from_the_digital_inputs(make: Make) -> None:
    mod = make({"axes": {1: {"anf": -5_000.0, "end": 20_000.0}}})
    mod.ready()
    mod.operate(1, 1, FORWARD, w=1000)
    mod.clock.advance(10)
    assert mod.device.read("axis.1.error") == 26
    mod.operate(1, 1, BACKWARD, w=1000)
    mod.clock.advance(30)
    assert mod.device.read("axis.1.error") == 25
    mod.operate(1, 7, FORWARD, w=1000, dd=10_000)
    mod.clock.advance(0.2)
    mod.device.set("input.START1", True)
    mod.clock.advance(5)
    assert mod.device.read("axis.1.error") == 27 and mod.device.read("axis.1.running") is False


@pytest.mark.manual("§7.2", "33 \"Zykluszeit überschritten\": an endless loop without any traverse or dwell "
                    "ends the program with this error; the module stays answering")
def test_error_33_an_endless_loop_without_motion(mod: Module) -> None:
    mod.ready()
    assert mod.store(1, "%  1\nN1 G24 F0\nN2 G90\nN3 G20\nN4 M02\n")[4] == 0
    answer = mod.operate(1, 8, START, b=1)
    assert answer[4] == 33 and mod.device.read("axis.1.running") is False
    assert mod.operate(1, 7, FORWARD, w=1000, dd=1_000)[4] == 0


@pytest.mark.manual("§7.2", "38 \"Endlosschleife nur als äussere Schleife\"; 39 \"Schachtelungstiefe "
                    "überschritten\"")
def test_errors_38_and_39_of_loops_and_subprograms(mod: Module) -> None:
    mod.ready()
    mod.store(30, "L 30\nN1 G24 F0\nN2 X1 F100\nN3 G20\nN4 M02\n")
    mod.store(1, "%  1\nN1 L30\nN2 M02\n")
    assert mod.operate(1, 8, START, b=1)[4] == 38
    for number in range(40, 46):
        mod.store(number, f"L{number:3d}\nN1 L{number + 1}\nN2 M02\n")
    mod.store(46, "L 46\nN1 X1 F100\nN2 M02\n")
    mod.store(2, "%  2\nN1 L40\nN2 M02\n")
    assert mod.operate(1, 8, START, b=2)[4] == 39


@pytest.mark.manual("§7.2", "43 \"Verfahrgeschwindigkeit zu gross\"; 58 \"Verfahrgeschwindigkeit zu klein\"")
def test_errors_43_and_58_of_a_programs_velocity(mod: Module) -> None:
    mod.ready()  # 1.1 µm per pulse, f_max 100 kHz: 6600 mm/min at most
    mod.store(1, "%  1\nN1 X10 F7000\nN2 M02\n")
    assert mod.operate(1, 8, START, b=1)[4] == 43
    slow = record(gear=400_000, pulses_per_rev=12, patterns=4, f_max=100, f_ss=1, a=100, jog1=6000, jog2=6000,
                  step_velocity=6000, reference_velocity=6000)
    assert mod.load_md(record=slow, axis=2)[8] == 0
    mod.operate(2, 5, START, b=1)  # 33.3 mm per pulse: F1 is below 1 Hz
    mod.store(2, "%  2\nN1 X10 F1\nN2 M02\n")
    assert mod.operate(2, 8, START, b=2)[4] == 58


@pytest.mark.manual("§7.2", "65 \"Verfahrprogramm wartet auf Fortsetzung\": a program stopped with Stopp waits; "
                    "Übernahme continues it")
def test_error_65_an_interrupted_program_waits(mod: Module) -> None:
    mod.ready()
    mod.store(1, "%  1\nN1 X20 F1000\nN2 M02\n")
    mod.operate(1, 8, START, b=1)
    mod.clock.advance(0.5)
    assert mod.operate(1, 8, STOP)[4] == 65
    mod.clock.advance(5)
    assert mod.device.read("axis.1.running") is False and observe(mod)[1] > 0
    assert mod.operate(1, 8, TAKE_OVER)[4] == 0
    mod.clock.advance(30)
    assert observe(mod)[:2] == (20_000, 0)


@pytest.mark.manual("§7.2", "33 \"Zykluszeit überschritten\": also an endless loop whose only traverse has "
                    "length 0 ends with this error; the module stays answering")
def test_error_33_an_endless_loop_of_empty_traverses(mod: Module) -> None:
    mod.ready()
    assert mod.store(1, "%  1\nN1 G91\nN2 G24 F0\nN3 X0 F100\nN4 G20\nN5 M02\n")[4] == 0
    assert mod.operate(1, 8, START, b=1)[4] == 33
    assert mod.device.read("axis.1.running") is False
    assert mod.store(2, "%  2\nN1 G91\nN2 G24 F3\nN3 X0 F100\nN4 G20\nN5 X1 F100\nN6 M02\n")[4] == 0
    assert mod.operate(1, 8, START, b=2)[4] == 0
    mod.clock.advance(5)
    assert observe(mod)[:2] == (2_000, 0)  # three empty traverses, then 1 mm from x_ref = 1 mm


@pytest.mark.manual("§7.2.2", "Fehler 52: a flying change (G10) whose conditions are not met cannot be executed")
@pytest.mark.manual("§7.2", "47 \"Keine Richtungsänderung bei fliegendem Wechsel\" (rotary axis)")
def test_errors_52_and_47_of_the_flying_change(mod: Module) -> None:
    mod.ready()
    mod.store(1, "%  1\nN1 G10 X20 F1000\nN2 X10 F1000\nN3 M02\n")  # the chain would reverse
    assert mod.operate(1, 8, START, b=1)[4] == 52 and mod.device.read("axis.1.running") is False
    mod.store(2, "%  2\nN1 G10 X20 F1000\nN2 G04 F10\nN3 M02\n")  # a dwell cannot be joined
    assert mod.operate(1, 8, START, b=2)[4] == 52
    rotary = record(rotary=True, unit=3, limit_begin=0, limit_end=360_000, reference=0)
    assert mod.load_md(axis=2, record=rotary)[8] == 0
    mod.operate(2, 5, START, b=1)
    mod.store(3, "%  3\nN1 G10 X90 F1000\nN2 X45 F1000\nN3 M02\n")  # G25: forward, then back the short way
    assert mod.operate(2, 8, START, b=3)[4] == 47


@pytest.mark.manual("§7.2", "62 \"Unzulässige Wegangabe\": a coordinate beyond ±100 m; 63 \"Unzulässige "
                    "Werkzeugkorrektur\": a rotary tool offset not shorter than the range")
def test_errors_62_and_63(mod: Module) -> None:
    mod.ready()
    assert mod.operate(1, 12, START, dd=100_000_000)[4] == 62
    assert mod.operate(1, 13, FORWARD, dd=-100_000_000)[4] == 62
    assert mod.operate(1, 15, FORWARD, dd=100_000_000)[4] == 62
    rotary = record(rotary=True, unit=3, limit_begin=0, limit_end=360_000, reference=0)
    assert mod.load_md(axis=2, record=rotary)[8] == 0
    mod.operate(2, 5, START, b=1)
    assert mod.operate(2, 15, FORWARD, dd=360_000)[4] == 63
    assert mod.operate(2, 15, FORWARD, dd=359_999)[4] == 0


@pytest.mark.manual("§7.2", "66 \"Wegangabe nicht BCD-codiert\"; 67 \"Geschwindigkeit nicht BCD-codiert\" (AG "
                    "values with 'AG BCD-codiert')")
def test_errors_66_and_67_from_the_plc(devsim_device: Any) -> None:
    module = devsim_device("ip247", {}, transport="tcp")
    module.set("input.ANF1", True)
    module.set("input.END1", True)
    md = words(COM247)
    md[3], md[47] = 0x0001, 1
    host, port = module.port_url("ag").removeprefix("socket://").rsplit(":", 1)
    with AgClient(host, int(port)) as plc:
        plc.write_record(0, 20, 1, md)
        plc.operate(0, 5, "Start", b=1)
        assert plc.operate(0, 6, "Start", w=0x1000, dd=0x0000_A000)[4] == 66
        assert plc.operate(0, 6, "Start", w=0x10A0, dd=0x0001_0000)[4] == 67
        assert plc.operate(0, 7, "Vorwärts", w=0x1000, dd=0x0000_0F00)[4] == 66
        module.advance(5)
        assert module.read("axis.1.position") == 1_000  # nothing moved
        assert plc.operate(0, 7, "Vorwärts", w=0x1000, dd=0x0000_1000)[4] == 0


@pytest.mark.manual("§7.2", "3 \"Satz abgespeichert\": in teach-in Übernahme stores the position as a block")
@pytest.mark.manual("§7.2", "8 \"Zustand nach Spannungsausfall auf der Baugruppe\" on every page after power-up")
def test_messages_3_and_8(mod: Module) -> None:
    assert observe(mod)[2] == bytes((8, 8, 8, 8))
    mod.ready()
    mod.operate(1, 10, START, b=7)
    mod.operate(1, 7, FORWARD, w=1000, dd=4_000)
    mod.clock.advance(10)
    assert mod.operate(1, 7, TAKE_OVER)[4] == 3
    mod.operate(1, 11, START)
    assert mod.device.read("program.7").splitlines()[1] == "N1 X5.000 F1000"


#: §7.2.1, each machine-data error at the edges the manual names (from COM247's record: f_max 100 kHz,
#: f_ss 10 kHz, 1000 pulses and 1.1 mm per revolution, software limits −10 mm … +500 mm).
MD_EDGES: list[tuple[dict[str, object], int]] = [
    ({"pulse_us": 0}, 2), ({"pulse_us": 32}, 2), ({"pulse_us": 5}, 2), ({"pulse_us": 4}, 0),
    ({"f_max": 100_001}, 3), ({"f_max": 100_000}, 0),
    ({"jog1": 6601}, 4), ({"step_velocity": 6601}, 4), ({"jog2": 6600}, 0),
    ({"pulses_per_rev": 11, "patterns": 11}, 5), ({"pulses_per_rev": 1001, "patterns": 7}, 5),
    ({"a": 19}, 6), ({"a": 36_000}, 6), ({"a": 37_000}, 0),
    ({"limit_begin": 500_000}, 7),
    ({"reference": 500_000}, 8), ({"reference": -10_000}, 8), ({"reference": 499_999}, 0),
    ({"gear": 11}, 9), ({"gear": 999}, 9), ({"gear": 1000}, 0),
    ({"patterns": 3}, 10), ({"patterns": 41}, 10), ({"patterns": 7}, 10), ({"patterns": 40}, 0),
    ({"unit": 0}, 11), ({"unit": 4}, 11),
    ({"module": 12}, 12),
    ({"zero_offsets": (100_000_000, 0, 0, 0)}, 13), ({"zero_offsets": (0, 0, 0, -99_500_000)}, 13),
    ({"zero_offsets": (0, 0, 0, -99_400_000)}, 0),
    ({"tool_length": 99_600_000}, 14),
    ({"reference_direction": 0x10}, 15), ({"reference_sync": 2}, 15),
    ({"reference_velocity": 660}, 17), ({"reference_velocity": 661}, 0),
    ({"pulse_polarity": 0x20}, 18),
    ({"backlash": 65_000}, 20), ({"backlash": 64_999}, 0),
    ({"rotary": True, "unit": 3, "limit_begin": 360_000, "limit_end": 0, "reference": 0}, 21),
    ({"f_ss": 0}, 22), ({"f_ss": 10_001}, 22),
]


@pytest.mark.manual("§7.2.1", "machine data are checked on the module; a faulty set gives 'Fehlerhafte "
                    "Maschinendaten' (15) and carries its MD error number in the set (read back with BA67/68)")
@pytest.mark.manual("§7.2.1", "2: pulse duration 1 … 31 µs and below half the period of the maximum frequency; "
                    "3: maximum frequency up to 100 kHz; 4: jog/step velocity at 1 Hz … f_max")
@pytest.mark.manual("§7.2.1", "5: pulses per revolution 12 … 1000; 6: frequency increase 0.020 … 2599.999 Hz/ms "
                    "with τ within 5 … 2600 ms; 7: SW limit start below SW limit end; 8: reference point "
                    "between the SW limits")
@pytest.mark.manual("§7.2.1", "9: gear 0.012 … 400 mm with a resolution of at least 1 µm; 10: 4 … 40 current "
                    "patterns dividing the pulses per revolution; 11: unit 1, 2 or 3; 12: module number of the "
                    "SYS-ID")
@pytest.mark.manual("§7.2.1", "13: zero offsets within ±100 m and not shifting the SW limits out of it; 14: tool "
                    "length within ±100 m; 15: reference direction 00H/20H, synchronisation 0/1")
@pytest.mark.manual("§7.2.1", "17: reference frequency above f_ss; 18: edge 0 or 40H; 20: backlash 0 … 64999 µm; "
                    "21: rotary range start below its end; 22: start/stop frequency 1 Hz … 10 kHz")
@pytest.mark.parametrize(("changes", "error"), MD_EDGES)
def test_each_machine_data_error_at_its_edges(mod: Module, changes: dict[str, object], error: int) -> None:
    answer = mod.load_md(record=record(**changes))
    assert (answer[8], answer[4]) == (error, 15 if error else 0)
    overview = struct.unpack(">15H", mod.call(0x64, bytes((4, 68, 0, 0)))[8:])
    assert overview[:5] == (101, int(changes.get("module", 11)), 1, 70, error)  # type: ignore[call-overload]
    assert struct.unpack(">70H", mod.call(0x64, bytes((1, 67, 101, 0)))[8:])[4] & 0xFF == error


@pytest.mark.manual("§7.2.1", "19: the limit switches selected by the polarity must be present (not actuated) "
                    "when the machine data are entered")
def test_md_error_19_with_an_actuated_limit_switch(mod: Module) -> None:
    mod.device.set("input.ANF1", True)
    mod.device.set("input.END1", False)  # NC contact at 0 V: actuated (or not wired)
    answer = mod.write(1, 20, 101, words(COM247))
    assert (answer[8], answer[4]) == (19, 15)


@pytest.mark.manual("§7.2.2", "Fehler 7: a velocity whose frequency is below 1 Hz runs at 1 Hz, with this "
                    "message")
def test_error_7_a_too_slow_jog_runs_at_1_hz(mod: Module) -> None:
    slow = record(gear=400_000, pulses_per_rev=12, patterns=4, f_max=100, f_ss=1, a=100, jog1=6000, jog2=6000,
                  step_velocity=6000, reference_velocity=6000)  # 33.333 mm per pulse
    assert mod.load_md(record=slow)[8] == 0
    mod.operate(1, 5, START, b=1)
    assert mod.operate(1, 1, FORWARD, w=1)[4] == 7  # 1 mm/min: 0.0005 Hz
    mod.clock.advance(5)
    assert mod.device.read("axis.1.velocity") == pytest.approx(400_000 / 12)  # one pulse per second


@pytest.mark.manual("§7.2.2", "two kinds of module errors: axis errors that abort the motion, and warnings or "
                    "notes for information only (errors 1 to 9)")
def test_warnings_do_not_abort_the_motion(mod: Module) -> None:
    mod.ready()
    assert mod.operate(1, 1, FORWARD, w=30_000)[4] == 7  # warning: the jog runs at f_max
    mod.clock.advance(1)
    assert mod.write(1, 20, 101, words(COM247), flags=1)[4] == 4  # warning: no input while running
    mod.clock.advance(1)
    assert mod.device.read("axis.1.running") is True and mod.device.read("axis.1.velocity") > 0
    mod.operate(1, 1, STOP)
    mod.clock.advance(5)
    assert mod.operate(1, 6, START, w=1000, dd=450_000)[4] == 0
    mod.clock.advance(1)
    assert mod.operate(1, 6, START, w=1000, dd=450_000)[4] == 2  # an axis error: the move is aborted
    mod.clock.advance(5)
    assert mod.device.read("axis.1.running") is False


@pytest.mark.manual("§3.1.3", "two LEDs show operation and errors: green while the module runs, red while an "
                    "axis error is pending (warnings 1 … 9 do not light it)")
def test_the_red_led_shows_axis_errors(mod: Module) -> None:
    mod.operate(4, 17, START)
    assert (mod.device.read("output.led_green"), mod.device.read("output.led_red")) == (True, False)
    mod.load_md()
    assert mod.operate(1, 6, START, w=1000, dd=5_000)[4] == 10
    assert mod.device.read("output.led_red") is True
    mod.operate(4, 17, START)
    assert mod.device.read("output.led_red") is False
    mod.operate(1, 5, START, b=1)
    assert mod.operate(1, 1, FORWARD, w=30_000)[4] == 7
    assert mod.device.read("output.led_red") is False
