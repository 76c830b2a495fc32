"""Fixtures of the fleet tests: a real mosquitto (tests/support/broker.py), devsim processes and
mosquitto's own clients as subprocesses, every wait bounded."""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import sys
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import pytest

from tests.support.broker import Broker, _program
from tests.support.process import OutputEnded, collect_lines, devsim_env, next_match
from tests.support.process import stop as stop_process

ROOT = Path(__file__).resolve().parents[2]

PLANT = """\
name: line3
devices:
  - {name: feeder, kind: sers, part: cell-a}
  - {name: press, kind: gms96, part: cell-b}
  - {name: robot, kind: sers, part: cell-c}
  - {name: robot2, kind: sers, part: cell-c}
  - {name: spare, kind: sers}
"""


class Program:
    """A subprocess whose stdout lines are collected by a thread; stderr goes to a file."""

    def __init__(self, args: list[str], log: Path) -> None:
        self.log = log
        self._err = log.open("w")
        self.proc = subprocess.Popen(args, cwd=ROOT, env=devsim_env(), stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                                     stderr=self._err, text=True)
        self.lines = collect_lines(self.proc.stdout)
        self.seen: list[str] = []

    def wait_for(self, prefix: str, timeout: float = 30.0) -> str:
        """The first stdout line (from now on) starting with ``prefix``; fails after ``timeout``."""
        try:
            return next_match(self.lines, lambda line: line.startswith(prefix), timeout, f"line {prefix!r}",
                              keep=self.seen)
        except AssertionError as exc:
            ended = f" (status {self.proc.wait(5)})" if isinstance(exc, OutputEnded) else ""
            raise AssertionError(f"{self.proc.args}: {exc}{ended}; got {self.seen}; "
                                 f"stderr: {self.log.read_text()[-2000:]}") from None

    def stop(self) -> None:
        stop_process(self.proc)
        self._err.close()


class Member(Program):
    """``devsim run|up ... --fleet URL``, started and announced (its ``fleet:`` line seen)."""

    def __init__(self, args: list[str], url: str, log: Path) -> None:
        super().__init__([sys.executable, "-m", "devsim", *args, "--fleet", url], log)
        self.process = self.wait_for("fleet: ").rsplit(" as ", 1)[1]


@contextmanager
def two_members(url: str, plant_file: Path, tmp_path: Path,
                via: dict[str, str] | None = None) -> Iterator[dict[str, Member]]:
    """feeder (sers, part cell-a) in one process, press (gms96, cell-b) in another, both on
    virtual time (nothing changes unless asked), members of the fleet at ``url`` (a part in
    ``via`` connects to the broker by the URL given there: a relay, tests/support/relay.py);
    stopped after, a frozen one continued first (SIGSTOP'd, it would not stop)."""
    started: dict[str, Member] = {}
    try:
        for part in ("cell-a", "cell-b"):
            started[part] = Member(["up", str(plant_file), "--part", part, "--virtual"], (via or {}).get(part, url),
                                   tmp_path / f"{part}.log")
        yield started
    finally:
        for member in started.values():
            if member.proc.poll() is None:
                os.kill(member.proc.pid, signal.SIGCONT)
            member.stop()


def ctl(url: str, *args: str, ok: bool = True) -> Any:
    """``devsim ctl --fleet URL --json ARGS``: its JSON (ok) or its stderr (not ok)."""
    done = subprocess.run([sys.executable, "-m", "devsim", "ctl", "--fleet", url, "--json", *args], cwd=ROOT,
                          env=devsim_env(), capture_output=True, text=True, timeout=60)
    if ok:
        assert done.returncode == 0, done.stderr
        return json.loads(done.stdout)
    assert done.returncode != 0, done.stdout
    return done.stderr.strip()


def mosquitto(name: str, *args: str, log: Path) -> Program:
    """mosquitto_sub / mosquitto_pub: MQTT clients nobody on this project wrote.  Line-buffered
    (``stdbuf -oL``): mosquitto_sub flushes its messages but not its ``-d`` lines, and
    ``Subscribed`` is how a test knows the subscription is in place."""
    stdbuf = shutil.which("stdbuf")
    return Program([*([stdbuf, "-oL"] if stdbuf else []), _program(name), *args], log)


@pytest.fixture(scope="module")
def broker() -> Iterator[Broker]:
    server = Broker().start()
    yield server
    server.stop()


@pytest.fixture(scope="module")
def plant_file(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("fleet") / "line3.yaml"
    path.write_text(PLANT)
    return path
