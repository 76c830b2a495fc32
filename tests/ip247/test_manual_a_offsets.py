"""Walk of manual §4.3.1–§4.3.9 and §4.4 (programs from the operator's side, teach-in, zero
offsets BA12–BA14, tool offsets BA15/BA16, the observe modes), driven through the PG port on a
real pty."""

from __future__ import annotations

import struct

import pytest

from tests.ip247.helpers import BACKWARD, FORWARD, START, STOP, TAKE_OVER, Make, Module, record


def actual(mod: Module) -> int:
    return int(mod.device.read("axis.1.position"))


@pytest.fixture
def plain(make: Make) -> Module:
    """COM247's machine data without backlash (x_A −10 mm, x_E 500 mm, x_ref 1 mm), reference set."""
    mod = make()
    assert mod.load_md(record=record(backlash=0))[8] == 0
    assert mod.operate(1, 5, START, b=1)[4] == 0
    return mod


# -- §4.3.1 ------------------------------------------------------------------------------------------
@pytest.mark.manual("§4.3.1", "a program that is being executed cannot be changed or deleted (51)")
def test_a_running_program_cannot_be_deleted(plain: Module) -> None:
    assert plain.store(4, "%  4\nN1 X100 F1000\nN2 M02\n")[4] == 0
    plain.operate(1, 8, START, b=4)
    plain.clock.advance(0.5)
    assert plain.client.delete_record(4, 23, 4)[4] == 51


@pytest.mark.manual("§4.3.1", "a program that is being executed cannot be changed or deleted (51): nor can a "
                    "subprogram the running program is executing")
def test_a_running_subprogram_cannot_be_deleted(plain: Module) -> None:
    assert plain.store(5, "L  5\nN1 X50 F1000\nN2 M02\n")[4] == 0
    assert plain.store(4, "%  4\nN1 L5\nN2 X10 F1000\nN3 M02\n")[4] == 0
    plain.operate(1, 8, START, b=4)
    plain.clock.advance(1)  # in L5's traverse
    assert plain.client.delete_record(4, 23, 5)[4] == 51
    plain.clock.advance(60)  # program 4 has ended
    assert actual(plain) == 10_000 and plain.client.delete_record(4, 23, 5)[4] == 0


@pytest.mark.manual("§4.3.1", "after an interruption Start begins the program again at its first block")
@pytest.mark.manual("§4.3.1", "a further Stopp aborts an interrupted program")
def test_restart_and_abort_after_an_interruption(plain: Module) -> None:
    assert plain.store(4, "%  4\nN1 G91\nN2 X10 F1000\nN3 X10 F1000\nN4 M02\n")[4] == 0
    plain.operate(1, 8, START, b=4)
    plain.clock.advance(0.2)
    assert plain.operate(1, 8, STOP)[4] == 65
    plain.clock.advance(5)
    stopped = actual(plain)
    assert plain.operate(1, 8, START, b=4)[4] == 0  # from N1 again: two more relative 10 mm
    plain.clock.advance(30)
    assert actual(plain) == stopped + 20_000
    plain.operate(1, 8, START, b=4)
    plain.clock.advance(0.2)
    plain.operate(1, 8, STOP)
    plain.clock.advance(5)
    assert plain.operate(1, 8, STOP)[4] == 0 and plain.m.units[0].automatic is None
    assert plain.operate(1, 8, TAKE_OVER, b=4)[4] == 2  # nothing left to continue


@pytest.mark.manual("§4.3.3", "a program interrupted during a dwell counts the dwell as expired: after Übernahme "
                    "the next traverse runs; switches before it are done at the interruption, then 65 and "
                    "position reached")
