"""A run of LM628 samples in one pass (spec pcd4h3.md §5.1–§5.9; issue 31, "sampled loops only
while they matter"): what :meth:`~devsim.devices.pcd4h3.lm628.Lm628.sample` does ``count`` times,
with the chip's working state held in local variables between the events that need the objects.

Bit-exact with the sample-by-sample reference: the same integer arithmetic of the profile
generator and the filter, the same floating-point operations of the motor in the same order
(``tests/pcd4h3/test_batch.py`` compares both at every sample).  The pass covers a motor that is
on, free and has a time constant; anything else (motor off, a blocked motor, τm = 0) and the
sample after a position-error stop take the reference :meth:`Lm628.sample`.  It also counts the
samples in which nothing changed, as :class:`~devsim.devices.pcd4h3.stepper.ChipStepper` decides
that the chip has settled.

While the profile generator only adds its velocity (at the top velocity) or its acceleration to
it (a ramp that cannot brake or reach the target, a smooth stop not yet at rest), and the
following error stays within a bound, the pass runs a loop without the branches that cannot be
taken; the motor's goal speed times its lag terms comes from a table by output level.
:func:`run_to` keeps a checkpoint of the state at given samples (the PLC's look-ahead) and ends
at the first whose status differs.
"""

from __future__ import annotations

import math

from devsim.devices.pcd4h3.lm628 import (
    COMPLETE,
    MOTOR_OFF,
    POSITION_ERROR,
    POSITION_RANGE,
    WRAPAROUND,
    Lm628,
    moved_flags,
    wrap,
)
from devsim.devices.pcd4h3.pid import _lag_terms, sat

__all__ = ["SETTLE", "STILL", "Checkpoint", "motion_of", "rest", "restore", "run", "run_reference", "run_to", "snapshot", "status_of"]

STILL = 1e-3  # counts/s: a motor slower than this stands (for the settled count)
SETTLE = 64  # samples without change after which a chip counts as settled (its rest begins)
# counts a sample at most per count/s of the motor's speed: a sample of the lag moves it by at
# most max(|v|, |goal|) · (τ·(1 − e^(−t/τ)) + t − τ·(1 − e^(−t/τ))) = … · t, with room for rounding
STEP_SLACK = 1.001  # per second of the sample time
ONE = 1 << 16
FAR_SPAN = 64  # samples one at a time that one look at the breakpoint's distance spares its checks
I16_LOW, I16_HIGH = -(1 << 15), (1 << 15) - 1
I24_LOW, I24_HIGH = -(1 << 23), (1 << 23) - 1
TWICE_RANGE = 2 * POSITION_RANGE


State = tuple[int | bool | float, ...]
Checkpoint = tuple[int, int, State]  # samples from a pass's start, samples without change, state


def snapshot(chip: Lm628) -> State:
    """Everything a run of samples changes in ``chip`` (not what only commands change)."""
    p, f, m = chip.profile, chip.filter, chip.motor
    return (p.position, p.velocity, p.target, p.stopping, p.complete,
            f.error_sum, f.derivative, f._previous, f._countdown, f.output, f.integral,
            m.position, m.velocity, chip.flags, chip.on_target, chip._raw, chip.udf_sample, chip.motor_off,
            chip.index_armed, chip.index_position, chip.rest_x, chip.rest_v, chip.rest_n)


def status_of(state: State) -> int:
    """RDSTAT of the chip in ``state`` (as :attr:`Lm628.status`)."""
    return state[13] | (MOTOR_OFF if state[17] else 0)  # type: ignore[operator]


def motion_of(state: State) -> tuple[float, float]:
    """The motor's position and velocity in ``state``."""
    return state[11], state[12]  # type: ignore[return-value]


def restore(chip: Lm628, state: State) -> None:
    """Put ``chip`` back where :func:`snapshot` found it (the same command state assumed)."""
    p, f, m = chip.profile, chip.filter, chip.motor
    (p.position, p.velocity, p.target, p.stopping, p.complete,
     f.error_sum, f.derivative, f._previous, f._countdown, f.output, f.integral,
     m.position, m.velocity, chip.flags, chip.on_target, chip._raw, chip.udf_sample, chip.motor_off,
     chip.index_armed, chip.index_position, chip.rest_x, chip.rest_v, chip.rest_n) = state  # type: ignore[assignment]


def _still(chip: Lm628) -> tuple[int, int, int, int]:
    """What a sample of a settled chip leaves as it was: the actual and desired positions, the
    flags, and Σe where it feeds an integral term."""
    f = chip.filter
    return chip.actual, chip.profile.position, chip.flags, f.error_sum if f.working.ki else 0


