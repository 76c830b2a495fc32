"""The velocity supervision of CiA 402's profile velocity mode (CiA 402-2, profile velocity mode:
the statusword's mode-specific bits and the objects that define them).

Bit 10, target reached: with halt (controlword bit 8) = 0, 1 once the velocity actual value (606Ch)
has stayed within the velocity window (606Dh) of the target velocity (60FFh) for the velocity
window time (606Eh, ms); with halt = 1 the axis decelerates to 0, and the bit is 1 once it has
stayed within the window of 0 that long.  Bit 12, speed: 0 ("speed is not 0") once the velocity
actual value has stayed above the velocity threshold (606Fh) for the velocity threshold time
(6070h, ms), else 1 ("speed is 0"): it returns to 1 as soon as the velocity is below the threshold.
The velocity is the drive's own (its ``DriveActions.velocity``, rounded as 606Ch shows it).

The times count from when the condition began, looked at (:mod:`devsim.facades.cia402_looks`) on the device clock every
:data:`SAMPLE` while the velocity changes (a ramp, a servo ringing around its velocity) and for
:data:`QUIET` after it stopped changing or after any command; at a constant velocity nothing
changes by itself, so the looks stop and cost nothing.  With both times 0 (their power-on values)
the bits are the comparison at the instant they are read, and nothing is looked at in between.
Every read of the statusword looks again (a velocity that changed without a command
of the node, at a limit switch say, is seen at the next read, or within 10 ms by an event-driven
TPDO carrying the statusword).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from devsim.facades.cia402_looks import QUIET, SAMPLE, Looks, held, since

__all__ = ["QUIET", "SAMPLE", "SPEED_IS_0", "TARGET_REACHED", "VelocityWatch"]

TARGET_REACHED, SPEED_IS_0 = 0x0400, 0x1000


class VelocityWatch:
    """606Dh … 6070h and the statusword bits 10 and 12 they make.  ``sample`` gives (velocity
    actual value, the velocity demanded) in profile velocity mode, ``None`` in any other."""

    def __init__(self, clock: Any, sample: Callable[[], tuple[float, float] | None],
                 defaults: dict[str, int]) -> None:
        self.clock, self._sample, self._defaults = clock, sample, defaults
        self._looks = Looks(clock, self.look)
        self.reset()

    def reset(self) -> None:
        """The power-on values of 606Dh … 6070h, nothing looked at yet."""
        self.window = self._defaults["velocity_window"]  # 606Dh, velocity units
        self.window_time = self._defaults["velocity_window_time"]  # 606Eh, ms
        self.threshold = self._defaults["velocity_threshold"]  # 606Fh, velocity units
        self.threshold_time = self._defaults["velocity_threshold_time"]  # 6070h, ms
        self._forget()

    def _forget(self) -> None:
        self._looks.forget()
        self._in_window_since: float | None = None
        self._above_since: float | None = None

    def set(self, name: str, value: int) -> None:
        """Write one of the four objects (``window``, ``window_time``, ``threshold``, ``threshold_time``)."""
        setattr(self, name, int(value))
        self.look(command=True)

    def look(self, command: bool = False) -> None:
        """Compare the velocity with the window and the threshold now; a ``command`` (a write that
        may change the demand or the velocity) restarts the looks."""
        now = self.clock.now()
        pair = self._sample()
        if pair is None:
            self._forget()
            return
        velocity, demand = pair
        shown = round(velocity)
        self._in_window_since = since(self._in_window_since, now, abs(shown - demand) <= self.window)
        self._above_since = since(self._above_since, now, abs(shown) > self.threshold)
        self._looks.after(velocity, now, command=command, timed=bool(self.window_time or self.threshold_time))

    def cancel(self) -> None:
        self._looks.cancel()

    def bits(self) -> int:
        """Bits 10 and 12 of the statusword as of now."""
        self.look()
        now, word = self.clock.now(), 0
        if held(self._in_window_since, now, self.window_time):
            word |= TARGET_REACHED
        if not held(self._above_since, now, self.threshold_time):
            word |= SPEED_IS_0
        return word
