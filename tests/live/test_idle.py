"""An idle simulator uses no CPU (design principle; issue 31): once `devsim run` is ready and
nobody talks to it, its process does not wake up at all -- no timer of its own, its log's
included (the log's repeat counter used to tick once a second)."""

from __future__ import annotations

import time
from pathlib import Path

from tests.support.process import DevsimProcess, wait_until


def _wake_ups(pid: int) -> int:
    """How often the process has gone to sleep and been woken (Linux: its voluntary switches)."""
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("voluntary_ctxt_switches:"):
            return int(line.split()[1])
    raise AssertionError("no voluntary_ctxt_switches in /proc/PID/status")


def test_an_idle_simulator_does_not_wake_up() -> None:
    sim = DevsimProcess("run", "sers")
    try:
        sim.next_match(sim.out, lambda text: text == "sers: ready", 30, "sers: ready")
        wchan = Path(f"/proc/{sim.proc.pid}/wchan")
        wait_until(lambda: "epoll" in wchan.read_text(), "the loop waiting in epoll", 10)  # (done printing)
        before = _wake_ups(sim.proc.pid)
        time.sleep(3.0)  # (the interval observed, not a wait for something: nothing is to happen)
        assert _wake_ups(sim.proc.pid) == before
    finally:
        sim.interrupt()
