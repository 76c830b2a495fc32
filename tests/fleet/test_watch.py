"""``devsim ctl --fleet URL watch`` (issue 29): two member processes on a real mosquitto, watched
over the broker with the lines of ``devsim ctl watch`` on one process, one per event, each naming
its device; mosquitto_sub is the independent view of the stream and presence topics."""

from __future__ import annotations

import json
import signal
import socket
import subprocess
import sys
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest

from devsim.fleet.client import FleetClient
from tests.fleet.conftest import Member, Program, mosquitto, two_members
from tests.support.broker import Broker
from tests.support.process import next_match, wait_until
from tests.support.process import stop as stop_process

STREAMS = "devsim-fleet/client/+/watch/+"
PRESENCES = "devsim-fleet/client/+/watching"


def line_where(program: Program, accept: Callable[[str], bool], what: str, timeout: float = 30.0) -> str:
    try:
        return next_match(program.lines, accept, timeout, what, keep=program.seen)
    except AssertionError as exc:
        raise AssertionError(f"{program.proc.args}: {exc}; got {program.seen[-20:]}; "
                             f"stderr: {program.log.read_text()[-2000:]}") from None


def devices_in(lines: list[str]) -> set[str]:
    """The devices named by watch lines ('12.300 feeder axis.position 1234.0')."""
    return {word for line in lines for word in line.split()[1:2]}


def watch(url: str, log: Path, *args: str) -> Program:
    return Program([sys.executable, "-m", "devsim", "ctl", "--fleet", url, "watch", *args], log)


@pytest.fixture
def members(broker: Broker, plant_file: Path, tmp_path: Path) -> Iterator[dict[str, Member]]:
    """feeder (sers) in one process, press (gms96) in another, both on virtual time (nothing
    changes unless asked)."""
    with two_members(broker.url, plant_file, tmp_path) as started:
        yield started


def test_a_fleet_watch_streams_every_device_of_two_processes(members: dict[str, Member], broker: Broker,
                                                              tmp_path: Path) -> None:
    sub = mosquitto("mosquitto_sub", "-p", str(broker.port), "-t", STREAMS, "-F", "%t %p", "-d",
                    log=tmp_path / "sub.log")
    sub.wait_for("Subscribed")
    watcher = watch(broker.url, tmp_path / "watch.log")
    try:
        # the first items: every watched value, as on one process; the two processes' lines come
        # in whichever order their members answer, so either device may come first
        line_where(watcher, lambda _line: devices_in(watcher.seen) >= {"feeder", "press"},
                   "a first line of feeder and of press")
        with FleetClient(broker.url) as fleet:
            fleet.fault("feeder", "emergency_stop", True)
            fleet.fault("press", "emergency_stop", True)
            fleet.fault("feeder", "emergency_stop", False)
        # one line per event, the device named, exactly as `devsim ctl watch` prints it on one
        # process; in order per device (two processes' lines interleave as they come)
        def faults_of(device: str) -> list[str]:
            return [line.split()[-1] for line in watcher.seen if line.split()[1:4] == [device, "fault", "emergency_stop"]]

        line_where(watcher, lambda _line: faults_of("feeder") == ["on", "off"] and faults_of("press") == ["on"],
                   "the three fault lines")
        for line in watcher.seen:
            float(line.split()[0])  # the device time leads every line, as on one process
        # the independent view: the member published each item on the stream topic, as JSON
        faults = []
        while len(faults) < 3:
            topic, payload = sub.wait_for("devsim-fleet/client/").split(" ", 1)
            item = json.loads(payload)
            assert topic.startswith("devsim-fleet/client/") and "/watch/" in topic and "watch" in item
            if item["type"] == "fault":
                faults.append((item["device"], item["name"], item["active"]))
        assert sorted(faults) == sorted([("feeder", "emergency_stop", True), ("press", "emergency_stop", True),
                                         ("feeder", "emergency_stop", False)])
        # both processes leave: the watch ends by itself, as it does when one simulator stops
        for member in members.values():
            member.stop()
        assert watcher.proc.wait(30) == 0, watcher.log.read_text()
    finally:
        watcher.stop()
        sub.stop()


