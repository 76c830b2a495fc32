"""Which operator job an IP247 axis takes, and which module error it gets instead (manual §4.1,
§4.1.1, §4.2–§4.4, §5.8.2, §7.2.2; spec ip247.md §3.1, §4.2): the preconditions in the spec's
order — page, machine data, state and other axes, reference point — before the mode runs.

Pure: :func:`refusal` looks at an :class:`AxisView` (what the module knows of the axis and its
neighbours) and a job, and gives the module error, or None when the job may run.
"""

from __future__ import annotations

import msgspec

from devsim.devices.ip247.tables import DATA_CHANNEL, page_error

__all__ = ["AxisView", "Job", "refusal"]

START, STOP, FORWARD, BACKWARD, TAKE_OVER = 1, 2, 3, 4, 5
#: Commands each mode takes (spec §3.3.1 table, §4.2); Stopp is taken by every mode.
COMMANDS: dict[int, frozenset[int]] = {
    1: frozenset((FORWARD, BACKWARD, STOP, TAKE_OVER)), 2: frozenset((FORWARD, BACKWARD, STOP, TAKE_OVER)),
    4: frozenset((START, STOP, FORWARD, BACKWARD, TAKE_OVER)), 5: frozenset((START, STOP)),
    6: frozenset((START, STOP, FORWARD, BACKWARD, TAKE_OVER)), 7: frozenset((FORWARD, BACKWARD, STOP, TAKE_OVER)),
    8: frozenset((START, STOP, TAKE_OVER)), 9: frozenset((START, STOP, TAKE_OVER)), 10: frozenset((START,)),
    11: frozenset((START,)), 12: frozenset((START,)), 13: frozenset((FORWARD, BACKWARD)), 14: frozenset((START,)),
    15: frozenset((FORWARD, BACKWARD)), 16: frozenset((START,)), 17: frozenset((START,)),
}
NEEDS_REFERENCE = frozenset((6, 8, 9, 10))
WITHOUT_MD = frozenset((4, 17))  # (and the data transfers)
IN_TEACH_IN = frozenset((1, 2, 4, 6, 7, 11, 17))  # spec §4.2 (BA4 and BA17 [DECISION])


class AxisView(msgspec.Struct, frozen=True):
    """What the checks need to know of one axis (page 1 … 3)."""

    page: int
    md_valid: bool
    reference_set: bool
    running: bool
    mode: int  # BTR: the current (or last) mode
    teach_in: bool = False
    rotary: bool = False


class Job(msgspec.Struct, frozen=True):
    page: int
    ba: int
    cmd: int


def refusal(axis: AxisView, job: Job) -> int | None:
    """The module error an operator job gets (spec §3.1, §4.2), or None: it runs.  A job on a
    running axis that is not one of the allowed ones is error 2 (and the caller aborts the
    running action)."""
    ba, cmd = job.ba, job.cmd
    page = page_error(ba, job.page)
    if page is not None:
        return page
    if job.page == DATA_CHANNEL:
        return None  # what page_error lets through there: BA17, the transfers, the reads
    if ba in (20, 21):
        return 4 if axis.running else None  # machine data while running (spec §4.2 [DECISION])
    if ba not in COMMANDS or ba >= 20:
        return None  # the reading modes: always
    if axis.running:
        if cmd == STOP or ba == 4:
            return None  # Stopp of the running mode, or BA4 + any command (§3.1)
        if ba in (1, 2) and axis.mode in (1, 2) and ba != axis.mode and cmd in (FORWARD, BACKWARD):
            return None  # from one jog mode to the other
        return 2
    if not axis.md_valid and ba not in WITHOUT_MD:
        return 14
    if axis.teach_in and ba not in IN_TEACH_IN:
        return 30
    if cmd not in COMMANDS[ba]:
        return 2
    if ba == 6 and cmd in (FORWARD, BACKWARD) and not axis.rotary:
        return 2  # BA6 Vorwärts/Rückwärts only on a rotary axis
    if ba in NEEDS_REFERENCE and not axis.reference_set:
        return 10
    if ba in (1, 2) and cmd == TAKE_OVER and not axis.teach_in:
        return 2
    return None
