"""The one clock (devsim/core/clock.py; design.md principle 3): timers in time order, each callback
at exactly its instant, ties in the order they were set, cancelled timers never run, a timer set in
the past runs at once, auto mode jumps to the next event only when the loop is idle; the real clock
scaled by ``--speed``."""

from __future__ import annotations

import asyncio

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from devsim.core.clock import RealClock, Timer, VirtualClock

#: No deadline, no speed health check: a loaded machine (or a mutation run) must not fail these.
BOUNDARY = settings(deadline=None, suppress_health_check=[HealthCheck.too_slow])


def test_timers_run_in_time_order_at_their_instant() -> None:
    clock = VirtualClock()
    seen: list[tuple[str, float]] = []
    clock.call_at(2.0, lambda: seen.append(("b", clock.now())))
    clock.call_at(1.0, lambda: seen.append(("a", clock.now())))
    clock.call_later(3.0, lambda: seen.append(("c", clock.now())))
    assert clock.next_event() == 1.0
    assert clock.advance(2.0) == 2  # a timer due exactly at the window's end runs
    assert seen == [("a", 1.0), ("b", 2.0)]
    assert clock.now() == 2.0
    assert clock.advance(0.5) == 0 and clock.now() == 2.5
    assert clock.advance(0.5) == 1 and seen[-1] == ("c", 3.0)
    assert clock.next_event() is None


@BOUNDARY
@given(st.lists(st.integers(0, 5), min_size=1, max_size=12), st.integers(0, 6))
def test_order_and_window_by_property(times: list[int], window: int) -> None:
    """Oracle: the timers due by the window's end run, sorted by time and then by the order
    they were set; each sees its own time."""
    clock = VirtualClock()
    seen: list[tuple[float, int]] = []
    for i, when in enumerate(times):
        clock.call_at(float(when), lambda i=i: seen.append((clock.now(), i)))
    ran = clock.advance(float(window))
    expected = sorted((float(w), i) for i, w in enumerate(times) if w <= window)
    assert seen == expected
    assert ran == len(expected)
    assert clock.now() == float(window)


def test_cancelled_timers_do_not_run_and_cancel_is_idempotent() -> None:
    clock = VirtualClock()
    seen: list[int] = []
    first = clock.call_at(1.0, lambda: seen.append(1))
    clock.call_at(2.0, lambda: seen.append(2))
    first.cancel()
    first.cancel()
    assert first.cancelled
    assert clock.next_event() == 2.0  # the cancelled one is not the next event
    assert clock.advance(5) == 1 and seen == [2]


def test_a_timer_in_the_past_runs_at_once_at_now() -> None:
    clock = VirtualClock(start=10.0)
    assert clock.now() == 10.0
    seen: list[float] = []
    timer = clock.call_at(4.0, lambda: seen.append(clock.now()))
    assert timer.when == 10.0
    later = clock.call_later(-3.0, lambda: seen.append(clock.now()))
    assert later.when == 10.0  # a negative delay is none
    assert clock.advance(0) == 2 and seen == [10.0, 10.0]


def test_callbacks_may_schedule_more_within_the_window() -> None:
    clock = VirtualClock()
    seen: list[float] = []

    def first() -> None:
        seen.append(clock.now())
        clock.call_later(0.5, lambda: seen.append(clock.now()))
        clock.call_later(5.0, lambda: seen.append(clock.now()))

    clock.call_at(1.0, first)
    assert clock.advance(2.0) == 2
    assert seen == [1.0, 1.5]


def test_time_does_not_run_backwards() -> None:
    clock = VirtualClock()
    clock.advance(3.0)
    with pytest.raises(ValueError, match="time does not run backwards"):
        clock.advance(-0.1)
    assert clock.advance_to(1.0) == 0 and clock.now() == 3.0
    assert clock.advance_to(4.5) == 0 and clock.now() == 4.5


def test_run_until() -> None:
    clock = VirtualClock()
    hits: list[float] = []
    for when in (1.0, 2.0, 3.0):
        clock.call_at(when, lambda: hits.append(clock.now()))
    assert clock.run_until(lambda: len(hits) == 2, timeout=10.0) is True
    assert clock.now() == 2.0 and hits == [1.0, 2.0]
    assert clock.run_until(lambda: len(hits) == 5, timeout=4.0) is False
    assert clock.now() == 6.0 and hits == [1.0, 2.0, 3.0]  # waited the whole timeout
    clock.call_at(20.0, lambda: hits.append(clock.now()))
    assert clock.run_until(lambda: len(hits) == 4, timeout=1.0) is False
    assert clock.now() == 7.0 and clock.next_event() == 20.0  # the event past the deadline waits
    assert clock.run_until(lambda: True, timeout=0.0) is True


def test_timer_order_ties_by_sequence() -> None:
    a, b, c = Timer(1.0, print, 0), Timer(1.0, print, 1), Timer(0.5, print, 2)
    assert a < b and not b < a
    assert c < a and not a < c
    assert not a < a


def test_virtual_and_real() -> None:
    assert VirtualClock().virtual is True
    assert RealClock().virtual is False
    with pytest.raises(ValueError, match="speed must be positive"):
        RealClock(0)
    with pytest.raises(ValueError):
        RealClock(-1)


