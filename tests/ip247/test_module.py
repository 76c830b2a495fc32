"""The IP247 kind through its PG port on a real pty, in virtual time (spec ip247.md §3.2, §4.1, §4.2,
§5.4–§5.14, §4.14; vectors §3.6.7 b and e, §5.9, §5.12, §6.2, §6.9)."""

from __future__ import annotations

import json
import struct

import pytest

from devsim.core.points import BadValue
from devsim.devices.ip247 import program as lang
from devsim.devices.ip247.machine_data import Ramp
from devsim.runtime import Runtime
from tests.ip247.helpers import BACKWARD, FORWARD, START, STOP, TAKE_OVER, Make, Module, record
from tests.ip247.test_machine_data import COM247, words
from tests.support.memory import refused_memory


def test_power_up_state(mod: Module) -> None:
    """§4.14: BA4 on every axis, error 8 pending on all four pages, no MD, no reference."""
    obs = mod.call(0x62, b"\x01")
    assert obs[:8] == bytes((0, 1, 0, 0, 8, 4, 0xE2, 2))
    assert obs[16:20] == bytes((8, 8, 8, 8))


def test_vector_b_automatic_start_answers_running_and_m255(mod: Module) -> None:
    mod.ready()
    assert mod.store(5, "%  5 TEST\nN1 X10 F1000\nN2 M02\n")[8:] == bytes(4)
    answer = mod.operate(1, 8, START, b=5)
    assert answer == bytes.fromhex("00 01 08 01 00 08 02 FF")
    mod.clock.advance(5)
    assert mod.operate(1, 66, START)[:1] == b"\x80"  # BA66 is a record mode, not an operator job
    assert mod.device.read("axis.1.position") == 10_000 and mod.device.read("axis.1.m_function") == 2


@pytest.mark.manual("§2.5", "without correct machine data an operator command to the axis is refused with "
                    "Keine oder fehlerhafte Maschinendaten (14)")
@pytest.mark.manual("§2.2", "an axis works only when a correct machine-data record is on the module")
def test_without_md_only_ba4_and_ba17_run(mod: Module) -> None:
    """§4.2: error 14 without machine data; BA17 clears every page's error."""
    assert mod.operate(1, 1, FORWARD)[4] == 14
    assert mod.operate(1, 4, START)[4] == 0
    assert mod.operate(4, 17, START)[4] == 0
    assert mod.call(0x62, b"\x02")[16:20] == bytes(4)


def test_page_rules_and_undefined_modes(mod: Module) -> None:
    """§3.2/§3.6.5: BA18 negatively acknowledged; BA1 on the data channel 80H + error 46; an
    undefined mode is accepted with error 2; program input on an axis page is 80H + 46."""
    assert mod.operate(1, 18, START)[0] == 0x80
    answer = mod.operate(4, 1, FORWARD)
    assert answer[0] == 0x80 and answer[4] == 46
    answer = mod.operate(2, 33, START)
    assert answer[0] == 0 and answer[4] == 2
    answer = mod.store(7, "%  7\nN1 M02\n")
    assert answer[0] == 0 and answer[4] == 0
    answer = mod.write(1, 22, 8, lang.record_words(8, "%  8\nN1 M02\n"))
    assert answer[0] == 0x80 and answer[4] == 46


def test_md_round_trip_directory_and_no_overwrite(mod: Module) -> None:
    """§6.2 record stored as DB 101, read back (BA67) with the MD error 0; a second write is
    error 17 unless the PG's overwrite flag is set; BA64 lists it."""
    assert mod.load_md()[8:10] == b"\x00\x00"
    record = mod.call(0x64, bytes((1, 67, 101, 0)))[8:]
    assert struct.unpack(">70H", record)[3] == 0x0B01 and struct.unpack(">70H", record)[2] == 0x4265
    assert mod.load_md()[4] == 17
    assert mod.write(1, 20, 101, words(COM247), flags=1)[4] == 0
    assert mod.call(0x64, bytes((4, 64, 0, 0)))[8:] == struct.pack(">6H", 101, 70, 0, 0, 0, 0)


@pytest.mark.manual("§2.7.1", "the attribute MD missing is cleared once machine data are transferred, even "
                    "faulty ones; only error-free machine data let operator commands move the axis")
