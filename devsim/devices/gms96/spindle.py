"""The spindle simulation ``Q8`` (manual §2.3.1 Q; spec §3.8.14, §5.12).

``Q8;P2;P3``: P2 selects the function (:data:`SPINDLE_FUNCTIONS`), P3 the speed (0..0x3EFFFF
inc/s, or from 0x3F0000 on a speed from the pulses on the counter input's reference track, each
pulse the distance in P3's low word).  While the spindle turns the card shows motion but not
BUSY.
"""

from __future__ import annotations

from collections.abc import Callable

from devsim.core.kit import Command, Table
from devsim.devices.gms96.motion import Indexer
from devsim.devices.gms96.params import NParameters

__all__ = ["SPINDLE_FUNCTIONS", "Spindle"]

PULSE_SPEED = 0x3F0000  # P3 from here on: the speed comes from the reference-track pulses
MAX_SPEED = 0x3EFFFF


class Spindle:
    """The spindle simulation of one card (spec §5.12): an endless run of the indexer."""

    def __init__(
        self, indexer: Indexer, params: NParameters, pulse_hz: Callable[[], float], changed: Callable[[], None]
    ) -> None:
        self.indexer = indexer
        self.params = params
        self.pulse_hz = pulse_hz
        self.changed = changed
        self.on = False
        #: The distance of one reference-track pulse (P3 >= 0x3F0000), or None.
        self.pulse_distance: int | None = None

    def run(self, p2: int, p3: int) -> None:
        """``Q8;P2;P3``."""
        if p3 >= PULSE_SPEED:
            self.pulse_distance = p3 & 0xFFFF
            speed = self.pulse_hz() * self.pulse_distance
        else:
            self.pulse_distance = None
            speed = float(min(p3, MAX_SPEED))
        handler = SPINDLE_FUNCTIONS.get(str(p2))
        if handler is not None:
            handler(self, speed)
        self.changed()

    def _turn(self, speed: float, direction: int) -> None:
        self.indexer.spindle_speed = speed
        self.on = True
        if self.params.motor_inverted == 1:
            direction = -direction
        self.indexer.run(direction, "spindle")

    def clockwise(self, speed: float) -> None:
        self._turn(speed, 1)

    def counter_clockwise(self, speed: float) -> None:
        self._turn(speed, -1)

    def stop(self, speed: float) -> None:
        self.on = False
        self.indexer.halt()

    def set_speed(self, speed: float) -> None:
        self.indexer.spindle_speed = speed
        self.indexer.replan()

    def pulse_rate_changed(self) -> None:
        """The reference-track pulse rate changed: a pulse-derived speed follows it."""
        if self.on and self.pulse_distance:
            self.indexer.spindle_speed = self.pulse_hz() * self.pulse_distance
            self.indexer.replan()


#: ``Q8;P2`` (spec §5.12); any other P2 only takes the speed's source.
SPINDLE_FUNCTIONS: Table[Callable[[Spindle, float], None]] = Table(
    [
        Command("3", Spindle.clockwise, "§2.3.1 Q", "motor clockwise at P3"),
        Command("4", Spindle.counter_clockwise, "§2.3.1 Q", "motor counter-clockwise at P3"),
        Command("5", Spindle.stop, "§2.3.1 Q", "stop the spindle"),
        Command("8", Spindle.set_speed, "§2.3.1 Q", "only a new speed from P3"),
    ]
)