def test_interruption_during_a_dwell(make: Make) -> None:
    mod = make()
    assert mod.load_md(record=record(backlash=0, zero_offsets=(0, 0, 5_000, 0)))[8] == 0
    mod.operate(1, 5, START, b=1)
    assert mod.store(4, "%  4\nN10 G04 F1000 M10\nN20 G56 X20 F1000 M20\nN30 M02\n")[4] == 0
    mod.operate(1, 8, START, b=4)
    mod.clock.advance(1)
    assert mod.operate(1, 8, STOP)[4] == 65
    assert actual(mod) == 1_000 - 5_000  # G56 of N20 already done
    assert mod.device.read("output.PE1") is True and mod.device.read("axis.1.running") is False
    mod.operate(1, 8, TAKE_OVER, b=4)
    mod.clock.advance(1)
    assert mod.device.read("axis.1.running") is True  # N20 runs now, not the rest of the 100 s dwell
    mod.clock.advance(60)
    assert actual(mod) == 20_000 + 5_000  # reached in the shifted system; the end removed G56


@pytest.mark.manual("§4.3.3", "an interruption while accelerating or cruising: no position reached, fertig, 65; "
                    "the residual is shown and Übernahme completes the traverse")
def test_interruption_while_cruising(plain: Module) -> None:
    assert plain.store(4, "%  4\nN1 X100 F1000\nN2 M02\n")[4] == 0
    plain.operate(1, 8, START, b=4)
    plain.clock.advance(3)
    assert plain.operate(1, 8, STOP)[4] == 65
    plain.clock.advance(5)
    residual = plain.device.read("axis.1.residual")
    assert residual > 0 and residual + actual(plain) == 100_000 and plain.device.read("output.PE1") is False
    plain.operate(1, 8, TAKE_OVER, b=4)
    plain.clock.advance(60)
    assert actual(plain) == 100_000 and plain.device.read("output.PE1") is True


@pytest.mark.manual("§4.3.3", "a wrong operation interrupts a program as a Stopp does: the axis brakes, position "
                    "reached is not set, the residual is shown and Übernahme continues the program")
@pytest.mark.manual("§4.1.1", "a wrong operation (e.g. Übernahme with another mode) while the axis runs gives "
                    "'Nicht erlaubter Auftrag' (2) and ends the running action")
@pytest.mark.parametrize(("ba", "cmd"), [(9, TAKE_OVER), (6, START), (3, START)],
                         ids=["BA9 Übernahme", "BA6 Start", "undefined BA3"])
def test_a_wrong_operation_interrupts_a_program(plain: Module, ba: int, cmd: int) -> None:
    assert plain.store(4, "%  4\nN1 X100 F1000 M10\nN2 X120 F1000 M20\nN3 M02\n")[4] == 0
    plain.operate(1, 8, START, b=4)
    plain.clock.advance(3)
    assert plain.operate(1, ba, cmd, b=4, dd=5_000)[4] == 2
    plain.clock.advance(5)
    residual = plain.device.read("axis.1.residual")
    assert plain.device.read("axis.1.running") is False and plain.device.read("output.PE1") is False
    assert residual > 0 and residual + actual(plain) == 100_000
    assert plain.operate(1, 8, TAKE_OVER, b=4)[4] == 0
    plain.clock.advance(60)
    assert (actual(plain), plain.device.read("axis.1.m_function"), plain.device.read("axis.1.error")) == (120_000, 2, 0)


# -- §4.3.4 teach-in ----------------------------------------------------------------------------------
@pytest.mark.manual("§4.3.4", "teach-in off without stored positions leaves an empty program")
def test_teach_in_without_positions(plain: Module) -> None:
    assert plain.operate(1, 10, START, b=7)[4] == 0
    assert plain.operate(1, 11, START, b=7)[4] == 0
    assert plain.device.read("program.7") == "%  7\nN1 M02\n"


@pytest.mark.manual("§4.3.4", "each Übernahme at standstill stores the actual value with the MD step velocity and "
                    "no M function, numbered on from N1; storing the same position twice gives two blocks")
def test_teach_in_blocks(plain: Module) -> None:
    assert plain.operate(1, 10, START, b=7)[4] == 0
    plain.operate(1, 7, FORWARD, dd=1_500)
    plain.clock.advance(10)
    assert plain.operate(1, 7, TAKE_OVER)[4] == 3  # "Satz abgespeichert"
    assert plain.operate(1, 7, TAKE_OVER)[4] == 3
    assert plain.operate(1, 11, START, b=7)[4] == 0
    assert plain.device.read("program.7") == "%  7\nN1 X2.500 F1000\nN2 X2.500 F1000\nN3 M02\n"


