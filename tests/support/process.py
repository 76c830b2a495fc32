"""``python -m devsim ARGS`` as a subprocess for tests: its stdout and stderr lines collected by
threads into queues, every wait bounded (the live and the record/replay tests); its environment;
a free loopback port."""

from __future__ import annotations

import os
import queue
import signal
import socket
import subprocess
import sys
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import IO

__all__ = ["DevsimProcess", "ROOT", "devsim_env", "free_port"]

ROOT = Path(__file__).resolve().parents[2]


def devsim_env() -> dict[str, str]:
    """The environment with this checkout first on the import path."""
    environ = dict(os.environ)
    environ["PYTHONPATH"] = os.pathsep.join(p for p in (str(ROOT), environ.get("PYTHONPATH", "")) if p)
    return environ


def free_port() -> int:
    """A TCP port on 127.0.0.1 that nobody holds now."""
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return int(sock.getsockname()[1])


class DevsimProcess:
    """``python -m devsim ARGS`` with its output lines in ``out`` and ``err`` (None ends each)."""

    def __init__(self, *args: str) -> None:
        self.proc = subprocess.Popen([sys.executable, "-m", "devsim", *args], cwd=ROOT, env=devsim_env(),
                                     stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                     text=True)
        self.out: queue.Queue[str | None] = queue.Queue()
        self.err: queue.Queue[str | None] = queue.Queue()
        for stream, into in ((self.proc.stdout, self.out), (self.proc.stderr, self.err)):
            threading.Thread(target=self._pump, args=(stream, into), daemon=True).start()

    @staticmethod
    def _pump(stream: IO[str] | None, into: queue.Queue[str | None]) -> None:
        assert stream is not None
        for line in stream:
            into.put(line.rstrip("\n"))
        into.put(None)

    def next_match(self, lines: queue.Queue[str | None], accept: Callable[[str], bool], timeout: float,
                   what: str, keep: list[str] | None = None) -> str:
        """The first line of ``lines`` that ``accept`` takes (the ones before it dropped, or
        appended to ``keep``); an AssertionError naming ``what`` after ``timeout`` or at the end."""
        deadline = time.monotonic() + timeout
        while True:
            try:
                line = lines.get(timeout=max(0.01, deadline - time.monotonic()))
            except queue.Empty:
                raise AssertionError(f"no {what} within {timeout} s") from None
            if line is None:
                raise AssertionError(f"the process ended (status {self.proc.wait()}) before {what}")
            if keep is not None:
                keep.append(line)
            if accept(line):
                return line

    def interrupt(self) -> int:
        """SIGINT and a bounded wait (then SIGKILL); the exit status."""
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGINT)
        try:
            return self.proc.wait(timeout=15)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            return self.proc.wait()
