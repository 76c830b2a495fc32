"""The LM628's samples run in one pass (devsim/devices/pcd4h3/batch.py) give the same chip, sample
for sample, as the reference loop :meth:`Lm628.sample` (spec pcd4h3.md §5.1–§5.9; issue 31):
position, velocity, following error, status and signals, breakpoints, errors, index capture,
stops, velocity mode, a parameter change mid-move.  Compared once with a pass per sample (every
sample), once with passes of random lengths (the state carried between samples), and once with
passes that keep checkpoints at marks (what the PLC's look-ahead computes, ending at a change
of status)."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from devsim.devices.pcd4h3 import batch
from devsim.devices.pcd4h3.lm628 import POSITION_RANGE, Lm628
from devsim.devices.pcd4h3.pid import Motor
from devsim.devices.pcd4h3.units import CHIP_SAMPLE

Action = Callable[[Lm628], None]
Script = dict[int, list[Action]]

SMOOTH, ABRUPT, MOTOR_OFF = 0x0400, 0x0200, 0x0100
VELOCITY_MODE, FORWARD = 0x0800, 0x1000


def state(chip: Lm628, quiet: int) -> tuple[Any, ...]:
    p, f, m = chip.profile, chip.filter, chip.motor
    return (m.position, m.velocity, chip.actual, chip.desired, chip.desired - chip.actual, chip.real_velocity,
            chip.status, chip.signals, chip.flags, chip.on_target, chip.motor_off, chip.udf_sample,
            chip.index_position, chip.index_armed, chip._raw,
            p.position, p.velocity, p.target, p.stopping, p.complete, p.velocity_mode, p.forward,
            f.error_sum, f.derivative, f._previous, f._countdown, f.output, f.integral, f.dac, quiet)


def chip_for(spec: dict[str, Any]) -> Lm628:
    motor = Motor(kv=spec.get("kv", 10_000.0), tau=spec.get("tau", 0.020), low=spec.get("low", float("-inf")),
                  high=spec.get("high", float("inf")))
    chip = Lm628(motor, encoder_sign=spec.get("sign", 1), index_period=spec.get("index_period", 0),
                 index_offset=spec.get("index_offset", 0), sample_time=spec.get("sample_time", CHIP_SAMPLE))
    chip.reset()
    chip.port(spec.get("port", 12))
    kp, ki, kd, il, ds = spec.get("pid", (40, 0, 400, 500, 3))
    chip.load_filter(ds << 8 | 0x0F, [kp, ki, kd, il])
    chip.update_filter()
    return chip


def reference_trace(spec: dict[str, Any], script: Script, samples: int) -> list[tuple[Any, ...]]:
    chip, quiet, trace = chip_for(spec), 0, []
    for n in range(samples):
        for action in script.get(n, ()):
            action(chip)
        quiet = batch.run_reference(chip, 1, quiet)
        trace.append(state(chip, quiet))
    return trace


def batched_trace(spec: dict[str, Any], script: Script, samples: int, lengths: list[int]) -> dict[int, tuple]:
    """The state after each pass, by the number of samples done; passes end at every action."""
    chip, quiet, seen, n = chip_for(spec), 0, {}, 0
    stops = sorted(k for k in script if k > 0)
    lengths = lengths or [1]
    i = 0
    while n < samples:
        for action in script.get(n, ()):
            action(chip)
        length = min(lengths[i % len(lengths)], samples - n, *(k - n for k in stops if k > n))
        i += 1
        quiet = batch.run(chip, length, quiet)
        n += length
        seen[n] = state(chip, quiet)
    return seen


def marked_trace(spec: dict[str, Any], script: Script, samples: int, lengths: list[int]) -> dict[int, tuple]:
    """Passes of :func:`batch.run_to` from action to action, a mark every ``lengths`` samples
    (in turn); returns each checkpoint's (state, quiet, status) by the number of samples done.
    A pass ends at its last mark or at the first checkpoint whose status differs from the
    chip's before it; the next pass goes on from there."""
    chip, quiet, seen, n, i = chip_for(spec), 0, {}, 0, 0
    stops = sorted(k for k in script if k > 0)
    while n < samples:
        for action in script.get(n, ()):
            action(chip)
        end, marks = min([samples, *(k for k in stops if k > n)]), []
        while not marks or marks[-1] < end - n:
            marks.append(min(end - n, (marks[-1] if marks else 0) + lengths[i % len(lengths)]))
            i += 1
        status = chip.status
        checkpoints, quiet = batch.run_to(chip, marks, quiet)
        assert [mark for mark, _, _ in checkpoints] == marks[:len(checkpoints)]
        changed = [batch.status_of(state) != status for _, _, state in checkpoints]
        assert changed == [False] * (len(marks) - 1) + [changed[-1]] if len(checkpoints) == len(marks) \
            else changed == [False] * (len(checkpoints) - 1) + [True], "the pass ends at the first change"
        assert batch.snapshot(chip) == checkpoints[-1][2] and quiet == checkpoints[-1][1]
        for mark, kept, state in checkpoints:
            seen[n + mark] = (state, kept, batch.status_of(state), batch.motion_of(state))
        n += checkpoints[-1][0]
    return seen


