"""The looks on the device clock behind CiA 402's supervised statusword bits (CiA 402-2: the
velocity window and threshold of profile velocity mode, 606Dh … 6070h,
:mod:`devsim.facades.cia402_velocity`; the position and following error windows of profile
position mode, 6065h … 6068h, :mod:`devsim.facades.cia402_position_watch`).

Such a bit is 1 once a condition has held for a time in ms (:func:`held`), counted from when it
began to hold (:func:`since`).  A watch looks every :data:`SAMPLE` of device time while what it
watches changes, and for :data:`QUIET` after that stopped changing or after any command, as long
as one of its times is set (:class:`Looks`); what stands still changes nothing by itself, so the
looks stop and cost nothing, and with its times 0 a bit is the comparison at the instant it is read.
"""

from __future__ import annotations

from collections.abc import Callable, Hashable
from typing import Any

__all__ = ["Looks", "QUIET", "SAMPLE", "held", "since"]

SAMPLE = 0.001  # s of device time between looks while the values change (the objects' times are in ms)
QUIET = 0.1  # s without a change after which the looks stop
_EPSILON = 1e-9  # (sums of SAMPLE steps on the clock)


def since(began: float | None, now: float, holds: bool) -> float | None:
    """When a condition that ``holds`` now began to hold (``began``: as of the last look, ``None``
    if it did not hold then); ``None`` if it does not hold."""
    if not holds:
        return None
    return began if began is not None else now


def held(began: float | None, now: float, ms: float) -> bool:
    """A condition that began to hold at ``began`` (``None``: it does not) has held for ``ms``."""
    return began is not None and now - began >= ms / 1000 - _EPSILON


class Looks:
    """When a watch looks next: ``look`` is called every :data:`SAMPLE` while :meth:`after` is told
    of values that change, and for :data:`QUIET` after they stopped changing or after a command,
    while the watch has a time set (``timed``)."""

    def __init__(self, clock: Any, look: Callable[[], None]) -> None:
        self.clock, self._look = clock, look
        self._timer: Any = None
        self._last: tuple[Hashable, float] | None = None  # (the values looked at last, when they changed)

    def forget(self) -> None:
        """Nothing looked at yet (no looks either)."""
        self.cancel()
        self._last = None

    def after(self, values: Hashable, now: float, *, command: bool, timed: bool) -> None:
        """A look at ``values`` is done (``command``: a write that may change them): look again
        in :data:`SAMPLE` or stop looking."""
        if command or self._last is None or values != self._last[0]:
            self._last = (values, now)
        if timed and now - self._last[1] < QUIET:
            if self._timer is None:
                self._timer = self.clock.call_later(SAMPLE, self._tick)
        else:
            self.cancel()

    def _tick(self) -> None:
        self._timer = None
        self._look()

    def cancel(self) -> None:
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None
