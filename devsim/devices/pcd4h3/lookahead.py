"""The PLC cycles a moving axis does not need (issue 31, "schedule timers only for events"; spec
pcd4h3.md §3.3.2, §9.6.1): while the axes only move, with no command flag, user program or
cyclic read to run, a cycle of AxHndlg copies the chips' status into the status flags, which is
the same status as before until the chip reports something (the trajectory complete, a
breakpoint, the index, a wrap-around, a position error, the motor off); and the shared axis
follows the motor, which only matters where a switch is near.

:func:`quiet_cycles` computes the moving chips ahead, cycle by cycle, up to the first cycle
that would see a change (or a horizon), and returns the cycles in between: the PLC skips them.
A look in between sees the chip of the present (the stepper keeps a checkpoint at each cycle,
:meth:`~devsim.devices.pcd4h3.stepper.ChipStepper.ahead`); a command ends the look-ahead.
"""

from __future__ import annotations

from collections.abc import Sequence

from devsim.devices.pcd4h3.drive import STILL, H3Drive

__all__ = ["HORIZON", "quiet_cycles", "switch_near"]

HORIZON = 0.2  # seconds of device time computed ahead at most (one pass: about 600 samples)
MARGIN = 1.0  # counts either side of a switch edge that count as near


def _may_look_ahead(drive: H3Drive) -> bool:
    chip = drive.chip
    return drive.settled or (not chip.profile.complete and not chip.motor_off)


def switch_near(drive: H3Drive, first: float, second: float) -> bool:
    """Whether a switch edge of ``drive`` lies between motor positions ``first`` and ``second``
    (or within the margin of them)."""
    low, high = min(first, second) - MARGIN, max(first, second) + MARGIN
    return any(low <= edge <= high for switch in drive.switches for edge in (switch.low, switch.high))


def quiet_cycles(drives: Sequence[H3Drive], first: float, step: float) -> list[float]:
    """The cycles from ``first`` on (every ``step``) that would find the status of every chip
    unchanged and no switch near: their chips computed ahead, the list of their times."""
    moving = [drive for drive in drives if not drive.settled]
    if not moving or not all(_may_look_ahead(drive) for drive in moving):
        return []
    statuses = [drive.chip.status for drive in moving]
    last = [drive.motor.position for drive in moving]
    quiet: list[float] = []
    t, end = first, first + HORIZON
    while t <= end:
        following = t + step
        for index, drive in enumerate(moving):
            drive.stepper.ahead(t)
            if drive.chip.status != statuses[index]:
                return quiet
            if drive.switches:
                x, v = drive.motor.position, drive.motor.velocity
                v = v if abs(v) > STILL else 0.0
                if (switch_near(drive, last[index], x) or switch_near(drive, x, x + v * step)
                        or switch_near(drive, drive.axis.position(t), drive.axis.position(following))):
                    return quiet
                last[index] = x
        quiet.append(t)
        t = following
    return quiet
