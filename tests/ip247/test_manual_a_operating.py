"""Walk of manual §4.1/§4.1.1 (principle of operation, the operator command) and §4.2 (the
operator modes), driven through the PG port on a real pty."""

from __future__ import annotations

import pytest

from tests.ip247.helpers import BACKWARD, FORWARD, START, STOP, Make, Module, record

ACK_QUEUED = 0x01


@pytest.mark.manual("§7.2.2", "error 2: the last job contained an undefined operating mode; the running mode "
                    "is aborted and the error shown")
@pytest.mark.manual("§4.1.1", "BA3 is free (not defined)")
def test_undefined_mode_while_running_aborts_with_2(mod: Module) -> None:
    mod.ready()
    mod.operate(1, 1, FORWARD, w=1000)
    mod.clock.advance(1)
    assert mod.device.read("axis.1.running") is True
    assert mod.operate(1, 3, START)[4] == 2
    mod.clock.advance(5)
    assert mod.device.read("axis.1.running") is False
    assert mod.device.read("axis.1.error") == 2


@pytest.mark.manual("§4.1", "while an axis brakes, further jobs are received into the job list but not "
                    "interpreted; at standstill they are interpreted in arrival order")
def test_a_job_while_braking_is_queued_and_interpreted_at_standstill(mod: Module) -> None:
    mod.ready()
    mod.operate(1, 1, FORWARD, w=1000)
    mod.clock.advance(1)
    mod.operate(1, 1, STOP)
    assert mod.device.read("axis.1.running") is True  # braking
    assert mod.operate(1, 3, START)[0] == ACK_QUEUED
    assert mod.device.read("axis.1.error") == 0  # not interpreted yet
    mod.clock.advance(5)
    assert mod.device.read("axis.1.running") is False and mod.device.read("axis.1.error") == 2


def observed(mod: Module, page: int = 1) -> bytes:
    return mod.call(0x62, bytes((page,)))


@pytest.mark.manual("§4.1", "observe commands are answered at once at any time, also while the axis brakes, "
                    "and do not touch the operating mode")
@pytest.mark.manual("§4.4", "the observe modes leave the operating mode as it is and run whatever the axis state")
def test_observe_at_any_time(mod: Module) -> None:
    mod.ready()
    mod.operate(1, 1, FORWARD, w=6000)
    mod.clock.advance(3)
    mod.operate(1, 1, STOP)
    assert mod.device.read("axis.1.running") is True  # braking
    answer = observed(mod)
    assert answer[0] == 0 and answer[5] == 1 and answer[6] & 0x80 == 0  # BA1, "läuft"
    assert mod.device.read("axis.1.mode") == 1


@pytest.mark.manual("§4.1", "an error stays pending until a new operator command on either interface "
                    "acknowledges it; observe commands in between show it again each time")
@pytest.mark.manual("§4.3.10", "error messages stay until a new operator command; observing in between shows them")
def test_errors_stay_until_the_next_operator_command(mod: Module) -> None:
    mod.ready()
    assert mod.operate(1, 6, START, dd=900_000)[4] == 23  # beyond x_E
    assert observed(mod)[4] == 23 and observed(mod)[4] == 23
    mod.device.set("ag.operate", {"page": 0, "ba": 12, "cmd": "Start", "dd": 0})  # from the PLC side
    assert observed(mod)[4] == 0


@pytest.mark.manual("§4.4", "Beobachtbetriebsarten sind: 66 Istwerte Lesen (FB165), 71, 73, 74")
@pytest.mark.manual("§4.1", "Dazwischen können beliebige Beobachtkommandos erfolgen, bei denen die anstehende "
                    "Fehlermeldung jeweils wieder mit ausgegeben wird")
def test_reading_the_actual_values_leaves_the_error_pending(mod: Module) -> None:
    """BA66 is an observe mode, not an operator command: it does not acknowledge the error; a data
    transfer such as BA67 is an operator command and does."""
    mod.ready()
    assert mod.operate(1, 6, START, dd=900_000)[4] == 23  # beyond x_E
    assert mod.call(0x64, bytes((1, 66, 0, 0)))[4] == 23
    assert observed(mod)[4] == 23
    assert mod.call(0x64, bytes((1, 67, 101, 0)))[4] == 0