def test_json_lines_name_the_process_and_a_killed_watcher_ends_its_stream(
        members: dict[str, Member], broker: Broker, tmp_path: Path) -> None:
    press = members["cell-b"].process
    presence = mosquitto("mosquitto_sub", "-p", str(broker.port), "-t", PRESENCES, "-t", STREAMS,
                         "-F", "%t %r [%p]", "-d", log=tmp_path / "presence.log")
    presence.wait_for("Subscribed")
    watcher = watch(broker.url, tmp_path / "watch.log", "press", "estop", "--json")
    try:
        first = json.loads(line_where(watcher, lambda line: line.startswith("{"), "a JSON line"))
        assert (first["device"], first["type"], first["name"], first["value"]) == ("press", "change", "estop", False)
        assert first["process"] == press
        watching = line_where(presence, lambda line: line.split(" ")[0].endswith("/watching"), "the presence")
        assert watching.endswith(" [1]")  # set (retained) before it asked
        client = watching.split("/")[2]
        with FleetClient(broker.url) as fleet:
            fleet.fault("press", "emergency_stop", True)
            fleet.advance(0.2, device="press")  # a value change is seen at the watch's next sample (0.1 s)
            item = json.loads(line_where(watcher, lambda line: '"estop"' in line and "true" in line, "estop true"))
            assert item["value"] is True and item["process"] == press

            stop_process(watcher.proc, signal.SIGKILL)  # no goodbye: its last will clears the presence
            line_where(presence, lambda line: line == f"devsim-fleet/client/{client}/watching 0 []", "the will")
            fleet.fault("press", "emergency_stop", False)  # after the presence was cleared: no item
            fleet.advance(0.2, device="press")
            assert fleet.read("press", "estop") is False
        probe = f"devsim-fleet/client/{client}/watch/probe"
        sent = mosquitto("mosquitto_pub", "-p", str(broker.port), "-t", probe, "-m", "end", log=tmp_path / "pub.log")
        assert sent.proc.wait(15) == 0
        sent.stop()
        line_where(presence, lambda line: line == f"{probe} 0 [end]", "the probe")
        stream = [json.loads(line.split(" [", 1)[1][:-1]) for line in presence.seen
                  if "/watch/" in line.split(" ")[0] and line.split(" ")[0] != probe]
        assert [item["value"] for item in stream if item.get("name") == "estop"] == [False, True]  # none after
    finally:
        watcher.stop()
        presence.stop()


def test_after_the_broker_restarts_a_member_ends_the_streams_of_watchers_that_are_gone(tmp_path: Path) -> None:
    """The broker dies (no will goes out) and so does the watcher; a new broker (no persistence)
    comes up at the address: the member reconnects, finds no presence of that watcher (its marker
    comes back after the retained presences) and publishes no more on its stream."""
    first = Broker().start()
    member = Member(["run", "sers", "--virtual"], first.url, tmp_path / "run.log")
    watcher = watch(first.url, tmp_path / "watch.log", "sers")
    second = Broker()
    sub: Program | None = None
    try:
        line_where(watcher, lambda line: line.split()[1:2] == ["sers"], "a first line")
        assert first.process is not None
        stop_process(first.process, signal.SIGKILL)  # gone at once: no will reaches anyone
        stop_process(watcher.proc, signal.SIGKILL)  # and the watcher with it, while the member is away
        second.port = first.port
        second.start()
        sub = mosquitto("mosquitto_sub", "-p", str(second.port), "-t", STREAMS, "-F", "%t %p", "-d",
                        log=tmp_path / "sub.log")
        sub.wait_for("Subscribed")
        with FleetClient(second.url) as fleet:
            fleet.wait_for_devices(["sers"], timeout=30)
            fleet.fault("sers", "emergency_stop", True)  # a fault item, were the stream still served
            assert fleet.read("sers", "input.stop") is True
        probe = "devsim-fleet/client/probe/watch/0"
        sent = mosquitto("mosquitto_pub", "-p", str(second.port), "-t", probe, "-m", "end", log=tmp_path / "pub.log")
        assert sent.proc.wait(15) == 0
        sent.stop()
        line_where(sub, lambda line: line == f"{probe} end", "the probe")
        assert [line for line in sub.seen if line.startswith("devsim-fleet/") and not line.startswith(probe)] == []
    finally:
        watcher.stop()
        if sub is not None:
            sub.stop()
        member.stop()
        second.stop()
        first.stop()


