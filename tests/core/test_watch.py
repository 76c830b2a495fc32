"""The point watch (devsim.core.watch): changes sampled on the device clock."""

from __future__ import annotations

import pytest

from devsim.core.clock import VirtualClock
from devsim.core.watch import PointWatch, readable_names
from devsim.devices.sers import SersDevice


def _device() -> tuple[VirtualClock, SersDevice]:
    clock = VirtualClock()
    return clock, SersDevice(clock=clock, config={"boot_time": 0})


def test_the_first_sample_reports_every_watched_name_then_only_changes() -> None:
    clock, device = _device()
    seen: list[dict] = []
    watch = PointWatch(device, seen.append, names=["input.limit_right", "axis.position"], period=0.1)
    watch.start()
    assert seen == [{"input.limit_right": False, "axis.position": 0.0}]
    device.set("input.limit_right", True)
    assert len(seen) == 1  # nothing until the next sample
    clock.advance(0.1)
    assert seen[-1] == {"input.limit_right": True}
    clock.advance(0.5)
    assert len(seen) == 2  # no change, no call
    watch.stop()
    device.set("input.limit_right", False)
    clock.advance(1.0)
    assert len(seen) == 2


def test_a_watch_without_a_period_sets_no_timer() -> None:
    clock, device = _device()
    seen: list[dict] = []
    watch = PointWatch(device, seen.append, names=["input.limit_right"])
    watch.start()
    device.set("input.limit_right", True)
    clock.advance(10)
    assert len(seen) == 1
    assert watch.sample() == {"input.limit_right": True}


def test_by_default_every_readable_declared_name_is_watched() -> None:
    _, device = _device()
    watch = PointWatch(device, lambda changes: None)
    assert watch.names == readable_names(device)
    assert "axis.position" in watch.names
    assert all(device.points.find(name).readable for name in watch.names)


def test_the_period_must_be_positive() -> None:
    _, device = _device()
    with pytest.raises(ValueError):
        PointWatch(device, lambda changes: None, period=0)


def test_a_sample_of_some_names_reports_only_their_changes() -> None:
    clock, device = _device()
    seen: list[dict] = []
    watch = PointWatch(device, seen.append, names=["input.limit_right", "input.limit_left"])
    watch.start()
    device.set("input.limit_right", True)
    device.set("input.limit_left", True)
    assert watch.sample(["input.limit_right"]) == {"input.limit_right": True}
    assert watch.sample() == {"input.limit_left": True}  # the other change waited for a full sample
    assert seen[1:] == [{"input.limit_right": True}, {"input.limit_left": True}]
