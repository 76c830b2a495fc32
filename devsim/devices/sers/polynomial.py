"""Polynomial moves – velocity profiles of several path segments (manual §4.6.7, spec §4.10.12).

A segment is defined with ``WP=`` (``WRP=``/``WAP=``; the last one ``WPT=``/``WRPT=``/``WAPT=``)
and closed with ``E``.  Each segment ramps with the current A from the speed it starts at to its
own V – the ramp is part of the segment's distance – and then runs at V until its distance is
covered; only the last one also brakes, with B (P1096), to stop exactly at its end.

Execution model (spec G-POLY): one running segment and a one-deep pending slot.  ``E`` of the
first segment starts it and the program goes on; a further segment goes to the pending slot and
the program waits until the running segment has ended (the pending one then runs).  P1123 is 1
while the slot is free.  A segment arriving with the slot occupied is refused (errno 123); when a
segment ends with nothing pending and the profile was not closed by a last segment, the drive
brakes with B to standstill and reports errno 108.  Not allowed with backlash (errno 107); a
last segment too short to brake with B gives errno 118.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Protocol

import msgspec

from devsim.core.axis import Axis, Watch
from devsim.devices.sers.errors import SersError
from devsim.devices.sers.params import SersParameters


class PolynomialHost(Protocol):
    """What a polynomial move (§4.6.7) needs of the motion (:class:`~.motion.Motion`)."""

    @property
    def moving(self) -> bool: ...

    @property
    def offset(self) -> float:
        """The axis position of P51 = 0."""

    def begin_polynomial(self, end: float) -> None:
        """The first segment starts toward ``end`` (the motion's refusals first)."""

    def polynomial_finished(self) -> None: ...


__all__ = ["PolynomialMove", "Segment"]

LAST = (1114, 1115, 1116)
RELATIVE = (1112, 1115)
ABSOLUTE = (1113, 1116)


class Segment(msgspec.Struct, frozen=True):
    """One path segment of a polynomial profile (§4.6.7)."""

    end: float  # physical position (increments) where the segment ends
    speed: float  # inc/s
    accel: float  # inc/s²
    brake: float  # inc/s² (B), used by the last segment
    last: bool
    exact: float = 0.0  # the end before rounding to whole increments (no drift over segments)


class PolynomialMove:
    """The polynomial mode of one drive (§4.6.7)."""

    def __init__(
        self,
        axis: Axis,
        params: SersParameters,
        motion: PolynomialHost,
        *,
        record_error: Callable[[int], None],
        segment_ended: Callable[[], None],
    ) -> None:
        self.axis = axis
        self.params = params
        self.motion = motion
        self._record_error = record_error
        self._segment_ended = segment_ended  # a program waiting for the segment goes on
        self.definition: tuple[float, int, bool] | None = None  # value (inc), mode, last
        self.running: Segment | None = None
        self.pending: Segment | None = None
        self.closed = False  # the last segment has been given
        self._watch: Watch | None = None

    @property
    def active(self) -> bool:
        return self.running is not None

    @property
    def slot_free(self) -> bool:
        """P1123: the next segment may be sent."""
        return self.active and self.pending is None and not self.closed

    def define(self, number: int, value: float) -> None:
        """``WP=`` … ``WAPT=`` (P1111–P1116): remember the segment until its ``E``."""
        params = self.params
        if number in RELATIVE:
            params.positioning_mode = 0
        elif number in ABSOLUTE:
            params.positioning_mode = 2
        self.definition = (value, int(params.positioning_mode), number in LAST)

    def execute(self) -> str:
        """``E`` after a segment definition: ``started`` (the program goes on), ``queued``
        (the program waits until the running segment ends)."""
        params = self.params
        assert self.definition is not None
        value, mode, last = self.definition
        self.definition = None
        if float(params.backlash):
            raise SersError(107)
        if self.pending is not None or self.closed:
            raise SersError(123)
        base = self.pending.exact if self.pending is not None else (self.running.exact if self.running else None)
        if base is None:
            base = self.axis.position()
        end = value + self.motion.offset if mode == 2 else base + value
        segment = Segment(
            exact=end,
            end=float(round(end)),
            speed=float(params.velocity),
            accel=float(params.acceleration),
            brake=float(params.polynomial_deceleration),
            last=last,
        )
        if last:
            self.closed = True
        if self.running is None:
            if self.motion.moving:
                raise SersError(70)
            self.motion.begin_polynomial(segment.end)
            self._start(segment)
            return "started"
        self.pending = segment
        return "queued"

    def _start(self, segment: Segment) -> None:
        self.running = segment
        if self._watch is not None:
            self._watch.cancel()
            self._watch = None
        axis = self.axis
        here = axis.position()
        direction = (segment.end > here) - (segment.end < here)
        if segment.last:
            v = abs(axis.velocity())
            if direction == 0 or v * v / (2 * segment.brake) > abs(segment.end - here) + 1e-6:
                self._record_error(118)
                self._abort()
                return
            velocity = axis.velocity()
            slow = (v * v - segment.speed**2) / (2 * segment.accel)
            if v > segment.speed and (velocity > 0) == (direction > 0) and (
                slow + segment.speed**2 / (2 * segment.brake) <= abs(segment.end - here) + 1e-6
            ):  # to v6 with a6 first; B is the brake ramp only (§4.6.7)
                axis.jog(direction, segment.speed, segment.accel, on_done=lambda: self._brake_to_end(segment))
                return
            self._brake_to_end(segment)
            return
        if direction == 0:
            self._segment_end(0)
            return
        axis.jog(direction, segment.speed, segment.accel)
        self._watch = axis.watch(segment.end, self._segment_end)

    def _brake_to_end(self, segment: Segment) -> None:
        """The last segment (§4.6.7): on to its end at v6 and brake with B to stand there."""
        if self.running is segment:
            self.axis.move_to(segment.end, segment.speed, segment.accel, decel=segment.brake, on_done=self._finished)

    def _segment_end(self, _direction: int) -> None:
        if self._watch is not None:
            self._watch.cancel()
            self._watch = None
        if self.running is None:
            return
        pending, self.pending = self.pending, None
        if pending is not None:
            self._start(pending)
            self._segment_ended()
            return
        # nothing to go on with: brake with B and report it (errno 108)
        segment = self.running
        self.running = None
        self._record_error(108)
        self.axis.stop(segment.brake, on_done=self._finished)

    def _finished(self) -> None:
        self.running = None
        self.pending = None
        self.closed = False
        self.motion.polynomial_finished()

    def _abort(self) -> None:
        brake = self.running.brake if self.running else float(self.params.error_deceleration)
        self.axis.stop(brake, on_done=self._finished)
        self.running = None
        self.pending = None

    def cancel(self) -> None:
        """The profile ends early (S, a drive error, POS0/POSR): forget the segments."""
        if self._watch is not None:
            self._watch.cancel()
            self._watch = None
        self.running = None
        self.pending = None
        self.closed = False
        self.definition = None