def test_md_error_12_when_the_module_number_differs(make: Make) -> None:
    """§6.3: the record names module 11; a module with SYS-ID module 5 gives MD error 12 and
    module error 15; the attributes say MD present (bit 6 clear) but motion is refused (14)."""
    mod = make({"sys_id": {"module": 5}})
    answer = mod.load_md()
    assert answer[8] == 12 and answer[4] == 15 and answer[6] & 0x40 == 0
    assert mod.operate(1, 1, FORWARD)[4] == 14


@pytest.mark.manual("§2.5.3.7", "the acceleration ramp is f = F(1 - e^(-t/tau)) + f_ss with F = (f_max - "
                    "f_ss)/0.95, the deceleration ramp its mirror; below f_max the acceleration stops at f_v")
@pytest.mark.manual("§2.5.3.4", "the travel resolution is the travel per revolution divided by the pulses per "
                    "revolution")
@pytest.mark.manual("§2.5.4.2", "velocity [unit/min] = frequency x resolution x 60")
@pytest.mark.manual("§2.7.7", "position reached is set when the target of a positioning is reached")
def test_ba7_takes_the_closed_form_time(mod: Module) -> None:
    """§5.3/§5.5: 10 mm at 1000 mm/min with r = 1.1 µm, f_ss 10 kHz, a 100 Hz/ms: the two
    exponential ramps and the cruise take exactly what the formulas say; PE at the end."""
    mod.ready()
    md = mod.m.units[0].md
    ramp, r = Ramp(100_000, 10_000, 100.0), 1.1
    f = 1000 * 1000 / (60 * r)
    pulses = 10_000 / r
    expected = 2 * ramp.time_to(f) + (pulses - 2 * ramp.pulses_to(f)) / f
    assert md is not None and md.resolution == r
    assert mod.operate(1, 7, FORWARD, w=1000, dd=10_000)[4] == 0
    mod.clock.advance(expected - 1e-6)
    assert mod.device.read("axis.1.running") is True and mod.device.read("output.PE1") is False
    mod.clock.advance(2e-6)
    assert mod.device.read("axis.1.running") is False and mod.device.read("output.PE1") is True
    assert mod.device.read("axis.1.position") == 1_000 + 10_000  # (from the reference coordinate, 1 mm)


def test_stop_keeps_the_residual_and_ba7_by_it_reaches_the_target(mod: Module) -> None:
    mod.ready()
    mod.operate(1, 6, START, w=1000, dd=50_000)
    mod.clock.advance(1.0)
    assert mod.operate(1, 6, STOP)[4] == 0
    mod.clock.advance(5)
    residual = mod.device.read("axis.1.residual")
    assert residual > 0 and mod.device.read("output.PE1") is False
    assert residual + mod.device.read("axis.1.position") == 50_000
    mod.operate(1, 7, FORWARD, w=1000, dd=residual)
    mod.clock.advance(60)
    assert mod.device.read("axis.1.position") == 50_000 and mod.device.read("output.PE1") is True


@pytest.mark.manual("§4.1.1", "operator commands given while the axis runs give Nicht erlaubter Auftrag (2) "
                    "and abort the running action")
def test_a_job_while_running_is_error_2_and_aborts(mod: Module) -> None:
    """§3.1: an operator command on a running axis (not Stopp, not BA4) aborts with error 2."""
    mod.ready()
    mod.operate(1, 1, FORWARD)
    mod.clock.advance(0.5)
    assert mod.operate(1, 6, START, dd=0)[4] == 2
    mod.clock.advance(5)
    assert mod.device.read("axis.1.running") is False and mod.device.read("axis.1.mode") == 1


@pytest.mark.manual("§2.8.3", "only the limit switch in the direction of travel is detected: the other "
                    "direction stays free")
def test_jog_into_a_limit_switch_stops_with_26_and_locks_forward(make: Make) -> None:
    """§5.7: END actuated while jogging forward: error 26, the direction is locked; backward
    is allowed and releases it once the switch is left."""
    mod = make({"axes": {1: {"end": 20_000.0}}})
    mod.ready()
    mod.operate(1, 1, FORWARD, w=1000)
    mod.clock.advance(10)
    assert mod.device.read("axis.1.error") == 26 and mod.device.read("axis.1.running") is False
    assert mod.operate(1, 1, FORWARD, w=1000)[4] == 26
    mod.operate(1, 1, BACKWARD, w=1000)
    mod.clock.advance(2)
    mod.operate(1, 1, STOP)
    mod.clock.advance(2)
    assert mod.operate(1, 1, FORWARD, w=100)[4] == 0


