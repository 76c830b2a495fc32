"""Fleet URLs, topic names, the plant file's ``part:`` and what a member answers, without a broker."""

from __future__ import annotations

import json

import pytest

from devsim.core.config import ConfigError
from devsim.fleet.member import FleetMember
from devsim.fleet.topics import FleetUrlError, Topics, parse_fleet_url
from devsim.runtime import Runtime
from devsim.scenario.schema import PlantSpec, load_plant


def test_fleet_urls() -> None:
    url = parse_fleet_url("mqtt://lab:s%40cret@broker.local:1884/line7")
    assert (url.host, url.port, url.fleet, url.username, url.password) == ("broker.local", 1884, "line7", "lab", "s@cret")
    assert url.root == "devsim-fleet/line7" and str(url) == "mqtt://broker.local:1884/line7"
    assert parse_fleet_url("mqtt://10.0.0.5").root == "devsim-fleet"
    assert parse_fleet_url("mqtt://10.0.0.5").port == 1883
    for bad in ("tcp://x", "mqtt://", "mqtt://h:99999", "mqtt://h/a/b", "mqtt://h/#"):
        with pytest.raises(FleetUrlError):
            parse_fleet_url(bad)


def test_topics() -> None:
    topics = Topics("devsim-fleet")
    assert topics.process_of(topics.announcement("h-1")) == "h-1"
    assert topics.process_of(topics.request("h-1")) is None
    assert topics.process_of("devsim-fleetX/process/h-1") is None


def test_parts_of_a_plant(tmp_path) -> None:  # type: ignore[no-untyped-def]
    spec = PlantSpec.parse({
        "devices": [{"name": "a", "kind": "sers", "part": "p1"}, {"name": "b", "kind": "sers", "part": "p2"},
                    {"name": "c", "kind": "sers", "part": "p1", "transport": {"bus": "line"}}],
        "buses": [{"name": "line"}, {"name": "other"}],
    })
    one = spec.only_part("p1")
    assert [d.name for d in one.devices] == ["a", "c"] and [b.name for b in one.buses] == ["line"]
    with pytest.raises(ValueError, match=r"no device has part 'p3' \(parts: p1, p2\)"):
        spec.only_part("p3")
    path = tmp_path / "plant.yaml"
    path.write_text("devices:\n  - {name: a, kind: sers, part: p1, transport: {bus: l}}\n"
                    "  - {name: b, kind: sers, part: p2, transport: {bus: l}}\nbuses:\n  - {name: l}\n")
    with pytest.raises(ConfigError, match="bus 'l' has devices of different parts"):
        load_plant(path)


def test_a_member_answers_with_the_control_api_and_only_to_client_topics() -> None:
    runtime = Runtime(virtual=True).start()
    try:
        runtime.add_device("sers", "s1", {})
        member = FleetMember(runtime, parse_fleet_url("mqtt://127.0.0.1"), process="h-1")
        request = {"id": 7, "op": "read", "device": "s1", "name": "input.I1", "reply_to": "devsim-fleet/client/c/reply"}
        answer = runtime.call(member.answer, json.dumps(request).encode())
        assert answer is not None
        topic, payload, _ = answer
        assert topic == "devsim-fleet/client/c/reply"
        assert json.loads(payload) == {"id": 7, "ok": True, "result": False}
        bad = runtime.call(member.answer, b'{"id": 8, "op": "jump", "reply_to": "devsim-fleet/client/c/reply"}')
        assert bad is not None and json.loads(bad[1])["type"] == "BadRequest"
        for reply_to in ("devsim-fleet/process/h-2", "elsewhere/x", "devsim-fleet/client/+/reply", None):
            request["reply_to"] = reply_to
            assert runtime.call(member.answer, json.dumps(request).encode()) is None
        request.pop("reply_to")
        request.update(op="set", name="input.I1", value=True)
        assert runtime.call(member.answer, json.dumps(request).encode()) is None  # executed, not answered
        assert runtime.read("s1", "input.I1") is True
    finally:
        runtime.stop()


def test_a_clash_is_listed_and_refused_and_offline_rows_give_way() -> None:
    from devsim.fleet.client import AsyncFleetClient
    from devsim.runtime.client import ControlError

    client = AsyncFleetClient("mqtt://127.0.0.1")
    row = {"name": "x", "kind": "sers"}
    client.processes = {
        "h-1-aaaa": {"host": "h", "pid": 1, "online": True, "devices": [row]},
        "g-2-bbbb": {"host": "g", "pid": 2, "online": True, "devices": [row, {"name": "y", "kind": "sers"}]},
        "f-3-cccc": {"host": "f", "pid": 3, "online": False, "devices": [row, {"name": "z", "kind": "sers"}]},
    }
    rows = client.devices()
    assert [(r["name"], r["process"], r.get("clash", False), r["online"]) for r in rows] == [
        ("x", "g-2-bbbb", True, True), ("x", "h-1-aaaa", True, True), ("y", "g-2-bbbb", False, True),
        ("z", "f-3-cccc", False, False)]  # the offline 'x' gives way to the online ones
    with pytest.raises(ControlError, match="served by 2 processes") as caught:
        client.serving("x")
    assert caught.value.type == "FleetClash"
    assert client.serving("y") == "g-2-bbbb"
    with pytest.raises(ControlError, match="offline"):
        client.serving("z")


def test_ctl_without_a_broker_says_so_in_one_line() -> None:
    import subprocess
    import sys

    from tests.support.process import free_port

    done = subprocess.run([sys.executable, "-m", "devsim", "ctl", "--fleet", f"mqtt://127.0.0.1:{free_port()}",
                           "devices"], capture_output=True, text=True, timeout=60)
    assert done.returncode == 5  # devsim.cli.exits.UNREACHABLE
    assert done.stderr.startswith("Error: cannot connect to mqtt://127.0.0.1:") and "cannot reach the fleet broker" in done.stderr
    assert len(done.stderr.strip().splitlines()) == 1