@pytest.mark.manual("§4.3.4", "teach-in on needs a program number not yet used on the IP247 (49)")
@pytest.mark.manual("§4.3.4", "teach-in on needs that no other axis is in teach-in (22)")
def test_teach_in_preconditions(plain: Module) -> None:
    plain.ready(2)
    assert plain.store(5, "%  5\nN1 M02\n")[4] == 0
    assert plain.operate(1, 10, START, b=5)[4] == 49
    assert plain.operate(1, 10, START, b=6)[4] == 0
    assert plain.operate(2, 10, START, b=8)[4] == 22


@pytest.mark.manual("§4.3.4", "in teach-in only jog and BA6/BA7 are allowed; other modes are not carried out (30)")
def test_teach_in_allows_only_jog_and_step_moves(plain: Module) -> None:
    assert plain.operate(1, 10, START, b=6)[4] == 0
    assert plain.operate(1, 13, FORWARD, dd=1_000)[4] == 30
    assert plain.operate(1, 7, FORWARD, dd=1_000)[4] == 0


@pytest.mark.manual("§4.3.4", "switching the module off during teach-in loses the program; teach-in is off "
                    "afterwards")
def test_power_off_during_teach_in(plain: Module) -> None:
    assert plain.operate(1, 10, START, b=6)[4] == 0
    assert plain.operate(1, 7, TAKE_OVER)[4] == 3
    plain.device.fault("power", True)
    plain.device.fault("power", False)
    plain.clock.advance(2)
    assert plain.device.read("program.6") is None
    assert not plain.call(0x62, b"\x01")[6] & 0x10


@pytest.mark.manual("§2.6.1", "Pro Programm sind maximal 1023 ASCII-Zeichen zulässig, einschließlich Programmkopf")
@pytest.mark.manual("§4.3.4", "at the memory's limit teach-in ends by itself, the last stored block becomes the end")
def test_teach_in_ends_at_the_limit_of_one_program(plain: Module) -> None:
    plain.store(5, "%  5\nN1 X2 F1000\nN2 M02\n")
    assert plain.operate(1, 10, START, b=7)[4] == 0
    errors = [plain.operate(1, 7, TAKE_OVER)[4] for _ in range(70)]  # 70 blocks of 17 characters: 1200
    text = plain.device.read("program.7")
    assert errors[0] == 3 and errors[-1] != 3 and text is not None and len(text) <= 1023
    assert text.endswith(" M02\n") and not plain.call(0x62, b"\x01")[6] & 0x10  # teach-in is off
    assert plain.operate(1, 8, START, b=5)[4] == 0  # the programs still run
    plain.clock.advance(5)
    assert actual(plain) == 2_000
    assert plain.operate(1, 8, START, b=7)[4] == 0


# -- §4.3.5 – §4.3.9 ----------------------------------------------------------------------------------
@pytest.mark.manual("§4.3.5", "BA12 gives the current position a new coordinate without motion; the SW limits and "
                    "the reference coordinate move with it (150 mm → 400 mm: all 250 mm more positive)")
def test_ba12_example(plain: Module) -> None:
    plain.operate(1, 6, START, w=6000, dd=150_000)
    plain.clock.advance(30)
    assert plain.operate(1, 12, START, dd=400_000)[4] == 0
    assert actual(plain) == 400_000
    assert plain.operate(1, 6, START, dd=500_000 + 250_000)[4] == 0  # x_E now at 750 mm
    plain.operate(1, 6, STOP)
    plain.clock.advance(60)
    assert plain.operate(1, 6, START, dd=750_001)[4] == 23


@pytest.mark.manual("§4.3.5", "a BA12 coordinate beyond ±100 m is refused with 62 'Unzulässige Wegangabe'; a "
                    "shift that takes other coordinates beyond it with 23")
