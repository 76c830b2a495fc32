"""Configuration of one simulated IP247 (manual §3.2, §3.3; spec ip247.md §2.1, §2.3, §4.14).

The S2 base page, the X21 jumper, the SYS-ID a fresh module starts with, the battery, and where
each axis's switches sit (in base units of the mechanical position, where the motor really is): the limit
switches ANF (active at and below) and END (at and above), and the reference cam [low, high].
"""

from __future__ import annotations

from typing import Annotated, Any, Literal

from devsim.core.settings import Keys, Meta, Settings, doc, field

__all__ = ["AXIS_GEOMETRY", "AxisGeometry", "Ip247Config", "SYS_ID", "SysId"]

_Byte = Annotated[int, Meta(ge=0, le=255)]


class SysId(Settings):
    """The module identification of a module whose battery RAM is empty (spec §4.12)."""

    module: Annotated[int, Meta(ge=0, le=99), doc("module number (Baugruppe Nr.)")] = 0
    slot: Annotated[_Byte, doc("slot number (Steckplatz Nr.)")] = 0
    page: Annotated[_Byte, doc("page address (Kacheladresse)")] = 0


class AxisGeometry(Settings):
    """Where an axis's switches sit (mechanical position, base units) and what its motor can do (spec §4.13,
    §5.7, §5.15)."""

    anf: Annotated[float | None, doc("limit switch ANF: actuated at and below this position")] = None
    end: Annotated[float | None, doc("limit switch END: actuated at and above this position")] = None
    cam: Annotated[tuple[float, float] | None, doc("reference cam (BERO) [low, high]")] = None
    max_start_hz: Annotated[Annotated[float, Meta(gt=0)] | None,
                            doc("the motor cannot start above this frequency (step loss)")] = None
    pullout_hz: Annotated[Annotated[float, Meta(gt=0)] | None, doc("the motor stalls at this frequency (step loss)")] = None


SYS_ID = SysId
AXIS_GEOMETRY = AxisGeometry


def _axis(key: object) -> int:
    text = str(key)
    if text not in ("1", "2", "3"):  # (int(): also ' 2', '+2', '٢'; '²' gave its own message)
        raise ValueError("an axis is 1, 2 or 3")
    return int(text)


class Ip247Config(Settings):
    """Configuration of one simulated IP247 (spec ip247.md §2, §4.14)."""

    base_page: Annotated[int, Meta(ge=0, le=252, multiple_of=4),
                         doc("switch S2: the first of the four pages (0 … 252, steps of 4; manual §3.3.2)")] = 0
    x21: Annotated[Literal["2-3", "1-2"], doc("jumper X21: 2-3 forces PE low under BASP")] = "2-3"
    firmware: Annotated[str, doc("firmware version in SYS-ID")] = "A02.1"
    sys_id: Annotated[SysId, doc("SYS-ID of a module with empty battery RAM")] = field(default_factory=SysId)
    boot_time: Annotated[float, Meta(ge=0),
                         doc("seconds after power-up until the module runs (LEDs blink, PG silent)")] = 1.0
    battery_ok: Annotated[bool, doc("false: battery RAM is lost at power-up (spec §4.14)")] = True
    powered: Annotated[bool, doc("false: the PG port answers nothing (COM247: F53H)")] = True
    s5_services: Annotated[bool, doc(
        "answer the standard S5 services 04H, 18H, 1AH, 1BH on the PG port, programs as DB n and machine data "
        "as DX n, for generic AS511 tools (off: spec vector 3.6.7 f)")] = False
    job_list: Annotated[int, Meta(ge=1, le=64), doc("jobs each interface may queue while an axis brakes (spec §5.16)")] = 8
    axes: Annotated[dict[Any, AxisGeometry], Keys(_axis, "axis"), doc("switch positions per axis 1 … 3")] = {}