@pytest.mark.manual("§4.2.4", "special case 1: the cam found before a limit switch reverses the run at the "
                    "end of the cam; back onto the cam at f_ss, then left in single steps in the reference "
                    "direction: the reference point")
def test_reference_run_ends_at_the_cam_edge(make: Make) -> None:
    """§5.6.2 (sync no; R backward in COM247's MD): the run goes forward over the cam, back over
    it, onto it again at f_ss and leaves it in single steps backward: H := x_ref there."""
    mod = make({"axes": {1: {"cam": [20_000.0, 30_000.0]}}})
    assert mod.load_md()[8] == 0
    assert mod.operate(1, 5, START, b=0)[4] == 0
    mod.clock.advance(120)
    assert mod.device.read("axis.1.reference_set") is True and mod.device.read("axis.1.running") is False
    md = mod.m.units[0].md
    assert md is not None and mod.device.read("axis.1.position") == md.reference
    machine = mod.device.read("axis.1.machine_position")
    assert 20_000 - 2 * md.resolution < machine < 20_000  # just off the cam's edge


def test_zero_offset_relative_vector_e(mod: Module) -> None:
    """§3.6.7 (e) / §2.6.6.7: BA13 10 mm forward at actual 0 gives −10 mm."""
    mod.ready(axis=2)
    mod.operate(2, 12, START, dd=0)
    assert mod.call(0x61, bytes.fromhex("02 0D 03 00 00 00 00 00 27 10"))[4] == 0
    assert mod.device.read("axis.2.position") == -10_000


@pytest.mark.manual("§4.3.2", "BA9 Start runs the blocks up to the first traverse or dwell, then waits for "
                    "the Übernahme command")
@pytest.mark.manual("§4.3.2", "each further traverse must be started separately with Übernahme")
def test_single_block_halts_and_stop_interrupts_with_65(mod: Module) -> None:
    """§5.11.3/§5.11.5: BA9 halts before the first traverse and after each; Übernahme goes on;
    Stopp at a halt interrupts (65, context kept); a second Stopp aborts it."""
    mod.ready()
    mod.store(3, "%  3\nN1 X5 F1000 M11\nN2 X8 F1000 M12\nN3 M02\n")
    mod.operate(1, 9, START, b=3)
    mod.clock.advance(5)
    assert mod.device.read("axis.1.position") == 1_000 and mod.device.read("axis.1.running") is False
    assert mod.call(0x62, b"\x01")[21] & 0x08  # waiting for Übernahme before N1
    mod.operate(1, 9, TAKE_OVER, b=3)
    mod.clock.advance(5)
    assert mod.device.read("axis.1.position") == 5_000 and mod.device.read("axis.1.m_function") == 11
    assert mod.call(0x62, b"\x01")[21] & 0x08  # waiting for Übernahme
    mod.operate(1, 9, TAKE_OVER, b=3)
    mod.clock.advance(5)
    assert mod.device.read("axis.1.position") == 8_000 and mod.device.read("axis.1.m_function") == 12
    assert mod.operate(1, 9, STOP)[4] == 65
    assert mod.operate(1, 9, STOP)[4] == 0 and mod.m.units[0].automatic is None


@pytest.mark.manual("§4.3.1", "Stopp interrupts a program; Übernahme continues it at the interruption")
def test_interrupted_traverse_completes_on_take_over(mod: Module) -> None:
    mod.ready()
    mod.store(4, "%  4\nN1 X30 F1000 M20\nN2 M02\n")
    mod.operate(1, 8, START, b=4)
    mod.clock.advance(0.5)
    assert mod.operate(1, 8, STOP)[4] == 65
    mod.clock.advance(5)
    assert 0 < mod.device.read("axis.1.position") < 30_000
    assert mod.operate(1, 8, TAKE_OVER, b=4)[4] == 0
    mod.clock.advance(60)
    assert mod.device.read("axis.1.position") == 30_000 and mod.device.read("axis.1.m_function") == 2


