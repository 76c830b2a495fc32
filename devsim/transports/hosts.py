"""How many hosts a TCP port serves, and what happens to one more (issue 32).

A port declares how many hosts it serves at once (:attr:`devsim.core.kit.PortDef.hosts`): a serial
port reached over TCP (a device server, RFC 2217) serves one, as the serial line has one host; a
port the real device has on its Ethernet interface (Ether-S-Bus TCP, Modbus TCP) several.  When a
new client connects and the port already serves that many:

* a host idle (nothing received from it) for longer than ``idle_drop`` seconds is dropped and the
  new client served in its place (the longest idle first), with a line in the log;
* otherwise the new client is refused at once (the connection closed), with a line in the log
  giving the reason (for a one-host port: who holds it, from where and since when).

The log lines go to stderr as ``devsim: ...``, at most one per port and cause every few seconds
(:func:`devsim.transports.fdlimit.report`).  :data:`DEFAULT_IDLE_DROP` is the default of
``devsim run --idle-drop`` / ``devsim up --idle-drop``.

The listen backlog (:func:`listen_backlog`) is the system's ``somaxconn``: a plant whose hosts
reconnect at once (a SCADA restart, churn) would otherwise overflow a short backlog, and each
connection dropped there costs the host a one-second SYN retransmission.
"""

from __future__ import annotations

import socket
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TypeVar

from devsim.transports.fdlimit import report

__all__ = ["DEFAULT_IDLE_DROP", "Admission", "admit", "dropped", "idle_drop_problem", "listen_backlog", "peer_text", "refuse", "since_text"]

#: Seconds a host may stay idle before a waiting client takes its place (``--idle-drop``).
DEFAULT_IDLE_DROP = 30.0
_SOMAXCONN = Path("/proc/sys/net/core/somaxconn")

H = TypeVar("H")


def idle_drop_problem(seconds: float) -> str | None:
    """What is wrong with ``seconds`` as an idle-drop time (``--idle-drop``), or None.

    NaN is refused (it passed click's ``FloatRange(min=0)`` and ``admit`` never found a host idle
    longer than NaN: it acted as "never" unsaid).  [SIM-CHOICE] Infinity is taken and means what
    it says: no host is ever idle long enough to be dropped, a full port refuses every newcomer."""
    if seconds != seconds:
        return "must be a number of seconds, not nan"
    if seconds < 0:
        return "must not be negative"
    return None


def listen_backlog() -> int:
    """The listen backlog of a port: the system's limit (``net.core.somaxconn``), at least 128."""
    try:
        limit = int(_SOMAXCONN.read_text().strip())
    except (OSError, ValueError):
        limit = socket.SOMAXCONN
    return max(128, limit)


class Admission:
    """What to do with a new client: ``serve`` it, ``drop`` the idle ``victim`` and serve it,
    or ``refuse`` it."""

    __slots__ = ("action", "victim")

    def __init__(self, action: str, victim: object = None) -> None:
        self.action, self.victim = action, victim


def admit(served: Sequence[H], hosts: int, idle_drop: float, last_heard: Callable[[H], float],
          now: float | None = None) -> Admission:
    """The decision for one more client on a port serving ``served`` (at most ``hosts``);
    ``last_heard(host)`` is when the host last sent something (``time.monotonic()``)."""
    if len(served) < hosts:
        return Admission("serve")
    now = time.monotonic() if now is None else now
    idlest = min(served, key=last_heard)
    if now - last_heard(idlest) > idle_drop:
        return Admission("drop", idlest)
    return Admission("refuse")


def peer_text(peer: object) -> str:
    """``HOST:PORT`` of a socket peer address (``?`` when unknown)."""
    if isinstance(peer, tuple) and len(peer) >= 2:
        host = str(peer[0])
        return f"[{host}]:{peer[1]}" if ":" in host else f"{host}:{peer[1]}"
    return "?"


def since_text(wall: float) -> str:
    """A wall-clock time as the log shows it (UTC, seconds)."""
    return time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime(wall))


def refuse(address: str, peer: object, hosts: int, holders: Sequence[tuple[object, float]]) -> str:
    """Log (rate-limited) and return the line for a client refused on ``address``; ``holders``
    are the (peer, connected since, wall clock) of the hosts served."""
    if hosts == 1 and holders:
        holder, since = holders[0]
        why = f"it serves one host, held by {peer_text(holder)} since {since_text(since)}"
    else:
        why = f"it serves {hosts} hosts at once, all active"
    text = f"{address}: refused {peer_text(peer)}: {why}"
    report(f"refuse {address}", text)
    return text


def dropped(address: str, victim_peer: object, idle: float, peer: object) -> str:
    """Log and return the line for an idle host dropped for a new client."""
    text = f"{address}: dropped {peer_text(victim_peer)}, idle {idle:.1f} s, for {peer_text(peer)}"
    report(f"drop {address}", text)
    return text
