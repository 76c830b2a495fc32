"""A `devsim run` subprocess for the live tests: stdout and stderr lines collected by threads,
waits bounded."""

from __future__ import annotations

import os
import queue
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def env() -> dict[str, str]:
    environ = dict(os.environ)
    environ["PYTHONPATH"] = os.pathsep.join(p for p in (str(ROOT), environ.get("PYTHONPATH", "")) if p)
    return environ


class Proc:
    """``python -m devsim ARGS`` with its output lines in two queues."""

    def __init__(self, *args: str) -> None:
        self.proc = subprocess.Popen([sys.executable, "-m", "devsim", *args], cwd=ROOT, env=env(),
                                     stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                     text=True)
        self.out: queue.Queue[str | None] = queue.Queue()
        self.err: queue.Queue[str | None] = queue.Queue()
        for stream, into in ((self.proc.stdout, self.out), (self.proc.stderr, self.err)):
            threading.Thread(target=self._pump, args=(stream, into), daemon=True).start()

    @staticmethod
    def _pump(stream: object, into: queue.Queue[str | None]) -> None:
        for line in stream:  # type: ignore[attr-defined]
            into.put(line.rstrip("\n"))
        into.put(None)

    def expect(self, predicate: object, *, err: bool = False, timeout: float = 15.0) -> str:
        """The first line (of stdout, or stderr) that ``predicate`` accepts; the lines before it
        are dropped."""
        lines = self.err if err else self.out
        deadline = time.monotonic() + timeout
        while True:
            try:
                line = lines.get(timeout=max(0.01, deadline - time.monotonic()))
            except queue.Empty:
                raise AssertionError(f"no such line within {timeout} s") from None
            if line is None:
                raise AssertionError(f"the process ended (status {self.proc.wait()})")
            if predicate(line):  # type: ignore[operator]
                return line

    def stop(self) -> int:
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGINT)
        try:
            return self.proc.wait(timeout=15)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            return self.proc.wait()


def ctl(addr: str, *args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "devsim", "ctl", "--control", addr, *args], cwd=ROOT, env=env(),
                          capture_output=True, text=True, timeout=30, stdin=subprocess.DEVNULL)