@pytest.mark.manual("§4.1", "a command not meaningful in the mode (BA1 with Start) changes into the mode but "
                    "leaves the axis fertig, with an error")
@pytest.mark.parametrize(("ba", "cmd"), [(1, START), (7, START), (6, FORWARD), (12, FORWARD), (13, START),
                                       (15, START), (16, FORWARD)])
def test_a_wrong_combination_leaves_the_axis_fertig(mod: Module, ba: int, cmd: int) -> None:
    """The answer's BTR is the new mode (it stayed at BA5 but for BA8/BA9 Übernahme)."""
    mod.ready()
    answer = mod.operate(1, ba, cmd)
    assert answer[4] == 2 and answer[5] == ba and answer[6] & 0x80 and mod.device.read("axis.1.running") is False


@pytest.mark.manual("§4.1", "a velocity outside 1 … 65000 or above the maximum velocity is limited to the bound "
                    "and error 7 'Geschwindigkeit ausserhalb des zulässigen Bereichs' is given")
@pytest.mark.manual("§4.2.1", "jog velocities given in the parameter are limited to the bounds; the move runs "
                    "at the bound")
def test_a_velocity_above_the_maximum_is_limited_with_error_7(mod: Module) -> None:
    mod.ready()
    md = mod.m.units[0].md
    assert md is not None
    assert mod.operate(1, 1, FORWARD, w=9000)[4] == 7  # v_max is 6600 mm/min
    mod.clock.advance(4)  # (the ramp to f_max takes 2.84 s)
    assert mod.device.read("axis.1.velocity") == pytest.approx(md.f_max * md.resolution, rel=1e-6)


@pytest.mark.parametrize(("ba", "jog"), [(1, 1000), (2, 2000)])
@pytest.mark.manual("§4.2.1", "with velocity parameter 0, BA1/BA2 jog at the MD jog velocity 1 / 2")
def test_jog_velocities_from_the_machine_data(make: Make, ba: int, jog: int) -> None:
    mod = make()
    assert mod.load_md(record=record(jog2=2000))[8] == 0
    mod.operate(1, 5, START, b=1)
    assert mod.operate(1, ba, FORWARD)[4] == 0
    mod.clock.advance(3)
    assert mod.device.read("axis.1.velocity") == pytest.approx(jog * 1000 / 60, rel=1e-6)


@pytest.mark.manual("§4.2.1", "switching between the jog modes while moving: the axis stops, then moves on in the "
                    "new jog mode")
def test_switching_jog_modes_while_moving(make: Make) -> None:
    mod = make()
    assert mod.load_md(record=record(jog2=2000))[8] == 0
    mod.operate(1, 5, START, b=1)
    mod.operate(1, 1, FORWARD)
    mod.clock.advance(2)
    assert mod.operate(1, 2, FORWARD)[4] == 0
    speeds = []
    for _ in range(400):
        mod.clock.advance(0.001)
        speeds.append(mod.device.read("axis.1.velocity"))
    md = mod.m.units[0].md
    assert md is not None  # it braked down to f_ss, where the pulse train stops, before it started again:
    assert min(speeds) <= md.f_ss * md.resolution * 1.01 < 1000 * 1000 / 60  # (sampled each ms)
    mod.clock.advance(3)
    assert mod.device.read("axis.1.mode") == 2
    assert mod.device.read("axis.1.velocity") == pytest.approx(2000 * 1000 / 60, rel=1e-6)


@pytest.mark.manual("§4.2.2", "BA4 is set after the IP247 starts")
def test_ba4_after_start_up(mod: Module) -> None:
    assert observed(mod)[5] == 4 and mod.device.read("axis.1.mode") == 4


@pytest.mark.manual("§4.2.2", "any command with BA4 becomes a Stopp of the running mode; the axis does not change "
                    "to BA4: the aborted mode and Stopp stay shown")
def test_ba4_aborts_the_running_mode(mod: Module) -> None:
    mod.ready()
    mod.operate(1, 6, START, w=1000, dd=50_000)
    mod.clock.advance(1)
    assert mod.operate(1, 4, FORWARD)[4] == 0
    mod.clock.advance(5)
    answer = observed(mod)
    assert mod.device.read("axis.1.running") is False and answer[5] == 6
    assert answer[20] == STOP  # the last command shown


