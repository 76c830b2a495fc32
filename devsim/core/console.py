"""The lines a serving process prints for whoever started it: ports, ``ready``, its log.

A simulator keeps serving when the reader of its output goes away: a supervisor that closed the
pipe after the port line, ``devsim run sers --pty | head -1``, a terminal that is gone.  Python
ignores SIGPIPE, so such a write raises (``BrokenPipeError``, ``EIO``) in the code that printed,
which may be a device announcing ``ready`` in the middle of its power-on (the rest of the
power-on would not run) or a log line from inside a model's step.  :func:`say` catches that,
and points the stream's descriptor at the null device: later lines, and the interpreter's own
flush at exit (which would otherwise end the process with status 120), go nowhere.
"""

from __future__ import annotations

import os
import sys
from typing import TextIO

__all__ = ["say", "warn"]


def say(line: str, stream: TextIO | None = None) -> None:
    """Print ``line`` to ``stream`` (default stdout) and flush; a stream nobody reads any more
    is handed to the null device and the line is dropped."""
    out = sys.stdout if stream is None else stream
    try:
        print(line, file=out, flush=True)
    except BlockingIOError:  # a full pipe set non-blocking by someone: the reader is slow, not gone
        pass  # (what did not fit waits in the stream's buffer, or is dropped: the loop must not wait)
    except OSError:  # (BrokenPipeError: the reader has gone; EIO: its terminal has)
        _to_null(out)


def warn(line: str) -> None:
    """:func:`say` on stderr."""
    say(line, sys.stderr)


def _to_null(stream: TextIO) -> None:
    try:
        fd = stream.fileno()
    except (OSError, ValueError):  # (a stream without a descriptor: nothing to point elsewhere)
        return
    null = os.open(os.devnull, os.O_WRONLY)
    try:
        os.dup2(null, fd)
    finally:
        os.close(null)
