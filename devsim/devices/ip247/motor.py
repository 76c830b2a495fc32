"""The stepper motor behind an IP247 axis, as the open-loop world sees it (spec ip247.md §5.15,
manual §7.1.5.3): the module counts every pulse it sends, the motor follows only while it can.

A start frequency above what the loaded motor can jump to (``max_start_hz``) and it "howls"
without moving; a frequency above its pull-out frequency (``pullout_hz``) and it stalls there.
Either way the module's actual value goes on counting while the mechanics stand: the step loss a
reference run or a measurement reveals.  Pure: a move's pieces in, how far the motor follows out.
"""

from __future__ import annotations

import math
from typing import Any

__all__ = ["SteppingMotor"]


class SteppingMotor:
    def __init__(self, max_start_hz: float | None = None, pullout_hz: float | None = None) -> None:
        self.max_start_hz = max_start_hz if max_start_hz is not None else math.inf
        self.pullout_hz = pullout_hz if pullout_hz is not None else math.inf

    def follows(self, pieces: list[tuple[float, Any]], resolution: float, from_rest: bool) -> float:
        """How far (base units of the motor position) the motor follows ``pieces``: ``inf`` when
        it follows all of them."""
        if not pieces:
            return math.inf
        x0 = pieces[0][1].state(0.0)[0]
        if from_rest and abs(pieces[0][1].state(0.0)[1]) / resolution > self.max_start_hz:
            return 0.0  # it cannot start at this frequency: it howls and stays
        for duration, piece in pieces:
            f_start = abs(piece.state(0.0)[1]) / resolution
            f_end = abs(piece.state(duration)[1]) / resolution
            if f_start >= self.pullout_hz:
                return abs(piece.state(0.0)[0] - x0)
            if f_end >= self.pullout_hz:
                low, high = 0.0, duration
                for _ in range(60):  # the frequency rises monotonically within a piece
                    mid = 0.5 * (low + high)
                    if abs(piece.state(mid)[1]) / resolution >= self.pullout_hz:
                        high = mid
                    else:
                        low = mid
                return abs(piece.state(high)[0] - x0)
        return math.inf
