"""The moments that make the MQTT facade sample at once (issue 29, issue 35): :class:`SampleOnEvent`
alone on a sers device with a virtual clock, in-process: after each step that announced a moment
(``recorded``, ``fault_switched``, ``fault``) or changed an input or output, one sample at the same
instant of device time, by the device clock's timer or the loop's next turn, whichever comes first;
none for an analog quantity, none from the sample's own reads.  The facade on a broker is in
test_mqtt_events.py."""

from __future__ import annotations

import asyncio
from collections.abc import Callable, Iterator
from typing import Any

import pytest

from devsim.core.clock import VirtualClock
from devsim.core.registry import device_class
from devsim.facades.mqtt_events import MOMENTS, SIGNAL_KINDS, SampleOnEvent


class Watched:
    """A sers device and a started :class:`SampleOnEvent` that logs the time of each sample."""

    def __init__(self, sample: Callable[[], Any] | None = None) -> None:
        self.clock = VirtualClock()
        self.device = device_class("sers")(clock=self.clock, config={})
        self.clock.advance(5.0)  # past its power-on (2 s)
        self.samples: list[float] = []
        self.extra = sample
        self.watch = SampleOnEvent(self.device, self._sample)
        self.watch.start()

    def _sample(self) -> None:
        self.samples.append(self.clock.now())
        if self.extra is not None:
            self.extra()

    @property
    def model(self) -> Any:
        return self.device.model

    def close(self) -> None:
        self.watch.stop()
        self.device.close()


@pytest.fixture
def watched() -> Iterator[Watched]:
    w = Watched()
    try:
        yield w
    finally:
        w.close()


def test_the_moments_and_signal_kinds() -> None:
    assert MOMENTS == ("recorded", "fault_switched", "fault")
    assert SIGNAL_KINDS == ("input", "output")


@pytest.mark.parametrize(("topic", "args"), [("recorded", (5.0, "move_start")), ("fault_switched", ("power", True)),
                                             ("fault", (1, 0x1000)), ("fault", ())])
def test_a_moment_is_sampled_after_the_step_at_the_same_instant(watched: Watched, topic: str,
                                                                 args: tuple[Any, ...]) -> None:
    watched.model.announce(topic, *args)
    assert watched.samples == []  # not inside the step that announced it
    watched.clock.advance(0.0)
    assert watched.samples == [5.0]
    watched.clock.advance(10.0)
    assert watched.samples == [5.0]  # once
    assert watched.clock.next_event() is None or watched.clock.next_event() > 5.0


def test_other_topics_are_no_moment(watched: Watched) -> None:
    for topic in ("ready", "device_error", "event", "recordedx"):
        watched.model.announce(topic, "x", False)
    watched.clock.advance(0.0)
    assert watched.samples == []


def test_every_input_and_output_that_changes_is_sampled_after(watched: Watched) -> None:
    signals = watched.model.signals
    for kind in ("input", "output"):
        for name in signals.names(kind):
            count = len(watched.samples)
            signals.set(name, not signals.get(name))
            watched.clock.advance(0.0)
            assert len(watched.samples) == count + 1, name
            signals.set(name, signals.get(name))  # no change: no moment
            watched.clock.advance(0.0)
            assert len(watched.samples) == count + 1, name


def test_an_analog_quantity_waits_for_the_tick(watched: Watched) -> None:
    """(A quantity that is a flag, short circuit or stall, makes a fault: that is a moment.)"""
    signals = watched.model.signals
    analog = [n for n in signals.names("quantity") if not isinstance(signals.get(n), bool)]
    assert len(analog) == 4
    for name in analog:
        signals.set(name, signals.get(name) + 0.5)
    watched.clock.advance(0.0)
    assert watched.samples == []


def test_several_moments_of_one_step_are_one_sample(watched: Watched) -> None:
    watched.model.record_event("move_start")
    watched.model.announce("fault_switched", "power", True)
    watched.model.signals.set("I1", True)
    watched.model.record_event("move_end")
    watched.clock.advance(0.0)
    assert watched.samples == [5.0]
    watched.clock.advance(1.0)
    watched.model.record_event("move_start")
    watched.clock.advance(0.0)
    assert watched.samples == [5.0, 6.0]  # the next step's moment samples again


def test_the_samples_own_reads_and_moments_make_no_sample() -> None:
    w = Watched()
    try:
        w.extra = lambda: w.model.record_event("sampled")
        w.model.record_event("move_start")
        w.clock.advance(0.0)
        w.clock.advance(1.0)
        assert w.samples == [5.0]
        w.model.record_event("move_end")  # after the sample: sampled again
        w.clock.advance(0.0)
        assert w.samples == [5.0, 6.0]
    finally:
        w.close()


def test_a_sample_that_fails_does_not_stop_the_next() -> None:
    calls: list[int] = []

    def sample() -> None:
        calls.append(1)
        if len(calls) == 1:
            raise RuntimeError("broken")

    w = Watched(sample)
    try:
        w.model.record_event("a")
        with pytest.raises(RuntimeError):
            w.clock.advance(0.0)
        w.model.record_event("b")
        w.clock.advance(0.0)
        assert w.samples == [5.0, 5.0]
    finally:
        w.close()


def test_stop_cancels_the_pending_sample_and_stops_listening(watched: Watched) -> None:
    watched.model.record_event("move_start")
    watched.watch.stop()
    assert watched.clock.next_event() is None
    watched.clock.advance(0.0)
    watched.model.record_event("move_end")
    watched.model.announce("fault", 1, 0x1000)
    watched.model.announce("fault_switched", "power", True)
    watched.model.signals.set("I1", True)
    watched.model.signals.set("O1", True)
    watched.clock.advance(1.0)
    assert watched.samples == []
    watched.watch.stop()  # twice is fine
    watched.watch.start()  # and it starts again, once
    watched.model.record_event("x")
    watched.clock.advance(0.0)
    assert watched.samples == [6.0]


def test_in_a_loop_the_next_turn_samples_and_the_clock_timer_is_cancelled(watched: Watched) -> None:
    async def step() -> None:
        watched.model.record_event("move_start")
        assert watched.samples == [] and watched.clock.next_event() == 5.0
        await asyncio.sleep(0)
        assert watched.samples == [5.0]
        assert watched.clock.next_event() is None  # the clock's timer cancelled
        watched.model.record_event("move_end")
        watched.clock.advance(0.0)  # here the clock comes first
        assert watched.samples == [5.0, 5.0]
        await asyncio.sleep(0)
        await asyncio.sleep(0)
        assert watched.samples == [5.0, 5.0]  # the loop's call cancelled

    asyncio.run(step())
