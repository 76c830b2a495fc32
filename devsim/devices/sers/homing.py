"""Homing of the SERS: the reference run ``H`` (manual §4.8.4.5; spec §5.5, G-HOME).

The drive seeks the reference edge at P41 (× the override P108) with P42, brakes, creeps back at
P1003 and stops exactly at the falling edge.  P147 chooses: bit 0 the direction, bit 1 a limit
switch as the reference, bit 2 then the next electrical zero, bit 3 no software limits while
homing, bit 5 the centre of the switch, bit 6 the encoder's zero pulse instead of the switch,
bit 7 the switch, then the zero pulse, then the electrical zero.  P1130 puts the reference
switch on a digital input.
"""

from __future__ import annotations

import math
from typing import Any, Protocol

from devsim.core.axis import Axis, Watch
from devsim.core.signals import SignalBank
from devsim.devices.sers.constants import ELECTRICAL_PERIOD, LIMIT
from devsim.devices.sers.errors import SersError
from devsim.devices.sers.params import SersParameters
from devsim.devices.sers.power import PowerStage

__all__ = ["Homing", "HomingMotion", "can_move"]


def can_move(speed: float, accel: float) -> None:
    """A jog, a homing run, POS0/POSR or a move's backlash legs need a speed and an acceleration
    above 0; with P108 = 0 % or a speed or ramp parameter set to 0 the motion is refused as V or
    A too small [SIM-CHOICE: the manual does not say what the drive does; it cannot move, and
    the simulator must not fail]."""
    if not speed > 0:
        raise SersError(121)
    if not accel > 0:
        raise SersError(119)


class HomingMotion(Protocol):
    """What a homing run (§4.8.4.5) needs of the motion (:class:`~.motion.Motion`)."""

    def checks(self, direction: int) -> None:
        """The refusals of a motion toward ``direction`` (limit, STOP, I7, power)."""

    def begin(self, kind: str, decel: float) -> None:
        """A motion of ``kind`` starts (stopped by S with ``decel``)."""

    def arm_watches(self, keep: bool = False) -> None:
        """Software limits, compare positions and standstill monitoring for the motion."""

    def home_reached(self) -> None:
        """The axis stands at the reference: P51 := 0, the motion ends."""


