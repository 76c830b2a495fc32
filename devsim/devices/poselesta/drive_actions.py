"""The POSELESTA's X axis as a drive for drive-profile facades such as CiA 402
(:class:`devsim.core.kit.DriveActions`): what the operator or the machine's PLC does at the
control, done on the model (spec poselesta.md §2.3–§2.5, manual §2.3.1, §2.3.3, §2.3.15, §2.4.7).

A CNC has no "go to" command: a positioning is a block.  A 402 target is entered as a
Hand-Einzelsatz block (MANUAL_SINGLE_BLOCK, ``N1 G90 G01 X… F…`` in mm and mm/min, or ``G00`` at
rapid when no profile velocity is given) and started with NC-Start, so it runs with the control's
own ramps, override and working-field limits.  Enabling is the machine's axis enable (V19,
Achsfreigabe); a jog is the X+/X− keys in MANUAL at the control's own manual feed (feed pot, or
rapid): the profile velocity's sign picks the key.  The quick stop is NC-Stop: the axes brake on
their ramp and the block is given up; so does a jog at 0 while a block runs (a halt).  A fault is NC ready L (an internal alarm, §2.4.5/§4.10);
it ends with its cause.  Positions are increments of X's resolution (the ``axis.x.position`` point).

Homing (CiA 402 homing mode) is the control's homing of X onto its reference mark in MANUAL
(``panel.reference``; manual §2.2.2: "Beim Ueberfahren der Referenzmarke muss der Pegel am Eingang
RM auf "1" wechseln", §2.3.23, the RM activation V24; the search itself is not in the manual: spec
§5.6's recommended one, in the configured ``home_direction`` at 10 % of the axis's maximum feed, up
to the first accepted mark, the actual value set to ``reference_value`` there).  The mark is the
encoder's index, so the run is method 33 (``home_direction`` −1) or 34 (+1); the other one is
refused at the start (a homing error).  Its speed is the control's own: 6099h/609Ah do not change it.
The quick stop (and a jog at 0, a halt) also ends a homing under way, braking the axis.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from devsim.core.kit import Command, DriveActions, Homing, Table
from devsim.core.points import BadValue

__all__ = ["DRIVE"]


def _ready(c: Any) -> None:
    if c.booting:
        raise BadValue("the control is not ready yet")
    if not c.signals.get("emergency_stop"):
        raise BadValue("Not-Stop is pressed")
    if not c.signals.get("nc_ready"):
        raise BadValue(f"NC ready is L: {c.message or 'an internal alarm'}")


def _enable(c: Any, on: bool) -> None:
    """The axis enable (V22/3); off, the axis is also stopped as by the quick stop, since the
    enable alone would not stop it (manual §2.3.15: "Nach Freigabe der Vorschübe ist es nicht mehr
    möglich, durch Aenderung der Achsfreigabe von H-Level auf L-Level die Bewegung zu stoppen"),
    and a disabled drive function does not run (CiA 402-2 §8.4.1)."""
    if on:
        _ready(c)
    else:
        _quick_stop(c)
    c.signals.set("axis_enable", on)


def _move_to(c: Any, target: float, speed: float) -> None:
    _ready(c)
    if c.executor.running:
        raise BadValue(f"block N{c.executor.block_number} executes ({c.executor.state})")
    c.select_mode("MANUAL_SINGLE_BLOCK")
    decimals = c.axes.formats.decimals["X"]
    position = f"X{c.axes.to_mm('x', target):.{decimals}f}"
    feed = round(c.axes.to_mm("x", speed) * 60 / c.block_motion.feed_unit())
    c.memory.mdi = f"N1 G90 G01 {position} F{feed}" if feed >= 1 else f"N1 G90 G00 {position}"
    c.executor.nc_start("panel" if int(c.params.nc_start_source) in (0, 1) else "external")
    if not c.executor.running:
        raise BadValue(f"the control did not start the block ({c.message or 'NC-Start ignored'})")


def _jog(c: Any, velocity: float) -> None:
    """A run at ``velocity``; 0 stops what moves with the ramp (the kit's ``jog``): the keys
    released, and a running block braked by NC-Stop and given up, as :func:`_quick_stop` does
    (manual §2.3.1: "Ein NC-Stop bewirkt einen Halt der Achsbewegungen entlang der Bremsrampe";
    CiA 402's halt in profile position mode is this)."""
    if velocity == 0:
        _quick_stop(c)
        return
    for key in ("jog_pos_x", "jog_neg_x"):
        c.signals.set(key, False)
    _ready(c)
    if c.mode != "MANUAL":
        c.select_mode("MANUAL")
    c.signals.set("jog_pos_x" if velocity > 0 else "jog_neg_x", True)


def _quick_stop(c: Any) -> None:
    for key in ("jog_pos_x", "jog_neg_x"):
        c.signals.set(key, False)
    if c.field.homing is not None:
        c.field.cancel()  # the search ends, the axis brakes
    if c.executor.running:
        c.signals.set("nc_stop", False)  # NC-Stop (active L): brake to HOLD
        c.signals.set("nc_stop", True)
        c.executor.reset()  # the held block is given up


def _home(direction: int) -> Callable[..., None]:
    def start(c: Any, fast: float, slow: float, accel: float) -> None:
        _ready(c)
        if c.cfg.axes.x.home_direction != direction:
            raise BadValue(f"X homes in the direction {c.cfg.axes.x.home_direction}, not {direction}")
        if c.mode != "MANUAL":
            c.select_mode("MANUAL")
        c.field.reference("x")

    return start


def _homing_state(c: Any) -> str:
    if c.field.homing == "x":
        return "running"
    return "attained" if "x" in c.field.referenced else "failed"


HOMING = Homing(
    methods=Table([
        Command("33", _home(-1), "§2.2.2", "the reference mark, searched in the negative direction"),
        Command("34", _home(1), "§2.2.2", "the reference mark, searched in the positive direction"),
    ]),
    state=_homing_state,
)


DRIVE = DriveActions(
    enable=_enable,
    move_to=_move_to,
    jog=_jog,
    quick_stop=_quick_stop,
    reset_fault=lambda c: None,  # an alarm ends with its cause (a declared fault switched off)
    position=lambda c: c.axes["x"].position(),
    velocity=lambda c: c.axes["x"].velocity(),
    enabled=lambda c: bool(not c.booting and c.signals.get("emergency_stop") and c.signals.get("nc_ready")
                           and c.signals.get("axis_enable")),
    fault=lambda c: bool(not c.booting and not c.signals.get("nc_ready")),
    moving=lambda c: bool(c.signals.get("travel_x")),
    following_error=lambda c: c.following_error("x"),
    homing=HOMING,
)