def reference_snapshots(spec: dict[str, Any], script: Script, samples: int) -> list[tuple[Any, ...]]:
    chip, quiet, trace = chip_for(spec), 0, []
    for n in range(samples):
        for action in script.get(n, ()):
            action(chip)
        quiet = batch.run_reference(chip, 1, quiet)
        trace.append((batch.snapshot(chip), quiet, chip.status, (chip.motor.position, chip.motor.velocity)))
    return trace


def check(spec: dict[str, Any], script: Script, samples: int, lengths: list[int] | None = None) -> None:
    reference = reference_trace(spec, script, samples)
    for n, got in batched_trace(spec, script, samples, [1]).items():  # every sample
        assert got == reference[n - 1], f"sample {n}"
    if lengths:
        for n, got in batched_trace(spec, script, samples, lengths).items():
            assert got == reference[n - 1], f"sample {n} (passes {lengths})"
        snapshots = reference_snapshots(spec, script, samples)
        for n, got in marked_trace(spec, script, samples, lengths).items():
            assert got == snapshots[n - 1], f"sample {n} (checkpoints every {lengths})"


def ltrj(control: int, *values: int) -> Action:
    return lambda chip: chip.command("LTRJ", control, *values)


def cmd(mnemonic: str, *words: int) -> Action:
    return lambda chip: chip.command(mnemonic, *words)


def move(target: int, velocity: int = 1_117_389, acceleration: int = 76) -> list[Action]:
    return [ltrj(0x002A, acceleration, velocity, target), cmd("STT")]


LENGTHS = [7, 64, 1, 300, 29]


def test_a_plain_move_to_rest() -> None:
    check({}, {0: move(30_000)}, 12_000, LENGTHS)


def test_a_move_and_a_breakpoint_at_another_sample_time() -> None:
    """chip_sample_time_us: an 8 MHz chip samples every 256 µs; the pass takes its sample time too."""
    check({"sample_time": 256e-6, "index_period": 2_000},
          {0: [cmd("SBPA", 5_000), cmd("SIP"), *move(30_000)]}, 12_000, LENGTHS)


def test_a_move_with_the_integrator_and_an_8_bit_port() -> None:
    check({"pid": (30, 4, 300, 2000, 1), "port": 8}, {0: move(-20_000, 900_000, 120)}, 9_000, LENGTHS)


def test_absolute_and_relative_breakpoints() -> None:
    script: Script = {0: [cmd("SBPA", 5_000), *move(20_000)], 3_000: [cmd("RSTI", 0), cmd("SBPR", -2_000)]}
    check({}, script, 9_000, LENGTHS)


def test_a_position_error_flag_and_a_position_error_stop() -> None:
    check({}, {0: [cmd("LPEI", 40), *move(30_000)]}, 6_000, LENGTHS)
    check({}, {0: [cmd("LPES", 40), *move(30_000)]}, 6_000, LENGTHS)  # motor off, the axis coasts


