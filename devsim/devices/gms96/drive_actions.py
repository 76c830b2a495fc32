"""The GMS96 as a drive for drive-profile facades such as CiA 402 (:class:`devsim.core.kit.DriveActions`):
what a PLC or host does with the card's commands, done on the card (spec gms96.md §4.2.3, §5.4,
§5.6): ``Q3`` switches the position controller on (set-point := actual, IDXOFF cleared), ``A``
moves to an absolute target (work coordinates: the 402 target is the machine frame less the active
offsets), ``#0`` aborts with the ramp, a jog runs the indexer in a direction.  The card moves at
its own work speed and ramp (N parameters, the feed): the profile velocity of the facade does not
change them.  Positions are increments in the machine frame (the ``axis.position`` point).
"""

from __future__ import annotations

from typing import Any

from devsim.core.kit import DriveActions
from devsim.core.points import BadValue
from devsim.devices.gms96.executor import Cmd

__all__ = ["DRIVE"]


def _enable(c: Any, on: bool) -> None:
    if on:
        if c.stage.faulted():
            raise BadValue("the card cannot switch on: emergency stop or a monitoring fault")
        c.executor.submit(Cmd("Q", 3, 0, 0, 1))
        return
    c.executor.abort()
    c.stage.controller = False
    c.indexer.power_off(brake=True)
    c.changed()


def _move_to(c: Any, target: float, speed: float) -> None:
    work = round(target - c.coordinates.offsets())
    if c.coordinates.g_relative:  # G91: "A" would be relative; move by the difference from the last target
        base = c.executor.last_target if c.executor.last_target is not None else c.axis.position()
        c.executor.submit(Cmd("+", round(c.coordinates.machine_to_physical(target) - base), 0, 0, 1))
        return
    c.executor.submit(Cmd("A", work, 0, 0, 1))


def _jog(c: Any, velocity: float) -> None:
    if velocity == 0:
        c.executor.abort()
        return
    c.indexer.run(1 if velocity > 0 else -1, "work")
    c.changed()


DRIVE = DriveActions(
    enable=_enable,
    move_to=_move_to,
    jog=_jog,
    quick_stop=lambda c: c.executor.abort(),
    reset_fault=lambda c: None,  # an emergency stop or a monitoring fault ends with its cause
    position=lambda c: c.coordinates.physical_to_machine(c.indexer.actual()),
    velocity=lambda c: c.axis.velocity(),
    enabled=lambda c: bool(c.stage.controller and not c.stage.idxoff),
    fault=lambda c: bool(c.stage.estop or c.stage.monitoring_cause()),
    moving=lambda c: bool(c.motion()),
    following_error=lambda c: c.indexer.following_error(),
)
