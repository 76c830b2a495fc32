"""Three devsim processes, each serving one part of one plant file, form a fleet on a real
mosquitto; ``devsim ctl --fleet`` and mosquitto's own clients see and reach every device."""

from __future__ import annotations

import json
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

from devsim.fleet.client import FleetClient
from devsim.runtime.client import ControlError
from tests.fleet.conftest import Member, ctl, mosquitto
from tests.support.broker import Broker

PARTS = {"cell-a": ["feeder"], "cell-b": ["press"], "cell-c": ["robot", "robot2"]}


@pytest.fixture(scope="module")
def fleet(broker: Broker, plant_file: Path, tmp_path_factory: pytest.TempPathFactory) -> Iterator[dict[str, Member]]:
    logs = tmp_path_factory.mktemp("logs")
    members: dict[str, Member] = {}
    try:
        for part in PARTS:
            extra = ["--virtual"] if part == "cell-b" else []
            members[part] = Member(["up", str(plant_file), "--part", part, *extra], broker.url, logs / f"{part}.log")
        yield members
    finally:
        for member in members.values():
            member.stop()


def test_ctl_lists_every_device_of_every_process(fleet: dict[str, Member], broker: Broker) -> None:
    rows = ctl(broker.url, "devices")
    assert sorted(row["name"] for row in rows) == sorted(sum(PARTS.values(), []))  # 'spare' has no part
    for part, member in fleet.items():
        mine = [row for row in rows if row["process"] == member.process]
        assert sorted(row["name"] for row in mine) == PARTS[part]
        for row in mine:
            assert row["online"] is True and row["part"] == part and row["plant"] == "line3"
            assert row["pid"] == member.proc.pid and row["host"]
            assert row["port"].startswith("/dev/pts/")  # the pty on that process's machine
    assert {row["name"]: row["kind"] for row in rows}["press"] == "gms96"


def test_read_set_fault_reach_each_process(fleet: dict[str, Member], broker: Broker) -> None:
    with FleetClient(broker.url) as client:
        for device in ("feeder", "robot", "robot2"):
            assert client.read(device, "input.I3") is False
            client.set(device, "input.I3", True)
            assert client.read(device, "input.I3") is True
            client.fault(device, "emergency_stop", True)
            assert client.read(device, "input.stop") is True
            client.fault(device, "emergency_stop", False)
            assert client.read(device, "input.stop") is False
            assert client.read("robot" if device == "feeder" else "feeder", "input.stop") is False
        client.fault("press", "emergency_stop", True)
        assert client.read("press", "estop") is True
        assert client.state("press")["estop"] is True
        client.fault("press", "emergency_stop", False)
        # the command line reaches them too, each op once
        ctl(broker.url, "set", "robot2", "input.I4", "on")
        assert ctl(broker.url, "read", "robot2", "input.I4") is True
        ctl(broker.url, "fault", "press", "emergency_stop", "on")
        assert client.read("press", "estop") is True
        client.fault("press", "emergency_stop", False)


def test_errors_are_the_control_apis(fleet: dict[str, Member], broker: Broker) -> None:
    with FleetClient(broker.url) as client:
        with pytest.raises(ControlError) as caught:
            client.read("feeder", "no.such.point")
        assert caught.value.type == "UnknownName"
        with pytest.raises(ControlError) as caught:
            client.set("robot", "encoder.pulses", "lots")
        assert caught.value.type == "BadValue"
    message = ctl(broker.url, "read", "nobody", "x", ok=False)
    assert message.startswith("Error: UnknownDevice: no device named 'nobody'") and "feeder" in message


def test_advance_is_per_process(fleet: dict[str, Member], broker: Broker) -> None:
    with FleetClient(broker.url) as client:
        before = client.now()
        assert set(before) == {member.process for member in fleet.values()}
        press = fleet["cell-b"].process
        assert client.advance(2.5, device="press") == pytest.approx(before[press] + 2.5)
        after = client.advance(1.0)  # every process on virtual time: only cell-b's
        assert after == {press: pytest.approx(before[press] + 3.5)}
        with pytest.raises(ControlError, match="virtual time"):
            client.advance(1.0, device="feeder")  # a real clock refuses, as over --control
    assert ctl(broker.url, "now", "--device", "press") == pytest.approx(before[press] + 3.5)


def test_info_is_per_process(fleet: dict[str, Member], broker: Broker) -> None:
    """``info`` (what ``devsim ps`` lists) names each process: its plant and part, pid and devices."""
    infos = ctl(broker.url, "info")
    assert set(infos) == {member.process for member in fleet.values()}
    for part, member in fleet.items():
        info = infos[member.process]
        assert info["name"] == f"line3.{part}" and info["pid"] == member.proc.pid
        assert info["devices"] == PARTS[part]
    press = ctl(broker.url, "info", "--device", "press")
    assert press["pid"] == fleet["cell-b"].proc.pid and press["clock"] == "virtual"


def test_mosquitto_sub_sees_the_retained_announcements(fleet: dict[str, Member], broker: Broker,
                                                       tmp_path: Path) -> None:
    sub = mosquitto("mosquitto_sub", "-p", str(broker.port), "-t", "devsim-fleet/process/+", "-F", "%t %r %p",
                    "-C", "3", "-W", "20", log=tmp_path / "sub.log")
    announcements = {}
    for _ in range(3):
        topic, retained, payload = sub.wait_for("devsim-fleet/").split(" ", 2)
        assert retained == "1"
        announcements[topic] = json.loads(payload)
    sub.stop()
    for part, member in fleet.items():
        body = announcements[f"devsim-fleet/process/{member.process}"]
        assert body["online"] is True and body["part"] == part and body["pid"] == member.proc.pid
        assert body["request"] == f"devsim-fleet/process/{member.process}/request"
        assert [row["name"] for row in body["devices"]] == PARTS[part]