def test_a_load_at_top_velocity_runs_into_the_position_error() -> None:
    """The pass's loop for a generator only adding its velocity (nothing watched): a load
    torque mid-cruise, the error flag, and the stop that switches the motor off."""
    def load(chip: Lm628) -> None:
        chip.motor.load = 3.0

    for threshold in ("LPEI", "LPES"):
        check({"pid": (30, 4, 300, 2000, 1)}, {0: [cmd(threshold, 300), *move(400_000, 1_117_389, 2_000)],
                                              2_000: [load]}, 5_000, LENGTHS)


def test_breakpoints_passed_at_top_velocity_and_across_the_wrap() -> None:
    """The loop for a generator only adding its velocity, with a breakpoint watched: passed
    absolute and relative while cruising, and a wrap-around with a breakpoint set."""
    script: Script = {0: [cmd("SBPA", 20_000), *move(200_000, 1_117_389, 2_000)],
                      3_000: [cmd("RSTI", 0), cmd("SBPR", -150_000)]}
    check({}, script, 5_000, LENGTHS)

    def near_the_end(chip: Lm628) -> None:
        chip.set_actual(POSITION_RANGE - 30_000)

    script = {0: [near_the_end, cmd("SBPA", -(1 << 30) + 20_000), ltrj(0x002A, 2_000, 1_117_389, 0), cmd("STT")],
              10: [ltrj(0x0008 | VELOCITY_MODE | FORWARD, 1_500_000), cmd("STT")]}
    check({}, script, 5_000, LENGTHS)


def test_cruising_with_the_integrator_saturated_and_its_coefficients_changed() -> None:
    """The loop for a generator only adding its velocity: the integral term computed again only
    when the error sum changes (ki set, then raised with il so that Σe stays at its limit, then cleared by UDF
    mid-cruise), the motor's goal-speed table by output level (both ports, a load, an encoder
    counting backwards), and a following error beyond the loop's bound."""
    def load(chip: Lm628) -> None:
        chip.motor.load = -0.4

    for sign, port in ((1, 12), (-1, 8)):
        script: Script = {0: move(400_000, 1_117_389, 2_000),
                          900: [cmd("LFIL", 0x0104, 40), cmd("UDF")],
                          1_700: [load, cmd("LFIL", 0x0105, 80, 400), cmd("UDF")],  # the same limit of Σe
                          2_600: [cmd("LFIL", 0x0104, 0), cmd("UDF")]}
        check({"pid": (30, 0, 300, 200, 1), "sign": sign, "port": port}, script, 3_500, LENGTHS)

    def loaded(volts: float) -> Action:
        def act(chip: Lm628) -> None:
            chip.motor.load = volts
        return act

    # the following error grows past what e holds without its 16-bit clamp (and past the
    # threshold, 7FFFh), and comes back once the load is gone
    script = {0: [cmd("LPEI", 0x7FFF), *move(4_000_000, 1_117_389, 2_000)], 1_000: [loaded(9.5)],
              3_600: [loaded(0.0)]}
    check({"pid": (30, 4, 300, 2000, 1)}, script, 6_500, LENGTHS)
    # a proportional filter alone, at a velocity the motor reaches only at full output: the
    # error creeps through the last counts below 7FFFh, a derivative taken at every sample
    check({"pid": (1, 0, 0, 0, 0)}, {0: [cmd("LPEI", 0x7FFF), *move(4_000_000, 2_240_000, 2_000)]}, 7_200, LENGTHS)


def test_wrap_around() -> None:
    def near_the_end(chip: Lm628) -> None:
        chip.set_actual(POSITION_RANGE - 3_000)

    script: Script = {0: [near_the_end, ltrj(0x002A, 76, 1_117_389, 0), cmd("STT")],
                      10: [ltrj(0x0008 | VELOCITY_MODE | FORWARD, 1_500_000), cmd("STT")]}
    check({}, script, 5_000, LENGTHS)