def test_ba12_limits(plain: Module) -> None:
    assert plain.operate(1, 12, START, dd=100_000_001)[4] == 62
    assert plain.operate(1, 12, START, dd=99_990_000)[4] == 23  # x_E would be beyond +100 m
    assert actual(plain) == 1_000


@pytest.mark.manual("§4.3.5", "zero offsets need valid machine data but no reference point")
@pytest.mark.manual("§4.3.8", "BA15 needs valid machine data but no reference point")
def test_offsets_without_reference_point(mod: Module) -> None:
    assert mod.operate(1, 12, START, dd=0)[4] == 14
    assert mod.load_md()[8] == 0
    assert mod.operate(1, 12, START, dd=0)[4] == 0
    assert mod.operate(1, 15, FORWARD, dd=0)[4] == 0


@pytest.mark.manual("§4.3.5", "after the module is switched on again the reference point is lost, a zero offset "
                    "is not")
@pytest.mark.manual("§4.3.8", "BA15 and program tool offsets stay after the module is switched on again")
def test_offsets_survive_power_up(plain: Module) -> None:
    plain.operate(1, 13, FORWARD, dd=4_000)
    plain.operate(1, 15, FORWARD, dd=3_000)
    plain.device.fault("power", True)
    plain.device.fault("power", False)
    plain.clock.advance(2)
    assert actual(plain) == 1_000 - 4_000 + 3_000  # shown at the reference coordinate


@pytest.mark.manual("§4.3.6", "BA13 Vorwärts makes all coordinates more negative by the value; the sign counts: "
                    "−50 mm Rückwärts is 50 mm Vorwärts")
@pytest.mark.manual("§4.3.6", "relative shifts add to absolute ones")
@pytest.mark.manual("§4.3.7", "BA14 removes the sum of all BA12/BA13 shifts")
def test_ba13_and_ba14(plain: Module) -> None:
    assert plain.operate(1, 13, BACKWARD, dd=-50_000)[4] == 0
    assert actual(plain) == 1_000 - 50_000
    assert plain.operate(1, 12, START, dd=0)[4] == 0
    assert plain.operate(1, 13, FORWARD, dd=7_000)[4] == 0
    assert actual(plain) == -7_000
    assert plain.operate(1, 14, START)[4] == 0
    assert actual(plain) == 1_000


@pytest.mark.manual("§4.3.8", "the tool tip goes to the target: the drilling example (BA6 50, BA15 100 Vorwärts, "
                    "BA6 200, BA16, BA6 50) puts the holder at 100 and back at 50")
@pytest.mark.manual("§4.3.8", "the actual value after a tool offset is the tool tip's position")
def test_drilling_example(plain: Module) -> None:
    motor0 = plain.device.read("axis.1.machine_position") - 1_000  # the holder at 0
    plain.operate(1, 6, START, w=6000, dd=50_000)
    plain.clock.advance(30)
    assert plain.operate(1, 15, FORWARD, dd=100_000)[4] == 0
    assert actual(plain) == 150_000
    plain.operate(1, 6, START, w=6000, dd=200_000)
    plain.clock.advance(30)
    assert plain.device.read("axis.1.machine_position") - motor0 == pytest.approx(100_000)
    plain.operate(1, 16, START)
    plain.operate(1, 6, START, w=6000, dd=50_000)
    plain.clock.advance(30)
    assert plain.device.read("axis.1.machine_position") - motor0 == pytest.approx(50_000)


