"""A real terminal for the live tests: tmux runs a command in a detached session, keys go in with
send-keys, the screen comes back with capture-pane; every wait is bounded."""

from __future__ import annotations

import shlex
import subprocess
import time
import uuid
from collections.abc import Iterator, Sequence
from contextlib import contextmanager

from tests.support.programs import needs_program

from .run import ROOT, env


def tmux(*args: str) -> str:
    return subprocess.run(["tmux", *args], capture_output=True, text=True, timeout=10, check=True).stdout


def screen_until(session: str, needle: str, timeout: float = 20.0) -> str:
    """The screen of ``session`` once ``needle`` is on it (an AssertionError with the screen after ``timeout``)."""
    deadline = time.monotonic() + timeout
    while True:
        screen = tmux("capture-pane", "-p", "-t", session)
        if needle in screen:
            return screen
        if time.monotonic() > deadline:
            raise AssertionError(f"{needle!r} not on the screen:\n{screen}")
        time.sleep(0.1)  # polling the screen (bounded by the deadline), not a synchronisation sleep


@contextmanager
def terminal(command: Sequence[str], *, width: int = 160, height: int = 50) -> Iterator[str]:
    """``command`` in a new tmux session (this checkout on its import path, a UTF-8 xterm); yields
    the session's name and kills the session at the end.  Skipped where tmux is missing (a
    failure under CI: :func:`tests.support.programs.needs_program`)."""
    needs_program("tmux")
    environ = env()
    line = " ".join(shlex.quote(part) for part in (
        "env", f"PYTHONPATH={environ['PYTHONPATH']}", "TERM=xterm-256color", "LANG=C.UTF-8", *command))
    session = f"devsim-{uuid.uuid4().hex[:8]}"
    tmux("-u", "new-session", "-d", "-s", session, "-x", str(width), "-y", str(height), "-c", str(ROOT), line)
    try:
        yield session
    finally:
        subprocess.run(["tmux", "kill-session", "-t", session], capture_output=True)
