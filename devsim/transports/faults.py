"""Faults injected into a :class:`~devsim.transports.line.Line`: what they are
(:class:`LineFault`, validated on construction), the line's bookkeeping for an active one, and
the handle an injector gets back (:class:`FaultHandle`).

How an active fault acts on the bytes is the line's business (:mod:`devsim.transports.line`,
which re-exports the public names here); the parts of it that need no clock and no I/O, given
the line's active faults, are here too (:func:`gate`, :func:`mangle`, :func:`take`; the last two
use up a counted fault's rest and draw from its random generator).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Literal, get_args

import msgspec

from devsim.core.clock import Timer

__all__ = ["DEFAULT_SPLIT_GAP", "FaultDirection", "FaultHandle", "FaultKind", "LineFault", "MAX_NOISE_RATE"]

FaultKind = Literal[
    "corrupt", "drop", "split", "delay", "jitter", "noise", "baud_mismatch", "unplug", "hang", "silent"
]
FaultDirection = Literal["to_device", "to_host", "both"]

#: Gap between the pieces of a split chunk when the fault does not give one.
DEFAULT_SPLIT_GAP = 0.005

# Which optional parameters each kind uses ("count" and "duration" are handled separately).
_PARAMS: dict[str, tuple[str, ...]] = {
    "corrupt": (),
    "drop": (),
    "split": ("delay",),
    "delay": ("delay",),
    "jitter": ("delay",),
    "noise": ("rate",),
    "baud_mismatch": ("baudrate",),
    "unplug": (),
    "hang": (),
    "silent": (),
}
_REQUIRED = {"delay": "delay", "jitter": "delay", "noise": "rate", "baud_mismatch": "baudrate"}
_COUNTED = ("corrupt", "drop", "split")
# Kinds whose ``direction`` is fixed by what they are (the field is ignored).
_UNDIRECTED = ("baud_mismatch", "unplug", "hang", "silent")
# Noise is emitted in batches no closer than this (a timer per byte would be wasteful at high rates).
_NOISE_TICK = 0.01
#: The most noise bytes per second (``rate``): more than any serial line carries (4 Mbd at 10 bits a
#: character is 400,000).  [SIM-CHOICE] a bound, where none was: 1e308 made the first tick draw more
#: bytes than memory holds and the simulator answered nothing again.
MAX_NOISE_RATE = 1_000_000.0


class LineFault(msgspec.Struct, frozen=True):
    """A fault injected into a :class:`Line` (see :meth:`Line.inject`).

    ``direction`` is ``"to_device"`` (the host's bytes), ``"to_host"`` (the device's bytes) or
    ``"both"``.  A fault ends when its ``duration`` (seconds of the line's clock) has passed, when
    its ``count`` of bytes is used up, when its :class:`FaultHandle` is cancelled or when
    :meth:`Line.clear_faults` is called; without ``count`` and ``duration`` it lasts until cleared.

    Kinds:

    ``corrupt``
        each of the next ``count`` bytes (or every byte while active) gets one bit flipped, the
        bit chosen by ``random.Random(seed)``: same length, wrong data.
    ``drop``
        the next ``count`` bytes (or every byte while active) vanish.
    ``split``
        chunks are delivered one byte at a time, ``delay`` seconds (default 5 ms) between the
        pieces, order preserved; ``count`` bytes are split, the rest of the chunk that uses up
        the count follows as one piece.
    ``delay``
        every chunk arrives ``delay`` seconds later, order preserved.
    ``jitter``
        every chunk is delayed by ``uniform(0, delay)``; a later chunk never overtakes an earlier
        one (it waits for it).  A delayed or split direction holds at most 64 KiB on its way
        (:data:`devsim.transports.pacing.MAX_PENDING`); more is lost.
    ``noise``
        ``rate`` random bytes per second appear on the line (towards the device, the host or
        both), regularly spaced in time: after ``t`` seconds ``floor(rate * t)`` bytes have been
        emitted in each direction; at most :data:`MAX_NOISE_RATE`.
    ``baud_mismatch``
        the host is treated as running at ``baudrate`` (its other frame settings unchanged), so
        both directions are garbled by :func:`garble`.  Always both directions.
    ``unplug``
        the cable is out: the target gets ``host_disconnected()`` at the start, nothing passes in
        either direction (bytes are lost, not queued – including those still in flight on a
        delayed or paced line).  Always both directions.
    ``hang``
        the device hangs with the link up: nothing reaches the device (not even bytes still in
        flight on a delayed line), nothing comes from it.  Line noise towards the host still
        arrives.  Always both directions.
    ``silent``
        the device's output is dropped; it still acts on its input.  Always towards the host.

    Several active faults combine in a fixed order, per chunk:

    1. gates – ``unplug``, ``hang``, ``silent``: a blocked chunk is lost and nothing else applies;
    2. ``baud_mismatch`` (the latest injected one decides the host's rate);
    3. ``drop`` faults, in injection order (dropped bytes do not count for later faults);
    4. ``corrupt`` faults, in injection order, each on the same next bytes (two faults may flip
       two bits of one byte, or the same bit twice);
    5. timing – the sum of all ``delay`` faults plus one ``uniform(0, delay)`` draw per ``jitter``
       fault is added to the chunk's latency, then the earliest injected ``split`` fault cuts it
       into pieces;
    6. output pacing (device → host only, when the line paces).

    Noise is injected at the receiving end: it passes the gates (``unplug`` blocks it both ways,
    ``hang`` blocks it towards the device) and nothing else.

    A parameter the kind does not use is rejected with :class:`ValueError`, so that a misspelt
    scenario does not silently inject a fault that never ends.
    """

    kind: FaultKind
    direction: FaultDirection = "both"
    count: int | None = None
    duration: float | None = None
    delay: float | None = None
    rate: float | None = None
    baudrate: int | None = None
    seed: int = 0

    def __post_init__(self) -> None:
        if self.kind not in _PARAMS:
            raise ValueError(f"unknown line fault kind {self.kind!r}; one of {', '.join(_PARAMS)}")
        if self.direction not in get_args(FaultDirection):
            raise ValueError(f"direction must be to_device, to_host or both, not {self.direction!r}")
        if self.count is not None:
            if self.kind not in _COUNTED:
                raise ValueError(f"count does not apply to a {self.kind} fault (only {', '.join(_COUNTED)})")
            if not (isinstance(self.count, int) or (isinstance(self.count, float) and self.count.is_integer())) \
                    or self.count < 1:
                raise ValueError("count must be a whole number from 1 on")
        if self.duration is not None and not (self.duration >= 0 and math.isfinite(self.duration)):
            raise ValueError("duration must be a finite number of seconds >= 0")
        for name in ("delay", "rate", "baudrate"):
            value = getattr(self, name)
            if value is None:
                if _REQUIRED.get(self.kind) == name:
                    raise ValueError(f"a {self.kind} fault needs {name}")
                continue
            if name not in _PARAMS[self.kind]:
                raise ValueError(f"{name} does not apply to a {self.kind} fault")
            if not math.isfinite(value):
                raise ValueError(f"{name} must be a finite number")
            if value < 0 or (name != "delay" and value == 0):
                raise ValueError(f"{name} must be positive" if name != "delay" else "delay must be 0 or more")
            if name == "rate" and value > MAX_NOISE_RATE:
                raise ValueError(f"rate must be at most {MAX_NOISE_RATE:,.0f} bytes per second")

    def applies(self, direction: str) -> bool:
        """Whether the fault acts on bytes going ``direction`` (``to_device``/``to_host``)."""
        return self.direction == "both" or self.direction == direction

    def describe(self) -> str:
        parts = [self.kind]
        if self.kind not in _UNDIRECTED:
            parts.append(self.direction)
        for name in ("count", "duration", "delay", "rate", "baudrate"):
            value = getattr(self, name)
            if value is not None:
                parts.append(f"{name}={value:g}" if isinstance(value, float) else f"{name}={value}")
        return " ".join(parts)


class _Active:
    """The line's bookkeeping for one injected fault."""

    __slots__ = ("fault", "rng", "remaining", "started", "timers", "emitted", "active")

    def __init__(self, fault: LineFault, started: float) -> None:
        import random  # (here: a port that never gets a fault starts without it)

        self.fault = fault
        self.rng = random.Random(fault.seed)
        self.remaining = fault.count
        self.started = started
        self.timers: list[Timer] = []
        self.emitted = {"to_device": 0, "to_host": 0}
        self.active = True


# -- how the active faults of a line act on its bytes (the line hands its faults in) ----------
def of_kind(faults: list[_Active], kind: str, direction: str) -> list[_Active]:
    """The active faults of ``kind`` that act on bytes going ``direction``."""
    return [a for a in faults if a.fault.kind == kind and a.fault.applies(direction)]


def gate(faults: list[_Active], direction: str, noise: bool = False) -> str | None:
    """The fault that blocks bytes going ``direction`` now, if any."""
    for active in faults:
        kind = active.fault.kind
        if kind == "unplug":
            return kind
        if kind == "hang" and (direction == "to_device" or not noise):
            return kind
        if kind == "silent" and direction == "to_host" and not noise:
            return kind
    return None


def take(active: _Active, available: int) -> int:
    """How many of ``available`` bytes a fault takes (a counted one: at most its rest)."""
    if active.remaining is None:
        return available
    taken = min(active.remaining, available)
    active.remaining -= taken
    return taken


def mangle(faults: list[_Active], data: bytes, direction: str) -> bytes:
    """Drop, then corrupt (see :class:`LineFault` for the order)."""
    for active in of_kind(faults, "drop", direction):
        data = data[take(active, len(data)) :]
    corrupt = of_kind(faults, "corrupt", direction)
    if corrupt and data:
        buf = bytearray(data)
        for active in corrupt:  # each one acts on the same next bytes
            for i in range(take(active, len(buf))):
                buf[i] ^= 1 << active.rng.randrange(8)
        data = bytes(buf)
    return data


def latency(faults: list[_Active], direction: str) -> float:
    """The extra latency of a chunk going ``direction`` now: every ``delay``, and a draw of every
    ``jitter`` (which uses up a draw of its random generator)."""
    total = 0.0
    for active in faults:
        fault = active.fault
        if not fault.applies(direction) or fault.delay is None:
            continue
        if fault.kind == "delay":
            total += fault.delay
        elif fault.kind == "jitter":
            total += active.rng.uniform(0.0, fault.delay)
    return total


def noise_due(active: _Active, now: float) -> list[tuple[str, bytes]]:
    """The noise bytes a ``noise`` fault owes each of its directions at ``now`` (drawn from its
    random generator, counted as emitted)."""
    fault = active.fault
    assert fault.rate is not None
    elapsed = now - active.started
    if fault.duration is not None:
        elapsed = min(elapsed, fault.duration)
    due = int(elapsed * fault.rate + 1e-9)
    out = []
    for direction in [d for d in ("to_device", "to_host") if fault.applies(d)]:
        n = due - active.emitted[direction]
        if n <= 0:
            continue
        active.emitted[direction] = due
        out.append((direction, active.rng.randbytes(n)))  # (in C: a byte drawn in Python each held the loop)
    return out


class FaultHandle:
    """Returned by :meth:`Line.inject`: lets the injector end the fault early.  ``end(active,
    how)`` is the line's own way of ending one of its faults."""

    __slots__ = ("_end", "_active")

    def __init__(self, active: _Active, end: Callable[[_Active, str], None]) -> None:
        self._end = end
        self._active = active

    @property
    def fault(self) -> LineFault:
        return self._active.fault

    @property
    def active(self) -> bool:
        """True until the fault has ended (by itself, by :meth:`cancel` or by clearing)."""
        return self._active.active

    def cancel(self) -> None:
        """End the fault now (idempotent)."""
        self._end(self._active, "cancelled")

    def __repr__(self) -> str:  # pragma: no cover - debugging aid
        return f"<FaultHandle {self.fault.describe()} {'active' if self.active else 'ended'}>"