def _quiet_after(chip: Lm628, before: tuple[int, int, int, int], quiet: int) -> int:
    """``quiet`` + 1 after a sample that changed nothing and leaves the filter at rest (the
    error e is the one of the last derivative sample and the derivative 0: the next samples
    change only the derivative's countdown and Σe without an integral term), else 0."""
    f = chip.filter
    if _still(chip) == before and chip.profile.complete and abs(chip.motor.velocity) < STILL \
            and f.derivative == 0 and f._previous == sat(chip.profile.desired - chip.unwrapped_actual, 16):
        quiet += 1
        if quiet == SETTLE:
            chip.rest_x, chip.rest_v, chip.rest_n = chip.motor.position, chip.motor.velocity, 0
        elif quiet > SETTLE:
            chip.rest_n += 1
        return quiet
    return 0


def rest(chip: Lm628, count: int) -> bool:
    """``count`` samples of a settled chip (:func:`run` counted the samples without change that
    make it so, :func:`_quiet_after`) in closed form: what :meth:`Lm628.sample` would change,
    the filter's derivative countdown, Σe without an integral term (clamped as each sample
    clamps it, which for a constant e is the sum's clamp), the UDF bit, and the motor's lag
    dying away towards its goal speed 0 (v·e^(−nT/τ), the position v·τ·(1 − e^(−nT/τ)) further:
    the floating-point sums of the samples one by one within their rounding).  Returns False,
    having changed nothing, where that is not all: a goal speed that is not 0 (a load the
    output does not hold exactly), a lag that would reach the next count or an end stop; the
    caller computes those samples.  The lag is taken from where the rest began (``rest_x``,
    ``rest_v``, ``rest_n`` + ``count`` samples), so that a settled chip's motor is the same
    floating point however its samples were taken (``count`` 0: just that)."""
    if count < 0:
        return True
    motor, f = chip.motor, chip.filter
    volts = f.volts if f.dac_bits == 12 else f.volts * 10.0  # (the filter's output, reset while the motor is off)
    x, velocity = motor.position, motor.velocity
    if not motor.blocked:
        if motor.kv * (volts - motor.load) != 0.0:
            return False
        if motor.tau > 0:
            if motor._decay[0] != chip.sample_time:
                motor._decay = (chip.sample_time, *_lag_terms(chip.sample_time, motor.tau))
            since = chip.rest_n + count
            decay = motor._decay[1] ** since
            x, velocity = chip.rest_x + chip.rest_v * motor.tau * (1.0 - decay), chip.rest_v * decay
            if not motor.low <= x <= motor.high or math.floor(chip.encoder_sign * x) != chip._raw:
                return False
        else:
            velocity = 0.0
    motor.position, motor.velocity = x, velocity
    chip.rest_n += count
    if not count:
        return True
    chip.udf_sample = False
    if chip.motor_off:
        return True  # the filter is reset at every sample
    countdown, ds = f._countdown, f.working.ds
    f._countdown = countdown - count if count <= countdown else ds - (count - countdown - 1) % (ds + 1)
    if not f.working.ki:
        e = sat(chip.profile.desired - chip.unwrapped_actual, 16)
        f.error_sum = max(I24_LOW, min(I24_HIGH, f.error_sum + count * e))
    return True


def run_reference(chip: Lm628, count: int, quiet: int) -> int:
    """``count`` samples by :meth:`Lm628.sample`, one at a time; returns the samples in a row
    without any change (``quiet`` before)."""
    for _ in range(count):
        before = _still(chip)
        chip.sample()
        quiet = _quiet_after(chip, before, quiet)
    return quiet


def _segment(raw: int, home: int) -> tuple[int, int]:
    """The raw counts in which the position (raw − home) does not wrap around (§5.7)."""
    low = ((raw - home + POSITION_RANGE) >> 31 << 31) + home - POSITION_RANGE
    return low, low + (1 << 31)


def _cruise(target: int, position: int, velocity: int, direction: int, acceleration: int) -> int:
    """Samples from ``position`` in which a position-mode profile at its top velocity only adds
    it: the remaining distance stays above both the braking distance and one step."""
    speed = abs(velocity)
    braking = speed * speed // (2 * acceleration) + speed // 2 if acceleration else 0
    margin = (target - position) * direction - max(braking, speed)
    return (margin - 1) // speed + 1 if margin > 0 else 0


