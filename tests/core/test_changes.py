"""Every door a device changes through counts (devsim/core/changes.py), and a SERS's repeated
poll answered from what was kept looks at nothing but its value while the count stands, and at
everything again after any door counted (issue 31)."""

from __future__ import annotations

import asyncio
from collections.abc import Callable
from typing import Any, ClassVar

import pytest

from devsim.core.bus import Bus
from devsim.core.changes import CHANGES
from devsim.core.clock import RealClock, VirtualClock
from devsim.core.device import Device, Face
from devsim.core.nvram import NonVolatileMemory
from devsim.devices.sers import SersDevice
from devsim.facades.cia402 import Cia402
from devsim.fleet.answers import FAST_OPS, Asked

POLL = b"#P11?\r"


def _sers(clock: VirtualClock | None = None) -> SersDevice:
    return SersDevice(clock=clock or VirtualClock(), config={"boot_time": 0}, nvram=NonVolatileMemory(None))


def _counted(action: Callable[[], Any]) -> int:
    before = CHANGES.count
    action()
    return CHANGES.count - before


def test_the_doors_of_the_device_api_count() -> None:
    device = _sers()
    assert _counted(lambda: device.set("param.P1017", 1)) == 1
    assert _counted(lambda: device.apply_state({"param.P1017": 0, "param.P100": 5})) >= 1
    assert _counted(lambda: device.fault("power", True)) == 1
    assert _counted(lambda: device.fault("power", False)) == 1
    assert _counted(lambda: device.power_cycle()) == 1
    assert _counted(lambda: device.unobserved_until(1.0)) == 1
    assert _counted(lambda: device.host_disconnected()) == 1
    assert _counted(lambda: Bus([device, _sers()])) == 1
    assert _counted(lambda: device.read("param.P1017")) == 0  # (a read changes nothing)


def test_bytes_count_unless_the_face_answers_them_at_once() -> None:
    device = _sers()
    device.attach(lambda data: None)
    assert _counted(lambda: device.feed(POLL)) == 1  # (the face's feed: the first time)
    assert _counted(lambda: device.feed(POLL)) == 0  # (answered at once, all checked)
    assert _counted(lambda: device.feed(POLL)) == 0  # (answered at once, the value read)
    assert _counted(lambda: device.feed(b"#P12?\r")) == 1


class _EchoFace(Face):
    """Notes the count at every chunk; the first chunk it is fed feeds its port again (as a bus
    hands on bytes to a device that is still digesting)."""

    __slots__ = ("seen",)

    def __init__(self, model: Any, port: Any) -> None:
        super().__init__(model, port)
        self.seen: list[int] = []

    def feed(self, data: bytes) -> None:
        self.seen.append(CHANGES.count)
        if len(self.seen) == 1:
            self.port.feed(b"again")


class _EchoDevice(Device):
    kind: ClassVar[str] = "changes-echo"
    face_classes: ClassVar[dict[str, Any]] = {"main": _EchoFace}


def test_bytes_fed_again_while_the_face_digests_count() -> None:
    device = _EchoDevice(clock=VirtualClock())
    before = CHANGES.count
    device.feed(b"first")
    assert device.face().seen == [before + 1, before + 2]  # type: ignore[attr-defined]


def test_timers_count_on_both_clocks() -> None:
    clock = VirtualClock()
    clock.call_later(0.5, lambda: None)
    assert _counted(lambda: clock.advance(1.0)) == 1

    async def real() -> int:
        real_clock = RealClock()
        fired = asyncio.get_running_loop().create_future()
        before = CHANGES.count
        real_clock.call_later(0.0, lambda: fired.set_result(CHANGES.count))
        return await fired - before

    assert asyncio.run(real()) == 1


def test_the_fleets_fast_set_counts() -> None:
    device = _sers()
    point = device.points.lookup("param.P1017")
    asked = Asked(op="set", device="d", name="param.P1017", id=1, value=2)
    assert _counted(lambda: FAST_OPS["set"].run(asked, device, point)) == 1
    assert device.read("param.P1017") == 2


def test_the_cia402_drive_actions_count() -> None:
    device = _sers()
    assert device.drive is not None
    drive = Cia402(device.drive, device.model)
    assert _counted(lambda: drive.write_controlword(0x06)) == 1
    for word in (0x07, 0x0F):
        drive.write_controlword(word)
    assert drive.state == "operation_enabled"
    drive.write_mode(3)  # profile velocity
    drive.write_controlword(0x0F)
    assert _counted(lambda: drive.write_target_velocity(100)) == 1
    assert _counted(lambda: drive.reset()) == 1  # (enabled: switched off)
    for word in (0x06, 0x07, 0x0F, 0x02):  # (enabled, then quick stop: the axis stands)
        drive.write_controlword(word)
    assert drive.state == "quick_stop_active"
    assert _counted(lambda: drive.statusword) == 1  # (stood still: the drive switched off)
    assert drive.state == "switch_on_disabled"


