"""The SERS as a drive for drive-profile facades such as CiA 402 (:class:`devsim.core.kit.DriveActions`):
what a host would do over the serial port, done on the model (manual §4.2, §4.5.1, §4.6.6,
§4.8.2.2): ON/OFF, an absolute positioning ``WA=… V=… E`` (P1014 = 2), a fast jog at the given
speed (P1020) without the serial jog's 0.5 s timeout, ``S``, and ``P11=0`` to clear the drive
errors.  Positions are the position counter P51 in motor increments, speeds increments per second;
a refusal of the drive (``SersError``, its errno) is the control API's :class:`BadValue`.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from devsim.core.kit import DriveActions
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
)