def test_battery_ram_survives_power_but_not_a_battery_fault(make: Make) -> None:
    """§4.14: MD, programs and offsets kept across power-up (reference lost, error 8); a failed
    battery loses them at the next power-up."""
    mod = make()
    mod.ready()
    mod.store(9, "%  9\nN1 X1 F100\nN2 M02\n")
    mod.operate(1, 15, FORWARD, dd=2_000)
    mod.device.fault("power", True)
    mod.device.fault("power", False)
    assert mod.device.read("axis.1.reference_set") is False and mod.device.read("axis.1.error") == 8
    assert mod.device.read("axis.1.md_error") == 0 and mod.device.read("programs") == [[9, 17]]
    assert mod.m.units[0].coords.to_ba15 == 2_000
    mod.device.fault("battery_failed", True)
    mod.device.fault("power", True)
    mod.device.fault("power", False)
    assert mod.device.read("axis.1.md_error") == -1 and mod.device.read("programs") == []


@pytest.mark.manual("§4.3.4", "the example: positions 1258.250 mm and 3000 mm stored with Übernahme in "
                    "program 7, BA11 closes it: N1 X1258.250 F2500 / N2 X3000.000 F2500 / N3 M02")
def test_teach_in_example_of_section_5_12(make: Make) -> None:
    """§5.12: BA10 program 7; positions stored with Übernahme (message 3) as N<k> X… F<step
    velocity>; another axis cannot start teach-in (22); BA8 meanwhile is 30; BA11 closes."""
    mod = make()
    assert mod.load_md(record=record(step_velocity=2500, limit_end=5_000_000))[8] == 0
    mod.load_md(axis=2)
    mod.operate(1, 5, START, b=1)
    mod.operate(2, 5, START, b=1)
    assert mod.operate(1, 10, START, b=7)[4] == 0 and mod.device.read("axis.1.attributes") & 0x10
    mod.operate(1, 7, FORWARD, w=6000, dd=1_257_250)
    mod.clock.advance(60)
    assert mod.operate(1, 1, TAKE_OVER)[4] == 3
    mod.operate(1, 6, START, w=6000, dd=3_000_000)
    mod.clock.advance(60)
    assert mod.operate(1, 6, TAKE_OVER)[4] == 3
    assert mod.operate(2, 10, START, b=8)[4] == 22
    assert mod.operate(1, 8, START, b=7)[4] == 30
    assert mod.operate(1, 11, START)[4] == 0
    assert mod.device.read("program.7") == "%  7\nN1 X1258.250 F2500\nN2 X3000.000 F2500\nN3 M02\n"


@pytest.mark.manual("§2.9", "with BASP evaluated the PE outputs go low, the jobs on the axes are aborted and "
                    "AG ist ausgefallen (55) is given")
@pytest.mark.manual("§2.8.1", "the ready input BB monitors the power unit: without it motion is refused and "
                    "its loss stops the axis (53)")
def test_basp_and_the_power_unit_ready_input(mod: Module) -> None:
    """§5.13/§5.14: BASP stops every axis with error 55 and forces PE low; without BB a motion
    job is refused with 53, and BB falling during motion stops the pulses (53)."""
    mod.ready()
    mod.operate(1, 7, FORWARD, w=1000, dd=1_000)
    mod.clock.advance(5)
    assert mod.device.read("output.PE1") is True
    mod.operate(1, 1, FORWARD)
    mod.device.set("input.BASP", True)
    mod.clock.advance(5)
    assert mod.device.read("axis.1.error") == 55 and mod.device.read("axis.2.error") == 55
    assert mod.device.read("axis.1.running") is False and mod.device.read("output.PE1") is False
    mod.device.set("input.BASP", False)
    mod.device.set("input.BB1", False)
    assert mod.operate(1, 1, FORWARD)[4] == 53
    mod.device.set("input.BB1", True)
    mod.operate(1, 1, FORWARD)
    mod.clock.advance(1)
    mod.device.set("input.BB1", False)
    assert mod.device.read("axis.1.error") == 53 and mod.device.read("axis.1.running") is False


