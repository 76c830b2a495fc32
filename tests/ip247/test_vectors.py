"""The IP247's worked examples through its PG port on a real pty, in virtual time (spec ip247.md §6.6
zero-offset program, §6.7 rotary axis, §6.8 reference run, §5.11.4 flying change, §5.15 step
loss)."""

from __future__ import annotations

import pytest

from tests.ip247.helpers import BACKWARD, FORWARD, START, STOP, TAKE_OVER, Make, Module, record

MAIN = ("%  1 HAUPTPROGRAMM\nN1 L9\nN2 X40.000 F500\nN3 G54\nN4 L9\nN5 X40.000 F500\nN6 G55\nN7 L9\n"
        "N8 X40.000 F500\nN9 G56\nN10 G74\nN11 M02\n")
SUB = "L  9 UNTERPROGRAMM\nN1 X0 F100 M10\nN2 G04 F50\nN3 X10 F100\nN4 G04 F50\nN5 X20 F100\nN6 G04 F50\nN7 M02\n"


@pytest.mark.manual("§2.6.6.7", "the manual example: BA13 10 mm forward, BA6 to 0, program 1 calling L9 three "
                    "times with G54, G55, G56 shows -130 mm after G74 and -10 mm after the end")
@pytest.mark.manual("§2.6.6.7", "a positive zero offset moves the origin in the positive direction: the "
                    "points of the axis get more negative values")
@pytest.mark.manual("§2.6.6.7", "zero offsets made in a subprogram stay after the return and are reset at the "
                    "end of the main program")
