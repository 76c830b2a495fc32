"""A fleet watch follows a watched member that comes back (docs/fleet.md, the watch paragraph):
two member processes on a real mosquitto, one taken off the broker until its last will marks it
offline and then let back so that it rejoins; while the other is still watched, the watch asks
the returning one again, says so in one line, and its items follow again, as ``tail -F`` follows
a file that comes back.  A member back without the watched device stays gone.

press's process reaches the broker through a relay (tests/support/relay.py).  Cutting the relay
is what a frozen process (a laptop asleep) comes to, without waiting for the broker's keep alive
(15 s at mosquitto's least, ``max_keepalive 10``) to give up on it: the broker finds the member's
connection lost without a DISCONNECT and sends its last will at once, while the member hears
nothing (its side is held silent, as a frozen process hears nothing); let back, the member reads
the end of its connection, as a frozen process does when continued after the broker dropped it,
and reconnects, through the relay again.  SIGSTOP is not kept: what it adds is the broker's keep
alive timing out (mosquitto's doing; the will it sends is the same) and a member that does
nothing while away (nothing of what these tests watch changes meanwhile: virtual time)."""

from __future__ import annotations

import json
import signal
import socket
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest

from devsim.fleet.client import FleetClient
from tests.fleet.conftest import Member, Program, mosquitto, two_members
from tests.fleet.test_watch import STREAMS, devices_in, line_where, stderr_lines, watch
from tests.support.broker import Broker
from tests.support.process import stop as stop_process
from tests.support.process import wait_until
from tests.support.relay import Relay


@pytest.fixture
def own() -> Iterator[Broker]:
    """A broker of its own: the offline marks stay out of the other tests."""
    server = Broker().start()
    yield server
    server.stop()


@pytest.fixture
def relay(own: Broker) -> Iterator[Relay]:
    """The way of press's process to the broker: cut (:meth:`Relay.cut`), it is off the broker."""
    between = Relay(own.port).start()
    yield between
    between.stop()


@pytest.fixture
def members(own: Broker, relay: Relay, plant_file: Path, tmp_path: Path) -> Iterator[dict[str, Member]]:
    """feeder (sers) in one process, press (gms96) in another (through ``relay``), both on virtual time."""
    with two_members(own.url, plant_file, tmp_path, via={"cell-b": relay.url}) as started:
        yield started


def said(program: Program, words: str) -> Callable[[], list[str]]:
    return lambda: [line for line in stderr_lines(program) if words in line]


def where(member: Member) -> str:
    return f"{member.process} (host {socket.gethostname()}, pid {member.proc.pid})"


def test_a_fleet_watch_watches_a_member_again_that_comes_back(members: dict[str, Member], own: Broker,
                                                               relay: Relay, tmp_path: Path) -> None:
    sub = mosquitto("mosquitto_sub", "-p", str(own.port), "-t", STREAMS, "-F", "%t %p", "-d",
                    log=tmp_path / "sub.log")
    sub.wait_for("Subscribed")
    watcher = watch(own.url, tmp_path / "watch.log")
    feeder, press = members["cell-a"], members["cell-b"]
    offline, back = said(watcher, " went offline "), said(watcher, " is back")
    try:
        line_where(watcher, lambda _line: devices_in(watcher.seen) >= {"feeder", "press"},
                   "a first line of feeder and of press")
        relay.cut()  # press's process is off the broker: the broker sends its last will
        wait_until(lambda: bool(offline()), "the line saying press's process went offline", timeout=30)
        assert offline() == [f"devsim: {where(press)} went offline (its last will): no more items of press"]
        relay.restore()  # it finds its connection gone and rejoins
        wait_until(lambda: bool(back()), "the line saying press's process is back", timeout=30)
        assert back() == [f"devsim: {where(press)} is back: items of press follow again"]
        assert watcher.proc.poll() is None
        with FleetClient(own.url) as fleet:  # asked again: its events are watched again
            fleet.fault("press", "emergency_stop", True)
        line_where(watcher, lambda line: line.split()[1:] == ["press", "fault", "emergency_stop", "on"],
                   "press's fault line after it came back")
        # its values came again first (as on a new watch), once before the freeze and once after
        assert len([line for line in watcher.seen if line.split()[1:3] == ["press", "estop"]]) == 2
        # the member serves the new stream only: the one its will ended is published on no more
        probe = "devsim-fleet/client/probe/watch/0"
        sent = mosquitto("mosquitto_pub", "-p", str(own.port), "-t", probe, "-m", "end", log=tmp_path / "pub.log")
        assert sent.proc.wait(15) == 0
        sent.stop()
        sub.wait_for(probe)
        faults = [line for line in sub.seen if '"type":"fault"' in line and '"device":"press"' in line]
        assert len(faults) == 1, faults  # (the old stream, were it served on, would carry it too)
        # the watch ends as before: when no watched member is left
        stop_process(feeder.proc, signal.SIGKILL)
        wait_until(lambda: len(offline()) == 2, "the line saying feeder's process went offline", timeout=30)
        assert watcher.proc.poll() is None  # press is watched on
        stop_process(press.proc, signal.SIGKILL)
        assert watcher.proc.wait(30) == 0, stderr_lines(watcher)
        assert len(offline()) == 3 and len(back()) == 1
        assert not any(line.startswith("Error") for line in stderr_lines(watcher))
    finally:
        watcher.stop()
        sub.stop()


