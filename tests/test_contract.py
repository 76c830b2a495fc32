"""The contract every registered device kind keeps, checked the moment it registers.

Parametrised over every kind of the registry (the shipped ones and the test kinds): boot, list
names, read every readable name, set every settable one with a valid and an invalid value (the
invalid one refused, nothing changed), power cycle, every declared fault on and off, garbage on
every port.  All under virtual time, through the kit's in-process API.
"""

from __future__ import annotations

import math
import random
from collections.abc import Iterator
from typing import Any

import pytest

from devsim.core.clock import VirtualClock
from devsim.core.device import Device
from devsim.core.nvram import NonVolatileMemory
from devsim.core.points import SHARED_VOCABULARY, BadValue, Point
from devsim.core.registry import device_class, kinds

TEST_KINDS = "echo=tests.support.echo:EchoDevice,twoport=tests.support.twoport:TwoPortDevice"
SHIPPED = ("sers", "gms96")
BOOT = 30.0  # simulated seconds a kind may take to boot


@pytest.fixture(autouse=True)
def _test_kinds(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("DEVSIM_EXTRA_KINDS", TEST_KINDS)


def _all_kinds() -> list[str]:
    import os

    old = os.environ.get("DEVSIM_EXTRA_KINDS")
    os.environ["DEVSIM_EXTRA_KINDS"] = TEST_KINDS
    try:
        return list(kinds())
    finally:
        if old is None:
            del os.environ["DEVSIM_EXTRA_KINDS"]
        else:
            os.environ["DEVSIM_EXTRA_KINDS"] = old


@pytest.fixture(params=_all_kinds())
def booted(request: pytest.FixtureRequest, tmp_path: Any) -> Iterator[tuple[Device, VirtualClock]]:
    clock = VirtualClock()
    cls = device_class(request.param)
    device = cls(clock=clock, nvram=NonVolatileMemory.for_device(tmp_path, "d"), name="d")
    assert clock.run_until(lambda: not device.booting, BOOT), f"{cls.kind} did not boot in {BOOT} s"
    yield device, clock
    device.close()


def _invalid(point: Point) -> list[Any]:
    return {
        "bool": ["maybe", 2, "False!"],
        "int": ["x", 1.5, math.nan],
        "float": ["hello", math.nan, math.inf, "1e400"],
        "str": [12345, None],
        "json": [math.nan, {"a": [math.inf]}],
    }[point.type]


def test_names_are_declared_once_with_doc(booted: tuple[Device, VirtualClock]) -> None:
    device, _clock = booted
    names = device.names()
    assert names and len(names) == len(set(names))
    for point in device.points:
        assert point.doc, f"{point.name} has no description"
        assert point.readable or point.settable
    if device.kind in SHIPPED:
        for name in SHARED_VOCABULARY:
            if not name.endswith("*"):
                assert name in names, f"{device.kind} lacks the shared name {name}"
        for point in device.points:
            assert point.section, f"{device.kind}: {point.name} cites no manual section"


def test_read_every_readable_name(booted: tuple[Device, VirtualClock]) -> None:
    device, _clock = booted
    for point in device.points:
        if point.readable:
            value = device.read(point.name)
            if isinstance(value, float):
                assert math.isfinite(value), point.name
    state = device.state()
    assert state["kind"] == device.kind


def test_set_every_settable_name_valid_and_invalid(booted: tuple[Device, VirtualClock]) -> None:
    device, clock = booted
    for point in device.points:
        if not point.settable:
            continue
        valid = device.read(point.name) if point.readable and point.example is None else point.example
        if valid is None and point.type != "json":
            continue  # nothing known to be valid (a write-only point without an example)
        try:
            device.set(point.name, valid)
        except BadValue as exc:
            # the device's own rule may refuse a well-typed value in its present state (a SERS
            # jog command while the drive is off, O5..O16 without option IO): its answer, not
            # a crash; it must name the point or the device's error
            assert str(exc), point.name
        before = device.read(point.name) if point.readable else None
        for bad in _invalid(point):
            with pytest.raises(BadValue):
                device.set(point.name, bad)
            if point.readable:
                assert device.read(point.name) == before, f"{point.name} changed by a refused value {bad!r}"
        clock.advance(0.01)


def _plain_json(value: Any) -> bool:
    """Whether ``value`` is JSON as a client receives it: no NaN or infinity, no other objects."""
    if value is None or isinstance(value, bool | int | str):
        return True
    if isinstance(value, float):
        return math.isfinite(value)
    if isinstance(value, list | tuple):
        return all(_plain_json(v) for v in value)
    if isinstance(value, dict):
        return all(isinstance(k, str) and _plain_json(v) for k, v in value.items())
    return False


#: Values of any shape for the points that take text or JSON.
ODD_SHAPES = ["", "x", "0", "zz 00", 0, -1, 1.5, True, None, [], [1], ["x", 1], {"a": 1}]


def test_text_and_json_points_take_any_shape_or_refuse_it(booted: tuple[Device, VirtualClock]) -> None:
    """A value of the wrong shape for a text or JSON point (from a control client, a plant or a
    facade) is taken or refused with :class:`BadValue`, never another exception; a refused value
    changes nothing, and every point stays readable as its type (text or nothing; plain JSON).  (A fuzz run found a SERS program set to ``0``, ``param.P1`` set to ``""`` and
    IP247 machine data in a string that is not hex raising TypeError, AssertionError, ValueError.)"""
    device, clock = booted
    for point in device.points:
        if not point.settable or point.type not in ("str", "json"):
            continue
        for odd in ODD_SHAPES:
            before = device.read(point.name) if point.readable else None
            try:
                device.set(point.name, odd)
            except BadValue:
                if point.readable:
                    assert device.read(point.name) == before, f"{point.name} changed by a refused {odd!r}"
            clock.advance(0.01)
    for point in device.points:
        if point.readable:
            value = device.read(point.name)
            if point.type == "str":
                assert value is None or isinstance(value, str), f"{point.name} reads {value!r}, not text or nothing"
            elif point.type == "json":
                assert _plain_json(value), f"{point.name} reads {value!r}, not plain JSON"


def test_power_cycle_boots_again(booted: tuple[Device, VirtualClock]) -> None:
    device, clock = booted
    ready: list[float] = []
    device.on_ready(lambda: ready.append(clock.now()))
    ready.clear()
    device.power_cycle()
    assert clock.run_until(lambda: not device.booting, BOOT)
    device.power_cycle(wipe=True)
    assert clock.run_until(lambda: not device.booting, BOOT)
    for point in device.points:
        if point.readable:
            device.read(point.name)


def test_every_declared_fault_on_and_off(booted: tuple[Device, VirtualClock]) -> None:
    device, clock = booted
    for fault in device.faults:
        assert fault.doc
        device.fault(fault.name, True)
        clock.advance(0.5)
        device.fault(fault.name, False)
        clock.advance(0.5)
        assert clock.run_until(lambda: not device.booting, BOOT)
    with pytest.raises(KeyError, match="has no fault"):
        device.fault("no_such_fault", True)


def _garbage(device: Device, clock: VirtualClock) -> dict[str, bytes]:
    """200 chunks of random bytes (seeded by the kind) on every port, a host disconnect after
    them: what each port sent back."""
    rng = random.Random(f"{device.kind}-garbage")
    sent: dict[str, bytes] = {}
    for name in device.port_names():
        port = device.port(name)
        out = bytearray()
        port.attach(out.extend)
        fed = 0
        for _ in range(200):
            chunk = bytes(rng.randrange(256) for _ in range(rng.randrange(1, 40)))
            fed += len(chunk)
            port.feed(chunk)
            clock.advance(rng.random() * 0.05)
        port.host_disconnected()
        port.attach(None)
        sent[name] = bytes(out)
        # an echo and an answer per garbage byte is already more than any kind sends; more is a runaway
        assert len(out) <= 4 * fed + 1024, f"{name}: {len(out)} bytes out for {fed} in"
    return sent


def test_garbage_on_every_port(booted: tuple[Device, VirtualClock], tmp_path: Any) -> None:
    """Garbage on every port: the device still reads every point (floats finite), and what it
    sends back is bounded and, byte for byte, what a second device of its kind sends for the
    same garbage at the same (virtual) times: it depends on the input and the device clock
    only, which is what a recorded trace replays."""
    device, clock = booted
    sent = _garbage(device, clock)
    for point in device.points:
        if point.readable:
            value = device.read(point.name)
            if isinstance(value, float):
                assert math.isfinite(value), point.name
    twin_clock = VirtualClock()
    twin = type(device)(clock=twin_clock, nvram=NonVolatileMemory.for_device(tmp_path / "twin", "d"), name="d")
    try:
        assert twin_clock.run_until(lambda: not twin.booting, BOOT)
        assert _garbage(twin, twin_clock) == sent
    finally:
        twin.close()