def test_the_plc_job_point_takes_bcd_values(mod: Module) -> None:
    """ag.operate: an FB164 job as the PLC sends it; with "AG BCD-codiert" 0012 0000H is 120 mm."""
    record = words(COM247)
    record[47] = 1
    mod.m.signals.set("ANF1", True)
    mod.m.signals.set("END1", True)
    assert mod.write(1, 20, 5, record)[8] == 0
    mod.device.set("ag.operate", {"page": 0, "ba": 5, "cmd": "Start", "b": 1})
    mod.device.set("ag.operate", {"page": 0, "ba": 6, "cmd": "Start", "w": 0x1000, "dd": 0x0012_0000})
    assert mod.device.read("ag.last")["err"] == 0
    mod.clock.advance(30)
    assert mod.device.read("axis.1.position") == 120_000


@pytest.mark.manual("§2.8.4", "BA9 with 1 at the input: the Übernahme gives Motor wartet auf externen Start; "
                    "the falling edge runs the traverse")
@pytest.mark.manual("§2.8.4", "a 1 applied after the traverse ended (position reached) interrupts the "
                    "program: error 65; after Übernahme the next traverse waits for the falling edge")
def test_external_start_vector_6_9(mod: Module) -> None:
    """§6.9/§5.10: with START-N/STOP = 1, BA9 halts before N1 (M00); Übernahme → error 6; the
    falling edge runs N1 to 100 mm; a rising edge after PE interrupts (65); Übernahme → 6; the
    falling edge runs N2 to 200 mm with M20."""
    mod.ready()
    mod.store(6, "%  6\nN1 X100 F2500 M00\nN2 X200 F1000 M20\nN3 M02\n")
    mod.device.set("input.START1", True)
    assert mod.operate(1, 9, START, b=6)[4] == 0
    mod.clock.advance(1)
    assert mod.device.read("axis.1.position") == 1_000  # (the reference coordinate: no motion)
    answer = mod.operate(1, 9, TAKE_OVER, b=6)
    assert answer[4] == 6 and mod.call(0x62, b"\x01")[21] & 0x01  # waiting for external start
    mod.device.set("input.START1", False)
    mod.clock.advance(10)
    assert mod.device.read("axis.1.position") == 100_000 and mod.device.read("output.PE1") is True
    mod.device.set("input.START1", True)
    assert mod.device.read("axis.1.error") == 65
    assert mod.operate(1, 9, TAKE_OVER, b=6)[4] == 6
    mod.device.set("input.START1", False)
    mod.clock.advance(30)
    assert mod.device.read("axis.1.position") == 200_000 and mod.device.read("axis.1.m_function") == 20


@pytest.mark.manual("§2.8.4", "a 0 to 1 change during a job gives externer Stopp aufgetreten (27) and aborts "
                    "the job")
@pytest.mark.manual("§2.8.4", "a job given while the input is 1 waits (error 6); Stopp with any mode cancels "
                    "the wait without error")
def test_external_stop_while_jogging_is_27_and_stopp_cancels_a_wait(mod: Module) -> None:
    mod.ready()
    mod.operate(1, 1, FORWARD)
    mod.clock.advance(0.5)
    mod.device.set("input.START1", True)
    mod.clock.advance(5)
    assert mod.device.read("axis.1.error") == 27 and mod.device.read("axis.1.running") is False
    assert mod.operate(1, 7, FORWARD, dd=1_000)[4] == 6
    assert mod.operate(1, 7, STOP)[4] == 0 and mod.device.read("axis.1.running") is False
    mod.device.set("input.START1", False)
    mod.clock.advance(5)
    assert mod.device.read("axis.1.residual") == 0 and mod.device.read("axis.1.running") is False


@pytest.mark.manual("§2.5.3.9", "at each reversal the module adds the backlash to the path; the actual value "
                    "stands while the play is taken up")
