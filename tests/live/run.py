"""A `devsim run` subprocess for the live tests: stdout and stderr lines collected by threads,
waits bounded."""

from __future__ import annotations

import subprocess
import sys
from collections.abc import Callable

from tests.support.process import ROOT, DevsimProcess, devsim_env


def env() -> dict[str, str]:
    return devsim_env()


class Proc(DevsimProcess):
    """``python -m devsim ARGS`` with its output lines in two queues."""

    def expect(self, predicate: Callable[[str], bool], *, err: bool = False, timeout: float = 15.0) -> str:
        """The first line (of stdout, or stderr) that ``predicate`` accepts; the lines before it
        are dropped."""
        return self.next_match(self.err if err else self.out, predicate, timeout, "such line")

    def stop(self) -> int:
        return self.interrupt()


def ctl(addr: str, *args: str) -> subprocess.CompletedProcess[str]:
    """``devsim ctl --control ADDR --json ARGS`` (the JSON for scripts)."""
    return subprocess.run([sys.executable, "-m", "devsim", "ctl", "--control", addr, "--json", *args], cwd=ROOT, env=env(),
                          capture_output=True, text=True, timeout=30, stdin=subprocess.DEVNULL)
