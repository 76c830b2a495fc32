"""The IP247's reference run, "Referenzpunkt fahren" (manual §4.2.3–§4.2.5, §2.7.5, §2.8.1;
spec ip247.md §5.6.2, §5.6.3): steps 0 … 7 driven by the reference cam (BERO) and the limit
switch inputs, one event at a time.

R is the reference direction (MD n+26).  The run leaves the cam towards R, comes back onto it at
f_ss and leaves it again in single steps; there the reference point is set (synchronous: at the
next current pattern 0).  2,500 single steps without leaving the cam: error 59; the limit in
direction R before the cam was found: error 25/26 (spec §5.6.2 [DECISION]).
"""

from __future__ import annotations

import math

from devsim.devices.ip247.axis_unit import AxisUnit

__all__ = ["ReferenceRun", "SINGLE_STEP_HZ"]

SINGLE_STEP_HZ = 100.0  # single steps off the cam: min(f_ss, 100 Hz) (spec §5.6.2 [DECISION])
CAM_STEPS = 2500  # single steps before the cam counts as defective (error 59)


class ReferenceRun:
    """One reference run of an axis; the axis forwards its cam and limit inputs here."""

    def __init__(self, unit: AxisUnit) -> None:
        md = unit.md
        assert md is not None
        self.unit, self.md = unit, md
        self.r = 1 if md.reference_direction == 0x00 else -1
        self.step = 0
        self._seen_cam = False
        self._timer = None

    def start(self) -> None:
        unit = self.unit
        unit.reference_run = self
        unit.pulse_rs()  # step 0: the RS pulse, pattern counter 0
        if self._cam():
            self._onto_cam()  # special case 3: already on the cam
        elif unit.actuated("anf" if self.r > 0 else "end"):
            self._away()  # special case 2: the limit behind is actuated
        else:
            self.step = 3
            self._jog(-self.r, self._reference_f())

    # -- inputs -------------------------------------------------------------------------------
    def cam(self, active: bool) -> None:
        if self.step == 3:
            if active:
                self._seen_cam = True
            elif self._seen_cam:
                self.unit.brake(lambda ok: self._away())  # end of cam in −R: reverse
        elif self.step == 4:
            if active:
                self._seen_cam = True
            elif self._seen_cam:
                self.step = 5
                self.unit.brake(lambda ok: self._back())
        elif self.step == 5 and active:
            self._onto_cam()
        elif self.step == 6 and not active:
            self._left_cam()

    def limit(self, name: str) -> None:
        """A limit input became actuated during the run."""
        towards_r = (name == "end") == (self.r > 0)
        if self.step == 3 and not towards_r:
            self.unit.brake(lambda ok: self._away())  # the limit in −R: reverse, no error
        elif towards_r and self.step in (3, 4, 5, 6):
            self._abort(26 if name == "end" else 25)

    # -- the steps ----------------------------------------------------------------------------
    def _cam(self) -> bool:
        return bool(self.unit.signals.get(f"BERO{self.unit.number}"))

    def _reference_f(self) -> float:
        return min(self.md.frequency(self.md.reference_velocity), float(self.md.f_max))

    def _jog(self, direction: int, f: float) -> None:
        self.unit.jog(direction, f)

    def _away(self) -> None:
        self.step, self._seen_cam = 4, self._cam()
        self._jog(self.r, self._reference_f())

    def _back(self) -> None:
        self.step = 5
        if self._cam():
            self._onto_cam()
            return
        self._jog(-self.r, float(self.md.f_ss))

    def _onto_cam(self) -> None:
        unit = self.unit
        unit.axis.quick_stop()
        self.step = 6
        rate = min(float(self.md.f_ss), SINGLE_STEP_HZ)
        unit.jog(self.r, rate)  # single steps: a constant rate at or below f_ss, no ramp
        self._timer = unit.clock.call_later(CAM_STEPS / rate, lambda: self._abort(59))

    def _left_cam(self) -> None:
        """The cam is left: at the pulse that crossed its edge; synchronous, more single steps
        in R up to the next current pattern 0 (at most patterns − 1, spec §5.6.3)."""
        unit, md = self.unit, self.md
        if self._timer is not None:
            self._timer.cancel()
        offset = (unit.axis.position() - unit.pattern_base) / md.resolution
        pulse = math.ceil(offset - 1e-9) if self.r > 0 else math.floor(offset + 1e-9)
        if md.reference_sync == 0:
            pulse += (-pulse) % md.patterns if self.r > 0 else -(pulse % md.patterns)
        self._set(unit.pattern_base + pulse * md.resolution)

    def _set(self, machine: float) -> None:
        unit = self.unit
        unit.axis.quick_stop()
        unit.axis.set_position(machine)
        unit.set_holder(self.md.reference, self.r)  # the last direction is R (spec §5.8)
        unit.reference_set = True
        unit.target = None
        self._finish(None)

    def cancel(self) -> None:
        """Stopp (or another job) aborted the run: no reference point."""
        if self._timer is not None:
            self._timer.cancel()
        self.step = 7
        self.unit.reference_run = None

    def _abort(self, error: int) -> None:
        if self._timer is not None:
            self._timer.cancel()
        self.unit.reference_set = False
        self.unit.reference_run = None
        self.unit.brake()
        self._finish(error)

    def _finish(self, error: int | None) -> None:
        unit = self.unit
        self.step = 7
        unit.reference_run = None
        if unit.running:
            unit.running = False
        unit.changed()
        if error is not None:
            unit.set_error(error)