@pytest.mark.parametrize(("ba", "b"), [(6, 0), (8, 1), (9, 1), (10, 5)], ids=["BA6", "BA8", "BA9", "BA10"])
@pytest.mark.manual("§4.2.3", "without a reference point BA6, BA8, BA9 and BA10 are locked (error 10)")
def test_modes_locked_without_a_reference_point(mod: Module, ba: int, b: int) -> None:
    assert mod.load_md()[8] == 0
    assert mod.store(1, "%  1\nN1 X1 F1000\nN2 M02\n")[4] == 0
    assert mod.operate(1, ba, START, b=b, dd=5_000)[4] == 10


@pytest.mark.manual("§4.2.3", "BA5 needs error-free machine data")
def test_ba5_needs_machine_data(mod: Module) -> None:
    assert mod.operate(1, 5, START, b=1)[4] == 14


@pytest.mark.manual("§4.2.3", "the start of BA5 deletes an existing reference point")
@pytest.mark.manual("§4.2.4", "an aborted reference run leaves no reference point, even if there was one before")
def test_an_aborted_reference_run_leaves_none(make: Make) -> None:
    mod = make({"axes": {1: {"cam": [20_000.0, 30_000.0]}}})
    mod.ready()
    assert mod.device.read("axis.1.reference_set") is True
    assert mod.operate(1, 5, START, b=0)[4] == 0
    assert mod.device.read("axis.1.reference_set") is False
    mod.clock.advance(0.5)
    mod.operate(1, 5, STOP)
    mod.clock.advance(5)
    assert mod.device.read("axis.1.reference_set") is False and observed(mod)[6] & 0x20


@pytest.mark.manual("§4.2.3", "the reference point is lost when the module is switched on again")
def test_the_reference_point_is_lost_at_power_up(mod: Module) -> None:
    mod.ready()
    mod.device.fault("power", True)
    mod.device.fault("power", False)
    mod.clock.advance(2)
    assert observed(mod)[6] & 0x20


@pytest.mark.manual("§4.2.4", "special case 3: starting on the cam, the run leaves it at once in single steps in "
                    "the reference direction (no reversal at a limit switch)")
def test_reference_run_started_on_the_cam(make: Make) -> None:
    mod = make({"axes": {1: {"cam": [-2_000.0, 1_000.0], "anf": -50_000.0, "end": 50_000.0}}})
    assert mod.load_md()[8] == 0
    assert mod.operate(1, 5, START, b=0)[4] == 0
    mod.clock.advance(120)
    md = mod.m.units[0].md
    assert md is not None and mod.device.read("axis.1.reference_set") is True
    machine = mod.device.read("axis.1.machine_position")
    assert -2_000 - 2 * md.resolution < machine < -2_000  # left at the cam's start (R backward)
    assert mod.device.read("axis.1.error") == 0


@pytest.mark.manual("§4.2.5", "Referenzpunkt setzen: no motion; the current position gets the MD reference "
                    "coordinate, zero offsets and tool offsets considered")
def test_reference_set_keeps_offsets(mod: Module) -> None:
    assert mod.load_md()[8] == 0
    assert mod.operate(1, 15, FORWARD, dd=2_000)[4] == 0
    motor = mod.device.read("axis.1.machine_position")
    assert mod.operate(1, 5, START, b=1)[4] == 0
    assert mod.device.read("axis.1.machine_position") == motor
    assert mod.device.read("axis.1.position") == 1_000 + 2_000  # x_ref 1 mm, the tip 2 mm ahead


@pytest.mark.manual("§4.2.6", "BA6 runs at the MD step velocity when the velocity parameter is 0")
@pytest.mark.manual("§4.2.7", "BA7 takes its velocity as BA6 does")
def test_step_moves_at_the_md_step_velocity(make: Make) -> None:
    mod = make()
    assert mod.load_md(record=record(step_velocity=2000))[8] == 0
    mod.operate(1, 5, START, b=1)
    mod.operate(1, 6, START, dd=200_000)
    mod.clock.advance(3.5)
    assert mod.device.read("axis.1.velocity") == pytest.approx(2000 * 1000 / 60, rel=1e-6)
    mod.clock.advance(60)
    mod.operate(1, 7, BACKWARD, dd=150_000)
    mod.clock.advance(3.5)
    assert mod.device.read("axis.1.velocity") == pytest.approx(-2000 * 1000 / 60, rel=1e-6)