def test_index_capture_forward_and_backward() -> None:
    spec = {"index_period": 2_000, "index_offset": 37}
    check(spec, {0: [cmd("SIP"), *move(9_000)], 4_000: [cmd("SIP"), *move(-3_000)]}, 10_000, LENGTHS)
    check({**spec, "sign": -1}, {0: [cmd("SIP"), *move(6_000)]}, 5_000, LENGTHS)


def test_smooth_abrupt_and_motor_off_stops_mid_move() -> None:
    for stop in (SMOOTH, ABRUPT, MOTOR_OFF):
        script: Script = {0: move(60_000), 1_500: [ltrj(stop), cmd("STT")], 6_000: move(0)}
        check({}, script, 10_000, LENGTHS)


def test_velocity_mode_both_ways_and_a_stop() -> None:
    script: Script = {0: [ltrj(0x0028 | VELOCITY_MODE | FORWARD, 90, 2_000_000), cmd("STT")],
                      2_000: [ltrj(0x0008 | VELOCITY_MODE, 800_000), cmd("STT")],
                      5_000: [ltrj(SMOOTH), cmd("STT")]}
    check({}, script, 8_000, LENGTHS)


def test_ramps_that_reach_their_goal_and_a_smooth_stop_to_rest() -> None:
    """The samples in which the generator only adds its acceleration to its velocity (a ramp, in
    the pass's loop for a generator that only adds): velocity-mode ramps up and down to goals
    that are not a multiple of the acceleration, a reversal, and smooth stops that come to rest
    (from a multiple of the acceleration and from between two)."""
    for reverse in (-500_500, -500_000):
        script: Script = {0: [ltrj(0x0028 | VELOCITY_MODE | FORWARD, 1_000, 1_117_389), cmd("STT")],
                          2_000: [ltrj(0x0008 | VELOCITY_MODE | FORWARD, 300_001), cmd("STT")],
                          3_500: [ltrj(0x0008 | VELOCITY_MODE, -reverse), cmd("STT")],
                          5_000: [ltrj(SMOOTH), cmd("STT")]}
        check({}, script, 6_000, LENGTHS)


def test_ramps_that_end_at_the_edge_of_braking_or_of_the_target() -> None:
    """A position-mode ramp is only added in one step while it can neither brake nor reach the
    target: short moves with steep accelerations whose ramps end exactly where the remaining
    distance equals the braking distance or the next step."""
    script: Script = {0: move(3, 6_000_000, 1 << 16), 150: move(15, 6_000_000, 1 << 16),
                      300: move(45, 6_000_000, 1 << 16), 450: move(54, 6_000_000, 3 << 16),
                      600: move(102, 6_000_000, 1 << 20)}
    check({"pid": (60, 0, 500, 0, 0)}, script, 800, LENGTHS)

    def no_acceleration(chip: Lm628) -> None:  # (an injection: no command loads it while moving)
        chip.profile.acceleration = 0

    check({}, {0: move(40_000), 300: [no_acceleration]}, 1_000, LENGTHS)  # a ramp that stays where it is


def test_parameters_changed_mid_move() -> None:
    script: Script = {0: move(80_000), 1_000: [ltrj(0x000A, 3_000_000, 80_000), cmd("STT")],
                      2_500: [cmd("LFIL", 0x000E, 60, 0, 600), cmd("UDF")], 3_000: [cmd("DFH")],
                      4_000: [cmd("PORT8")], 4_200: [ltrj(0x0003, -10_000), cmd("STT")]}
    check({"pid": (40, 3, 400, 900, 2)}, script, 12_000, LENGTHS)


def test_end_stops_a_load_and_a_blocked_motor() -> None:
    def block(chip: Lm628) -> None:
        chip.motor.blocked = True

    def free(chip: Lm628) -> None:
        chip.motor.blocked, chip.motor.load = False, 0.05

    check({"low": -1_000.0, "high": 4_000.0}, {0: move(10_000), 4_000: move(-8_000)}, 9_000, LENGTHS)
    check({}, {0: move(20_000), 800: [block], 1_600: [free]}, 5_000, LENGTHS)


