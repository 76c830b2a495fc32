"""State on change of an event, not only on the sampling tick (issue 29): a move of about 0.25 s
that starts and ends between two samples of a 1 s rate still shows ``motion: true`` once, on the
devsim convention's ``state/motion`` (seen by mosquitto_sub) and in Sparkplug DDATA (decoded by
the Tahu binding's own parser, ``tahutils.parse``); a fault and an input switched through the
control API are published at once, with no tick in between (virtual time does not move)."""

from __future__ import annotations

import itertools
from collections.abc import Iterator
from typing import Any

import pytest
from tahutils.parse import parse_payload_to_metric_dict, payload_from_string

from devsim.core.device import Device
from devsim.facades.mqtt import start_mqtt
from devsim.runtime import Runtime
from tests.facades.test_mqtt import mosquitto  # noqa: F401 - the module's broker fixture
from tests.support.broker import Broker
from tests.support.mqtt import Message, Sub

_plants = itertools.count()
RATE = 1.0  # seconds of device time between two samples
SPB = "spBv1.0/devsim"


class Ready:
    """A sers ``x`` past its power-on, set up to move and enabled (virtual time), not yet served."""

    def __init__(self) -> None:
        self.runtime = Runtime(virtual=True).start()
        self.device: Device = self.runtime.add_device("sers", "x")
        self.runtime.advance(3.0)  # the SERS boots in 2 s
        self.runtime.call(self.device.apply_state, self.device.drive_setup)
        self.runtime.call(self.device.drive.enable, self.device.model, True)
        self.runtime.advance(0.5)

    def moves(self) -> list[tuple[float, str]]:
        return [(t, e) for t, e in self.device.model.events if e in ("move_start", "move_end")]

    def short_move_between_ticks(self, started: float) -> tuple[float, float]:
        """Start a 250-increment move at 1000 inc/s 0.2 s after a tick (the watch ticks at
        ``started`` + k · RATE) and run one whole period: start and end fall inside one
        ``advance``, between two ticks.  Returns (move_start, move_end)."""
        drive, model = self.device.drive, self.device.model
        next_tick = started + RATE * (int((self.runtime.now() - started) / RATE) + 1)

        def move() -> None:
            drive.move_to(model, drive.position(model) + 250, 1000)

        self.runtime.call(lambda: self.device.clock.call_at(next_tick + 0.2, move))
        before = len(self.moves())
        self.runtime.advance(next_tick + RATE - self.runtime.now())
        (start, _s), (end, _e) = self.moves()[before:]
        assert next_tick < start < end < next_tick + RATE  # no tick sees it moving
        assert end - start == pytest.approx(0.25, abs=0.05)
        return start, end


@pytest.fixture
def ready() -> Iterator[Ready]:
    sers = Ready()
    try:
        yield sers
    finally:
        sers.runtime.stop()


def test_a_move_between_two_samples_shows_motion_on_the_state_topic(ready: Ready, mosquitto: Broker) -> None:  # noqa: F811
    plant = f"e{next(_plants)}"
    motion = f"devsim/{plant}/x/state/motion"
    with Sub(mosquitto.port, f"devsim/{plant}/x/state/#").sync() as sub:
        ready.runtime.run(start_mqtt(ready.runtime, [ready.device], mosquitto.url, plant=plant, rate=RATE),
                          timeout=20)
        started = ready.runtime.now()
        assert sub.wait(motion).json() is False
        ready.short_move_between_ticks(started)
        assert sub.wait(motion).json() is True
        assert sub.wait(motion).json() is False
        assert [m for m in sub.seen if m.topic == motion] == []  # once each


def _motion(message: Message) -> Any:
    return parse_payload_to_metric_dict(payload_from_string(message.payload)).get("motion")


def test_a_move_between_two_samples_shows_motion_in_sparkplug_ddata(ready: Ready, mosquitto: Broker) -> None:  # noqa: F811
    plant = f"s{next(_plants)}"
    ddata = f"{SPB}/DDATA/{plant}/x"
    with Sub(mosquitto.port, f"{SPB}/+/{plant}/#").sync() as sub:
        ready.runtime.run(start_mqtt(ready.runtime, [ready.device], mosquitto.url, plant=plant,
                                     convention="sparkplug", rate=RATE), timeout=20)
        started = ready.runtime.now()
        birth = parse_payload_to_metric_dict(payload_from_string(sub.wait(f"{SPB}/DBIRTH/{plant}/x").payload))
        assert birth["motion"].value is False
        ready.short_move_between_ticks(started)
        assert _motion(sub.wait(ddata, lambda m: _motion(m) is not None)).value is True
        assert _motion(sub.wait(ddata, lambda m: _motion(m) is not None)).value is False
        assert [m for m in sub.seen if m.topic == ddata and _motion(m) is not None] == []  # once each


def test_a_fault_and_an_input_are_published_without_a_tick(ready: Ready, mosquitto: Broker) -> None:  # noqa: F811
    """Virtual time stands still: only the moments themselves can publish these."""
    plant = f"f{next(_plants)}"
    state = f"devsim/{plant}/x/state"
    with Sub(mosquitto.port, f"{state}/#").sync() as sub:
        ready.runtime.run(start_mqtt(ready.runtime, [ready.device], mosquitto.url, plant=plant, rate=RATE),
                          timeout=20)
        now = ready.runtime.now()
        assert sub.wait(f"{state}/input.I2").json() is False
        assert sub.wait(f"{state}/input.stop").json() is False
        ready.runtime.set("x", "input.I2", True)  # through the control API, not the facade
        assert sub.wait(f"{state}/input.I2", lambda m: m.json() is True)
        ready.runtime.fault("x", "emergency_stop", True)
        assert sub.wait(f"{state}/input.stop", lambda m: m.json() is True)
        assert ready.runtime.now() == now
