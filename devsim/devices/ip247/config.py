"""Configuration of one simulated IP247 (manual §3.2, §3.3; spec ip247.md §2.1, §2.3, §4.14).

The S2 base page, the X21 jumper, the SYS-ID a fresh module starts with, the battery, and where
each axis's switches sit (in base units of the mechanical position, where the motor really is): the limit
switches ANF (active at and below) and END (at and above), and the reference cam [low, high].
"""

from __future__ import annotations

from devsim.core.settings import Bool, DictOf, Float, Int, Maybe, OneOf, PairOf, Section, Setting, Text

__all__ = ["AXIS_GEOMETRY", "Ip247Config", "SYS_ID"]

_BYTE = Int(ge=0, le=255)

SYS_ID = Section("The module identification of a module whose battery RAM is empty (spec §4.12).", (
    Setting("module", Int(ge=0, le=99), 0, "module number (Baugruppe Nr.)"),
    Setting("slot", _BYTE, 0, "slot number (Steckplatz Nr.)"),
    Setting("page", _BYTE, 0, "page address (Kacheladresse)"),
))

AXIS_GEOMETRY = Section("Where an axis's switches sit (mechanical position, base units) and what its motor can do "
                        "(spec §4.13, §5.7, §5.15).", (
    Setting("anf", Maybe(Float()), None, "limit switch ANF: actuated at and below this position"),
    Setting("end", Maybe(Float()), None, "limit switch END: actuated at and above this position"),
    Setting("cam", Maybe(PairOf(Float())), None, "reference cam (BERO) [low, high]"),
    Setting("max_start_hz", Maybe(Float(gt=0)), None, "the motor cannot start above this frequency (step loss)"),
    Setting("pullout_hz", Maybe(Float(gt=0)), None, "the motor stalls at this frequency (step loss)"),
))


def _axis(key: object) -> int:
    number = int(str(key))
    if number not in (1, 2, 3):
        raise ValueError("an axis is 1, 2 or 3")
    return number


Ip247Config = Section("Configuration of one simulated IP247 (spec ip247.md §2, §4.14).", (
    Setting("base_page", Int(ge=0, le=252), 0, "switch S2: the first of the four pages (0 … 252, steps of 4)"),
    Setting("x21", OneOf("2-3", "1-2"), "2-3", "jumper X21: 2-3 forces PE low under BASP"),
    Setting("firmware", Text(), "A02.1", "firmware version in SYS-ID"),
    Setting("sys_id", SYS_ID, {}, "SYS-ID of a module with empty battery RAM"),
    Setting("boot_time", Float(ge=0), 1.0, "seconds after power-up until the module runs (LEDs blink, PG silent)"),
    Setting("battery_ok", Bool(), True, "false: battery RAM is lost at power-up (spec §4.14)"),
    Setting("powered", Bool(), True, "false: the PG port answers nothing (COM247: F53H)"),
    Setting("s5_services", Bool(), False, "answer the standard S5 services 04H, 18H, 1AH, 1BH on the PG port, "
            "programs as DB n and machine data as DX n, for generic AS511 tools (off: spec vector 3.6.7 f)"),
    Setting("job_list", Int(ge=1, le=64), 8, "jobs each interface may queue while an axis brakes (spec §5.16)"),
    Setting("axes", DictOf(_axis, AXIS_GEOMETRY, "axis"), {}, "switch positions per axis 1 … 3"),
))