@pytest.mark.manual("§4.3.8", "the sign of the value counts: −80 mm Rückwärts is a tool offset forward")
@pytest.mark.manual("§4.3.8", "a new BA15 replaces the tool offset, the program's too")
@pytest.mark.manual("§4.3.8", "values beyond ±100 m are refused with 62 'Unzulässige Wegangabe'")
def test_ba15_sign_replacement_and_range(make: Make) -> None:
    mod = make()
    assert mod.load_md(record=record(backlash=0, tool_length=10_000))[8] == 0
    mod.operate(1, 5, START, b=1)
    assert mod.operate(1, 15, BACKWARD, dd=-80_000)[4] == 0
    assert actual(mod) == 1_000 + 80_000
    assert mod.store(1, "%  1\nN1 G43\nN2 M02\n")[4] == 0
    mod.operate(1, 8, START, b=1)
    mod.clock.advance(1)
    assert actual(mod) == 1_000 + 90_000
    assert mod.operate(1, 15, FORWARD, dd=5_000)[4] == 0
    assert actual(mod) == 1_000 + 5_000
    assert mod.operate(1, 15, FORWARD, dd=100_000_001)[4] == 62


@pytest.mark.manual("§4.3.8", "the tool tip must stay within ±100 m at the SW limits, else the offset is refused "
                    "with 23")
def test_ba15_checks_the_tip_at_the_limits(make: Make) -> None:
    mod = make()
    assert mod.load_md(record=record(limit_end=99_000_000, backlash=0))[8] == 0
    assert mod.operate(1, 15, FORWARD, dd=1_000_000)[4] == 23  # x_E + 1 m = 100 m: beyond +99.999999 m
    assert mod.operate(1, 15, FORWARD, dd=999_999)[4] == 0


@pytest.mark.manual("§4.3.8", "on a rotary axis at 60° a tool offset of 30° forward shows 90°: the coordinate "
                    "system turns; the range stays 0 … 360°")
@pytest.mark.manual("§4.3.8", "a rotary tool offset not smaller than the range is refused with 63")
def test_rotary_tool_offset(make: Make) -> None:
    mod = make()
    assert mod.load_md(record=record(unit=3, rotary=True, limit_begin=0, limit_end=360_000, gear=1_600,
                                     pulses_per_rev=400, reference=0, backlash=0, f_ss=200, f_max=20_000,
                                     a=100_000, jog1=1000, jog2=1000, step_velocity=1000,
                                     reference_velocity=1000, zero_offsets=(0, 0, 0, 0)))[8] == 0
    mod.operate(1, 5, START, b=1)
    mod.operate(1, 7, FORWARD, w=4_000, dd=60_000)
    mod.clock.advance(30)
    assert mod.operate(1, 15, FORWARD, dd=360_000)[4] == 63
    assert mod.operate(1, 15, FORWARD, dd=30_000)[4] == 0
    assert actual(mod) == 90_000
    mod.operate(1, 7, FORWARD, w=4_000, dd=290_000)  # the tip passes 360° and wraps
    mod.clock.advance(60)
    assert actual(mod) == 20_000


@pytest.mark.manual("§4.3.9", "BA16 removes every tool offset, BA15's and the programs' alike")
def test_ba16_clears_all_tool_offsets(make: Make) -> None:
    mod = make()
    assert mod.load_md(record=record(backlash=0, tool_length=10_000))[8] == 0
    mod.operate(1, 5, START, b=1)
    mod.operate(1, 15, FORWARD, dd=5_000)
    assert mod.store(1, "%  1\nN1 G43\nN2 M02\n")[4] == 0
    mod.operate(1, 8, START, b=1)
    mod.clock.advance(1)
    assert actual(mod) == 1_000 + 15_000
    assert mod.operate(1, 16, START)[4] == 0
    assert actual(mod) == 1_000


@pytest.mark.manual("§4.3.10", "BA17 Start resets the pending errors of all axes and the data channel")
def test_ba17_clears_every_page(mod: Module) -> None:
    assert mod.operate(1, 1, FORWARD)[4] == 14
    assert mod.operate(2, 1, FORWARD)[4] == 14
    assert mod.operate(3, 17, START)[4] == 0
    errors = mod.call(0x62, b"\x01")[16:20]
    assert errors == bytes(4)  # axes 1 … 3 and the data channel (8 after power-up) cleared