def next_of(items: Iterator[dict[str, Any]], accept: Callable[[dict[str, Any]], bool], seen: list[dict[str, Any]]
            ) -> dict[str, Any]:
    """The next watch item that ``accept`` takes (each one appended to ``seen``; the watch's own
    timeout bounds each wait)."""
    for item in items:
        seen.append(item)
        if accept(item):
            return item
    raise AssertionError(f"the watch ended; got {seen[-20:]}")


def fault_of(device: str, active: bool) -> Callable[[dict[str, Any]], bool]:
    return lambda item: (item["device"], item["type"], item.get("active")) == (device, "fault", active)


def test_fleet_client_watch_tells_on_back_and_yields_the_items_again(members: dict[str, Member],
                                                                     own: Broker, relay: Relay) -> None:
    feeder, press = members["cell-a"], members["cell-b"]
    told: list[str] = []
    seen: list[dict[str, Any]] = []
    with FleetClient(own.url) as fleet:
        items = fleet.watch(None, on_offline=told.append, on_back=lambda line: told.append(f"back: {line}"),
                            timeout=30)
        try:
            next_of(items, lambda _item: {item["device"] for item in seen} >= {"feeder", "press"}, seen)
            relay.cut()
            fleet.wait_for_devices(["press"], timeout=30, online=False)  # its will is out
            fleet.fault("feeder", "emergency_stop", True)  # an item after the will: the will is told first
            next_of(items, fault_of("feeder", True), seen)
            assert told == [f"devsim: {where(press)} went offline (its last will): no more items of press"]
            relay.restore()
            fleet.wait_for_devices(["press"], timeout=30)  # back in the fleet
            fleet.fault("feeder", "emergency_stop", False)
            mark = len(seen)
            next_of(items, fault_of("feeder", False), seen)
            assert told[1:] == [f"back: devsim: {where(press)} is back: items of press follow again"]
            fleet.fault("press", "emergency_stop", True)  # (its watch was answered before on_back was told)
            item = next_of(items, fault_of("press", True), seen)
            assert item["process"] == press.process
            again = [item for item in seen[mark:] if item["device"] == "press" and item["type"] == "change"]
            assert {item["name"] for item in again} >= {"estop"}  # its values, as a new watch starts
            assert all(json.dumps(item) for item in seen)
        finally:
            items.close()  # type: ignore[attr-defined]
    assert feeder.proc.poll() is None


def test_a_member_back_without_the_watched_device_stays_gone(members: dict[str, Member], own: Broker,
                                                             relay: Relay, tmp_path: Path) -> None:
    """press's process, off the broker, is replaced meanwhile (another process serves press): it rejoins
    without press (withdrawn), so there is nothing of it to watch again; the watch goes on with
    feeder and ends when feeder's process goes, as before.  The replacement was not watched."""
    feeder, press = members["cell-a"], members["cell-b"]
    told: list[str] = []
    seen: list[dict[str, Any]] = []
    replacement: Member | None = None
    with FleetClient(own.url) as fleet:
        items = fleet.watch(None, on_offline=told.append, on_back=told.append, timeout=30)
        try:
            next_of(items, lambda _item: {item["device"] for item in seen} >= {"feeder", "press"}, seen)
            relay.cut()
            fleet.wait_for_devices(["press"], timeout=30, online=False)
            only_press = tmp_path / "press.yaml"
            only_press.write_text("devices:\n  - {name: press, kind: gms96}\n")
            replacement = Member(["up", str(only_press), "--virtual"], own.url, tmp_path / "replacement.log")
            relay.restore()
            wait_until(lambda: " back; announced again without 'press'" in press.log.read_text(),
                       "the old press process rejoining without press", timeout=30)
            fleet.fault("feeder", "emergency_stop", True)  # after its new announcement
            next_of(items, fault_of("feeder", True), seen)
            assert told == [f"devsim: {where(press)} went offline (its last will): no more items of press"]
            fleet.fault("press", "emergency_stop", True)  # the replacement's press: not watched
            stop_process(feeder.proc, signal.SIGKILL)
            rest = list(items)  # the watch ends: no watched member is left
            assert [item for item in rest if item["device"] == "press"] == []
            assert len(told) == 2 and "no more items of feeder" in told[1]
        finally:
            items.close()  # type: ignore[attr-defined]
            if replacement is not None:
                replacement.stop()
