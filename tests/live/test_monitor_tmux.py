"""`devsim monitor` in a real terminal: tmux runs it against a `devsim run` subprocess; keys go
in with send-keys, the screen comes back with capture-pane."""

from __future__ import annotations

import shlex
import subprocess
import sys
import time
import uuid
from pathlib import Path

from tests.support.programs import needs_program

from .run import ROOT, Proc, ctl, env


def _tmux(*args: str) -> str:
    return subprocess.run(["tmux", *args], capture_output=True, text=True, timeout=10, check=True).stdout


def _screen_until(session: str, needle: str, timeout: float = 20.0) -> str:
    deadline = time.monotonic() + timeout
    while True:
        screen = _tmux("capture-pane", "-p", "-t", session)
        if needle in screen:
            return screen
        if time.monotonic() > deadline:
            raise AssertionError(f"{needle!r} not on the screen:\n{screen}")
        time.sleep(0.1)  # polling the screen (bounded by the deadline), not a synchronisation sleep


def test_monitor_in_tmux(tmp_path: Path) -> None:
    needs_program("tmux")
    sim = Proc("run", "sers", "--tcp", "0", "--virtual", "--control", f"unix:{tmp_path}/ctl.sock")
    session = f"devsim-{uuid.uuid4().hex[:8]}"
    try:
        addr = sim.expect(lambda line: line.startswith("control: ")).split()[-1]
        ctl(addr, "advance", "3")
        environ = env()
        command = " ".join(shlex.quote(part) for part in (
            "env", f"PYTHONPATH={environ['PYTHONPATH']}", "TERM=xterm-256color",
            sys.executable, "-m", "devsim", "monitor", "--control", addr))
        _tmux("new-session", "-d", "-s", session, "-x", "160", "-y", "50", "-c", str(ROOT), command)
        screen = _screen_until(session, "axis: pos 0.0")
        assert "sers (sers)" in screen and "faults: none" in screen
        _tmux("send-keys", "-t", session, "a")  # advance 0.1 s of virtual time
        deadline = time.monotonic() + 20
        while float(ctl(addr, "now").stdout) < 3.1:
            assert time.monotonic() < deadline, "the 'a' key did not advance time"
        _tmux("send-keys", "-t", session, "f")
        _screen_until(session, "sers: blocked_axis on")
        _tmux("send-keys", "-t", session, "Enter")  # the first entry: blocked_axis on
        _screen_until(session, "faults: blocked_axis")
        _tmux("send-keys", "-t", session, "q")
        deadline = time.monotonic() + 20
        while session in subprocess.run(["tmux", "ls"], capture_output=True, text=True).stdout:
            assert time.monotonic() < deadline, "q did not end the monitor"
            time.sleep(0.1)
    finally:
        subprocess.run(["tmux", "kill-session", "-t", session], capture_output=True)
        sim.stop()