@pytest.mark.manual("§4.2.5", "after Referenzpunkt setzen the first move takes no backlash up")
def test_backlash_is_taken_up_at_each_reversal(mod: Module) -> None:
    """§5.8 (COM247 MD: b = 1 mm): no take-up on the first move after "Referenzpunkt setzen";
    on a reversal the motor travels b more while the actual value stands still."""
    mod.ready()
    read = mod.device.read
    motor = read("axis.1.machine_position")
    mod.operate(1, 7, FORWARD, w=1000, dd=10_000)
    mod.clock.advance(5)
    assert read("axis.1.position") == 11_000 and read("axis.1.machine_position") - motor == pytest.approx(10_000)
    motor = read("axis.1.machine_position")
    mod.operate(1, 7, BACKWARD, w=1000, dd=5_000)
    mod.clock.advance(0.02)
    assert read("axis.1.machine_position") < motor and read("axis.1.position") == 11_000  # taking up the play
    mod.clock.advance(5)
    assert read("axis.1.position") == 6_000 and motor - read("axis.1.machine_position") == pytest.approx(6_000)
    motor = read("axis.1.machine_position")
    mod.operate(1, 7, BACKWARD, w=1000, dd=1_000)
    mod.clock.advance(5)
    assert read("axis.1.position") == 5_000 and motor - read("axis.1.machine_position") == pytest.approx(1_000)


def test_jobs_while_braking_wait_in_the_job_list(mod: Module) -> None:
    """§3.1/§3.6.4: while the axis brakes, OPERATE is queued (ack 01H) and interpreted at
    standstill in arrival order; the ninth job overflows the PG list: ack 81H, error 1."""
    mod.ready()
    mod.operate(1, 1, FORWARD, w=6000)
    mod.clock.advance(3)
    mod.operate(1, 1, STOP)
    assert mod.m.units[0].braking
    answers = [mod.operate(1, 13, FORWARD, dd=1_000)[0] for _ in range(9)]
    assert answers == [0x01] * 8 + [0x81] and mod.device.read("axis.1.error") == 1
    assert mod.m.units[0].coords.zo_mode == 0  # nothing interpreted yet
    mod.clock.advance(10)
    assert mod.device.read("axis.1.running") is False and mod.m.units[0].coords.zo_mode == 8_000 and not mod.m.job_lists["pg"]


def test_the_plc_record_point_never_overwrites(mod: Module) -> None:
    """ag.record: FB165 in process; BA20 for an axis that has MD is 17 from the PLC, BA67 reads."""
    mod.load_md()
    mod.device.set("ag.record", {"ba": 20, "page": 0, "db": 123, "words": words(COM247)})
    assert mod.device.read("ag.last")["err"] == 17
    mod.device.set("ag.record", {"ba": 67, "page": 0, "db": 101})
    assert mod.device.read("ag.last")["words"] == mod.device.read("axis.1.machine_data")
    mod.operate(1, 5, START, b=1)
    mod.operate(1, 7, BACKWARD, w=1000, dd=1_000)
    assert mod.device.read("output.RP1") is False


@pytest.mark.parametrize("job", [
    ("ag.record", {"ba": "x"}), ("ag.record", {"ba": None}), ("ag.record", {"ba": 67, "page": "x"}),
    ("ag.record", {"ba": 67, "page": None}), ("ag.record", {"ba": 20, "words": ["a"]}),
    ("ag.record", {"ba": 20, "words": 5}), ("ag.record", {"ba": 67, "db": None}),
    ("ag.operate", {"ba": "x"}), ("ag.operate", {"ba": None}), ("ag.operate", {"ba": 5, "page": "x"}),
    ("ag.operate", {"ba": 5, "b": "q"}), ("ag.operate", {"ba": 7, "cmd": "Vorwärts", "dd": [1]}),
    ("ag.operate", {"ba": 5, "cmd": 300}), ("ag.operate", {"ba": 5, "cmd": -1}),  # no byte: ValueError (bytes())
    ("ag.operate", {"ba": 5, "cmd": True}),  # no command: was Start
], ids=lambda job: f"{job[0]}-{job[1]}")
def test_a_plc_job_with_a_field_that_is_no_whole_number_is_refused(mod: Module, job: tuple[str, dict[str, object]]) -> None:
    """Found by fuzzing: an FB164/FB165 job whose BA, page, DB, B, W, DD or words are no whole
    numbers (``{"ba": "x"}``, ``{"page": None}``, ``{"words": 5}``) raised ValueError/TypeError out
    of the point write; it is a bad value (BadValue), and nothing reaches the module."""
    mod.load_md()
    before = mod.device.read("ag.last"), mod.device.read("axis.1.machine_data")
    name, value = job
    with pytest.raises(BadValue):
        mod.device.set(name, value)
    assert (mod.device.read("ag.last"), mod.device.read("axis.1.machine_data")) == before