@pytest.mark.manual("§4.4", "BA66 Istwerte Lesen gives both values at once")
def test_ba66_reads_actual_and_residual(plain: Module) -> None:
    plain.operate(1, 6, START, w=1000, dd=50_000)
    plain.clock.advance(1)
    plain.operate(1, 6, STOP)
    plain.clock.advance(5)
    values = struct.unpack(">3i", plain.client.read_record(1, 66)[8:])
    assert values[0] == actual(plain) and values[2] == 50_000 - actual(plain)  # (§6.3.8.6: 2 words unused)


@pytest.mark.manual("§4.3.3", "a program interrupted inside a G10 chain brakes; position reached is not set; 65; "
                    "Übernahme goes on to the chain's target")
def test_interruption_inside_a_flying_change(plain: Module) -> None:
    assert plain.store(4, "%  4\nN1 G10 X50 F1000 M30\nN2 X100 F1000 M31\nN3 M02\n")[4] == 0
    plain.operate(1, 8, START, b=4)
    plain.clock.advance(2)
    assert plain.operate(1, 8, STOP)[4] == 65
    plain.clock.advance(5)
    assert plain.device.read("axis.1.running") is False and plain.device.read("output.PE1") is False
    assert plain.operate(1, 8, TAKE_OVER, b=4)[4] == 0
    plain.clock.advance(60)
    assert actual(plain) == 100_000 and plain.device.read("output.PE1") is True


@pytest.mark.manual("§4.3.3", "in a G10 chain the residual is that of the block's own (intermediate) target; braking "
                    "past it gives a negative residual, and the interrupted block's M function stays output "
                    "until the program goes on")
def test_interruption_past_the_intermediate_target_of_a_flying_change(plain: Module) -> None:
    assert plain.store(4, "%  4\nN1 G10 X50 F3000 M30\nN2 X100 F3000 M31\nN3 M02\n")[4] == 0
    plain.operate(1, 8, START, b=4)
    plain.clock.advance(0.5)
    assert plain.device.read("axis.1.residual") == 50_000 - actual(plain)  # to N1's target, not the chain's
    plain.clock.advance(0.5)  # at 43 mm: braking from 3000 mm/min takes 14 mm, past N1's 50 mm
    assert plain.operate(1, 8, STOP)[4] == 65
    plain.clock.advance(5)
    assert actual(plain) > 50_000 and plain.device.read("axis.1.residual") == 50_000 - actual(plain)
    assert plain.device.read("axis.1.m_function") == 30 and plain.device.read("output.PE1") is False
    assert plain.operate(1, 8, TAKE_OVER, b=4)[4] == 0
    assert plain.device.read("axis.1.m_function") == 31
    plain.clock.advance(60)
    assert actual(plain) == 100_000 and plain.device.read("output.PE1") is True


@pytest.mark.manual("§4.3.3", "G10 chain interrupted before its intermediate target with path enough left to reach "
                    "the programmed velocity: on Übernahme the flying change is carried out normally")
@pytest.mark.manual("§4.3.3", "G10 chain interrupted before its intermediate target without path enough left to reach "
                    "the velocity: the rest is added to the following traverse; the residual after Übernahme is "
                    "the new target minus the actual value")
@pytest.mark.parametrize(("stop_after", "m", "velocity", "target"), [(0.3, 30, 50_000, 50_000),
                                                                      (0.6, 31, 25_000, 100_000)],
                         ids=["path enough", "path too short"])
def test_a_flying_change_goes_on_after_an_interruption(plain: Module, stop_after: float, m: int, velocity: int,
                                                       target: int) -> None:
    assert plain.store(4, "%  4\nN1 G10 X50 F3000 M30\nN2 G10 X100 F1500 M31\nN3 X150 F3000 M32\nN4 M02\n")[4] == 0
    plain.operate(1, 8, START, b=4)
    plain.clock.advance(stop_after)
    assert plain.operate(1, 8, STOP)[4] == 65
    plain.clock.advance(5)
    assert actual(plain) < 50_000 and plain.device.read("axis.1.residual") == 50_000 - actual(plain)
    assert plain.operate(1, 8, TAKE_OVER, b=4)[4] == 0
    plain.clock.advance(0.7)  # N1 at 3000 mm/min again, or N2 at 1500 mm/min with N1's rest
    read = plain.device.read
    assert (read("axis.1.m_function"), read("axis.1.velocity")) == (m, pytest.approx(velocity))
    assert read("axis.1.residual") == target - actual(plain)
    plain.clock.advance(60)
    assert actual(plain) == 150_000 and read("axis.1.m_function") == 2 and read("output.PE1") is True


