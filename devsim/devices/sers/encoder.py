"""The SERS's encoder and load-angle monitoring: step loss, its reaction and the automatic POSR
(manual §4.8.6.6; spec §5.9).

The stator field is the axis; the rotor lags behind it by the steps lost while the load stalls
it.  With an encoder (P1053 = 4, or 8 with option E50) and P1029 ≠ 0 a load angle beyond P1002
is a step loss: P1029 1 = drive error, 2 = warning, 3 = error with the motor kept on; P1138 /
P1139 retry with POSR.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Protocol

from devsim.core.axis import Axis, Watch
from devsim.core.clock import Clock, Timer
from devsim.devices.sers.constants import STEP_LOSS
from devsim.devices.sers.errors import SersError
from devsim.devices.sers.params import SersParameters
from devsim.devices.sers.power import PowerStage

__all__ = ["Retry", "StepMonitor"]


class Retry(Protocol):
    """What the step-loss reaction (§4.8.6.6) needs of the motion (:class:`~.motion.Motion`)."""

    @property
    def moving(self) -> bool: ...

    def stop_motion(self) -> None: ...

    def posr(self, force: bool) -> None: ...

    def out_of_position(self) -> None:
        """POS (P336) = 0 until the retry has brought the motor back."""


class StepMonitor:
    """Where the rotor is, and what a step loss does (§4.8.6.6)."""

    def __init__(
        self,
        clock: Clock,
        axis: Axis,
        params: SersParameters,
        power: PowerStage,
        motion: Retry,
        *,
        has_option_e50: Callable[[], bool],
    ) -> None:
        self.clock = clock
        self.axis = axis
        self.params = params
        self.power = power
        self.motion = motion
        self._has_option_e50 = has_option_e50
        self.lost = 0.0  # increments the rotor lags behind the stator field (step loss)
        self.max_load_angle = 0.0  # P1057
        self._stall_rotor: float | None = None  # where the stalled rotor stands
        self._load_watches: list[Watch] = []
        self._attempts = 0  # automatic POSR attempts (P1138)
        self._timers: list[Timer] = []

    def power_on(self) -> None:
        self.cancel()
        self.lost = 0.0
        self._stall_rotor = None
        self._drop_load_watches()
        self._attempts = 0
        self.max_load_angle = 0.0

    def cancel(self) -> None:
        for timer in self._timers:
            timer.cancel()
        self._timers.clear()

    def _drop_load_watches(self) -> None:
        """The load-angle watches go (cancelled on the axis: none fires later)."""
        for watch in self._load_watches:
            watch.cancel()
        self._load_watches = []

    def encoder_position(self) -> float:
        """Where the rotor really is (increments): the stator field minus the steps lost."""
        if self._stall_rotor is not None:
            return self._stall_rotor
        return self.axis.position() - self.lost

    def load_angle(self) -> float:
        return self.axis.position() - self.encoder_position()

    def _monitoring(self) -> bool:
        mode = int(self.params.pulse_input)
        encoder = mode == 4 or (mode == 8 and self._has_option_e50())
        return encoder and int(self.params.step_monitoring) != 0

    def stall(self, stalled: bool) -> None:
        """The load stalls the rotor (True) or lets it go."""
        if stalled:
            self._stall_rotor = self.axis.position() - self.lost
            self._arm_load_watch()
        elif self._stall_rotor is not None:
            self.lost = self.axis.position() - self._stall_rotor
            self._stall_rotor = None
            self._drop_load_watches()

    def _arm_load_watch(self) -> None:
        self._drop_load_watches()
        if self._stall_rotor is None or not self._monitoring():
            return
        window = float(self.params.load_angle_window)
        rotor = self._stall_rotor
        for where in (rotor + window, rotor - window):
            self._load_watches.append(self.axis.watch(where, lambda _d: self._step_loss()))

    def _step_loss(self) -> None:
        """The load angle exceeded P1002: P1029 1 = drive error, 2 = warning, 3 = error, motor on."""
        self.max_load_angle = max(self.max_load_angle, abs(self.load_angle()))
        params = self.params
        reaction = int(params.step_monitoring)
        if reaction == 2:
            self.power.warn(STEP_LOSS)
            self.motion.stop_motion()
        elif reaction in (1, 3):
            self.power.drive_error(STEP_LOSS)
        retries = int(params.posr_attempts)
        if retries and self._attempts < retries:
            self._attempts += 1
            delay = float(params.posr_wait) * 0.1
            self.motion.out_of_position()
            self._timers.append(self.clock.call_later(delay, self._auto_posr))

    def _auto_posr(self) -> None:
        """P1138/P1139: automatic POSR after a step loss."""
        if self.motion.moving:
            self._timers.append(self.clock.call_later(0.01, self._auto_posr))
            return
        self.power.clear_error(STEP_LOSS)
        self.power.energize()
        try:
            self.motion.posr(force=True)
        except SersError as exc:
            self.power.record_error(exc.errno)

    def retried(self) -> None:
        """A POSR reached its target: with P1140 bit 1 the attempts count afresh."""
        if int(self.params.posr_mode) & 2:
            self._attempts = 0

    def resync(self) -> None:
        """Clearing a step loss: P51 takes the encoder's position (§4.8.6.6)."""
        if self.axis.moving:
            return
        rotor = self.encoder_position()
        if self._stall_rotor is None:
            self.lost = 0.0
        if rotor != self.axis.position():
            self.axis.set_position(rotor)
            if self._stall_rotor is not None:
                self._arm_load_watch()