@pytest.mark.manual("§4.2.6", "the target must lie within the software limits (23 Verfahrbereichsüberschreitung)")
@pytest.mark.manual("§4.2.7", "with a reference point a relative move must end within the software limits, else "
                    "23; without one BA7 runs")
def test_targets_outside_the_sw_limits(mod: Module) -> None:
    assert mod.load_md()[8] == 0
    assert mod.operate(1, 7, FORWARD, w=6000, dd=600_000)[4] == 0  # no reference point: it runs
    mod.clock.advance(1)
    mod.operate(1, 7, STOP)
    mod.clock.advance(5)
    mod.operate(1, 5, START, b=1)
    assert mod.operate(1, 6, START, dd=500_001)[4] == 23
    assert mod.operate(1, 7, FORWARD, dd=499_001)[4] == 23
    assert mod.operate(1, 7, BACKWARD, dd=11_001)[4] == 23


@pytest.mark.manual("§4.2.6", "on a rotary axis Start to the position it stands on makes no motion")
def test_rotary_start_to_where_it_stands(make: Make) -> None:
    mod = make()
    assert mod.load_md(record=record(unit=3, rotary=True, limit_begin=0, limit_end=360_000, gear=1_600,
                                     pulses_per_rev=400, reference=0, backlash=0, f_ss=200, f_max=20_000,
                                     a=100_000, jog1=1000, jog2=1000, step_velocity=1000,
                                     reference_velocity=1000, zero_offsets=(0, 0, 0, 0)))[8] == 0
    mod.operate(1, 5, START, b=1)
    motor = mod.device.read("axis.1.machine_position")
    assert mod.operate(1, 6, START, dd=0)[4] == 0
    mod.clock.advance(10)
    assert mod.device.read("axis.1.machine_position") == motor


@pytest.mark.manual("§4.2.4", "the run starts against the reference direction at the reference velocity, reverses "
                    "at the limit switch and goes on past the cam; it comes back onto the cam at f_ss and leaves "
                    "it in single steps in the reference direction")
def test_reference_run_reverses_at_the_limit_switch(make: Make) -> None:
    mod = make({"axes": {1: {"cam": [-8_000.0, -6_000.0], "end": 20_000.0}}})
    assert mod.load_md()[8] == 0  # COM247: reference direction backward
    assert mod.operate(1, 5, START, b=0)[4] == 0
    mod.clock.advance(0.5)
    assert mod.device.read("axis.1.velocity") > 0  # first forward, against the reference direction
    mod.clock.advance(120)
    md = mod.m.units[0].md
    assert md is not None and mod.device.read("axis.1.reference_set") is True
    assert mod.device.read("axis.1.error") == 0  # the limit switch reversed the run: no error
    machine = mod.device.read("axis.1.machine_position")
    assert -8_000 - 2 * md.resolution < machine < -8_000
    assert mod.device.read("axis.1.position") == md.reference


@pytest.mark.manual("§4.2.4", "special case 2: with the reversing limit switch actuated at the start the run goes "
                    "in the reference direction at once")
def test_reference_run_started_on_the_limit_switch(make: Make) -> None:
    mod = make({"axes": {1: {"cam": [-8_000.0, -6_000.0], "end": 5_000.0}}})
    assert mod.load_md()[8] == 0
    mod.operate(1, 7, FORWARD, w=1000, dd=10_000)  # onto the END switch: 26
    mod.clock.advance(10)
    assert mod.device.read("axis.1.error") == 26 and mod.device.read("input.END1") is False
    assert mod.operate(1, 5, START, b=0)[4] == 0
    mod.clock.advance(0.5)
    assert mod.device.read("axis.1.velocity") < 0  # at once backward, in the reference direction
    mod.clock.advance(120)
    assert mod.device.read("axis.1.reference_set") is True and mod.device.read("axis.1.error") == 0
