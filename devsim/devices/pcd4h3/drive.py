"""One axis of the installation as hardware (spec pcd4h3.md §2.3–§2.6, §5.4, §5.9, §5.10): the
LM628/LM629 with its motor and encoder on the device clock, the shared axis the motor moves, and
the limit and reference switches at their places on it.

The chip's samples run in batches (:class:`~devsim.devices.pcd4h3.stepper.ChipStepper`); after
each batch the shared :class:`~devsim.core.axis.Axis` passes through the motor's position at the
moment of the batch's last sample, at its velocity, so the switches
(:class:`~devsim.core.axis.RegionSwitch`) change where the motor really is.  The
limit switches are normally closed (input 1 = 24 V, healthy; G-15), the reference switch closes
on its region; the module only passes them to the PLC (§2.6).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

from devsim.core.axis import Axis, RegionSwitch
from devsim.core.clock import Clock
from devsim.core.signals import SignalBank
from devsim.devices.pcd4h3.lm628 import Lm628
from devsim.devices.pcd4h3.pid import Motor
from devsim.devices.pcd4h3.stepper import ChipStepper
from devsim.devices.pcd4h3.units import CHIP_SAMPLE

__all__ = ["H3Drive", "axis_signals"]

STILL = 1e-3  # counts/s below which the shared axis stands


def axis_signals(n: int) -> tuple[tuple[str, str, Any, str], ...]:
    """(name, kind, initial, doc) of axis n's signals."""
    return (
        (f"LS1_{n}", "input", True, f"axis {n} limit switch LS1 (NC: True = 24 V, not at the limit)"),
        (f"LS2_{n}", "input", True, f"axis {n} limit switch LS2 (NC: True = 24 V, not at the limit)"),
        (f"REF_{n}", "input", False, f"axis {n} reference switch / index input terminal 4/12"),
        (f"LED_LS1_{n}", "output", False, f"axis {n} LED LS1: LS1 open, LS2 closed"),
        (f"LED_LS2_{n}", "output", False, f"axis {n} LED LS2: LS2 open, LS1 closed"),
        (f"LED_STOP_{n}", "output", False, f"axis {n} LED STOP: both limit switches open"),
    )


class H3Drive:
    """Axis ``number``: chip, motor, encoder, the shared axis, the switches."""

    def __init__(self, number: int, clock: Clock, signals: SignalBank, settings: Mapping[str, Any], *,
                 lm629: bool, rs422: bool, present: bool, jumpers: Mapping[str, Any] | None = None,
                 host_interrupt: bool = False, sample_time: float = CHIP_SAMPLE) -> None:
        self.number, self.signals, self.clock = number, signals, clock
        stops = settings.get("hard_stops")
        low, high = (float(min(stops)), float(max(stops))) if stops else (-math.inf, math.inf)
        self.motor = Motor(kv=float(settings["kv"]), tau=float(settings["tau_ms"]) / 1000, low=low, high=high)
        lines = int(settings["encoder_lines"])
        # the index reaches the decoder through the D-Sub (5 V types) or terminal 4/12 with IN/RP = IN
        index_period = 4 * lines if rs422 or settings["in_rp"] == "index" else 0
        jumpers = jumpers or {}
        # one phase the wrong way round: the decoder counts backwards
        encoder_sign = -1 if jumpers.get("invert_a", True) != jumpers.get("invert_b", True) else 1
        if jumpers.get("index_invert", False) and (index_period or not rs422):
            # A = B = ĪN = 0 once per line: a capture at the next line; with IN/RP = RP the 24 V decoder's
            # index input rests at 0 through the inverter: the same malfunction (manual §6.4, "Wichtig")
            index_period = 4
        self.chip = Lm628(self.motor, lm629=lm629, present=present, encoder_sign=encoder_sign,
                          index_period=index_period, index_offset=int(settings["index_offset"]),
                          host_interrupt=host_interrupt, sample_time=sample_time)
        self.stepper = ChipStepper(self.chip, clock, own_timer=False, on_batch=self._follow)
        self.axis = Axis(clock, counts_per_rev=4 * lines, index_offset=float(settings["index_offset"]),
                         name=f"axis{number}")
        self.switches: list[RegionSwitch] = []
        self._switch(settings.get("ls1"), lambda p: (-math.inf, p), f"LS1_{number}", closed_inside=False)
        self._switch(settings.get("ls2"), lambda p: (p, math.inf), f"LS2_{number}", closed_inside=False)
        ref = settings.get("ref_switch")
        if ref:
            self._switch(ref, lambda r: (float(min(r)), float(max(r))), f"REF_{number}", closed_inside=True)
        for name in (f"LS1_{number}", f"LS2_{number}"):
            signals.subscribe(name, lambda *_: self._leds())
        self._leds()

    def _switch(self, where: Any, region: Any, signal: str, *, closed_inside: bool) -> None:
        if where is None:
            return
        low, high = region(where)

        def changed(active: bool) -> None:
            self.signals.set(signal, active == closed_inside)

        switch = RegionSwitch(self.axis, low, high, changed)
        self.switches.append(switch)
        self.signals.set(signal, switch.active == closed_inside)

    def _leds(self) -> None:
        n, get = self.number, self.signals.get
        ls1, ls2 = get(f"LS1_{n}"), get(f"LS2_{n}")
        self.signals.set(f"LED_LS1_{n}", not ls1 and ls2)
        self.signals.set(f"LED_LS2_{n}", ls1 and not ls2)
        self.signals.set(f"LED_STOP_{n}", not ls1 and not ls2)

    def _follow(self) -> None:
        """The shared axis through the motor's position at the moment of the chip's last sample
        (:attr:`ChipStepper.moment`, which a PLC function's look puts up to a cycle ahead of the
        clock), at its velocity: a switch changes where the motor is, not where it will be."""
        velocity = self.motor.velocity
        velocity = velocity if abs(velocity) > STILL else 0.0
        self.axis.track(self.motor.position - velocity * (self.stepper.moment - self.clock.now()), velocity)

    def catch_up(self, until: float | None = None, *, follow: bool = True) -> None:
        self.stepper.catch_up(until, follow=follow)

    def poke(self) -> None:
        """Something changed the chip or the motor: sample until it settles again."""
        self.stepper.poke()

    @property
    def settled(self) -> bool:
        return self.stepper.settled

    def close(self) -> None:
        for switch in self.switches:
            switch.cancel()
        self.axis.quick_stop()  # no plan left: no timers of the shared axis outlive the device