class _Untouchable:
    """A part the repeated poll must not look at while the count stands."""

    def __getattr__(self, name: str) -> Any:
        raise AssertionError(f"looked at {name}")


def _kept_and_gated(device: SersDevice, poll: bytes = POLL) -> Any:
    device.attach(lambda data: None)
    device.feed(poll)
    device.feed(poll)  # (answered at once, all checked: the reply stamped)
    polls = device.face().polls  # type: ignore[attr-defined]
    assert polls.kept is not None and polls.kept.stamp == CHANGES.count
    return polls


def test_while_the_count_stands_the_port_gives_a_timeless_reply_without_the_face() -> None:
    """P11 changes only with the drive's state: its reply stands at the port (Standing) and the
    face is not asked; P1016 changes with time: the face reads it every time."""
    device = _sers()
    polls = _kept_and_gated(device)
    assert device.main.standing.data == POLL
    access, out = polls.access, bytearray()
    polls.access = _Untouchable()
    device.attach(out.extend)
    device.feed(POLL)
    assert bytes(out) == b"#P11?\rP11=0\n\r\nok1\n\r"
    polls.access = access
    device.feed(b"#P1016?\r")
    device.feed(b"#P1016?\r")  # (answered at once: the standing reply no longer the face's last)
    assert device.main.standing.stamp == -1
    polls.access = _Untouchable()
    with pytest.raises(AssertionError, match="looked at"):
        device.feed(b"#P1016?\r")
    polls.access = access


def test_while_the_count_stands_a_repeated_poll_reads_its_value_only() -> None:
    device = _sers()
    poll = b"#P1016?\r"  # (a value that changes with time: read by the face every time)
    polls = _kept_and_gated(device, poll)
    master, out = polls.master, bytearray()
    polls.master = _Untouchable()
    device.attach(out.extend)
    device.feed(poll)
    assert bytes(out) == b"#P1016?\rP1016=0\n\r\nok1\n\r"
    CHANGES.count += 1  # (any door)
    with pytest.raises(AssertionError, match="looked at awaiting"):
        device.feed(poll)
    polls.master = master


def _through(door: str, device: SersDevice, clock: VirtualClock) -> None:
    """Change what the drive answers to P11 (echo mode, an error) through one door only."""
    point = device.points.lookup("param.P1017")
    if door == "set":
        device.set("param.P1017", 2)  # (echo mode 2)
    elif door == "fault":
        device.fault("power", True)  # (the supply off: nothing answers)
    elif door == "timer":  # (the point put by the timer itself: no other door)
        clock.call_later(0.1, lambda: point.put(device.model, 2))
    elif door == "line":
        device.feed(b"#P1017=2\r")
    elif door == "power":
        device.power_cycle()
    else:
        FAST_OPS["set"].run(Asked(op="set", device="d", name="param.P1017", id=1, value=2), device, point)
    clock.advance(1.0)


@pytest.mark.parametrize("door", ["set", "fault", "timer", "line", "power", "fleet"])
def test_after_any_door_the_repeated_poll_answers_what_the_drive_answers_now(door: str) -> None:
    """The same door on two drives that answered the poll at once before: the next poll, fed
    whole to one (the poll path) and in two pieces to the other (the general way), gets the same
    answer, and for every door but a power cycle not the one it got before."""
    answers = []
    for pieces in ([POLL], [POLL[:1], POLL[1:]]):
        clock = VirtualClock()
        device = _sers(clock)
        _kept_and_gated(device)
        _through(door, device, clock)
        out = bytearray()
        device.attach(out.extend)
        for piece in pieces:
            device.feed(piece)
        answers.append(bytes(out))
    assert answers[0] == answers[1]
    assert (answers[0] == b"#P11?\rP11=0\n\r\nok1\n\r") == (door == "power")


def test_a_value_that_changes_with_time_alone_is_read_at_every_poll() -> None:
    """P1016 (at constant speed) turns 1 while the axis moves, with no timer, no byte, no call in
    between: the repeated poll answered at once shows it."""
    clock = VirtualClock()
    device = _sers(clock)
    out = bytearray()
    device.attach(out.extend)
    device.feed(b"#ON V=30 WR=200000 E\r")
    poll = b"#P1016?\r"
    device.feed(poll)
    device.feed(poll)
    counted = CHANGES.count
    out.clear()
    device.feed(poll)  # (at once, while the count stands)
    clock.advance(0.5)
    device.feed(poll)
    assert CHANGES.count == counted  # (no door between the polls)
    assert bytes(out) == b"#P1016?\rP1016=0\n\r\nok0\n\r" + b"#P1016?\rP1016=1\n\r\nok0\n\r"
