"""Two mosquitto brokers joined by a mosquitto bridge (``topic devsim-fleet/# both 0``), a devsim
process on each side: each side's clients see and reach both, and a process killed on one side
goes offline on the other."""

from __future__ import annotations

import json
from collections.abc import Iterator
from pathlib import Path

import pytest

from devsim.fleet.client import FleetClient
from tests.fleet.conftest import Member, mosquitto
from tests.support.broker import Broker


@pytest.fixture
def brokers() -> Iterator[tuple[Broker, Broker]]:
    near = Broker().start()
    far = Broker(extra=f"connection to-near\naddress 127.0.0.1:{near.port}\ntopic devsim-fleet/# both 0\n")
    try:
        far.start()
        yield near, far
    finally:
        far.stop()
        near.stop()


def test_processes_on_both_sides_of_a_bridge_see_each_other(brokers: tuple[Broker, Broker], plant_file: Path,
                                                           tmp_path: Path) -> None:
    near, far = brokers
    on_near = Member(["up", str(plant_file), "--part", "cell-a"], near.url, tmp_path / "a.log")
    on_far = Member(["up", str(plant_file), "--part", "cell-c"], far.url, tmp_path / "c.log")
    try:
        with FleetClient(near.url) as here, FleetClient(far.url) as there:
            for client in (here, there):  # the bridge carries the announcements both ways
                rows = client.wait_for_devices(["feeder", "robot", "robot2"], timeout=20)
                assert {row["name"]: row["process"] for row in rows} == {
                    "feeder": on_near.process, "robot": on_far.process, "robot2": on_far.process}
            here.set("robot", "input.I5", True)  # near → bridge → far's process, and the answer back
            assert there.read("robot", "input.I5") is True
            there.fault("feeder", "emergency_stop", True)
            assert here.read("feeder", "input.stop") is True

            # an independent client on the near broker sees the far process's last will
            topic = f"devsim-fleet/process/{on_far.process}"
            sub = mosquitto("mosquitto_sub", "-p", str(near.port), "-t", topic, "-F", "%p", "-C", "2", "-W", "30",
                            log=tmp_path / "sub.log")
            assert json.loads(sub.wait_for("{"))["online"] is True
            on_far.proc.kill()
            on_far.proc.wait(10)
            assert json.loads(sub.wait_for("{"))["online"] is False
            sub.stop()
            rows = here.wait_for_devices(["robot", "robot2"], timeout=10, online=False)
            assert {row["name"] for row in rows if not row["online"]} == {"robot", "robot2"}
            assert here.read("feeder", "input.stop") is True
    finally:
        on_far.stop()
        on_near.stop()
