"""The PCD's timers (spec pcd4h3.md §6.3, §9.4, §9.5; manual §9.1): ``LD T n tenths`` loads timer n,
which counts down to 0 in tenths of a second on the device clock; S-Bus reads them (07h)."""

from __future__ import annotations

import math

from devsim.core.clock import Clock

__all__ = ["Timers"]


class Timers:
    """The timers T n of one PCD, by number."""

    def __init__(self, clock: Clock) -> None:
        self.clock = clock
        self._ends: dict[int, float] = {}

    def load(self, n: int, tenths: int) -> None:
        """``LD T n tenths``."""
        self._ends[n] = self.clock.now() + tenths / 10

    def value(self, n: int, at: float | None = None) -> int:
        """Timer n's value in tenths of a second (0 once it ran out), now or ``at``."""
        end = self._ends.get(n)
        if end is None:
            return 0
        if at is None:
            at = self.clock.now()
        return max(0, math.ceil((end - at) * 10 - 1e-9))

    def running(self) -> bool:
        """Whether a loaded timer has not run out yet."""
        return any(self.value(n) for n in self._ends)

    def none_runs_out(self, at: float) -> bool:
        """Whether every timer running now still runs at ``at``."""
        return all(self.value(n, at) for n in self._ends if self.value(n))
