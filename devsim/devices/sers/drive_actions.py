"""The SERS as a drive for drive-profile facades such as CiA 402 (:class:`devsim.core.kit.DriveActions`):
what a host would do over the serial port, done on the model (manual §4.2, §4.5.1, §4.6.6,
§4.8.2.2): ON/OFF, an absolute positioning ``WA=… V=… E`` (P1014 = 2), a fast jog at the given
speed (P1020) without the serial jog's 0.5 s timeout, ``S``, and ``P11=0`` to clear the drive
errors.  Positions are the position counter P51 in motor increments, speeds increments per second;
a refusal of the drive (``SersError``, its errno) is the control API's :class:`BadValue`.

Homing (CiA 402 homing mode) is the drive's own reference run ``H`` (manual §4.8.4.5
"Referenzfahr-Parameter": "Der Antrieb beschleunigt mit der "Referenzfahr-Beschleunigung" (P42) auf
die "Geschwindigkeit Referenzfahren" (P41).  Nach einer positiven Flanke am
Referenzschaltereingang bremst der Antrieb bis zum Stillstand ab.  Dann fährt der Antrieb mit der
"Geschwindigkeit Referenzfahren langsam" (P1003) in die entgegengesetzte Richtung, bis zum
Erreichen einer negativen Flanke"), P147 chosen by the homing method: bit 0 "Drehrichtung"
(0 positive, 1 negative), bit 1 "Referenzfahren auf Endschalter", bit 6 "Nullimpuls statt
Referenzschalter"; its other bits (3: software limits, 4: inverted input) stay as set.  So 19/21
are the reference switch found in the positive/negative direction, its edge approached back at
P1003; 18/17 the positive/negative limit switch the same way; 34/33 the zero pulse in the
positive/negative direction.  6099h sub 1 → P41, sub 2 → P1003, 609Ah → P42 (0: as set).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from devsim.core.kit import Command, DriveActions, Homing, Table
from devsim.core.points import BadValue
from devsim.devices.sers.errors import SersError

__all__ = ["DRIVE"]


def _refusals(action: Callable[..., None]) -> Callable[..., None]:
    def run(model: Any, *args: Any) -> None:
        try:
            action(model, *args)
        except SersError as exc:
            raise BadValue(f"the drive refuses: {exc}") from None

    return run


def _enable(m: Any, on: bool) -> None:
    if on:
        m.power_stage.switch_on()
    else:
        m.power_stage.switch_off()


def _move_to(m: Any, target: float, speed: float) -> None:
    scaling = m.params.scaling
    if speed > 0:
        m.access.write_param(91, scaling.incps_to_vel(speed))
    m.access.write_param(1014, 2)
    m.access.write_param(47, scaling.inc_to_pos(target))
    m.motion.start_positioning()


def _jog(m: Any, velocity: float) -> None:
    if velocity == 0:
        m.motion.stop_motion()
        return
    m.access.write_param(1020, m.params.scaling.incps_to_vel(abs(velocity)))
    m.motion.jog.start("RF" if velocity > 0 else "LF", serial=False)


#: The bits of P147 a homing method sets or clears (0 direction, 1 limit switch, 6 zero pulse; 2, 5
#: and 7, the manual's special runs, cleared).
P147_METHOD_BITS = 0x01 | 0x02 | 0x04 | 0x20 | 0x40 | 0x80


def _home(p147: int) -> Callable[..., None]:
    def start(m: Any, fast: float, slow: float, accel: float) -> None:
        scaling = m.params.scaling
        for number, value in ((41, fast), (1003, slow)):
            if value > 0:
                m.access.write_param(number, scaling.incps_to_vel(value))
        if accel > 0:
            m.access.write_param(42, scaling.incps2_to_acc(accel))
        m.access.write_param(147, int(m.params.homing_parameters) & ~P147_METHOD_BITS | p147)
        m.motion.home()

    return _refusals(start)


def _homing_state(m: Any) -> str:
    """Running while ``H`` runs; attained when it ended at its reference (P51 = 0 there, P403)."""
    homing = m.motion.homing
    if homing.phase is not None:
        return "running"
    return "attained" if homing.homed and round(m.motion.p51_inc()) == 0 else "failed"


HOMING = Homing(
    methods=Table([
        Command("19", _home(0x00), "§4.8.4.5", "reference switch in the positive direction (P147 = 0)"),
        Command("21", _home(0x01), "§4.8.4.5", "reference switch in the negative direction (P147 bit 0)"),
        Command("18", _home(0x02), "§4.8.4.5", "positive limit switch (P147 bit 1)"),
        Command("17", _home(0x03), "§4.8.4.5", "negative limit switch (P147 bits 0, 1)"),
        Command("34", _home(0x40), "§4.8.4.5", "zero pulse in the positive direction (P147 bit 6)"),
        Command("33", _home(0x41), "§4.8.4.5", "zero pulse in the negative direction (P147 bits 0, 6)"),
    ]),
    state=_homing_state,
)

DRIVE = DriveActions(
    enable=_refusals(_enable),
    move_to=_refusals(_move_to),
    jog=_refusals(_jog),
    quick_stop=_refusals(lambda m: m.motion.stop_motion()),
    reset_fault=_refusals(lambda m: m.access.write_param(11, 0)),
    position=lambda m: m.motion.p51_inc(),
    velocity=lambda m: m.axis.velocity(),
    enabled=lambda m: bool(m.power_stage.energized),
    fault=lambda m: bool(m.power_stage.errors),
    moving=lambda m: bool(m.motion.moving),
    homing=HOMING,
)
