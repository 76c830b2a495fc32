"""Runs an LM628 on the device clock (spec pcd4h3.md §5.1; design principle: an idle simulator
uses no CPU): the chip's samples are computed in batches, up to the present, whenever someone
looks (:meth:`ChipStepper.catch_up`) and by a periodic tick while anything moves; once the
trajectory is complete, the motor stands still on its position and the filter rests, the ticks
stop, and a look computes what the samples since change in closed form
(:func:`~devsim.devices.pcd4h3.batch.rest`), on the chip's own sample grid, which runs on.  Only a
command wakes the chip (:meth:`ChipStepper.poke`); a read changes nothing in it (§3.5.3).

A batch computes every sample (341.333 µs apart) in order, in one pass
(:func:`~devsim.devices.pcd4h3.batch.run`, bit-exact with :meth:`Lm628.sample` one at a time), so
the loop's behaviour is the same however the batches fall; only the moment at which a flag
becomes visible is rounded to the next look or tick.

A caller that wants to know what comes (the PLC, issue 31: "schedule timers only for events")
computes the chip ahead of the present (:meth:`ChipStepper.ahead`), which keeps a checkpoint of
the chip's state at each point it was asked for; a look before the end goes back to the last
checkpoint before it and computes the few samples from there, so that a look sees exactly the
chip of the present.  A command (:meth:`ChipStepper.poke`) drops what was computed ahead.
"""

from __future__ import annotations

from bisect import bisect_right
from collections.abc import Callable, Sequence

from devsim.core.clock import Clock, Timer
from devsim.devices.pcd4h3 import batch
from devsim.devices.pcd4h3.lm628 import Lm628

__all__ = ["ChipStepper"]

TICK = 0.010  # seconds of device time between batches while the chip is active
QUIET = batch.SETTLE  # samples without any change before the chip counts as settled


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
        #: (sample index, quiet, chip state) computed ahead of the last look, in order; the first
        #: is where the chip was when :meth:`ahead` began
        self._ahead: list[tuple[int, int, batch.State]] = []
        self._unseen = False  # the chip's state was computed ahead: on_batch has not followed it
        self._present = 0  # the sample the present has reached (while the chip is computed ahead)

    @property
    def active(self) -> bool:
        return self._timer is not None

    @property
    def moment(self) -> float:
        """The device time of the chip's last computed sample: after a catch-up, up to a PLC
        cycle after the clock where a function of the cycle looked at the chip at its moment
        (§10.1), a little before it after a look (further ahead only between :meth:`ahead` and
        the next catch-up)."""
        return self._epoch + self._samples * self.chip.sample_time

    @property
    def settled(self) -> bool:
        """Nothing has changed for a while: no sample needs computing until a command (and none
        was computed ahead of the present, whose count of samples without change a look finds)."""
        return self._quiet >= QUIET and not self._ahead

    def catch_up(self, until: float | None = None, *, follow: bool = True) -> None:
        """Compute every sample due by now (or by ``until``); a settled chip just rests.
        ``follow=False``: a moment of the past (a skipped PLC cycle): ``on_batch`` waits for the
        next look."""
        now = self.clock.now() if until is None else until
        due = int((now - self._epoch) / self.chip.sample_time + 1e-9)
        moved, self._unseen = self._unseen, False
        if self._ahead:
            # the chip as the present has it: never before what a catch-up already reached (a
            # function of the PLC cycle acts a little after the cycle's start)
            target = max(due, self._present)
            moved = moved or target > self._present
            self._rewind(target)
            moved = self._advance(target) or moved
            self._present = target
        else:
            settled = self.settled
            if self._samples < due or settled:
                moved = self._advance(due) or moved
            self._present = self._samples
        if moved and not follow:
            self._unseen = True
        elif moved and self.on_batch is not None:
            self.on_batch()

    def _advance(self, target: int) -> bool:
        """Take the chip to sample ``target``: a settled one in closed form where it can
        (:func:`~devsim.devices.pcd4h3.batch.rest`, which also puts its motor where its rest
        puts it however its samples were taken), else sample by sample.  Returns whether the
        motor moved."""
        count = max(0, target - self._samples)
        self._samples += count
        motor = self.chip.motor
        x = motor.position
        if self._quiet >= QUIET and batch.rest(self.chip, count):
            return motor.position != x  # (its lag's last thousandths of a count)
        if count:
            self._quiet = batch.run(self.chip, count, self._quiet)
        return bool(count)

    def _rewind(self, target: int) -> None:
        """Take the chip from what was computed ahead to the last checkpoint at or before
        sample ``target`` (when the chip is beyond it, or the checkpoint beyond the chip)."""
        ahead = self._ahead
        index = bisect_right(ahead, target, key=lambda checkpoint: checkpoint[0]) - 1
        samples, quiet, state = ahead[index]  # (the first is where the present was: at or before target)
        del ahead[:index]
        if self._samples > target or samples > self._samples:
            batch.restore(self.chip, state)
            self._samples, self._quiet = samples, quiet

    def ahead(self, untils: Sequence[float]) -> list[batch.State]:
        """Compute the chip's samples up to each of ``untils`` (in order, after the present) in
        one pass, with a checkpoint at each; the pass ends at the first whose status differs
        from the chip's now (:func:`~devsim.devices.pcd4h3.batch.run_to`).  Returns the chip's
        state at each of ``untils`` the pass reached.  The present stays where it was for every
        look (:meth:`catch_up`)."""
        start = self._samples
        if not self._ahead:
            self._present = start
            self._ahead.append((start, self._quiet, batch.snapshot(self.chip)))
        now = self._ahead[-1][2] if self._ahead[-1][0] == start else batch.snapshot(self.chip)
        dues = [int((until - self._epoch) / self.chip.sample_time + 1e-9) - start for until in untils]
        marks = sorted({due for due in dues if due > 0})
        reached: dict[int, batch.State] = {}
        if marks:
            checkpoints, self._quiet = batch.run_to(self.chip, marks, self._quiet, settle=True)
            for mark, quiet, state in checkpoints:
                self._ahead.append((start + mark, quiet, state))
                reached[mark] = state
            self._samples, self._unseen = start + checkpoints[-1][0], True
        states = []
        for due in dues:
            state = now if due <= 0 else reached.get(due)
            if state is None:
                break
            states.append(state)
        return states

    def present(self) -> None:
        """The chip is at the present (just caught up): forget what was computed ahead."""
        self._ahead.clear()

    def poke(self) -> None:
        """A command changed the chip (call :meth:`catch_up` before the command, so it acts at
        the right sample): keep ticking until the chip settles."""
        self._ahead.clear()
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

    def close(self) -> None:
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None