def _rotary(make: Make) -> Module:
    """0 … 360° in m°, r = 4 m° (gear 1.6°, 400 pulses), reference 0° set."""
    mod = make()
    assert mod.load_md(record=record(unit=3, rotary=True, limit_begin=0, limit_end=360_000, gear=1_600,
                                     pulses_per_rev=400, reference=0, backlash=0, f_ss=200, f_max=20_000,
                                     a=100_000, jog1=1000, jog2=1000, step_velocity=1000,
                                     reference_velocity=1000, zero_offsets=(0, 0, 0, 0)))[8] == 0
    mod.operate(1, 5, START, b=1)
    return mod


@pytest.mark.manual("§4.3.5", "rotary example: 60° becomes 400°; the range is then 340° … 700° and absolute targets "
                    "must lie in it (0° no longer exists)")
def test_rotary_ba12_example(make: Make) -> None:
    mod = _rotary(make)
    mod.operate(1, 7, FORWARD, w=4_000, dd=60_000)
    mod.clock.advance(30)
    assert mod.operate(1, 12, START, dd=400_000)[4] == 0
    assert actual(mod) == 400_000
    assert mod.operate(1, 6, START, w=4_000, dd=0)[4] == 23
    assert mod.operate(1, 6, START, w=4_000, dd=690_000)[4] == 0
    mod.clock.advance(60)
    assert actual(mod) == 690_000


@pytest.mark.manual("§4.3.8", "on a rotary axis with a tool offset the shortest way of a step move is reckoned from "
                    "the tool tip")
@pytest.mark.manual("§4.2.6", "rotary Start takes the shortest way; with equal ways forward (clockwise)")
def test_rotary_shortest_way_from_the_tip(make: Make) -> None:
    mod = _rotary(make)
    mod.operate(1, 7, FORWARD, w=4_000, dd=60_000)
    mod.clock.advance(30)
    assert mod.operate(1, 15, FORWARD, dd=30_000)[4] == 0  # the tip at 90°
    motor = mod.device.read("axis.1.machine_position")
    assert mod.operate(1, 6, START, w=4_000, dd=270_000)[4] == 0  # 180° either way from the tip: forward
    mod.clock.advance(60)
    assert mod.device.read("axis.1.machine_position") - motor == pytest.approx(180_000)
    assert actual(mod) == 270_000


@pytest.mark.manual("§2.6.6.5", "the shortest way ignores the backlash: with equal ways the axis goes clockwise even "
                    "when the backlash makes that way longer")
def test_shortest_way_ignores_the_backlash(make: Make) -> None:
    mod = make()
    assert mod.load_md(record=record(unit=3, rotary=True, limit_begin=0, limit_end=360_000, gear=1_600,
                                     pulses_per_rev=400, reference=0, backlash=1_000, f_ss=200, f_max=20_000,
                                     a=100_000, jog1=1000, jog2=1000, step_velocity=1000,
                                     reference_velocity=1000, zero_offsets=(0, 0, 0, 0)))[8] == 0
    mod.operate(1, 5, START, b=1)
    mod.operate(1, 7, BACKWARD, w=4_000, dd=10_000)  # the last move counter-clockwise
    mod.clock.advance(30)
    assert actual(mod) == 350_000
    motor = mod.device.read("axis.1.machine_position")
    assert mod.operate(1, 6, START, w=4_000, dd=170_000)[4] == 0  # 180° either way
    mod.clock.advance(60)
    assert actual(mod) == 170_000
    assert mod.device.read("axis.1.machine_position") - motor == pytest.approx(180_000 + 1_000)
