"""A serving process's face to whoever started it: the lines it prints (ports, ``ready``, its
log) and the signals that stop it.

A simulator keeps serving when the reader of its output goes away: a supervisor that closed the
pipe after the port line, ``devsim run sers --pty | head -1``, a terminal that is gone.  Python
ignores SIGPIPE, so such a write raises (``BrokenPipeError``, ``EIO``) in the code that printed,
which may be a device announcing ``ready`` in the middle of its power-on (the rest of the
power-on would not run) or a log line from inside a model's step.  :func:`say` catches that,
and points the stream's descriptor at the null device: later lines, and the interpreter's own
flush at exit, go nowhere.

Nor does a simulator wait for a reader that is there but does not read: a harness that started it
with ``stderr=PIPE`` and never reads the pipe, a terminal stopped with Ctrl-S.  A write into a full
pipe blocks, and the whole simulator with it, in the middle of a line from inside the model (with
``-v`` every telegram is logged: a pipe's 64 KiB were full after about 400 SERS requests, the host
got no answer after that, and SIGTERM could not stop the process).  So :func:`say` first asks the
descriptor whether it takes a line now (``poll``); a line it would not take is dropped and counted,
and the next line that goes out says how many were lost before it.

:func:`stop_on_signals`: Ctrl-C (SIGINT), SIGTERM and SIGHUP (the terminal that started it has
closed) stop a serving process the same clean way: its motion log gets its last rows, its
control socket is removed.  Under ``nohup`` (SIGHUP ignored) the terminal's end is ignored still.
"""

from __future__ import annotations

import asyncio
import os
import select
import signal
import sys
from collections.abc import Callable
from typing import TextIO

__all__ = ["say", "stop_on_signals", "to_null", "warn"]


#: Lines dropped since the last that went out, per descriptor (a reader that did not read).
_dropped: dict[int, int] = {}


def say(line: str, stream: TextIO | None = None) -> None:
    """Print ``line`` to ``stream`` (default stdout) and flush; a stream nobody reads any more
    is handed to the null device and the line is dropped, and so is a line a full pipe or a
    stopped terminal would not take now (the next line that goes out counts them)."""
    out = sys.stdout if stream is None else stream
    fd = _descriptor(out)
    if fd is not None:
        if not _takes_a_line(fd):
            _dropped[fd] = _dropped.get(fd, 0) + 1
            return
        lost = _dropped.pop(fd, 0)
        if lost:
            line = f"devsim: {lost} line{'' if lost == 1 else 's'} of output dropped here: nobody read them\n{line}"
    try:
        print(line, file=out, flush=True)
    except BlockingIOError:  # a full pipe set non-blocking by someone: the reader is slow, not gone
        pass  # (what did not fit waits in the stream's buffer, or is dropped: the loop must not wait)
    except OSError:  # (BrokenPipeError: the reader has gone; EIO: its terminal has)
        to_null(out)


def _descriptor(stream: TextIO) -> int | None:
    try:
        return stream.fileno()
    except (OSError, ValueError):  # (a stream without a descriptor, or closed: print decides)
        return None


def _takes_a_line(fd: int) -> bool:
    """Whether a write to ``fd`` would not block now (a pipe with a free page, a terminal not
    stopped, any file); an error or hang-up counts as taking it: the write then says which."""
    poller = select.poll()
    poller.register(fd, select.POLLOUT)
    return bool(poller.poll(0))


def warn(line: str) -> None:
    """:func:`say` on stderr."""
    say(line, sys.stderr)


def to_null(stream: TextIO) -> None:
    """Point ``stream``'s descriptor at the null device (Python's recipe for a reader gone)."""
    try:
        fd = stream.fileno()
    except (OSError, ValueError):  # (a stream without a descriptor: nothing to point elsewhere)
        return
    null = os.open(os.devnull, os.O_WRONLY)
    try:
        os.dup2(null, fd)
    finally:
        os.close(null)


def stop_on_signals(loop: asyncio.AbstractEventLoop, stop: Callable[[], object]) -> Callable[[], None]:
    """Call ``stop`` in ``loop`` on SIGINT, SIGTERM and SIGHUP (not SIGHUP where it is ignored, as
    ``nohup`` does); returns what removes the handlers again."""
    signals = [signal.SIGINT, signal.SIGTERM]
    if signal.getsignal(signal.SIGHUP) is not signal.SIG_IGN:
        signals.append(signal.SIGHUP)
    for signum in signals:
        loop.add_signal_handler(signum, stop)

    def undo() -> None:
        for signum in signals:
            loop.remove_signal_handler(signum)

    return undo