async def test_sleep_on_a_virtual_clock_in_auto_mode() -> None:
    clock = VirtualClock()
    clock.start_auto()
    clock.start_auto()  # once is enough
    try:
        order: list[tuple[str, float]] = []

        async def sleeper(name: str, delay: float) -> None:
            await clock.sleep(delay)
            order.append((name, clock.now()))

        await asyncio.wait_for(asyncio.gather(sleeper("long", 100.0), sleeper("short", 2.5)), 5)
        assert order == [("short", 2.5), ("long", 100.0)]
        assert clock.now() == 100.0
        # idle with nothing pending, then a new timer wakes auto mode
        for expected in (107.0, 114.0):  # each new timer wakes it, again and again
            # the loop idles (a wall-time wait, no virtual timer): auto mode waits for a timer;
            # the check below holds however long this takes, it only reaches that path
            await asyncio.sleep(0.02)
            fired = asyncio.Event()
            clock.call_later(7.0, fired.set)
            await asyncio.wait_for(fired.wait(), 5)
            assert clock.now() == expected
        # virtual time costs no wall time: ten events in a row, each a jump (the bound is a
        # thousand times what they take; a jump that waited a wall second would miss it)
        await asyncio.wait_for(_ten_sleeps(clock), 5)
        assert clock.now() == 124.0
    finally:
        clock.stop_auto()
        clock.stop_auto()
    assert clock._auto_task is None


async def _ten_sleeps(clock: VirtualClock) -> None:
    for _ in range(10):
        await clock.sleep(1.0)


async def test_auto_mode_waits_for_a_busy_loop() -> None:
    """Time does not jump while other callbacks are ready: a task that keeps the loop busy for a
    few turns sees the clock still at 0."""
    clock = VirtualClock()
    clock.call_at(50.0, lambda: None)
    clock.start_auto()
    try:
        seen = []
        for _ in range(20):
            seen.append(clock.now())
            await asyncio.sleep(0)
        assert seen == [0.0] * 20
        await asyncio.wait_for(clock.sleep(1.0), 5)
        assert clock.now() == 1.0  # the earlier event first; the one at 50 still waits
        assert clock.next_event() == 50.0
    finally:
        clock.stop_auto()


async def test_a_cancelled_sleep_leaves_no_timer() -> None:
    clock = VirtualClock()
    task = asyncio.ensure_future(clock.sleep(5.0))
    await asyncio.sleep(0)
    assert clock.next_event() == 5.0
    task.cancel()
    with pytest.raises(asyncio.CancelledError):
        await task
    assert clock.next_event() is None


async def test_real_clock_scaled_by_speed() -> None:
    clock = RealClock(speed=1000.0)
    loop = asyncio.get_running_loop()
    start = clock.now()
    assert 0.0 <= start < 1000.0
    done = asyncio.Event()
    fired_at: list[float] = []
    timer = clock.call_later(50.0, lambda: (fired_at.append(clock.now()), done.set()))  # 50 ms of wall time
    skipped = clock.call_later(10.0, lambda: fired_at.append(-1.0))
    skipped.cancel()
    wall = loop.time()
    await asyncio.wait_for(done.wait(), 10)
    assert fired_at[0] >= start + 50.0  # never early, in simulated seconds
    assert (loop.time() - wall) * 1000.0 >= 50.0 - 1e-6  # the wall time scaled by the speed
    assert fired_at == [fired_at[0]]
    assert timer.cancelled  # a fired timer is spent
    timer.cancel()


def test_timer_repr_for_debugging() -> None:
    timer = Timer(1.5, print)
    assert repr(timer) == "<Timer at 1.500000 pending <built-in function print>>"
    timer.cancel()
    assert repr(timer) == "<Timer at 1.500000 cancelled <built-in function print>>"


def test_a_cancelled_timer_first_in_line_does_not_stop_the_others() -> None:
    clock = VirtualClock()
    seen: list[float] = []
    first = clock.call_at(1.0, lambda: seen.append(1.0))
    clock.call_at(2.0, lambda: seen.append(2.0))
    first.cancel()
    assert clock.advance(3.0) == 1 and seen == [2.0]


def test_a_fired_timer_is_spent() -> None:
    clock = VirtualClock()
    timer = clock.call_at(1.0, lambda: None)
    assert timer.cancelled is False and timer.when == 1.0
    clock.advance(1.0)
    assert timer.cancelled is True


def test_timers_of_one_instant_order_by_creation() -> None:
    clock = VirtualClock()
    a, b = clock.call_at(1.0, print), clock.call_at(1.0, print)
    assert a < b and not b < a
    assert not Timer(1.0, print) < Timer(1.0, print, 0) and not Timer(1.0, print, 0) < Timer(1.0, print)


def test_run_until_runs_an_event_exactly_at_the_deadline() -> None:
    clock = VirtualClock()
    hits: list[float] = []
    clock.call_at(4.0, lambda: hits.append(clock.now()))
    assert clock.run_until(lambda: bool(hits), timeout=4.0) is True
    assert hits == [4.0]


def test_clock_messages() -> None:
    with pytest.raises(ValueError, match="^time does not run backwards$"):
        VirtualClock().advance(-1.0)
    with pytest.raises(ValueError, match="^speed must be positive$"):
        RealClock(0.0)
    assert RealClock().speed == 1.0


async def test_real_clock_timer_fields_and_double_cancel() -> None:
    clock = RealClock(speed=1000.0)

    def callback() -> None:
        return None

    timer = clock.call_at(1e6, callback)
    assert (timer.when, timer.callback, timer.cancelled) == (1e6, callback, False)
    timer.cancel()
    timer.cancel()
    assert timer.cancelled