def test_a_program_text_with_a_character_no_record_carries_is_refused(mod: Module) -> None:
    """(Found with the battery RAM fuzz.)  program.N with a character beyond latin-1 raised
    UnicodeEncodeError out of the point write (ctl: 'Error: UnicodeEncodeError: ...'); it is a bad
    value, and nothing is stored."""
    with pytest.raises(BadValue, match="'€' is no character a record carries"):
        mod.device.set("program.7", "%  7\nN1 M02 €\n")
    assert mod.device.read("programs") == []


def test_tbit_follows_jobs_from_the_plc_side(mod: Module) -> None:
    """§3.7/§6.2.6: TBIT set while a job the PLC issued runs, cleared at "fertig"; a program the
    PG continues with Übernahme is the PG's (no TBIT)."""
    mod.ready()
    mod.store(4, "%  4\nN1 X30 F1000 M20\nN2 M02\n")
    mod.device.set("ag.operate", {"page": 0, "ba": 7, "cmd": "Vorwärts", "w": 0x1000, "dd": 0x0000_1000})
    assert mod.device.read("axis.1.tbit") is True
    mod.clock.advance(5)
    assert mod.device.read("axis.1.tbit") is False
    mod.device.set("ag.operate", {"page": 0, "ba": 8, "cmd": "Start", "b": 4})
    assert mod.device.read("axis.1.tbit") is True
    mod.operate(1, 8, STOP)
    mod.clock.advance(2)
    assert mod.device.read("axis.1.tbit") is False
    mod.operate(1, 8, TAKE_OVER, b=4)
    assert mod.device.read("axis.1.running") is True and mod.device.read("axis.1.tbit") is False


def test_an_interrupted_relative_traverse_keeps_its_target(mod: Module) -> None:
    """§5.11.5: Übernahme completes the interrupted traverse to its target, also under G91 (the
    distance is not added again from where the axis stopped)."""
    mod.ready()
    mod.store(8, "%  8\nN1 G91\nN2 X30 F1000\nN3 M02\n")
    mod.operate(1, 8, START, b=8)
    mod.clock.advance(0.5)
    assert mod.operate(1, 8, STOP)[4] == 65
    mod.clock.advance(5)
    assert mod.operate(1, 8, TAKE_OVER, b=8)[4] == 0
    mod.clock.advance(60)
    assert mod.device.read("axis.1.position") == 1_000 + 30_000


@pytest.mark.manual("§2.7.7", "in automatic mode position reached is generated after each traverse block and "
                    "each dwell")
@pytest.mark.manual("§2.8.2", "position reached goes to the CPU (attribute bit 2) and to a digital output "
                    "alike")
@pytest.mark.manual("§2.7.6", "in automatic mode the axis state stays läuft until the program ends or is "
                    "interrupted")
def test_position_reached_drops_during_a_dwell(mod: Module) -> None:
    """§4.1.3 [DECISION]: PE is cleared when a motion or a dwell starts, and set when the dwell
    has run (output and attribute bit 2 alike)."""
    mod.ready()
    mod.store(12, "%  12\nN1 X10 F1000\nN2 G04 F30\nN3 M02\n")
    mod.operate(1, 8, START, b=12)
    mod.clock.advance(1.5)  # the traverse is done, the 3 s dwell runs
    assert mod.device.read("axis.1.running") is True
    assert mod.device.read("output.PE1") is False and not mod.device.read("axis.1.attributes") & 0x04
    mod.clock.advance(3)
    assert mod.device.read("output.PE1") is True and mod.device.read("axis.1.attributes") & 0x04


# -- battery RAM from a state file (a hand edit, a damaged file: fuzzed) --------------------------------
def _image() -> dict:
    """A battery RAM as a module saves it: SYS-ID module 11, COM247's MD on axis 1 (DB 101), a
    program and a faulty one (syntax error 16 in block 1, as BA22 marks it), BA15 offset 2000."""
    md = words(COM247)
    md[2] = 0x4200 | 101
    return {"devsim-kind": "ip247", "sys_id": [11, 2, 3], "md": {"1": md},
            "offsets": {"1": [0, 2_000, 0], "2": [0, 0, 0], "3": [0, 0, 0]},
            "programs": {"gaps": 0, "programs": [[7, "%  7\nN1 X30 F1000\nN2 M02\n", 0, 0],
                                                 [12, "%  12\nN1 X1 F100 Q\nN2 M02\n", 16, 1]]}}