def test_zero_offset_program_of_section_6_6(make: Make) -> None:
    """BA9 step by step: the actual value at each halt is the table's (mm ×1000), G74 gives
    −130 mm, the end −10 mm; M10 from L9's first traverse on (held before it at the Start), M02 at
    the end."""
    mod = make()
    assert mod.load_md(record=record(reference=0, zero_offsets=(40_000, 80_000, 120_000, 0), backlash=0,
                                     limit_begin=-1_000_000, limit_end=1_000_000))[8] == 0
    mod.operate(1, 5, START, b=1)
    mod.operate(1, 13, FORWARD, dd=10_000)
    assert mod.device.read("axis.1.position") == -10_000
    mod.operate(1, 6, START, dd=0)
    mod.clock.advance(30)
    assert mod.device.read("axis.1.position") == 0 and mod.device.read("axis.1.machine_position") == 10_000
    assert mod.store(9, SUB)[8:] == bytes(4) and mod.store(1, MAIN)[8:] == bytes(4)
    holes = [0, 0, 10, 10, 20, 20]
    expected = [*holes, 40, *holes, 40, *holes, 40, -130]
    # (L9 N1 X0 M10: halted before its traverse, manual §4.3.2; M10 comes with the block, §2.6.9)
    assert mod.operate(1, 9, START, b=1)[7] == 255
    seen, m = [], []
    for _ in range(len(expected)):
        assert mod.operate(1, 9, TAKE_OVER, b=1)[4] == 0
        mod.clock.advance(30)
        seen.append(mod.device.read("axis.1.position") // 1000)
        m.append(mod.device.read("axis.1.m_function"))
    assert seen == expected
    assert set(m) == {10}
    mod.operate(1, 9, TAKE_OVER, b=1)
    assert mod.device.read("axis.1.position") == -10_000 and mod.device.read("axis.1.m_function") == 2


def rotary(make: Make) -> Module:
    """§6.7: range 0 … 360°, r = 4 m° (gear 1.6°, 400 pulses)."""
    mod = make()
    answer = mod.load_md(record=record(unit=3, rotary=True, limit_begin=0, limit_end=360_000, gear=1_600,
                                       pulses_per_rev=400, reference=0, backlash=0, f_ss=200, f_max=20_000,
                                       zero_offsets=(0, 0, 0, 0)))
    assert answer[8] == 0 and answer[6] & 0x03 == 0x01  # RMLD unit bits: degree
    mod.operate(1, 5, START, b=1)
    return mod


@pytest.mark.parametrize(("target", "command", "travel"), [
    (270_000, START, -90_000),  # shortest path: backward
    (180_000, START, 180_000),  # a tie: forward
    (0, FORWARD, 360_000),  # Vorwärts to where it stands: one revolution
    (0, BACKWARD, -360_000),
])
@pytest.mark.manual("§2.5.3.3", "absolute targets of a rotary axis lie within the range; range start and end "
                    "are the same point")
@pytest.mark.manual("§4.2.6", "rotary BA6: Vorwärts/Rückwärts approach the target in that direction; standing "
                    "on it they go once round")
def test_rotary_targets_of_section_6_7(make: Make, target: int, command: int, travel: int) -> None:
    mod = rotary(make)
    motor = mod.device.read("axis.1.machine_position")
    assert mod.operate(1, 6, command, w=4_000, dd=target)[4] == 0
    mod.clock.advance(60)
    assert mod.device.read("axis.1.position") == target
    assert mod.device.read("axis.1.machine_position") - motor == pytest.approx(travel)


@pytest.mark.manual("§2.5.3.3", "a relative move on a rotary axis may be longer than the traverse range")
@pytest.mark.manual("§4.2.7", "on a rotary axis the relative distance is limited to +-200 m (degrees: "
                    "+-200000); beyond it 62 Unzulässige Wegangabe")
def test_rotary_offsets_and_long_relative_moves_of_section_6_7(make: Make) -> None:
    mod = rotary(make)
    mod.operate(1, 7, FORWARD, w=4_000, dd=60_000)
    mod.clock.advance(30)
    assert mod.operate(1, 15, FORWARD, dd=30_000)[4] == 0
    assert mod.device.read("axis.1.position") == 90_000  # BA15 30° at 60°
    mod.operate(1, 16, START)
    assert mod.operate(1, 12, START, dd=400_000)[4] == 0
    assert mod.device.read("axis.1.position") == 400_000 and mod.m.units[0].coords.range() == (340_000, 700_000)
    mod.operate(1, 14, START)
    mod.operate(1, 7, FORWARD, w=4_000, dd=500_000)
    mod.clock.advance(120)
    assert mod.device.read("axis.1.position") == (60_000 + 500_000) % 360_000
    assert mod.operate(1, 7, FORWARD, dd=200_000_001)[4] == 62


@pytest.mark.manual("§4.2.4", "the cam is monitored: not left after 2500 single steps, the run is aborted "
                    "with 59 Der Referenznocken ist defekt")
@pytest.mark.manual("§7.2.2", "Fehler 59: the reference cam is to be left in single steps but gives no falling "
                    "edge within 2500 steps")
def test_a_cam_never_left_is_error_59_after_2500_steps(make: Make) -> None:
    """§6.8: BERO stuck at 1: 2,500 single steps, then error 59, reference missing (bit 5)."""
    mod = make()
    mod.load_md()
    mod.device.set("input.BERO1", True)
    mod.operate(1, 5, START, b=0)
    mod.clock.advance(2500 / 100 - 0.01)
    assert mod.device.read("axis.1.running") is True
    mod.clock.advance(5)
    assert mod.device.read("axis.1.error") == 59 and mod.device.read("axis.1.attributes") & 0x20
    assert mod.device.read("axis.1.running") is False


@pytest.mark.parametrize("cam_edge", [20_000.0, 20_002.2, 20_004.4, 20_006.6])
@pytest.mark.manual("§4.2.4", "with synchronisation the reference point is the first zero of the "
                    "current-pattern counter after the cam is left")
def test_synchronous_reference_at_pattern_zero(make: Make, cam_edge: float) -> None:
    """§6.8: synchronous with 4 patterns: at most 3 single steps after the cam's falling edge,
    and the reference point lies where the pattern counter is 0."""
    mod = make({"axes": {1: {"cam": [cam_edge, cam_edge + 10_000]}}})
    mod.load_md(record=record(reference_sync=0, patterns=4))
    mod.operate(1, 5, START, b=0)
    mod.clock.advance(120)
    assert mod.device.read("axis.1.reference_set") is True
    unit = mod.m.units[0]
    pulses = round((unit.axis.position() - unit.pattern_base) / 1.1)
    assert pulses % 4 == 0
    assert 0 <= (cam_edge - unit.axis.position()) / 1.1 <= 3 + 1  # (the edge lies within a step)


@pytest.mark.manual("§4.2.3", "example: after a zero offset of 100 mm backward, Referenzpunkt setzen with "
                    "reference coordinate 0 shows 100 mm")
def test_reference_set_after_a_zero_offset_of_section_6_8(make: Make) -> None:
    """BA13 100 mm Rückwärts, then "Referenzpunkt setzen" with x_ref = 0: actual 100 mm."""
    mod = make()
    mod.load_md(record=record(reference=0))
    mod.operate(1, 13, BACKWARD, dd=100_000)
    mod.operate(1, 5, START, b=1)
    assert mod.device.read("axis.1.position") == 100_000
    assert mod.operate(1, 5, STOP)[4] == 0


@pytest.mark.manual("§2.6.6.3", "G10 joins the next block without stopping the axis: a velocity change during "
                    "a motion (example 1)")
@pytest.mark.manual("§2.6.9", "with G10 the new M function is output from the transition point on")
def test_flying_change_runs_through_without_a_stop(make: Make) -> None:
    """§5.11.4 manual example: 0→50 at 1000 mm/min, 50→100 at 500, 100→150 at 1000 without a
    stop; M30, M31 from the joint at 50, M32 from 100; PE only at the end."""
    mod = make()
    mod.ready()
    mod.store(17, "%  17\nN30 G10 X50 F1000 M30\nN32 G10 X100 F500 M31\nN34 X150 F1000 M32\nN36 M02\n")
    mod.operate(1, 8, START, b=17)
    seen: dict[int, list[tuple[int, float]]] = {}
    while mod.device.read("axis.1.running"):
        mod.clock.advance(0.05)
        position, velocity = mod.device.read("axis.1.position"), mod.m.units[0].axis.velocity()
        seen.setdefault(mod.device.read("axis.1.m_function"), []).append((position, velocity))
        if position < 149_000:
            assert velocity > 0 and mod.device.read("output.PE1") is False
    assert mod.device.read("axis.1.position") == 150_000 and mod.device.read("output.PE1") is True
    assert min(p for p, _ in seen[31]) >= 50_000 and max(p for p, _ in seen[30]) <= 50_000 + 1_000
    assert min(p for p, _ in seen[32]) >= 100_000
    cruising = [v for p, v in seen[31] if 70_000 < p < 99_000]
    assert cruising and all(v == pytest.approx(500 * 1000 / 60) for v in cruising)


@pytest.mark.parametrize(("text", "error"), [
    ("N10 G10 X100 F1000\nN20 X50 F1000\nN30 M02", 52),  # a reversal
    ("N10 G10 X100 F1000\nN20 G04 F10\nN30 M02", 52),  # a dwell
    ("N10 G10 X100 F3000\nN20 X101 F3000\nN30 M02", 52),  # shorter than the braking distance
    ("N10 G10 X100 F1000\nN20 G56\nN25 X120 F1000\nN30 M02", 52),  # a shift
])
@pytest.mark.manual("§2.6.6.3", "a flying change into the opposite direction, into a dwell, onto a path "
                    "shorter than the braking distance or into a shift is not possible: error 52, the program "
                    "is aborted")
def test_flying_change_not_possible(make: Make, text: str, error: int) -> None:
    mod = make()
    mod.ready()
    mod.store(18, f"%  18\n{text}\n")
    mod.operate(1, 8, START, b=18)
    mod.clock.advance(30)
    assert mod.device.read("axis.1.error") == error and mod.m.units[0].automatic is None


@pytest.mark.manual("§2.6.6.3", "on a rotary axis a chain that is not shortest-path all the way needs "
                    "G26/G27, else error 47 Keine Richtungsaenderung beim FW")
@pytest.mark.manual("§2.6.6.5", "G26 approaches absolute targets of a rotary axis clockwise (forward)")
def test_flying_change_on_a_rotary_axis_needs_a_fixed_direction(make: Make) -> None:
    """§5.11.4: X300 (backward by shortest path from 0°) then X10 (forward): error 47; with
    G26 the chain runs forward."""
    mod = rotary(make)
    mod.store(19, "%  19\nN10 G10 X300 F1000\nN20 X10 F1000\nN30 M02\n")
    mod.operate(1, 8, START, b=19)
    assert mod.device.read("axis.1.error") == 47
    mod.store(20, "%  20\nN5 G26\nN10 G10 X300 F1000\nN20 X10 F1000\nN30 M02\n")
    mod.operate(1, 8, START, b=20)
    mod.clock.advance(120)
    assert mod.device.read("axis.1.error") == 0 and mod.device.read("axis.1.position") == 10_000
    assert mod.device.read("axis.1.machine_position") == pytest.approx(370_000)


@pytest.mark.manual("§2.3.1", "the drive position is not monitored: the actual value is computed from the "
                    "pulses output")
@pytest.mark.manual("§2.4", "a stepper motor dimensioned wrongly loses steps, and the axis is positioned "
                    "wrongly")
def test_step_loss_when_the_motor_cannot_start_or_stalls(make: Make) -> None:
    """§5.15 / §8 scenario 24: f_ss 2000 Hz on a motor that starts only up to 800 Hz howls
    without moving while the actual value counts 100 mm; a pull-out frequency of 3000 Hz stops
    the motor where the ramp passes it (the module still counts the whole move)."""
    howl = make({"axes": {1: {"max_start_hz": 800}}})
    howl.load_md(record=record(f_ss=2000))
    howl.operate(1, 5, START, b=1)
    howl.operate(1, 7, FORWARD, w=1000, dd=100_000)
    howl.clock.advance(60)
    assert howl.device.read("axis.1.position") == 1_000 + 100_000
    assert howl.device.read("axis.1.mechanical_position") == 0
    stall = make({"axes": {1: {"pullout_hz": 12_000}}})
    stall.ready()
    stall.operate(1, 7, FORWARD, w=1000, dd=100_000)  # 15 151.5 Hz
    stall.clock.advance(60)
    md = stall.m.units[0].md
    assert md is not None
    ramp = md.ramp
    assert stall.device.read("axis.1.machine_position") == pytest.approx(100_000)
    assert stall.device.read("axis.1.mechanical_position") == pytest.approx(1.1 * ramp.pulses_to(12_000), rel=1e-6)


def test_wiring_faults_move_the_motor_wrongly_while_the_module_counts(make: Make) -> None:
    """§5.15: with T/RP swapped the motor goes backward by what the module counts forward; with
    RS stuck it stands; the module's actual value counts the pulses either way."""
    mod = make()
    mod.ready()
    mod.device.fault("rp_swapped_1", True)
    mod.operate(1, 7, FORWARD, w=1000, dd=10_000)
    mod.clock.advance(5)
    assert mod.device.read("axis.1.position") == 11_000
    assert mod.device.read("axis.1.mechanical_position") == pytest.approx(-10_000)
    mod.device.fault("rp_swapped_1", False)
    mod.device.fault("rs_stuck_1", True)
    mod.operate(1, 7, FORWARD, w=1000, dd=10_000)
    mod.clock.advance(5)
    assert mod.device.read("axis.1.position") == 21_000
    assert mod.device.read("axis.1.mechanical_position") == pytest.approx(-10_000)


def test_switches_sit_at_mechanical_positions(make: Make) -> None:
    """§5.15: a motor that howls (no start at f_ss) never reaches END at 20 mm, so the module
    counts through it without error 26; a healthy motor stops there."""
    howl = make({"axes": {1: {"max_start_hz": 800, "end": 20_000}}})
    howl.load_md(record=record(f_ss=2000))
    howl.operate(1, 5, START, b=1)
    howl.operate(1, 7, FORWARD, w=1000, dd=50_000)
    howl.clock.advance(60)
    assert howl.device.read("axis.1.position") == 51_000 and howl.device.read("axis.1.error") == 0
    assert howl.device.read("input.END1") is True  # NC contact, not actuated
    healthy = make({"axes": {1: {"end": 20_000}}})
    healthy.load_md(record=record(f_ss=2000))
    healthy.operate(1, 5, START, b=1)
    healthy.operate(1, 7, FORWARD, w=1000, dd=50_000)
    healthy.clock.advance(60)
    assert healthy.device.read("axis.1.error") == 26 and healthy.device.read("input.END1") is False


def test_a_refused_rotary_record_with_an_empty_range_reads_as_no_values(make: Make) -> None:
    """A rotary record whose range end is not above its start is refused (error 21, spec §4.4),
    and like every axis without valid MD it reports position and residual 0 (§5.8.2).  (Found by
    fuzzing: the empty range divided by zero at every read of the actual value.)"""
    mod = make()
    answer = mod.load_md(record=record(rotary=True, limit_begin=0, limit_end=0, reference=0))
    assert answer[8] == 21
    assert mod.device.read("axis.1.position") == 0
    assert mod.client.observe(1)[8:16] == bytes(8)  # (header, then position and residual)
    assert mod.client.read_record(1, 66)[8:] == bytes(12)  # BA66 "Istwerte Lesen": 6 words, all 0