@pytest.mark.parametrize("how", ["json", "mqtt5"])
def test_mosquitto_pub_request_answered(fleet: dict[str, Member], broker: Broker, tmp_path: Path, how: str) -> None:
    """A request from mosquitto_pub: reply topic in the JSON, or as MQTT 5 response topic with
    correlation data; the answer arrives at mosquitto_sub."""
    reply = f"devsim-fleet/client/outsider-{how}/reply"
    sub = mosquitto("mosquitto_sub", "-V", "mqttv5", "-p", str(broker.port), "-t", reply, "-F", "%t %D %p",
                    "-C", "1", "-W", "20", "-d", log=tmp_path / "sub.log")
    sub.wait_for("Subscribed")  # its debug line once the broker acknowledged the subscription
    request = {"id": "o-1", "op": "read", "device": "robot2", "name": "input.I3"}
    args = ["-V", "mqttv5", "-p", str(broker.port), "-t", f"devsim-fleet/process/{fleet['cell-c'].process}/request"]
    if how == "json":
        request["reply_to"] = reply
    else:
        args += ["-D", "publish", "response-topic", reply, "-D", "publish", "correlation-data", "corr-7"]
    pub = mosquitto("mosquitto_pub", *args, "-m", json.dumps(request), log=tmp_path / "pub.log")
    assert pub.proc.wait(20) == 0
    line = sub.wait_for(reply)
    sub.stop()
    _topic, correlation, payload = line.split(" ", 2)
    answer = json.loads(payload)
    assert answer["id"] == "o-1" and answer["ok"] is True and isinstance(answer["result"], bool)
    if how == "mqtt5":
        assert correlation == "corr-7"


def test_a_reply_topic_that_is_no_string_is_not_answered_and_keeps_the_connection(
        fleet: dict[str, Member], broker: Broker, tmp_path: Path) -> None:
    """A ``reply_to`` that is a list or an object names no topic: the request is executed and not
    answered, and the member keeps its connection (it had raised out of the read and dropped it)."""
    member = fleet["cell-c"]
    topic = f"devsim-fleet/process/{member.process}/request"
    for reply_to in (["devsim-fleet/client/x/reply"], {"topic": "devsim-fleet/client/x/reply"}):
        request = {"id": "odd", "op": "read", "device": "robot", "name": "input.I1", "reply_to": reply_to}
        pub = mosquitto("mosquitto_pub", "-p", str(broker.port), "-t", topic, "-m", json.dumps(request),
                        log=tmp_path / "pub.log")
        assert pub.proc.wait(20) == 0
    with FleetClient(broker.url, timeout=20) as client:  # its request arrives after those, on the same connection
        assert isinstance(client.read("robot", "input.I1"), bool)
    assert "lost" not in member.log.read_text()


def test_a_name_already_in_the_fleet_is_refused(fleet: dict[str, Member], broker: Broker, plant_file: Path,
                                                tmp_path: Path) -> None:
    with pytest.raises(AssertionError, match="already in the fleet"):
        Member(["up", str(plant_file), "--part", "cell-a"], broker.url, tmp_path / "clash.log")
    assert "served by " + fleet["cell-a"].process in (tmp_path / "clash.log").read_text()
    assert [r["process"] for r in ctl(broker.url, "devices") if r["name"] == "feeder"] == [fleet["cell-a"].process]


def test_killed_process_goes_offline(tmp_path: Path) -> None:
    """SIGKILL: the broker publishes the last will; every client sees the devices offline (a
    broker of its own, so that the offline mark stays out of the other tests' listings)."""
    broker = Broker().start()
    member = Member(["run", "sers"], broker.url, tmp_path / "run.log")
    try:
        topic = f"devsim-fleet/process/{member.process}"
        sub = mosquitto("mosquitto_sub", "-p", str(broker.port), "-t", topic, "-F", "%p", "-C", "2", "-W", "30",
                        log=tmp_path / "sub.log")
        assert json.loads(sub.wait_for("{"))["online"] is True
        member.proc.kill()
        member.proc.wait(10)
        will = json.loads(sub.wait_for("{"))
        sub.stop()
        assert will["online"] is False and will["pid"] == member.proc.pid
        assert [row["name"] for row in will["devices"]] == ["sers"]
        rows = ctl(broker.url, "devices")
        assert [(row["name"], row["online"], row["process"]) for row in rows] == [("sers", False, member.process)]
        with FleetClient(broker.url) as client, pytest.raises(ControlError) as caught:
            client.read("sers", "input.I1")
        assert caught.value.type == "Offline"
    finally:
        member.stop()
        broker.stop()


def test_part_that_matches_nothing(plant_file: Path) -> None:
    import subprocess

    done = subprocess.run([sys.executable, "-m", "devsim", "up", str(plant_file), "--part", "cell-z"],
                          capture_output=True, text=True, timeout=60)
    assert done.returncode == 2
    assert "no device has part 'cell-z' (parts: cell-a, cell-b, cell-c)" in done.stderr


def test_a_member_announces_again_after_the_broker_restarts(tmp_path: Path) -> None:
    first = Broker().start()
    member = Member(["run", "sers"], first.url, tmp_path / "run.log")
    second = Broker()
    try:
        first.stop()
        second.port = first.port  # the same address, a new broker with no retained messages
        second.start()
        with FleetClient(second.url) as client:
            rows = client.wait_for_devices(["sers"], timeout=30)
            assert [(row["name"], row["process"]) for row in rows] == [("sers", member.process)]
            assert client.read("sers", "input.I1") is False
        assert "reconnecting" in (tmp_path / "run.log").read_text()
    finally:
        member.stop()
        second.stop()