Goals = dict[int, tuple[float, float]]
_GOALS: dict[tuple[float, ...], Goals] = {}


def _goals(kv: float, load: float, scale: int, travelled: float, gained: float) -> Goals:
    """The motor's goal speed times its two lag terms by output level (``output >> shift``), as
    :meth:`~devsim.devices.pcd4h3.pid.Motor.step` computes them; shared by every chip with the
    same motor, filled as levels occur (at most 4096 each).  A memo of a pure function of its
    key, like :func:`functools.lru_cache` (at most 64 motors, then it starts anew): no state of
    one device reaches another, and a table per device would cost each its memory."""
    key = (kv, load, math.copysign(1.0, kv), math.copysign(1.0, load), scale, travelled, gained)
    table = _GOALS.get(key)
    if table is None:
        if len(_GOALS) >= 64:
            _GOALS.clear()
        table = _GOALS[key] = {}
    return table


def _goal(goals: Goals, level: int, kv: float, load: float, scale: int, travelled: float,
          gained: float) -> tuple[float, float]:
    goal_speed = kv * (level / scale * 10.0 - load)
    pair = goals[level] = (goal_speed * travelled, goal_speed * gained)
    return pair


def _unclamped(v: int, threshold: int) -> int:
    """The following error up to which the next sample's e = err + Δdesired (|Δdesired| at most
    |v| / 2^16 + 1 counts) fits 16 bits without its clamp, and no position error is flagged."""
    bound = I16_HIGH - (abs(v) >> 16) - 1
    return threshold if threshold < bound else bound


def _ramp(distance: int, speed: int, acceleration: int, top: int) -> int:
    """Samples from now in which a position-mode profile ramping up at ``speed`` (0 < speed <
    top) only adds ``acceleration`` to it: the speed stays below ``top``, and the distance to
    the target (``distance``, in the direction of motion) above both the braking distance and
    one step.  Both only tighten from sample to sample, so the last sample that keeps them is
    found by bisection."""
    def keeps(m: int) -> bool:  # the m-th sample from now, and with it every one before
        k = m - 1
        before = speed + k * acceleration  # the speed that sample starts with
        left = distance - k * speed - acceleration * k * (k + 1) // 2
        return left > before * before // (2 * acceleration) + before // 2 and left > before + acceleration

    low, high = 0, (top - speed - 1) // acceleration  # below top: speed + m · acceleration < top
    while low < high:
        middle = (low + high + 1) // 2
        if keeps(middle):
            low = middle
        else:
            high = middle - 1
    return low


def _far(raw: int, home: int, breakpoint: int, segment: tuple[int, int], travel: float) -> bool:
    """Whether the encoder, at ``raw`` counts, stays more than ``travel`` counts from the
    breakpoint and from the ends of its segment (no wrap-around, no breakpoint passed)."""
    position = (raw - home + POSITION_RANGE) % TWICE_RANGE - POSITION_RANGE
    return abs(position - breakpoint) > travel and raw - segment[0] > travel and segment[1] - 1 - raw > travel


def _fast(chip: Lm628) -> bool:
    motor = chip.motor
    return not chip.motor_off and not motor.blocked and motor.tau > 0


def run(chip: Lm628, count: int, quiet: int) -> int:
    """``count`` samples of ``chip``, exactly as :func:`run_reference` computes them."""
    return _run(chip, count, quiet, [], [])


def run_to(chip: Lm628, marks: list[int], quiet: int, *, settle: bool = False) -> tuple[list[Checkpoint], int]:
    """The samples up to each of ``marks`` (increasing counts of samples from now, the first at
    least 1) in one pass, as :func:`run` computes them, with a checkpoint ``(samples, quiet,
    state)`` at each (the state as :func:`snapshot` takes it); the pass ends at the first
    checkpoint whose status (RDSTAT) differs from the chip's now: between commands the status
    only gains bits, so the checkpoints before it all have the status of now.  ``settle``: also
    at the first where the chip has settled (:data:`SETTLE`; :func:`rest` goes on from there)."""
    checkpoints: list[Checkpoint] = []
    quiet = _run(chip, marks[-1], quiet, marks, checkpoints, SETTLE if settle else 1 << 62)
    return checkpoints, quiet


