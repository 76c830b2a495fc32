"""The position supervision of CiA 402's profile position mode (CiA 402-2, position control
function and profile position mode: 6065h following error window, 6066h following error time out,
6067h position window, 6068h position window time, and the statusword bits they make).

Bit 13, following error: 1 once the following error (60F4h, position demand value − position
actual value, the drive's ``DriveActions.following_error``) has stayed outside ±6065h for the
following error time out (6066h, ms), in Operation enabled; 0 again as soon as it is back within
the window.  A following error window of FFFFFFFFh switches the check off ("the following control
shall be switched off"): bit 13 stays 0.  That is the power-on value, so a master that does not
write 6065h sees bit 13 as the node showed it before it had the object.

Bit 10, target reached (halt = 0): "if the actual value of the position encoder is within the
position window for the position window time, the target position is regarded as having been
reached": :meth:`PositionWatch.reached` says whether the position actual value (6064h) has stayed
within ±6067h of the target of the last positioning for 6068h ms, one condition of
:mod:`devsim.facades.cia402_position`'s bit (the axis standing and no set-point waiting are the
others).  A position window of FFFFFFFFh switches that control off, and the bit is the
positioning's own end as before the node had the object (the power-on value).

Looked at as :mod:`devsim.facades.cia402_velocity` looks at the velocity
(:mod:`devsim.facades.cia402_looks`): on the device clock every :data:`SAMPLE` while the position
or the following error changes and for :data:`QUIET` after it stopped changing or after any
command, when a time (6066h, 6068h) is set; with both times 0 the bits are the comparison at the
instant they are read.  Every read of the statusword looks again.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from devsim.facades.cia402_looks import QUIET, SAMPLE, Looks, held, since

__all__ = ["FOLLOWING_ERROR", "OFF", "PositionWatch", "QUIET", "SAMPLE"]

FOLLOWING_ERROR = 0x2000
OFF = 0xFFFF_FFFF  # 6065h / 6067h: the control switched off (CiA 402-2)


class PositionWatch:
    """6065h … 6068h and the statusword bits 10 (its window part) and 13 they make.  ``sample``
    gives (position actual value, the target of the last positioning or ``None`` before the
    first, the following error or ``None`` outside Operation enabled) in profile position mode,
    ``None`` in any other; positions as 6064h and 60F4h show them."""

    def __init__(self, clock: Any, sample: Callable[[], tuple[int, float | None, int | None] | None],
                 defaults: dict[str, int]) -> None:
        self.clock, self._sample, self._defaults = clock, sample, defaults
        self._looks = Looks(clock, self.look)
        self.reset()

    def reset(self) -> None:
        """The power-on values of 6065h … 6068h, nothing looked at yet."""
        self.following_window = self._defaults["following_error_window"]  # 6065h, position units
        self.following_time = self._defaults["following_error_time_out"]  # 6066h, ms
        self.window = self._defaults["position_window"]  # 6067h, position units
        self.window_time = self._defaults["position_window_time"]  # 6068h, ms
        self._forget()

    def _forget(self) -> None:
        self._looks.forget()
        self._in_window_since: float | None = None
        self._error_since: float | None = None
        self._goal: float | None = None  # the target the window time counts for

    def set(self, name: str, value: int) -> None:
        """Write one of the four objects (``following_window``, ``following_time``, ``window``,
        ``window_time``)."""
        setattr(self, name, int(value))
        self.look(command=True)

    def look(self, command: bool = False) -> None:
        """Compare the position with the window and the following error with its window now; a
        ``command`` (a write that may start a positioning) restarts the looks."""
        now = self.clock.now()
        values = self._sample()
        if values is None:
            self._forget()
            return
        position, goal, error = values
        if goal != self._goal:  # (another target: its window time counts from now)
            self._goal, self._in_window_since = goal, None
        inside = goal is not None and self.window != OFF and abs(position - goal) <= self.window
        self._in_window_since = since(self._in_window_since, now, inside)
        outside = error is not None and self.following_window != OFF and abs(error) > self.following_window
        self._error_since = since(self._error_since, now, outside)
        self._looks.after((position, error), now, command=command,
                          timed=bool(self.window_time or self.following_time))

    def cancel(self) -> None:
        self._looks.cancel()

    def reached(self) -> bool | None:
        """Whether the position actual value has stayed within the position window of the target
        for the position window time (as of the last look); ``None`` with the window switched off."""
        if self.window == OFF:
            return None
        return held(self._in_window_since, self.clock.now(), self.window_time)

    def bits(self) -> int:
        """Bit 13 of the statusword as of now (looking first)."""
        self.look()
        return FOLLOWING_ERROR if held(self._error_since, self.clock.now(), self.following_time) else 0