def test_a_watch_of_an_empty_fleet_or_of_no_device_is_one_line(broker: Broker) -> None:
    from tests.fleet.conftest import ctl

    assert ctl(broker.url, "watch", ok=False) == f"Error: UnknownDevice: no device online in the fleet {broker.url}"
    assert "no device named 'nobody'" in ctl(broker.url, "watch", "nobody", ok=False)
    done = subprocess.run([sys.executable, "-m", "devsim", "ctl", "--control", "127.0.0.1:1", "watch"],
                          capture_output=True, text=True, timeout=60)
    assert done.returncode == 2 and "watch needs DEVICE" in done.stderr


def stderr_lines(program: Program) -> list[str]:
    return program.log.read_text().splitlines()


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGKILL], ids=["broker-shuts-down", "broker-killed"])
def test_a_watch_that_loses_the_broker_says_so_and_fails(sig: signal.Signals, plant_file: Path,
                                                         tmp_path: Path) -> None:
    """Losing the broker is neither the watched processes leaving nor Ctrl-C: one line names the
    broker and the status is 5 (nothing answers).  mosquitto shutting down (SIGTERM) sends the
    members' last wills before it closes: that must not pass for the members going offline."""
    own = Broker().start()
    started = [Member(["up", str(plant_file), "--part", part, "--virtual"], own.url, tmp_path / f"{part}.log")
               for part in ("cell-a", "cell-b")]
    watcher = watch(own.url, tmp_path / "watch.log")
    try:
        line_where(watcher, lambda _line: devices_in(watcher.seen) >= {"feeder", "press"},
                   "a first line of feeder and of press")
        assert own.process is not None
        stop_process(own.process, sig)
        assert watcher.proc.wait(30) == 5, stderr_lines(watcher)
        assert stderr_lines(watcher) == [stderr_lines(watcher)[0]]  # one line
        assert stderr_lines(watcher)[0].startswith(f"Error: fleet broker {own.url} lost (")
        assert all(member.proc.poll() is None for member in started)  # they wait for the broker to return
    finally:
        watcher.stop()
        for member in started:
            member.stop()
        own.stop()


def test_a_fleet_watch_says_which_process_went_offline_and_watches_the_others_on(
        members: dict[str, Member], tmp_path: Path, broker: Broker) -> None:
    watcher = watch(broker.url, tmp_path / "watch.log")
    try:
        line_where(watcher, lambda _line: devices_in(watcher.seen) >= {"feeder", "press"},
                   "a first line of feeder and of press")
        press = members["cell-b"]
        stop_process(press.proc, signal.SIGKILL)  # no goodbye: the broker publishes its last will

        def offline() -> list[str]:
            return [line for line in stderr_lines(watcher) if "went offline" in line]

        wait_until(lambda: bool(offline()), "a line saying press's process went offline", timeout=30)
        assert offline() == [f"devsim: {press.process} (host {socket.gethostname()}, pid {press.proc.pid})"
                             " went offline (its last will): no more items of press"]
        with FleetClient(broker.url) as fleet:  # the other process's device is still watched
            fleet.fault("feeder", "emergency_stop", True)
        line_where(watcher, lambda line: line.split()[1:] == ["feeder", "fault", "emergency_stop", "on"],
                   "feeder's fault line")
        assert watcher.proc.poll() is None
        stop_process(members["cell-a"].proc, signal.SIGKILL)  # the last one: the watch ends, as it
        assert watcher.proc.wait(30) == 0, stderr_lines(watcher)  # does when a simulator stops
        assert len(offline()) == 2 and not any(line.startswith("Error") for line in stderr_lines(watcher))
    finally:
        watcher.stop()
