"""The PLC cycles a moving axis does not need at their time (issue 31, "schedule timers only
for events"; spec pcd4h3.md §3.3.2, §9.6.1): while the axes only move, with no command flag and
no user program waiting on a condition or a timer, a cycle of AxHndlg copies the chips' status
into the status flags, which stays the same until the chip reports something (the trajectory
complete, a breakpoint, the index, a wrap-around, a position error, the motor off), and runs the
cyclic reads (registers, the display), which only a host sees; and the shared axis follows the
motor, which only matters where a switch is near.

:func:`quiet_cycles` computes each moving chip ahead in one pass, up to the first cycle that
would see a change (or its reach, which the PLC doubles from :data:`FIRST_HORIZON` up to
:data:`HORIZON` while nothing ends a look-ahead early), and returns the cycles in between: the PLC
does not wake for them.  A look in between sees the chip of the present (the stepper keeps a
checkpoint at each cycle's last look, :meth:`~devsim.devices.pcd4h3.stepper.ChipStepper.ahead`,
and computes an earlier moment from the one before)
and, where the skipped cycles
read the chips, the PLC runs their reads first, each at its moment (``Pcd4._materialize``); a
command or a host's write ends the skipping.
"""

from __future__ import annotations

from collections.abc import Sequence

from devsim.devices.pcd4h3 import batch
from devsim.devices.pcd4h3.drive import STILL, H3Drive

__all__ = ["FIRST_HORIZON", "HORIZON", "quiet_cycles", "switch_near"]

HORIZON = 0.8  # seconds of device time computed ahead at most (one pass: about 2,300 samples)
FIRST_HORIZON = 0.05  # after a command or a host's write ended a look-ahead early: it doubles from here
MARGIN = 1.0  # counts either side of a switch edge that count as near


def _may_look_ahead(drive: H3Drive) -> bool:
    chip = drive.chip
    return drive.settled or not chip.motor_off


def switch_near(drive: H3Drive, first: float, second: float, margin: float = MARGIN) -> bool:
    """Whether a switch edge of ``drive`` lies between motor positions ``first`` and ``second``
    (or within ``margin`` of them)."""
    low, high = min(first, second) - margin, max(first, second) + margin
    return any(low <= edge <= high for switch in drive.switches for edge in (switch.low, switch.high))


Moments = tuple[tuple[float, float], ...]


def quiet_cycles(drives: Sequence[H3Drive], first: float, step: float,
                 moments: Sequence[Moments] | None = None, horizon: float = HORIZON) -> list[float]:
    """The cycles from ``first`` on (every ``step``, for ``horizon`` seconds) that would find the
    status of every chip unchanged and no switch near: their chips computed ahead, the list of
    their times.  A cycle looks at drive i's chip at ``moments[i]``, each ``(offset, ms)`` after
    its start as the PLC cycle computes it (``offset + ms / 1000``: the reads act then, §10.1;
    the status is copied at the last); without ``moments`` at the start only.  Each chip is
    computed in one pass, with a checkpoint at each cycle's last look, up to the first cycle that sees its
    status change (the status only gains bits while no command comes: the cycles before it see
    the status of now).  With every chip settled, every cycle of the reach (a settled chip's
    status and switches stay until a command)."""
    at_start: Moments = ((0.0, 0.0),)
    looks = {id(drive): (moments[index] if moments else at_start) for index, drive in enumerate(drives)}
    moving = [drive for drive in drives if not drive.settled]
    if moving and not all(_may_look_ahead(drive) for drive in moving):
        return []
    times: list[float] = []
    t, end = first, first + horizon
    while t <= end:
        times.append(t)
        t += step
    if not moving:  # every chip rests: its status stays, its switches too
        return times
    quiet = len(times)
    ends: list[tuple[H3Drive, float, float, list[batch.State]]] = []
    for drive in moving:
        seen = looks[id(drive)]
        status, position = drive.chip.status, drive.motor.position
        reach = seen[-1][0] + seen[-1][1] / 1000  # the cycle's last look: the status copied
        last = drive.stepper.ahead([t + reach for t in times[:quiet]])  # the chip at each cycle's last look
        cycles = 0
        while cycles < min(quiet, len(last)) and batch.status_of(last[cycles]) == status:
            cycles += 1
        quiet = cycles
        if drive.switches:
            ends.append((drive, position, reach, last))
    for drive, last_x, reach, last in ends:
        for cycle in range(quiet):
            x, v = batch.motion_of(last[cycle])
            v = v if abs(v) > STILL else 0.0
            margin = MARGIN + abs(v) * reach
            t = times[cycle]
            if (switch_near(drive, last_x, x, margin) or switch_near(drive, x, x + v * step, margin)
                    or switch_near(drive, drive.axis.position(t), drive.axis.position(t + step), margin)):
                quiet = cycle
                break
            last_x = x
    return times[:quiet]
