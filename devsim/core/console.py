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
got no answer after that, and SIGTERM could not stop the process).  So :func:`say` writes
through a :class:`~devsim.core.backlog.Backlog`: what the reader does not take now waits, up to
1 MiB, and goes out as the reader takes it; only a line beyond that is dropped, and the next line
that goes out says how many were lost before it.  (Dropping every line a full pipe did not take
at once lost port lines of a 6,000-device plant to a harness that read them a little behind.)

:func:`stop_on_signals`: Ctrl-C (SIGINT), SIGTERM and SIGHUP (the terminal that started it has
closed) stop a serving process the same clean way: its motion log gets its last rows, its
control socket is removed.  Under ``nohup`` (SIGHUP ignored) the terminal's end is ignored still.
"""

from __future__ import annotations

import asyncio
import atexit
import os
import signal
import sys
from collections.abc import Callable
from typing import TextIO

from devsim.core.backlog import Backlog

__all__ = ["say", "stop_on_signals", "to_null", "warn"]


#: What waits for each descriptor's reader (:class:`~devsim.core.backlog.Backlog`), by descriptor,
#: with the file it was made for (a descriptor closed and opened again is another file).
_backlogs: dict[int, tuple[tuple[int, int], Backlog]] = {}


def say(line: str, stream: TextIO | None = None) -> None:
    """Print ``line`` to ``stream`` (default stdout) without ever waiting for its reader: what a
    full pipe or a stopped terminal does not take now waits, up to 1 MiB, and goes out as the
    reader takes it; a line beyond that is dropped (the next line that goes out counts them).  A
    stream nobody reads any more is handed to the null device."""
    _put(line, sys.stdout if stream is None else stream)


def _put(line: str, out: TextIO | None) -> None:
    if out is None:  # (started with the descriptor closed, `devsim run ... >&-`: nowhere to print)
        return
    fd = _descriptor(out)
    if fd is None:
        try:
            print(line, file=out, flush=True)
        except OSError:  # (BrokenPipeError: the reader has gone; EIO: its terminal has)
            to_null(out)
        return
    backlog = _backlog(out, fd)
    lost = backlog.dropped
    if lost:
        line = f"devsim: {lost} line{'' if lost == 1 else 's'} of output dropped here: nobody read them\n{line}"
    try:
        backlog.write((line + "\n").encode(out.encoding or "utf-8", "backslashreplace"))
    except OSError:
        _gone(out, fd)


def _backlog(out: TextIO, fd: int) -> Backlog:
    """The backlog of ``out``'s descriptor, made at its first line (what ``out`` holds goes first,
    if it can go now)."""
    try:
        info = os.fstat(fd)
        file = (info.st_dev, info.st_ino)
    except OSError:
        file = (-1, -1)
    known = _backlogs.get(fd)
    if known is not None:
        if known[0] == file:
            return known[1]
        known[1].settle(0)  # (its file is gone: what waited for it too)
    backlog = Backlog(fd, lambda _exc: _gone(out, fd))
    if backlog.takes_now():
        try:
            out.flush()
        except OSError:
            pass  # (the backlog's first write says which)
    if not _backlogs:
        atexit.register(_settle_all)
    _backlogs[fd] = (file, backlog)
    return backlog


def _gone(out: TextIO, fd: int) -> None:
    """The reader has gone: later lines go to the null device, and what waited with them."""
    known = _backlogs.pop(fd, None)
    if known is not None:
        known[1].settle(0)
    to_null(out)


def _settle_all(patience: float = 1.0) -> None:
    """At the end of the run, each reader gets a moment to take what still waits for it."""
    for fd, (_file, backlog) in list(_backlogs.items()):
        try:
            backlog.settle(patience)
        except OSError:
            _backlogs.pop(fd, None)


def _descriptor(stream: TextIO) -> int | None:
    try:
        return stream.fileno()
    except (OSError, ValueError):  # (a stream without a descriptor, or closed: print decides)
        return None


def warn(line: str) -> None:
    """:func:`say` on stderr (nowhere when the process has none: not on stdout)."""
    _put(line, sys.stderr)


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
