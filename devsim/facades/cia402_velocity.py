"""The velocity supervision of CiA 402's profile velocity mode (CiA 402-2, profile velocity mode:
the statusword's mode-specific bits and the objects that define them).

Bit 10, target reached: with halt (controlword bit 8) = 0, 1 once the velocity actual value (606Ch)
has stayed within the velocity window (606Dh) of the target velocity (60FFh) for the velocity
window time (606Eh, ms); with halt = 1 the axis decelerates to 0, and the bit is 1 once it has
stayed within the window of 0 that long.  Bit 12, speed: 0 ("speed is not 0") once the velocity
actual value has stayed above the velocity threshold (606Fh) for the velocity threshold time
(6070h, ms), else 1 ("speed is 0"): it returns to 1 as soon as the velocity is below the threshold.
The velocity is the drive's own (its ``DriveActions.velocity``, rounded as 606Ch shows it).

The times count from when the condition began, looked at on the device clock every
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

__all__ = ["QUIET", "SAMPLE", "SPEED_IS_0", "TARGET_REACHED", "VelocityWatch"]

SAMPLE = 0.001  # s of device time between looks while the velocity changes (the window times are in ms)
QUIET = 0.1  # s without a change of the velocity after which the looks stop
TARGET_REACHED, SPEED_IS_0 = 0x0400, 0x1000
_EPSILON = 1e-9  # (sums of SAMPLE steps on the clock)


class VelocityWatch:
    """606Dh … 6070h and the statusword bits 10 and 12 they make.  ``sample`` gives (velocity
    actual value, the velocity demanded) in profile velocity mode, ``None`` in any other."""

    def __init__(self, clock: Any, sample: Callable[[], tuple[float, float] | None],
                 defaults: dict[str, int]) -> None:
        self.clock, self._sample, self._defaults = clock, sample, defaults
        self._timer: Any = None
        self.reset()

    def reset(self) -> None:
        """The power-on values of 606Dh … 6070h, nothing looked at yet."""
        self.cancel()
        self.window = self._defaults["velocity_window"]  # 606Dh, velocity units
        self.window_time = self._defaults["velocity_window_time"]  # 606Eh, ms
        self.threshold = self._defaults["velocity_threshold"]  # 606Fh, velocity units
        self.threshold_time = self._defaults["velocity_threshold_time"]  # 6070h, ms
        self._in_window_since: float | None = None
        self._above_since: float | None = None
        self._last: tuple[float, float] | None = None  # (the velocity looked at last, when it last changed)

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
            self.cancel()
            self._in_window_since = self._above_since = self._last = None
            return
        velocity, demand = pair
        shown = round(velocity)
        inside, above = abs(shown - demand) <= self.window, abs(shown) > self.threshold
        self._in_window_since = (self._in_window_since if self._in_window_since is not None else now) if inside \
            else None
        self._above_since = (self._above_since if self._above_since is not None else now) if above else None
        if command or self._last is None or velocity != self._last[0]:
            self._last = (velocity, now)
        if (self.window_time or self.threshold_time) and now - self._last[1] < QUIET:
            if self._timer is None:
                self._timer = self.clock.call_later(SAMPLE, self._tick)
        else:
            self.cancel()

    def _tick(self) -> None:
        self._timer = None
        self.look()

    def cancel(self) -> None:
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None

    def bits(self) -> int:
        """Bits 10 and 12 of the statusword as of now."""
        self.look()
        now, word = self.clock.now(), 0
        since = self._in_window_since
        if since is not None and now - since >= self.window_time / 1000 - _EPSILON:
            word |= TARGET_REACHED
        since = self._above_since
        if since is None or now - since < self.threshold_time / 1000 - _EPSILON:
            word |= SPEED_IS_0
        return word