def test_a_battery_ram_image_the_module_saves_loads_as_saved(tmp_path) -> None:  # noqa: ANN001
    (tmp_path / "ip247.nvram.json").write_text(json.dumps(_image()))
    runtime = Runtime(virtual=True, state_dir=tmp_path).start()
    try:
        m = runtime.add_device("ip247").model
        assert m.channel.sys_id == (11, 2, 3) and m.units[0].md_valid and m.units[0].coords.to_ba15 == 2_000
        assert m.programs.store.directory() == [(7, 18), (12, 18)]
        assert m.channel.read_record(4, 69, 12)[1][3:5] == [16, 1]
    finally:
        runtime.stop()


def _damaged(section: str, change: object) -> dict:
    image = _image()
    if callable(change):
        change(image[section])
    else:
        image[section] = change
    return image


@pytest.mark.parametrize(("section", "change"), [
    ("sys_id", "abc"), ("sys_id", [11, 2]), ("sys_id", [11, 2, "3"]), ("sys_id", [256, 0, 0]),
    ("sys_id", [True, 2, 3]),
    ("programs", lambda p: p["programs"][0].__setitem__(1, "%  7\nN1 X30 F1000 Q\nN2 M02\n")),  # marked 0
    ("programs", lambda p: p["programs"][1].__setitem__(2, 0)),  # a faulty program marked fault-free
    ("programs", lambda p: p["programs"][0].__setitem__(1, "%  7\nN1 X30 F1000\nN2 M02 €\n")),
    ("programs", lambda p: p["programs"][0].__setitem__(0, 256)),
    ("programs", lambda p: p["programs"][1].__setitem__(0, 7)),  # twice
    ("programs", lambda p: p.__setitem__("gaps", -1)),
    ("programs", lambda p: p.__setitem__("gaps", 6_000)),  # more characters than the memory holds
    ("md", lambda md: md["1"].__setitem__(5, 65_536)),
    ("md", lambda md: md["1"].__setitem__(46, True)),
    ("md", lambda md: md["1"].__setitem__(47, 0x81)),  # a bit BA20 does not store
    ("md", lambda md: md.__setitem__("2", md["1"])),  # axis 1's record on axis 2
    ("md", lambda md: md["1"].__setitem__(14, 0)),  # error-free, yet 0 pulses per revolution
    ("offsets", lambda o: o["1"].__setitem__(1, "5")),
    ("offsets", lambda o: o["1"].__setitem__(1, 1.5)),
    ("offsets", lambda o: o["1"].__setitem__(0, None)),
    ("offsets", lambda o: o["1"].__setitem__(0, 10**400)),
], ids=["sys-id-text", "sys-id-two", "sys-id-string-byte", "sys-id-256", "sys-id-bool", "program-fault-marked-0",
        "faulty-marked-0", "program-euro", "program-256", "program-twice", "gaps-negative", "gaps-6000",
        "md-word-65536", "md-word-bool", "md-bit-not-stored", "md-other-axis", "md-error-free-unchecked",
        "offset-string", "offset-fraction", "offset-null",
        "offset-10**400"])
def test_battery_ram_the_module_never_stores_refuses_the_memory(tmp_path, section: str, change: object) -> None:  # noqa: ANN001
    """(Fuzzed, /tmp/probe_images/mut.py: 2071 damaged images.)  A SYS-ID of another shape loaded
    and failed every BA70 with TypeError; a program marked fault-free whose text the check refuses
    failed every program start (SyntaxFault out of the job); characters beyond latin-1 failed BA69;
    offsets that are no whole numbers failed every observation, read and save (10^400: a program
    start); MD words beyond 16 bits, program numbers beyond 255, duplicates and a negative gap were
    served to the host.  Now the start stops naming the file, which stays as it was."""
    text = json.dumps(_damaged(section, change))
    (tmp_path / "ip247.nvram.json").write_text(text)
    refused_memory(tmp_path, "ip247", match="this memory image does not fit the kind 'ip247'")
    assert (tmp_path / "ip247.nvram.json").read_text() == text
