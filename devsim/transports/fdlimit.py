"""Running out of file descriptors: say so once, refuse what cannot be served, serve the rest.

Every port costs descriptors (a pty two: the master and the slave devsim holds open; a TCP or
RFC 2217 port one to listen plus one per connected host; the control API one per client, up to
:func:`client_bound` of them).
When the process reaches its limit (``ulimit -n``), accepting or opening fails with EMFILE.
Then devsim

* refuses the connection at once (a host sees it closed instead of waiting forever): one
  descriptor is kept in reserve to accept and close it (:func:`shed`);
* reports each cause once per :data:`REPORT_EVERY` seconds with the count of repeats
  (:func:`report`), instead of a traceback per attempt;
* keeps serving the ports and hosts it has.

:func:`capacity` tells at start-up how many ports the limit allows, with the control clients'
share kept (:func:`client_bound`: the control server serves no more than that).  The reserve
descriptor and the report counters are per process (they describe the process's descriptor
table, not a device).
"""

from __future__ import annotations

import errno
import os
import socket
import time
from typing import Any

from devsim.core.console import say, warn

__all__ = [
    "OUT_OF_FDS",
    "REPORT_EVERY",
    "CLIENT_SHARE",
    "MAX_CLIENTS",
    "capacity",
    "client_bound",
    "fd_limit",
    "in_use",
    "is_out_of_fds",
    "port_budget",
    "report",
    "shed",
]

OUT_OF_FDS = frozenset({errno.EMFILE, errno.ENFILE, errno.ENOBUFS, errno.ENOMEM})
REPORT_EVERY = 10.0  # seconds between two lines about the same cause
FDS_PER_PORT = 2
BASE_FDS = 32  # the interpreter, the loop, stdio, the control server's listener
#: [SIM-CHOICE] Control connections served at once; one more is answered with one ``Busy`` error
#: line and closed.  Each costs a descriptor and about 4 KB (9,000 idle ones: 9,011 descriptors,
#: +37 MB resident, kept after they closed), and the descriptors are those the device's ports,
#: traces and state files need: about 1,000 idle clients of a loopback TCP control port (any
#: local user) took the default limit of 1,024, and the device's hosts waited in the backlog.
#: (Here, below the control server, so that :func:`capacity` keeps their share.)
MAX_CLIENTS = 256
#: [SIM-CHOICE] Nor more than this share of the process's descriptor limit (the soft
#: ``RLIMIT_NOFILE``, ``ulimit -n``): under ``ulimit -n 128`` the bound of 256 let 119 idle clients
#: take every descriptor (the next one was not even accepted); now 32 are served.
CLIENT_SHARE = 0.25


class _Reports:
    def __init__(self) -> None:
        self.last: dict[str, float] = {}
        self.repeats: dict[str, int] = {}


_REPORTS = _Reports()
_RESERVE: list[int] = []


def fd_limit() -> int:
    """The soft limit on open descriptors of this process.

    Asked through ``sysconf`` (``getrlimit(RLIMIT_NOFILE)``'s soft limit), not the ``resource``
    module: that is loaded from a file, and the limit is asked when the descriptors have run out
    (an ``import resource`` there raised ImportError in the loop's exception handler, a traceback
    for every accept that failed); nor at start (a plain run does not need it)."""
    soft = os.sysconf("SC_OPEN_MAX")
    return soft if soft > 0 else 1 << 20


def client_bound(limit: int | None = None) -> int:
    """How many control connections are served at once (the control server's bound):
    :data:`MAX_CLIENTS`, or :data:`CLIENT_SHARE` of the descriptor ``limit`` (the process's,
    :func:`fd_limit`) when that is fewer; at least one."""
    limit = fd_limit() if limit is None else limit
    return max(1, min(MAX_CLIENTS, int(limit * CLIENT_SHARE)))


def _kept(limit: int, control: bool) -> int:
    """Descriptors not for ports: the base, and the control clients' share when a control
    server is served."""
    return BASE_FDS + (client_bound(limit) if control else 0)


def capacity(limit: int | None = None, *, control: bool = True) -> int:
    """About how many ports (each with its host connected) fit under the descriptor limit, beside
    a full set of control clients when ``control`` (a control server is served)."""
    limit = fd_limit() if limit is None else limit
    return max(0, (limit - _kept(limit, control)) // FDS_PER_PORT)


def in_use() -> int:
    """Descriptors this process has open now (0 where the system does not tell)."""
    try:
        return len(os.listdir("/proc/self/fd"))
    except OSError:
        return 0


def port_budget(limit: int | None = None, *, control: bool = True) -> int:
    """How many more ports can be opened with a host each, keeping room for the rest (and for
    a full set of control clients when ``control``)."""
    limit = fd_limit() if limit is None else limit
    return max(0, (limit - in_use() - _kept(limit, control)) // FDS_PER_PORT)


def is_out_of_fds(exc: BaseException) -> bool:
    return isinstance(exc, OSError) and exc.errno in OUT_OF_FDS


def report(cause: str, text: str, *, stream: Any = None) -> bool:
    """Print ``devsim: TEXT`` on stderr unless the same cause was reported in the last
    :data:`REPORT_EVERY` seconds; returns whether it printed.  Repeats are counted and shown
    with the next line."""
    now = time.monotonic()
    last = _REPORTS.last.get(cause)
    if last is not None and now - last < REPORT_EVERY:
        _REPORTS.repeats[cause] = _REPORTS.repeats.get(cause, 0) + 1
        return False
    repeats = _REPORTS.repeats.pop(cause, 0)
    _REPORTS.last[cause] = now
    extra = f" ({repeats} more since the last report)" if repeats else ""
    if stream is None:
        warn(f"devsim: {text}{extra}")
    else:
        say(f"devsim: {text}{extra}", stream)
    return True


def keep_reserve() -> None:
    """Hold one descriptor back, so that a connection can still be accepted (and closed) when
    the limit is reached."""
    if not _RESERVE:
        try:
            _RESERVE.append(os.open(os.devnull, os.O_RDONLY | os.O_CLOEXEC))
        except OSError:
            pass


def shed(listener: socket.socket) -> int:
    """Out of descriptors: accept and close the connections waiting on ``listener`` with the
    reserve descriptor; returns how many were refused."""
    refused = 0
    while _RESERVE:
        os.close(_RESERVE.pop())
        try:
            conn, _addr = listener.accept()
        except OSError:
            keep_reserve()
            break
        conn.close()
        refused += 1
        keep_reserve()
    return refused


def loop_exception_handler(loop: Any, context: dict[str, Any]) -> None:
    """An asyncio exception handler: descriptor exhaustion reported once per cause, the rest as
    asyncio would."""
    exc = context.get("exception")
    if exc is not None and is_out_of_fds(exc):
        report(
            "accept",
            f"out of file descriptors (limit {fd_limit()}): refusing new connections; {exc.strerror}",
        )
        return
    loop.default_exception_handler(context)
