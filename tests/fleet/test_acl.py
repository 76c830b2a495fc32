"""The ACL docs/fleet.md gives for a shared broker, on a real mosquitto with passwords: devsim
processes read and write their topics, a controller reads and sets, an observer reads and is
refused what would move the machinery."""

from __future__ import annotations

import shutil
import subprocess
import tempfile
from collections.abc import Iterator
from pathlib import Path

import pytest

from tests.fleet.conftest import Member, ctl
from tests.support.broker import Broker
from tests.support.programs import needs_program

#: docs/fleet.md: "devsim processes `readwrite devsim-fleet/#`; who may control them `write
#: devsim-fleet/process/+/request`, `readwrite devsim-fleet/client/#`, `read devsim-fleet/process/+`;
#: observers `readwrite devsim-fleet/client/#` and `read devsim-fleet/process/+`"
ACL = """\
user sim
topic readwrite devsim-fleet/#

user ctrl
topic write devsim-fleet/process/+/request
topic readwrite devsim-fleet/client/#
topic read devsim-fleet/process/+

user obs
topic readwrite devsim-fleet/client/#
topic read devsim-fleet/process/+
"""


@pytest.fixture(scope="module")
def secured(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[Broker, Member]]:
    needs_program("mosquitto_passwd")
    files = Path(tempfile.mkdtemp(prefix="devsim-acl-"))  # (mosquitto started as root reads as user mosquitto)
    files.chmod(0o755)
    (files / "acl").write_text(ACL)
    passwords = files / "passwd"
    for user in ("sim", "ctrl", "obs"):
        subprocess.run(["mosquitto_passwd", "-b", *(["-c"] if user == "sim" else []), str(passwords), user, user + "pw"],
                       check=True, capture_output=True, timeout=30)
    for path in (files / "acl", passwords):
        path.chmod(0o644)
    broker = Broker(f"allow_anonymous false\npassword_file {passwords}\nacl_file {files / 'acl'}").start()
    try:
        member = Member(["run", "sers", "--pty", "--virtual", "--no-control"],
                        f"mqtt://sim:simpw@127.0.0.1:{broker.port}", tmp_path_factory.mktemp("member") / "member.log")
        try:
            yield broker, member
        finally:
            member.stop()
    finally:
        broker.stop()
        shutil.rmtree(files, ignore_errors=True)


def _url(broker: Broker, user: str) -> str:
    return f"mqtt://{user}:{user}pw@127.0.0.1:{broker.port}"


def test_a_controller_reads_and_sets(secured: tuple[Broker, Member]) -> None:
    broker, _member = secured
    assert [row["name"] for row in ctl(_url(broker, "ctrl"), "devices")] == ["sers"]
    ctl(_url(broker, "ctrl"), "set", "sers", "input.I1", "true")
    assert ctl(_url(broker, "ctrl"), "read", "sers", "input.I1") is True


def test_an_observer_lists_the_fleet_and_is_refused_a_set(secured: tuple[Broker, Member]) -> None:
    """(It waited 10 s and said the broker did not answer: the client's sync marker is under
    client/, which the observer line of the ACL did not let it write.)  The request goes out at
    QoS 1, and mosquitto answers the one the ACL refuses with PUBACK reason 0x87 (MQTT 5, 3.4.2.1:
    "Not authorized"): the set is refused at once, saying so, instead of a 10 s timeout."""
    broker, _member = secured
    assert [row["name"] for row in ctl(_url(broker, "obs"), "devices")] == ["sers"]
    refused = ctl(_url(broker, "obs"), "set", "sers", "input.I2", "true", ok=False)
    assert refused.startswith("Error: Refused: the broker refused the request 'set'"), refused
    assert "0x87, not authorized" in refused, refused
    assert ctl(_url(broker, "ctrl"), "read", "sers", "input.I2") is False