def _run(chip: Lm628, count: int, quiet: int, marks: list[int], checkpoints: list[Checkpoint],
         settle: int = 1 << 62) -> int:
    status = chip.status
    done = 0
    while done < count:
        if _fast(chip):
            n, quiet = _run_fast(chip, count - done, quiet, marks, done, status, checkpoints, settle)
            done += n
        else:
            quiet = run_reference(chip, 1, quiet)
            done += 1
        at = len(checkpoints)
        if at < len(marks) and marks[at] == done:  # reached by the reference or after a stop
            checkpoints.append((done, quiet, snapshot(chip)))
        if checkpoints and (status_of(checkpoints[-1][2]) != status or checkpoints[-1][1] >= settle):
            break
    return quiet


def _run_fast(chip: Lm628, count: int, quiet: int, marks: list[int], base: int, status: int,  # noqa: C901, PLR0912, PLR0913, PLR0915
              checkpoints: list[Checkpoint], settle: int = 1 << 62) -> tuple[int, int]:
    """Samples while the motor is on; returns (samples done, quiet).  Stops early after a
    sample that switched the motor off (a position error with LPES), and at a mark (``marks``
    counted from ``base`` samples before this call) whose status differs from ``status`` or
    whose quiet count reached ``settle``."""
    profile, filt, motor = chip.profile, chip.filter, chip.motor
    floor = math.floor
    # the profile generator
    p, v, a, top, target = profile.position, profile.velocity, profile.acceleration, profile.top, profile.target
    vmode, forward, stopping, complete = profile.velocity_mode, profile.forward, profile.stopping, profile.complete
    twice_a = 2 * a
    # the filter
    c = filt.working
    kp, ki, kd, il, ds = c.kp, c.ki, c.kd, c.il, c.ds
    limit = (il * 256 + ki - 1) // ki if ki else 1 << 23
    error_sum, derivative, previous, countdown = filt.error_sum, filt.derivative, filt._previous, filt._countdown
    output, integral = filt.output, filt.integral if ki else 0  # the term is 0 from the first sample
    twelve = filt.dac_bits == 12
    # the motor
    if motor._decay[0] != chip.sample_time:
        motor._decay = (chip.sample_time, *_lag_terms(chip.sample_time, motor.tau))
    step_slack = chip.sample_time * STEP_SLACK
    _, kept, gained, travelled = motor._decay
    kv, tau, load, low, high = motor.kv, motor.tau, motor.load, motor.low, motor.high
    x, speed_now = motor.position, motor.velocity
    # encoder and checks
    sign, home, threshold, stop_on_error = chip.encoder_sign, chip.home, chip.error_threshold, chip.stop_on_error
    break_at = chip.breakpoint if chip.breakpoint is not None else 0
    index_watch = chip.index_armed and chip.index_period
    watch_moves = chip.breakpoint is not None or index_watch
    flags, on_target = chip.flags, chip.on_target
    rest_x, rest_v, rest_n = chip.rest_x, chip.rest_v, chip.rest_n
    raw = chip._raw
    seen = floor(sign * x)  # the encoder before the first sample (the stepper's look)
    segment = _segment(raw, home)
    bounded = low > -math.inf or high < math.inf
    chip.udf_sample = False
    done = 0
    cruise = 0  # samples ahead in which the generator only adds da to its velocity and that to the position
    da = 0  # 0 at the top velocity; ±a while it ramps far from the target (or stops smoothly)
    stopped = False
    far_until = check_at = 0  # the samples up to far_until need no breakpoint check (one sample at a time)
    shift, scale = (4, 2048) if twelve else (8, 128)
    goals = _goals(kv, load, scale, travelled, gained)
    unit = float(sign)  # (a float product: 1.0 · x and −1.0 · x are exact)
    fastest = abs(kv) * (10.0 + abs(load))  # counts/s: the motor's goal speed at most (±10 V)
    sum_low, sum_high = max(I24_LOW, -limit), min(I24_HIGH, limit)  # the two limits of Σe in one
    at = len(checkpoints)
    mark = marks[at] - base if at < len(marks) else count  # the next sample that takes a checkpoint
    while True:
        if done == mark:
            if at < len(marks):  # the state as snapshot() takes it once the locals are written back
                checkpoints.append((base + done, quiet, (
                    p, v, target, stopping, complete, error_sum, derivative, previous, countdown, output, integral,
                    x, speed_now, flags, on_target, raw, False, False, chip.index_armed, chip.index_position,
                    rest_x, rest_v, rest_n)))
                at += 1
                if flags != status or quiet >= settle:
                    break
                mark = marks[at] - base if at < len(marks) else count
            if done == count:
                break
        if cruise and not index_watch and not bounded \
                and -(bound := _unclamped(top if top > abs(v) else abs(v), threshold)) <= (p >> 16) + home - seen <= bound:
            # the generator only adds its acceleration (or nothing) to its velocity and that to
            # its position, no index is watched and the following error
            # is within ±bound: the same operations as below without the branches that cannot
            # be taken (e needs no 16-bit clamp); the integral term is computed again only when
            # the error sum changes, and the motor's two products of the goal speed come from a
            # table by output level (the same floating-point operations)
            n = 0
            lo16, hi16, below = I16_LOW, I16_HIGH, -bound
            first_count, end_count = segment
            bias = integral + kd * derivative  # (integral is error_sum's: a pass starts with a sample below)
            length = cruise if cruise < mark - done else mark - done
            # a breakpoint the motor cannot reach in these samples need not be checked in them
            watching = watch_moves and not _far(seen, home, break_at, segment,
                                                length * (max(abs(speed_now), fastest) * step_slack) + 2)
            for n in range(1, length + 1):  # noqa: B007
                if da:
                    v += da
                p += v
                desired = (p >> 16) + home  # in raw counts
                e = desired - seen  # within ±(bound + the step): no clamp
                s = error_sum + e
                s = sum_low if s < sum_low else sum_high if s > sum_high else s
                if s != error_sum:
                    error_sum = s
                    if ki:  # Σe / 256 truncated: |Σe| < 2^24, so the quotient of the reference is exact
                        term = ki * (s >> 8 if s >= 0 else -(-s >> 8))
                        integral = -il if term < -il else il if term > il else term
                        bias = integral + kd * derivative
                if countdown:
                    countdown -= 1
                else:
                    derivative = e - previous
                    previous = e
                    countdown = ds
                    bias = integral + kd * derivative
                u = kp * e + bias
                output = lo16 if u < lo16 else hi16 if u > hi16 else u
                try:
                    travel, gain = goals[output >> shift]
                except KeyError:
                    travel, gain = _goal(goals, output >> shift, kv, load, scale, travelled, gained)
                x += speed_now * tau * gained + travel
                speed_now = speed_now * kept + gain
                before = seen
                seen = floor(unit * x)
                if not first_count <= seen < end_count:
                    if not watching:
                        flags |= WRAPAROUND
                    first_count, end_count = segment = _segment(seen, home)
                if watching and before != seen:  # the breakpoint: as in the loop below
                    flags |= moved_flags(before, seen, home, break_at)
                err = desired - seen
                if err > bound or err < below:  # the next sample's e may need its clamp: below
                    if err > threshold or err < -threshold:
                        flags |= POSITION_ERROR
                        stopped = stop_on_error
                    break
            done += n
            cruise -= n
            raw = seen
            quiet = 0
            if stopped:
                break
            continue
        done += 1
        before_actual, before_p, before_flags, before_sum = seen, p, flags, error_sum
        before = raw
        # -- profile generator (Profile.sample) --
        if cruise:
            cruise -= 1
            v += da
            p += v
        elif not complete:
            if stopping:
                if v < 0:
                    v = v + a if v + a < 0 else 0
                elif v > 0:
                    v = v - a if v - a > 0 else 0
                if v == 0:
                    stopping, complete = False, True
                    target = p
                p += v
                if v and a:  # the samples in which v only comes a nearer to 0
                    cruise, da = (abs(v) - 1) // a, a if v < 0 else -a
            elif vmode:
                goal = top if forward else -top
                if v < goal:
                    v = v + a if v + a < goal else goal
                elif v > goal:
                    v = v - a if v - a > goal else goal
                p += v
                if v == goal or not a:
                    cruise, da = count, 0  # held until a command (none comes inside this pass)
                else:  # the samples in which v only comes a nearer to the goal
                    cruise, da = ((goal - v - 1) // a, a) if v < goal else ((v - goal - 1) // a, -a)
            else:
                remaining = target - p
                if remaining == 0 and v == 0:
                    complete = True
                else:
                    direction = 1 if remaining > 0 else -1
                    v0 = v
                    ramping = False
                    if v * direction < 0:
                        if v < 0:
                            v = v + a if v + a < 0 else 0
                        elif v > 0:
                            v = v - a if v - a > 0 else 0
                    else:
                        speed, distance = v * direction, remaining * direction  # |v|, |remaining|
                        braking = speed * speed // twice_a + speed // 2 if a else 0
                        if distance <= braking:
                            least = (a if a < distance else distance) * direction if a else 0
                            if v < 0:
                                v = v + a if v + a < 0 else 0
                            elif v > 0:
                                v = v - a if v - a > 0 else 0
                            if least and abs(v) < abs(least):
                                v = least
                        else:
                            goal = top * direction
                            if v < goal:
                                v = v + a if v + a < goal else goal
                            elif v > goal:
                                v = v - a if v - a > goal else goal
                            ramping = True
                    if v and (target - (p + v)) * direction <= 0 and v0 * direction >= 0:
                        p, v, complete = target, 0, True
                    elif v == 0 and abs(remaining) < ONE:
                        p, complete = target, True
                    else:
                        p += v
                        if v and v == top * direction:
                            cruise, da = _cruise(target, p, v, direction, a), 0
                        elif ramping and a and 0 < v * direction < top:  # ramping up, far from the target
                            cruise, da = _ramp((target - p) * direction, v * direction, a, top), a * direction
            if complete:
                flags |= COMPLETE
                on_target = True
        desired = p >> 16
        # -- filter (Filter.sample) --
        e = desired - (seen - home)
        e = I16_LOW if e < I16_LOW else I16_HIGH if e > I16_HIGH else e
        s = error_sum + e
        error_sum = sum_low if s < sum_low else sum_high if s > sum_high else s
        if ki:
            term = ki * (error_sum >> 8 if error_sum >= 0 else -(-error_sum >> 8))
            integral = -il if term < -il else il if term > il else term
        if countdown == 0:
            derivative = e - previous
            previous = e
            countdown = ds
        else:
            countdown -= 1
        u = kp * e + integral + kd * derivative
        output = I16_LOW if u < I16_LOW else I16_HIGH if u > I16_HIGH else u
        # -- motor (Motor.step), the goal speed kv · (volts − load) times the lag terms by level --
        try:
            travel, gain = goals[output >> shift]
        except KeyError:
            travel, gain = _goal(goals, output >> shift, kv, load, scale, travelled, gained)
        x += speed_now * tau * gained + travel
        speed_now = speed_now * kept + gain
        if bounded and not low <= x <= high:
            x = min(high, max(low, x))
            speed_now = 0.0
        # -- encoder and checks (Lm628._moved) --
        raw = floor(unit * x)
        if not segment[0] <= raw < segment[1]:
            if not watch_moves:
                flags |= WRAPAROUND
            segment = _segment(raw, home)
        if watch_moves and before != raw:
            if index_watch:
                chip.flags = flags
                chip._moved(before, raw)
                flags = chip.flags
                index_watch = chip.index_armed and chip.index_period
                watch_moves = chip.breakpoint is not None or index_watch
            elif done > far_until:  # the breakpoint alone: Lm628._moved's wrap-around and breakpoint checks
                flags |= moved_flags(before, raw, home, break_at)
                if done >= check_at:  # (not again for a while where the breakpoint is near)
                    span = count - done if count - done < FAR_SPAN else FAR_SPAN
                    if _far(raw, home, break_at, segment, span * (max(abs(speed_now), fastest) * step_slack) + 2):
                        far_until = done + span  # the motor cannot reach it, nor wrap, in these samples
                    else:
                        check_at = done + FAR_SPAN // 4
        err = desired - (raw - home)  # |err| > threshold ≤ 7FFFh, saturated to 32 bits or not
        if err > threshold or err < -threshold:
            flags |= POSITION_ERROR
            if stop_on_error:
                stopped = True
        seen = raw
        if complete and p == before_p and flags == before_flags and abs(speed_now) < STILL \
                and (raw == before_actual or wrap(raw - home) == wrap(before_actual - home)) \
                and derivative == 0 and previous == e and (error_sum == before_sum or not ki):  # (_quiet_after)
            quiet += 1
            if quiet == SETTLE:
                rest_x, rest_v, rest_n = x, speed_now, 0
            elif quiet > SETTLE:
                rest_n += 1
        else:
            quiet = 0
        if stopped:
            break
    profile.position, profile.velocity, profile.target = p, v, target
    profile.stopping, profile.complete = stopping, complete
    filt.error_sum, filt.derivative, filt._previous, filt._countdown = error_sum, derivative, previous, countdown
    filt.output, filt.integral = output, integral
    motor.position, motor.velocity = x, speed_now
    chip.flags, chip.on_target, chip._raw = flags, on_target, raw
    chip.rest_x, chip.rest_v, chip.rest_n = rest_x, rest_v, rest_n
    if stopped:
        chip.motor_off = True
        chip.flags |= COMPLETE  # (switching the motor off completes the trajectory, as Lm628.sample)
    return done, quiet
