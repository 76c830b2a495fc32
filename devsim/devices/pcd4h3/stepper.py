"""Runs an LM628 on the device clock (spec pcd4h3.md §5.1; design principle: an idle simulator
uses no CPU): the chip's samples are computed in batches, up to the present, whenever someone
looks (:meth:`ChipStepper.catch_up`) and by a periodic tick while anything moves; once the
trajectory is complete and the motor stands still on its position the ticks stop.

A batch computes every sample (341.333 µs apart) in order, in one pass
(:func:`~devsim.devices.pcd4h3.batch.run`, bit-exact with :meth:`Lm628.sample` one at a time), so
the loop's behaviour is the same however the batches fall; only the moment at which a flag
becomes visible is rounded to the next look or tick.
"""

from __future__ import annotations

from collections.abc import Callable

from devsim.core.clock import Clock, Timer
from devsim.devices.pcd4h3 import batch
from devsim.devices.pcd4h3.lm628 import Lm628
from devsim.devices.pcd4h3.units import CHIP_SAMPLE

__all__ = ["ChipStepper"]

TICK = 0.010  # seconds of device time between batches while the chip is active
QUIET = 64  # samples without any change before the chip counts as settled


class ChipStepper:
    def __init__(self, chip: Lm628, clock: Clock, on_tick: Callable[[], None] | None = None, *,
                 own_timer: bool = True, on_batch: Callable[[], None] | None = None) -> None:
        self.chip, self.clock, self.on_tick = chip, clock, on_tick
        self.own_timer = own_timer  # False: someone else (the PLC cycle) calls catch_up while active
        #: Called after each batch that computed samples (the shared axis follows the motor).
        self.on_batch = on_batch
        self._samples = 0  # samples computed since the epoch
        self._epoch = clock.now()
        self._timer: Timer | None = None
        self._quiet = 0

    @property
    def active(self) -> bool:
        return self._timer is not None

    @property
    def settled(self) -> bool:
        """Nothing has changed for a while: no sample needs computing until a command."""
        return self._quiet >= QUIET

    def catch_up(self, until: float | None = None) -> None:
        """Compute every sample due by now (or by ``until``); a settled chip just rests."""
        now = self.clock.now() if until is None else until
        if self.settled:
            if now > self._epoch + self._samples * CHIP_SAMPLE:
                self._epoch, self._samples = now, 0
            return
        due = int((now - self._epoch) / CHIP_SAMPLE + 1e-9)
        if self._samples >= due:
            return
        self._quiet = batch.run(self.chip, due - self._samples, self._quiet)
        self._samples = due
        if self.on_batch is not None:
            self.on_batch()

    def poke(self) -> None:
        """A command changed the chip (call :meth:`catch_up` before the command, so it acts at
        the right sample): keep ticking until the chip settles."""
        self._quiet = 0
        if self._timer is None and self.own_timer:
            self._timer = self.clock.call_later(TICK, self._tick)

    def _tick(self) -> None:
        self._timer = None
        self.catch_up()
        if self.on_tick is not None:
            self.on_tick()
        if self._quiet < QUIET:
            self._timer = self.clock.call_later(TICK, self._tick)
        else:
            self._rest()

    def _rest(self) -> None:
        """Settled: no ticks; the sample count restarts from now when the chip wakes."""
        self._epoch, self._samples = self.clock.now(), 0

    def close(self) -> None:
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None
