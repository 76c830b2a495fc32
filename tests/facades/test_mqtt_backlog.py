"""The MQTT facade's backlog while the broker does not read (mosquitto stopped with SIGSTOP): the
samples that wait unsent stay within the link's limit (``PAUSED_LIMIT``, made small here), the
newer ones being dropped [SIM-CHOICE], and once the broker reads again every value is sent
again, so that the retained states are the device's (docs/facades/mqtt.md).

Before, every sample waited in the link's buffer until the link was given up for a silent broker
(1.5 keep-alive intervals, 15 s or more): with ``--mqtt-rate 0.001`` and five moving devices
that was 1.5 MB, growing 0.35 MB a second with a longer keep alive."""

from __future__ import annotations

import contextlib
import os
import signal
import socket
from collections.abc import Callable, Iterator

import pytest

from devsim.facades import mqtt_link
from devsim.facades.mqtt import PlantLink, start_mqtt
from devsim.runtime import Runtime
from tests.support.broker import Broker
from tests.support.mqtt import Sub

LIMIT = 32 * 1024  # the link's PAUSED_LIMIT in this test (1 MiB in use): less to write to reach it
RATE = 0.5
BATCH = 10  # rounds of changes and samples per step of the loop
WITNESS = "quantity.heatsink_temperature"  # set higher each round: its last value is new to the broker


@contextlib.contextmanager
def _stopped(broker: Broker) -> Iterator[None]:
    assert broker.process is not None
    os.kill(broker.process.pid, signal.SIGSTOP)
    try:
        yield
    finally:
        os.kill(broker.process.pid, signal.SIGCONT)


def _dropped_by_a_round_while_behind(plant: PlantLink, some_rounds: Callable[[int], int]) -> int | None:
    """The samples one round drops if the link is behind now (None if it is not), in the loop's thread."""
    if not plant.shared or not plant.shared.behind:
        some_rounds(1)
        return None
    before = plant.dropped
    some_rounds(1)
    return plant.dropped - before


def test_samples_waiting_for_a_broker_that_does_not_read_stay_bounded_and_every_value_follows(
        monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(mqtt_link, "PAUSED_LIMIT", LIMIT)
    broker = Broker().start()
    runtime = Runtime(virtual=True).start()
    try:
        device = runtime.add_device("sers", "x")
        runtime.run(start_mqtt(runtime, [device], broker.url, plant="backlog", rate=RATE), timeout=20)
        [plant] = [close.__self__ for close in runtime.closers if isinstance(getattr(close, "__self__", None), PlantLink)]
        shared = plant.shared
        assert shared is not None and shared._sock is not None
        shared._sock.setsockopt(socket.SOL_SOCKET, socket.SO_SNDBUF, 4096)  # (the kernel holds little)
        toggled = ["param.P1", "param.P2", "param.P3", "param.P100", "param.P101", "param.P102", "param.P1021",
                   "param.P1022", "param.P1023", "param.P1025", "quantity.adc_volts", "quantity.pulse_frequency"]
        rounds = 0

        def some_rounds(count: int = BATCH) -> int:
            """``count`` rounds in one step of the loop (written together at its end): change the
            points, sample them (a period of virtual time); then the bytes waiting unsent."""
            nonlocal rounds
            for _ in range(count):
                rounds += 1
                for name in toggled:
                    device.set(name, rounds % 2)
                device.set(WITNESS, 30 + rounds / 100)
                runtime.clock.advance(RATE)
            return len(shared._unsent)

        with _stopped(broker):
            waiting, grew = 0, 0
            while waiting <= LIMIT:  # until the socket took what it could and more than LIMIT waits
                assert rounds < 10_000, "the socket never filled"
                before, waiting = waiting, runtime.call(some_rounds)
                grew = max(grew, waiting - before)  # what one step adds at most
            for _ in range(4):  # about as much again as LIMIT: before, it all waited too
                waiting = runtime.call(some_rounds)
                assert waiting <= LIMIT + grew, f"{waiting} bytes wait after {rounds} rounds"
            # A round while the link is behind drops its samples.  (Looked at in one step of the
            # loop: the stopped broker's kernel still takes bytes now and then, as it compacts its
            # receive queue, so between steps the link may be down to a quarter and caught up.)
            dropped = None
            while dropped is None:
                assert rounds < 10_000, "the link was never behind"
                dropped = runtime.call(lambda: _dropped_by_a_round_while_behind(plant, some_rounds))
                assert len(shared._unsent) <= LIMIT + grew
            assert dropped > 0
            final = runtime.read("x", WITNESS)
        with Sub(broker.port, f"devsim/backlog/x/state/{WITNESS}") as sub:  # the retained one, then what comes
            assert sub.wait(f"devsim/backlog/x/state/{WITNESS}", lambda m: m.json() == final, timeout=30)
        assert plant.dropped == 0  # (told and counted again from 0)
    finally:
        runtime.stop()
        broker.stop()