class Homing:
    """The reference run of one SERS (§4.8.4.5)."""

    def __init__(
        self, axis: Axis, params: SersParameters, signals: SignalBank, power: PowerStage, motion: HomingMotion
    ) -> None:
        self.axis = axis
        self.params = params
        self.signals = signals
        self.power = power
        self.motion = motion
        #: A homing run (H) has completed since power-on (P403).
        self.homed = False
        self._run: dict[str, Any] | None = None  # signal, direction, phase, p147, creep, accel
        self._index_watches: list[Watch] = []

    @property
    def phase(self) -> str | None:
        """The phase of the run under way (seek, braking, creep, measure, centre, to_index,
        edge, reset), or None."""
        return self._run["phase"] if self._run else None

    def cancel(self) -> None:
        """The run is over (the motion ended, S, a drive error, power off or on): its phase and
        its zero-pulse watches go, so no switch edge or index mark continues it later."""
        self._run = None
        for watch in self._index_watches:
            watch.cancel()
        self._index_watches = []

    def home(self, moving: bool) -> None:
        """H (§4.8.4.5, spec §5.5): seek the reference edge at P41, creep back at P1003."""
        if moving:
            raise SersError(70)
        params = self.params
        p147 = int(params.homing_parameters)
        direction = -1 if p147 & 1 else 1
        if p147 & 2:
            signal = "limit_left" if direction < 0 else "limit_right"
            if self.signals.get("stop"):
                raise SersError(68)
            if not self.power.energized or self.power.errors & ~LIMIT:
                raise SersError(79)
        else:
            signal = "index" if p147 & 64 and not p147 & 128 else "reference"
            self.motion.checks(0)
        accel = float(params.homing_acceleration)
        can_move(float(params.homing_velocity) * float(params.feedrate_override) / 100, accel)
        can_move(float(params.homing_velocity_slow), accel)
        # (creep speed and ramp as at the start: a write during the run cannot stop it midway)
        self._run = {"signal": signal, "direction": direction, "phase": "seek", "p147": p147,
                     "creep": float(params.homing_velocity_slow), "accel": accel}
        self.motion.begin("home", accel)
        if signal == "index":
            self._index_watches.append(self.axis.watch_index(self._on_index))
        if signal != "index" and self._signal_active():
            self._creep()
        else:
            speed = float(params.homing_velocity) * float(params.feedrate_override) / 100
            self.axis.jog(direction, speed, accel)
            self.motion.arm_watches(keep=True)

    def reference_active(self) -> bool:
        """The drive stands on the reference switch: the reference input, or the digital input
        P1130 names -- that one with a signal, or with P147 bit 4 ("invertiert, Eingang Öffner
        (kein Signal = Antrieb steht auf Referenzschalter)", §4.8.4.5) without one.  (The
        reference input itself is the switch's state, not its wiring: see the deviations.)"""
        selector = int(self.params.reference_input)
        if selector:
            signal = bool(self.signals.get(f"I{selector}"))
            return not signal if int(self.params.homing_parameters) & 16 else signal
        return bool(self.signals.get("reference"))

    def edge(self, signal: str, active: bool) -> bool:
        """A switch changed: True if it was the one this run seeks (and the run took it)."""
        run = self._run
        if run is None or run["signal"] != signal:
            return False
        self._edge(active)
        return True

    def _signal_active(self) -> bool:
        assert self._run is not None
        if self._run["signal"] == "reference":
            return self.reference_active()
        return bool(self.signals.get(self._run["signal"]))

    def _creep(self) -> None:
        assert self._run is not None
        self._run["phase"] = "creep"
        self.axis.jog(-self._run["direction"], self._run["creep"], self._run["accel"])

    def _on_index(self, _direction: int) -> None:
        """Encoder zero pulse (once per motor revolution) during homing with P147 bit 6/7."""
        run = self._run
        if run is None:
            return
        if run["signal"] == "index":
            self._edge(run["phase"] == "seek")
        elif run["phase"] == "to_index":
            run["phase"] = "edge"
            self.axis.quick_stop()
            self._electrical_reset()

    def _edge(self, active: bool) -> None:
        run = self._run
        if run is None:
            return
        phase, p147 = run["phase"], run["p147"]
        if phase == "seek" and active:
            run["phase"] = "braking"
            self.axis.stop(run["accel"], on_done=self._creep)
        elif phase == "creep" and not active:
            # G-HOME: at creep speed the drive stops exactly at the falling edge
            if p147 & 32 and run["signal"] == "reference":
                run["phase"] = "measure"
                self.axis.quick_stop()
                run["first_edge"] = self.axis.position()
                self.axis.jog(run["direction"], run["creep"], run["accel"])
            elif p147 & 128:
                run["phase"] = "to_index"  # keep creeping to the next zero pulse
                self._index_watches.append(self.axis.watch_index(self._on_index))
            else:
                run["phase"] = "edge"
                self.axis.quick_stop()
                self._electrical_reset()
        elif phase == "measure" and not active:
            run["phase"] = "centre"
            self.axis.quick_stop()
            centre = (run["first_edge"] + self.axis.position()) / 2
            self.axis.move_to(centre, run["creep"], run["accel"], on_done=self._done)

    def _electrical_reset(self) -> None:
        """P147 bit 2/7: move on to the next electrical zero (every 256 increments)."""
        run = self._run
        assert run is not None
        if not run["p147"] & (4 | 128):
            self._done()
            return
        here = self.axis.position()
        if -run["direction"] > 0:
            target = math.ceil(here / ELECTRICAL_PERIOD - 1e-9) * ELECTRICAL_PERIOD
        else:
            target = math.floor(here / ELECTRICAL_PERIOD + 1e-9) * ELECTRICAL_PERIOD
        run["phase"] = "reset"
        self.axis.move_to(target, run["creep"], run["accel"], on_done=self._done)

    def _done(self) -> None:
        self.homed = True
        self.motion.home_reached()
