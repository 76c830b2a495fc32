"""Master mode on the wire (manual §3.6.2, §4.5.2, §4.8.5.5; spec §3.8, G-MASTER).

A SERS with DIP address 0 runs its program and, after ``Z=n``, sends the following statements
to slave n over its serial line instead of executing them: ``#<n><statement>\\r`` with the
master's own operands already substituted (``Z=1 V=X`` → ``#1V=1000\\r``).  It then waits for
the slave's acknowledgement (``ok…``) or error message (``*…``); no answer within 100 ms is a
program error.  Values come back through the slave's P3 (``#1P3=91\\r`` → ``P3=<value>``) and,
for IF and WAIT, P2 (``#1P2=336\\r`` → ``P2=<value>``).  ``Z=*`` broadcasts and does not wait.
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable

from devsim.core.clock import Clock, Timer
from devsim.devices.sers.units import parse_number

__all__ = ["MasterLink", "REPLY_TIMEOUT"]

REPLY_TIMEOUT = 0.1  # seconds (G-MASTER)
#: (compiled by :mod:`re` at the first answer a master hears, not by every start: issue 31)
_END = rb"\n(?:ok\d|pgm)\n\r|\n\*([^\n]*)\n\r"

Done = Callable[[bool, float | None, str], None]


def _number(text: bytes) -> float | None:
    """A slave's value as a finite decimal constant (:func:`~.units.parse_number`), or None: what
    another device on the line sent in its place (``1.2.3``, ``.``, 400 digits) is no value
    (G-MASTER: a slave answers a number)."""
    try:
        value = parse_number(text.decode("latin-1"))
    except ValueError:
        return None
    return value if math.isfinite(value) else None


class MasterLink:
    """Requests to slaves, one at a time, and what comes back (§3.6.2, G-MASTER).  (Slots: a
    host's repeated poll reads :attr:`awaiting`, one block of memory.)"""

    __slots__ = ("clock", "send", "_buffer", "_want", "_done", "awaiting", "_timer", "sent")

    def __init__(self, clock: Clock, send: Callable[[bytes], None]) -> None:
        self.clock = clock
        self.send = send
        self._buffer = bytearray()
        self._want: bytes | None = None
        self._done: Done | None = None
        #: A request waits for its answer: ``_done`` is set (a plain attribute, set and cleared
        #: with it in :meth:`request` and :meth:`cancel`: every chunk from the host asks).
        self.awaiting = False
        self._timer: Timer | None = None
        self.sent: list[bytes] = []  # for tests and traces: everything the master sent

    def request(self, address: int | str, text: str, done: Done, want: str | None = None) -> None:
        """Send ``#<address><text>\\r``; ``done(ok, value, message)`` when answered or timed out."""
        data = f"#{address}{text}\r".encode("latin-1")
        self.sent.append(data)
        if address == "*":
            self.send(data)
            done(True, None, "")
            return
        self._buffer.clear()
        self._want = want.encode() if want else None
        self._done = done
        self.awaiting = True
        self._timer = self.clock.call_later(REPLY_TIMEOUT, self._timeout)
        self.send(data)

    def feed(self, data: bytes) -> None:
        """Bytes the master hears on the line while it waits."""
        if not self.awaiting:
            return
        self._buffer += data
        end = re.search(_END, self._buffer)
        if end is None:
            return
        value = None
        if self._want is not None:
            found = re.search(rb"(?:^|[\r\n])" + re.escape(self._want) + rb"=(-?[0-9.]+)", self._buffer)
            if found is not None:
                value = _number(found.group(1))
        error = end.group(1)
        self._finish(error is None, value, error.decode("latin-1") if error else "")

    def _timeout(self) -> None:
        self._timer = None
        self._finish(False, None, "no answer")

    def _finish(self, ok: bool, value: float | None, message: str) -> None:
        done = self._done
        self.cancel()
        if done is not None:
            done(ok, value, message)

    def cancel(self) -> None:
        """Stop waiting (no answer is reported)."""
        self._done = None
        self.awaiting = False
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None
        self._buffer.clear()