def test_a_breakpoint_passed_by_a_motor_speeding_up_after_the_profile_ended() -> None:
    """The breakpoint checked one sample at a time (the profile complete): a motor held until
    the profile has reached its target, then let go, passes a breakpoint at a speed far above
    the one it had when the pass began to check."""
    def block(chip: Lm628) -> None:
        chip.motor.blocked = True

    def free(chip: Lm628) -> None:
        chip.motor.blocked = False

    for breakpoint in (150, 400, 1_500, 6_000):
        check({}, {0: [cmd("SBPA", breakpoint), block, *move(8_000, 4_000_000, 20_000)], 400: [free]}, 1_500,
              LENGTHS)


def test_a_motor_without_lag() -> None:
    check({"tau": 0.0, "kv": 2_000.0}, {0: move(5_000)}, 3_000, LENGTHS)


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(target=st.integers(-60_000, 60_000), velocity=st.integers(1, 4_000_000), acceleration=st.one_of(st.integers(1, 3_000), st.integers(3_000, 1 << 21)),
       kp=st.integers(1, 200), ki=st.integers(0, 20), kd=st.integers(0, 2_000), il=st.integers(0, 0x7FFF),
       ds=st.integers(0, 7), port=st.sampled_from([8, 12]), tau=st.sampled_from([0.0, 0.002, 0.020, 0.3]),
       kv=st.sampled_from([500.0, 10_000.0, 80_000.0]), threshold=st.integers(0, 0x7FFF),
       stop_on_error=st.booleans(), breakpoint=st.integers(-60_000, 60_000),
       lengths=st.lists(st.integers(1, 400), min_size=1, max_size=6))
def test_random_moves(target: int, velocity: int, acceleration: int, kp: int, ki: int, kd: int, il: int, ds: int,
                      port: int, tau: float, kv: float, threshold: int, stop_on_error: bool, breakpoint: int,
                      lengths: list[int]) -> None:
    spec = {"pid": (kp, ki, kd, il, ds), "port": port, "tau": tau, "kv": kv, "index_period": 1_000}
    error = cmd("LPES" if stop_on_error else "LPEI", threshold)
    script: Script = {0: [error, cmd("SBPA", breakpoint), cmd("SIP"), *move(target, velocity, acceleration)],
                      1_200: [ltrj(0x0008, max(1, velocity // 2)), cmd("STT")]}
    check(spec, script, 2_500, lengths)


def test_the_last_steps_of_a_steep_braking() -> None:
    """An acceleration above one count per sample²: the generator keeps at least the remaining
    distance's step while braking (so the last sub-count steps arrive)."""
    for acceleration in (70_000, 200_000, 1 << 20):
        check({"pid": (60, 0, 500, 0, 0)}, {0: move(3_000, 6_000_000, acceleration),
                                           600: move(-1_234, 900_000, acceleration)}, 1_500, LENGTHS)


def test_a_pcd_whose_axis_stands_has_no_timer() -> None:
    """An idle axis uses no CPU: once the move has ended and the motor stands, neither the PLC
    cycle nor the chip has a timer; while it moves the PLC cycles."""
    from devsim.core.clock import VirtualClock
    from devsim.devices.pcd4h3.model import Pcd4

    clock = VirtualClock()
    pcd = Pcd4(clock=clock, config={"h3def": {"fmah3": 48, "bar": 200, "baf": 200, "mna": 1}})
    clock.advance(1.0)
    assert clock.next_event() is None
    axis = pcd.axes[0]
    axis.registers.load("DestP", 3)
    axis.set_flag("FLdDA", 1)
    axis.set_flag("FStart", 1)
    pcd.wake()
    clock.advance(0.5)
    assert clock.next_event() is not None and not pcd.drives[0].settled
    assert clock.run_until(lambda: clock.next_event() is None, 60.0)
    assert pcd.drives[0].settled and pcd.drives[0].chip.actual == 300  # 100 counts per unit (MCFac)
    pcd.close()
