"""The GMS96 as a drive for drive-profile facades such as CiA 402 (:class:`devsim.core.kit.DriveActions`):
what a PLC or host does with the card's commands, done on the card (spec gms96.md §4.2.3, §5.4,
§5.6): ``Q3`` switches the position controller on (set-point := actual, IDXOFF cleared), ``A``
moves to an absolute target (work coordinates: the 402 target is the machine frame less the active
offsets), a jog runs the indexer endlessly in a direction (as the spindle simulation ``Q8;3``/``Q8;4``
does, at the work speed).  A jog to 0 and the quick stop are the card's ``#0`` Abbruch (manual
§2.3.2: "Dieser Befehl bewirkt den Abbruch der gerade laufenden Operation … Dabei werden alle, bis
dorthin anstehenden Kommandos, nicht mehr ausgeführt"), and the endless run brakes to standstill
with the card's ramp (B, N24), as ``Q8;5`` "Stillstand" stops it (manual §2.3.1 Q; spec §3.8.23 [R]:
"A running move decelerates with the programmed ramp to standstill"): ``#0`` alone ends only what
the executor runs, so the jog ran on.  The card moves at its own work speed and ramp (N
parameters, the feed): the profile velocity of the facade does not change them.  Positions are
increments in the machine frame (the ``axis.position`` point).

Homing (CiA 402 homing mode) is the card's reference run ``Q`` (manual §2.3.1 Q;
:mod:`devsim.devices.gms96.reference`): Q2 searches the cam in the "negative" direction, drives
off it the other way and takes the point where it leaves it: the negative home switch approached
in the positive direction, method 21; Q0 then searches the index mark in the "negative" direction,
back over the cam's edge: method 6; Q1 the index mark alone, in the "negative" direction: method
33.  P2.1 ("umgekehrte Richtung") mirrors them: 19, 4 and 34.  P2's other bits (the cam's input
and polarity, the counter kept, the counter track) are the card's, from N19.  The runs go at the
card's own speeds (its feed: the work speed, the search speed S), so 6099h/609Ah do not change
them.  While a run is under way the card's IDXOFF is set (the run sets it): the drive counts as
enabled then, since the position controller is on.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from devsim.core.kit import Command, DriveActions, Homing, Table
from devsim.core.points import BadValue
from devsim.devices.gms96.executor import Cmd

__all__ = ["DRIVE"]


def _enable(c: Any, on: bool) -> None:
    """On: ``Q3``.  Off: the position controller off as a following error switches it off (spec
    §4.5.3: "motion aborted, queue flushed"), the executor idle at once, so the next ``Q3`` runs."""
    if on:
        if c.stage.faulted():
            raise BadValue("the card cannot switch on: emergency stop or a monitoring fault")
        c.executor.submit(Cmd("Q", 3, 0, 0, 1))
        return
    c.executor.flush()
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


def _abort(c: Any) -> None:
    """``#0``: the queue and the running command given up, an endless run braked with the ramp."""
    c.spindle.on = False
    c.executor.abort()
    if c.indexer.jog_dir:
        c.indexer.halt()
        c.changed()


def _jog(c: Any, velocity: float) -> None:
    if velocity == 0:
        _abort(c)
        return
    c.indexer.run(1 if velocity > 0 else -1, "work")
    c.changed()


def _home(p1: int, reversed_direction: bool) -> Callable[..., None]:
    def start(c: Any, fast: float, slow: float, accel: float) -> None:
        p2 = (c.params.reference_type >> 8) & 0xFF & ~0x02 | (0x02 if reversed_direction else 0)
        c.executor.submit(Cmd("Q", p1, p2, 0, 1))

    return start


def _reference_running(c: Any) -> bool:
    run = c.executor.reference
    return run is not None and not run.finished


def _homing_state(c: Any) -> str:
    if _reference_running(c) or (c.executor.current is not None and c.executor.current.letter == "Q"):
        return "running"
    return "attained" if not c.stage.idxoff else "failed"


HOMING = Homing(
    methods=Table([
        Command("21", _home(2, False), "§2.3.1 Q", "Q2: the cam, left in the positive direction"),
        Command("19", _home(2, True), "§2.3.1 Q", "Q2 with P2.1: the cam, left in the negative direction"),
        Command("6", _home(0, False), "§2.3.1 Q", "Q0: the cam, then the index mark in the negative direction"),
        Command("4", _home(0, True), "§2.3.1 Q", "Q0 with P2.1: the cam, then the index mark in the positive direction"),
        Command("33", _home(1, False), "§2.3.1 Q", "Q1: the index mark in the negative direction"),
        Command("34", _home(1, True), "§2.3.1 Q", "Q1 with P2.1: the index mark in the positive direction"),
    ]),
    state=_homing_state,
)


DRIVE = DriveActions(
    enable=_enable,
    move_to=_move_to,
    jog=_jog,
    quick_stop=_abort,
    reset_fault=lambda c: None,  # an emergency stop or a monitoring fault ends with its cause
    position=lambda c: c.coordinates.physical_to_machine(c.indexer.actual()),
    velocity=lambda c: c.axis.velocity(),
    enabled=lambda c: bool(c.stage.controller and (not c.stage.idxoff or _reference_running(c))),
    fault=lambda c: bool(c.stage.estop or c.stage.monitoring_cause()),
    moving=lambda c: bool(c.motion()),
    following_error=lambda c: c.indexer.following_error(),
    homing=HOMING,
)
