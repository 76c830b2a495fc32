"""A member that stops cleanly leaves the fleet: its retained announcement is cleared (not
marked offline by its last will), so a client that joins afterwards does not list it at all."""

from __future__ import annotations

from pathlib import Path

from devsim.fleet.client import FleetClient
from tests.fleet.conftest import Member
from tests.support.broker import Broker


def test_a_clean_stop_removes_the_process_from_the_listing(broker: Broker, plant_file: Path, tmp_path: Path) -> None:
    member = Member(["up", str(plant_file), "--part", "cell-c"], broker.url, tmp_path / "c.log")
    try:
        with FleetClient(broker.url) as client:
            rows = client.wait_for_devices(["robot", "robot2"], timeout=20)
            assert {row["process"] for row in rows} == {member.process}
    finally:
        member.stop()
    assert member.proc.returncode == 0, member.log.read_text()
    with FleetClient(broker.url) as later:  # it takes every retained announcement before it returns
        assert later.devices() == []
        assert member.process not in later.fleet.processes
