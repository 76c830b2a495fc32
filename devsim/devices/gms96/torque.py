"""The motor current model and the torque abort ``H7`` (manual §2.3.1 H, T1;5; spec §5.5, §5.7).

The current (fraction of Imax): ``I_BASE + K_ACC·|a|/A_REF + load``, limited by N39 and, while
I²t limits, by the N15 level; ``i_lim`` while a blockage or an end stop holds the axis.  H7 aborts
the armed move at the instant the current reaches its level, solved from the plan.
"""

from __future__ import annotations

import math
from collections.abc import Callable

from devsim.core.axis import Axis
from devsim.core.clock import Clock, Timer
from devsim.devices.gms96.executor import Executor
from devsim.devices.gms96.i2t import A_REF, I_BASE, K_ACC, I2t
from devsim.devices.gms96.motion import Indexer
from devsim.devices.gms96.params import NParameters
from devsim.devices.gms96.stage import PowerStage

__all__ = ["Torque"]


class Torque:
    """Motor current, blockage and H7 of one card (spec §5.5, §5.7)."""

    def __init__(
        self,
        clock: Clock,
        axis: Axis,
        indexer: Indexer,
        params: NParameters,
        stage: PowerStage,
        i2t: I2t,
        executor: Executor,
        blocked_input: Callable[[], bool],
        record_event: Callable[[str], None],
    ) -> None:
        self.clock = clock
        self.axis = axis
        self.indexer = indexer
        self.params = params
        self.stage = stage
        self.i2t = i2t
        self.executor = executor
        self.blocked_input = blocked_input  # the ``blocked`` quantity: the mechanics hold the axis
        self.record_event = record_event
        self._h7_timer: Timer | None = None

    def current(self) -> float:
        """Motor current as a fraction of Imax (``T1;5`` = round(252·i))."""
        if not self.stage.controller:
            return 0.0
        ix = self.indexer
        i_lim = self.params.peak_current_pct / 100.0
        if (ix.blocked_at is not None or ix.at_end_stop()) and self.axis.moving:
            i = i_lim  # held by a blockage or pressing against an end stop
        else:
            i = I_BASE + K_ACC * abs(self.axis.acceleration()) / A_REF + self.i2t.load_pct() / 100.0
        i = min(i, i_lim)
        if self.i2t.limiting:
            i = min(i, self.i2t.level())
        return i

    def blocked(self) -> bool:
        """The axis is held: a blockage, or I²t limits below what the load demands."""
        return bool(self.blocked_input()) or (self.i2t.limiting and self.i2t.demand() > self.i2t.level())

    def update_block(self) -> None:
        self.indexer.block(self.blocked())
        self.arm(now_only=True)

    def arm(self, now_only: bool = False) -> None:
        """H7 (spec §5.5): the armed move is aborted when the motor current reaches P2 % of Imax
        (acceleration and load current, or i_lim when the axis is held by a blockage or an end
        stop).  The instant is solved from the plan; ``now_only``: abort at once if it is due now,
        schedule nothing (an external change, synchronous)."""
        when = self._due()
        if when is not None and when <= self.clock.now():
            if self._h7_timer is not None:
                self._h7_timer.cancel()
                self._h7_timer = None
            if now_only:
                self._abort()
                return
        if now_only:
            return
        if self._h7_timer is not None:
            self._h7_timer.cancel()
            self._h7_timer = None
        if when is not None:
            self._h7_timer = self.clock.call_at(max(when, self.clock.now()), self._fire)

    def _fire(self) -> None:
        self._h7_timer = None
        if self.executor.h7_active() is not None and self.axis.moving:
            self._abort()

    def _due(self) -> float | None:
        """The first instant >= now at which the current reaches the armed H7 level, or None."""
        level = self.executor.h7_active()
        if level is None or not self.stage.controller or not self.axis.moving:
            return None
        now = self.clock.now()
        cap = self.params.peak_current_pct / 100.0
        if self.i2t.limiting:
            cap = min(cap, self.i2t.level())
        if level > cap + 1e-12:
            return None  # the stage never delivers that much
        ix = self.indexer
        if ix.blocked_at is not None or ix.at_end_stop():
            return now
        static = I_BASE + self.i2t.load_pct() / 100.0
        if static >= level - 1e-12:
            return now
        best = ix.end_stop_contact()
        a_min = (level - static) * A_REF / K_ACC  # the acceleration whose current reaches the level
        for seg in self.axis.segments():
            if seg.t1 <= now or (best is not None and seg.t0 >= best):
                continue
            t0 = max(seg.t0, now)
            if seg.shape == "linear":
                hit = t0 if abs(seg.a) >= a_min else None
            else:
                peak = 0.5 * math.pi * abs(seg.a)
                if peak < a_min:
                    continue
                tau = seg.span / math.pi * math.asin(min(1.0, a_min / peak))
                lo, hi = seg.t0 + tau, seg.t0 + seg.span - tau
                hit = max(lo, t0) if t0 <= hi else None
            if hit is not None:
                best = hit if best is None else min(best, hit)
                break
        return best

    def _abort(self) -> None:
        """H7: the move ends where the axis stands, no following error (spec §5.5).  A blockage
        that still holds the axis stays (the next move sees it)."""
        self.executor.disarm_h7()
        ix = self.indexer
        actual = ix.actual()
        ix.target = None
        ix.set_junction(None)
        self.axis.quick_stop()
        self.axis.set_position(actual)
        self.record_event("torque_abort")
        ix.block(self.blocked())
        self.executor.torque_aborted()
