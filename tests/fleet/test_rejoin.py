"""A member that comes back after losing the broker checks its names again, as it does when it
joins: while it was away its devices were offline, and a replacement may have joined serving one
of them.  It withdraws that name (says so on stderr) instead of clashing with the replacement."""

from __future__ import annotations

import json
import os
import signal
from pathlib import Path

from devsim.fleet.client import FleetClient
from tests.fleet.conftest import Member, ctl, mosquitto
from tests.support.broker import Broker
from tests.support.process import wait_until


def test_a_member_back_from_a_lost_broker_withdraws_a_name_a_replacement_serves(
        plant_file: Path, tmp_path: Path) -> None:
    first = Broker().start()
    old = Member(["up", str(plant_file), "--part", "cell-c", "--virtual"], first.url, tmp_path / "old.log")
    second = Broker()
    replacement: Member | None = None
    try:
        os.kill(old.proc.pid, signal.SIGSTOP)  # frozen (a laptop asleep): it misses the broker going away
        first.stop()  # its connection is gone; the new broker has no announcement of it
        second.port = first.port
        second.start()
        robot_only = tmp_path / "robot.yaml"
        robot_only.write_text("devices:\n  - {name: robot, kind: sers}\n")
        replacement = Member(["up", str(robot_only), "--virtual"], second.url, tmp_path / "replacement.log")
        os.kill(old.proc.pid, signal.SIGCONT)  # it finds the connection lost and rejoins
        with FleetClient(second.url) as fleet:
            fleet.wait_for_devices(["robot2"], timeout=30)  # the old one's new announcement is in
        rows = ctl(second.url, "devices")
        assert {(row["name"], row["process"]) for row in rows} == {("robot", replacement.process),
                                                                   ("robot2", old.process)}
        assert not any(row.get("clash") for row in rows) and all(row["online"] for row in rows)
        assert ctl(second.url, "read", "robot", "input.I3") is False  # not refused as a clash
        ctl(second.url, "set", "robot2", "input.I3", "on")
        assert ctl(second.url, "read", "robot2", "input.I3") is True

        def rejoined() -> list[str]:
            return [line for line in old.log.read_text().splitlines() if " back; " in line]

        wait_until(lambda: bool(rejoined()), "the rejoining line on the old member's stderr", timeout=15)
        line = rejoined()[0]
        assert line.startswith(f"devsim: fleet broker {second.url} back; announced again without 'robot': ")
        assert replacement.process in line and "robot2" not in line
        assert old.proc.poll() is None and replacement.proc.poll() is None  # both serve on
        # a request for the withdrawn name sent to the old process anyway (by hand) is refused
        reply = "devsim-fleet/client/by-hand/reply"
        sub = mosquitto("mosquitto_sub", "-p", str(second.port), "-t", reply, "-C", "1", "-W", "20", "-d",
                        log=tmp_path / "sub.log")
        sub.wait_for("Subscribed")
        request = {"id": "h-1", "op": "read", "device": "robot", "name": "input.I3", "reply_to": reply}
        pub = mosquitto("mosquitto_pub", "-p", str(second.port), "-t", f"devsim-fleet/process/{old.process}/request",
                        "-m", json.dumps(request), log=tmp_path / "pub.log")
        assert pub.proc.wait(20) == 0
        answer = json.loads(sub.wait_for("{"))
        sub.stop()
        pub.stop()
        assert (answer["id"], answer["ok"], answer["type"]) == ("h-1", False, "FleetClash")
        assert answer["error"].startswith(f"device 'robot' of {old.process} is out of the fleet: {replacement.process}")
    finally:
        if old.proc.poll() is None:
            os.kill(old.proc.pid, signal.SIGCONT)
        old.stop()
        if replacement is not None:
            replacement.stop()
        second.stop()
        first.stop()
