"""The power stage and the position controller's state (manual §2.2 Notaus, §3.1, §2.3.1 T3;
spec §4.2.4, §4.5.3).
"""

from __future__ import annotations

from devsim.core.signals import SignalBank

__all__ = ["PowerStage"]


class PowerStage:
    """Emergency stop, monitoring, the position controller, IDXOFF and the outputs' overload
    latch of one card: the state every motion asks about (spec §4.2.4, §4.5.3)."""

    def __init__(self, signals: SignalBank) -> None:
        self.signals = signals
        self.estop = False
        self.controller = False  # the position controller drives the motor
        self.idxoff = True  # the indexer is not ready (after power-on, a following error)
        self.nv_error = False  # the NV power-stage parameters failed their check (T3;4 I.5)
        self.brake_output = False  # A0.0 is the brake output (N21 at the last start)
        self.overload_latched = False  # 24 V outputs off until the supply is switched off

    def monitoring_cause(self) -> str:
        """The monitoring cause ('' = none), e.g. ``dc_undervoltage``."""
        return str(self.signals.get("monitoring") or "")

    def faulted(self) -> bool:
        """The stage cannot go into control: emergency stop, monitoring or an NV error."""
        return bool(self.estop or self.monitoring_cause() or self.nv_error)

    def ready(self) -> bool:
        """A move may start (spec §4.2.4): no fault, controller on, IDXOFF = 0."""
        return not (self.faulted() or not self.controller or self.idxoff)

    def switch_off(self) -> None:
        """A fault: IDXOFF, the controller off."""
        self.idxoff = True
        self.controller = False
