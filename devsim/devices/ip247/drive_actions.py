"""The IP247's axis 1 as a drive for drive-profile facades such as CiA 402
(:class:`devsim.core.kit.DriveActions`): what FB164 would ask of page 1 (spec ip247.md §4.1), done
on the module: BA6 "Start" to an absolute target, BA1 Vorwärts/Rückwärts to jog, "Stopp" to stop.
A jog at another velocity or the other way while one runs is the other jog mode (BA2 while BA1
runs, BA1 while BA2 does): the module cannot change a running jog ("Sie können die
Geschwindigkeit während der Fahrt nicht ändern"; a second BA1 is error 2, "Nicht erlaubter
Auftrag … Starten einer bereits laufenden Achse") but "Sie können zwischen den
Tippenbetriebsarten auch während der Bewegung umschalten. Die Achse hält dann an und führt
anschließend ihre Bewegung in der neuen Tippenbetriebsart aus" (manual §4.2.1).
The module has no power stage of its own to switch: enabled means machine data are loaded and the
power unit is ready (BB), and switching off ends a running job with Stopp; a fault is a pending
error of 10 or more.  Positions are base units (the ``axis.1.position`` point), speeds base units
per second, sent as the velocity word in units/min (the base unit × 1000, as the machine data
count it).

``SETUP`` is what a test or a plant must set first for the axis to move: the manual's example
machine data (§6.1; r = 10 µm, 3000 mm/min) for module 0 (the SYS-ID of a fresh module), the NC limit
switches closed, and the reference point
set (BA5) at 0.

Homing (CiA 402 homing mode) is the module's own reference run, BA5 "Referenzpunkt fahren" with
B = 0 (manual §4.2.3 … §4.2.5; :mod:`devsim.devices.ip247.reference`): it searches the cam (BERO)
against the reference direction R (MD n+26), leaves it in R in single steps and sets the reference
point at the cam's edge, synchronous (MD n+25 = 0) at the next zero of the current pattern counter
after it, the stepper's index.  The cam lies against R from the home position, so R forward is
the negative home switch approached in the positive direction: method 21, and 5 with the
synchronisation (the first "index" after the edge); R backward, the positive home switch: 19, and
3.  The run's direction and synchronisation are machine data, so a method that does not match
the loaded ones is refused at the start (a homing error); its speed is the reference velocity of
the machine data (MD n+23) and f_ss: 6099h/609Ah do not change them.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from devsim.core.kit import Command, DriveActions, Homing, Table
from devsim.core.points import BadValue
from devsim.devices.ip247.jobs import BACKWARD, FORWARD, START, STOP

__all__ = ["DRIVE", "SETUP"]

PAGE = 1
MANUALS_MD = (
    "0046 0044 427B 0001 0100 0001 86A0 0000 2710 0001 86A0 0001 0040 000A 03E8 0000 044C 0000 03E8 0000 "
    "03E8 0000 03E8 0000 03E8 0001 0020 0000 03E8 FFFF D8F0 0007 A120 0001 0000 0000 0000 03E8 0000 0000 "
    "0000 0000 0000 0000 0000 0000 0000 0001 0000 0000" + " 0000" * 20
)
SETUP: dict[str, Any] = {
    "input.ANF1": True,
    "input.END1": True,
    "axis.1.machine_data": MANUALS_MD,
    "ag.operate": {"page": 0, "ba": 5, "cmd": "Start", "b": 1},  # BA5: set the reference point here
}


def _unit(m: Any) -> Any:
    return m.units[PAGE - 1]


def _operate(m: Any, ba: int, cmd: int, w: int = 0, dd: int = 0) -> None:
    m.operate(PAGE, ba, cmd, 0, w, dd, source="ag")
    error = _unit(m).error
    if error >= 10:
        raise BadValue(f"the module refuses: error {error}")


def _per_minute(speed: float) -> int:
    return max(1, min(65000, round(abs(speed) * 60 / 1000)))


def _jog(m: Any, velocity: float) -> None:
    if velocity == 0:
        _operate(m, 1, STOP)
        return
    unit = _unit(m)
    ba = 3 - unit.mode if unit.running and unit.mode in (1, 2) else 1
    _operate(m, ba, FORWARD if velocity > 0 else BACKWARD, _per_minute(velocity))


def _enable(m: Any, on: bool) -> None:
    """On: the module must be ready.  Off: it has no power stage to switch off, so a running job
    is ended with Stopp of its mode (manual §2.8.4: "Ein Stoppbefehl in Verbindung mit
    irgendeiner Betriebsart führt zum fehlerfreien Abbruch"): a disabled drive function does not
    run (CiA 402-2 §8.4.1)."""
    if on and not _enabled(m):
        raise BadValue("no machine data on axis 1, or the power unit is not ready (BB)")
    if not on and _unit(m).running:
        _operate(m, _unit(m).mode, STOP)


def _enabled(m: Any) -> bool:
    return _unit(m).md is not None and bool(m.signals.get("BB1"))


def _home(forward: bool, synchronous: bool) -> Callable[..., None]:
    def start(m: Any, fast: float, slow: float, accel: float) -> None:
        md = _unit(m).md
        if md is None or (md.reference_direction == 0x00) != forward or (md.reference_sync == 0) != synchronous:
            raise BadValue("the machine data's reference direction or synchronisation is another homing method")
        _operate(m, 5, START)  # BA5, B = 0: Referenzpunkt fahren

    return start


def _homing_state(m: Any) -> str:
    unit = _unit(m)
    if unit.reference_run is not None:
        return "running"
    return "attained" if unit.reference_set else "failed"


HOMING = Homing(
    methods=Table([
        Command("21", _home(True, False), "§4.2.4", "R forward, asynchronous: the cam's edge left in the positive direction"),
        Command("5", _home(True, True), "§4.2.4", "R forward, synchronous: the next pattern zero after the cam"),
        Command("19", _home(False, False), "§4.2.4", "R backward, asynchronous: the cam's edge left in the negative direction"),
        Command("3", _home(False, True), "§4.2.4", "R backward, synchronous: the next pattern zero after the cam"),
    ]),
    state=_homing_state,
)


DRIVE = DriveActions(
    enable=_enable,
    move_to=lambda m, target, speed: _operate(m, 6, START, _per_minute(speed) if speed > 0 else 0, round(target)),
    jog=_jog,
    quick_stop=lambda m: _operate(m, _unit(m).mode, STOP),
    reset_fault=lambda m: m.operate(PAGE, 17, START, source="ag"),  # BA17: acknowledge the error
    position=lambda m: _unit(m).actual(),
    velocity=lambda m: _unit(m).axis.velocity(),
    enabled=_enabled,
    fault=lambda m: _unit(m).error >= 10,
    moving=lambda m: bool(_unit(m).running),
    homing=HOMING,
)
