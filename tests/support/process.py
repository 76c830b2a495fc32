"""Subprocesses for tests: ``python -m devsim ARGS`` with its stdout and stderr lines collected by
threads into queues (:class:`DevsimProcess`), the same for any program's lines
(:func:`collect_lines`, :func:`next_match`, every wait bounded), a bounded stop; the environment
that runs this checkout; a free loopback port."""

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
from typing import IO, Any

__all__ = ["ROOT", "DevsimProcess", "OutputEnded", "collect_lines", "devsim_env", "free_port", "next_match", "stop"]

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


def collect_lines(stream: IO[str] | None) -> queue.Queue[str | None]:
    """A queue a thread fills with ``stream``'s lines (None at its end)."""
    lines: queue.Queue[str | None] = queue.Queue()

    def pump() -> None:
        assert stream is not None
        for line in stream:
            lines.put(line.rstrip("\n"))
        lines.put(None)

    threading.Thread(target=pump, daemon=True).start()
    return lines


def wait_until(predicate: Callable[[], bool], what: str, timeout: float = 5.0, step: float = 0.01) -> None:
    """Ask ``predicate`` every ``step`` seconds until it holds; an AssertionError naming ``what``
    after ``timeout``.  For state another process or thread holds and announces nowhere (a
    line's counters, a file being written): where an event or a line says it, wait for that."""
    deadline = time.monotonic() + timeout
    while not predicate():
        assert time.monotonic() < deadline, f"no {what} within {timeout} s"
        time.sleep(step)


class OutputEnded(AssertionError):
    """The lines ended before the one waited for."""


def next_match(lines: queue.Queue[str | None], accept: Callable[[str], bool], timeout: float, what: str,
               keep: list[str] | None = None) -> str:
    """The first line of ``lines`` that ``accept`` takes (the ones before it dropped, or appended
    to ``keep``); an AssertionError naming ``what`` after ``timeout``, :class:`OutputEnded` at
    the end of the lines."""
    deadline = time.monotonic() + timeout
    while True:
        try:
            line = lines.get(timeout=max(0.01, deadline - time.monotonic()))
        except queue.Empty:
            raise AssertionError(f"no {what} within {timeout} s") from None
        if line is None:
            raise OutputEnded(f"the output ended before {what}")
        if keep is not None:
            keep.append(line)
        if accept(line):
            return line


def stop(proc: subprocess.Popen[Any], sig: int = signal.SIGTERM, timeout: float = 10.0) -> int:
    """``sig`` to ``proc`` (if it runs) and a bounded wait, then SIGKILL; the exit status."""
    if proc.poll() is None:
        proc.send_signal(sig)
    try:
        return proc.wait(timeout=timeout)
    except subprocess.TimeoutExpired:
        proc.kill()
        return proc.wait()


class DevsimProcess:
    """``python -m devsim ARGS`` with its output lines in ``out`` and ``err`` (None ends each)."""

    def __init__(self, *args: str) -> None:
        self.proc = subprocess.Popen([sys.executable, "-m", "devsim", *args], cwd=ROOT, env=devsim_env(),
                                     stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                     text=True)
        self.out = collect_lines(self.proc.stdout)
        self.err = collect_lines(self.proc.stderr)

    def next_match(self, lines: queue.Queue[str | None], accept: Callable[[str], bool], timeout: float,
                   what: str, keep: list[str] | None = None) -> str:
        """:func:`next_match`, the end of the lines said as the end of the process."""
        try:
            return next_match(lines, accept, timeout, what, keep)
        except OutputEnded:
            raise AssertionError(f"the process ended (status {self.proc.wait()}) before {what}") from None

    def interrupt(self) -> int:
        """SIGINT and a bounded wait (then SIGKILL); the exit status."""
        return stop(self.proc, signal.SIGINT, 15)

    def rest_of_err(self, timeout: float = 10.0) -> list[str]:
        """The stderr lines not taken yet, up to its end (the process stopped: ``timeout`` bounds
        the wait for each line)."""
        lines: list[str] = []
        while (text := self.err.get(timeout=timeout)) is not None:
            lines.append(text)
        return lines
