"""``program.<n>``: a CNC program set through the control API is stored as its download
``p3;100;n`` … ``p3;101`` would store it (manual §2.5, §2.3.1 p), and runs like one."""

from __future__ import annotations

from typing import Any

import pytest

from devsim.core.points import BadValue
from tests.gms96.conftest import Plant
from tests.gms96.test_manual_programs import FLASH_ERASE, RESO, SETO, WAIT, download, output
from tests.gms96.test_motion_reference import send

#: Commands of every route a download records: moves, a wait, outputs, p11 (on receipt outside a
#: download), o1 (o2 is on receipt), a PLC line letter, a nested start, negative and 24-bit values.
COMMANDS: list[tuple[Any, ...]] = [
    ("A", 1000), ("+", -500), ("m", 50), ("p", 10, WAIT, 5), ("p", 10, SETO, 2), ("p", 11, 13, 1),
    ("o", 1), ("f", 4000), ("G", 91), ("p", 3, 1, 7), ("p", 10, RESO, 2), ("A", -0x800000), ("A", 0xFFFFFF),
    ("a", 1, 2),
]


def text(command: tuple[Any, ...]) -> str:
    letter, *params = command
    return letter + ";".join(str(p) for p in params)


def test_a_program_set_is_stored_as_its_download_stores_it(referenced: Plant) -> None:
    c = referenced.client()
    download(referenced, c, 1, *COMMANDS)
    referenced.set("program.2", [text(command) for command in COMMANDS])
    programs = referenced.device().flash.programs
    assert programs[2] == programs[1] and len(programs[1]) == len(COMMANDS)
    assert referenced.read("programs") == {1: len(COMMANDS), 2: len(COMMANDS)}
    assert referenced.read("program.1") == referenced.read("program.2")
    assert referenced.read("program.2")[-3:] == ["A-8388608", "A-1", "a1;2"]  # 24 bits, as on the line


def test_a_program_set_as_lines_runs_when_started(referenced: Plant) -> None:
    referenced.set("program.3", "A2000\np10;16;4\n\n  + -1000  \np10;17;5")
    assert referenced.read("program.3") == ["A2000", "p10;16;4", "+-1000", "p10;17;5"]
    c = referenced.client()
    send(c, "p", 3, 1, 3)
    referenced.idle()
    assert output(c, 4)
    assert referenced.read("position") == 1000
    assert referenced.read("marker.M1.0") is True  # the program ended successfully (manual §2.4.1)


def test_program_0_replaces_every_program_as_its_download_does(referenced: Plant) -> None:
    referenced.set("program.1", ["A10"])
    referenced.set("program.5", ["A20"])
    referenced.set("program.0", ["A40"])
    assert referenced.read("programs") == {0: 1}
    assert referenced.read("program.5") == []


@pytest.mark.parametrize("bad", [
    ["T0"], ["c5;1"], ["N20;100"], ["q"], ["o2;50"], ["p3;100;1"], ["p3;101"], ["p1;100"], ["A1;2;3;4"],
    ["A16777216"], ["A-8388609"], ["A 1e3"], ["A1000", 7], "", 12,
])
def test_a_command_a_download_would_not_record_is_refused(referenced: Plant, bad: Any) -> None:
    referenced.set("program.4", ["A10"])
    if bad == "":
        referenced.set("program.4", bad)  # no command: an empty program, as an empty download
        assert referenced.read("program.4") == []
        return
    with pytest.raises(BadValue):
        referenced.set("program.4", bad)
    assert referenced.read("program.4") == ["A10"]


def test_the_cards_limits_hold(plant_factory: Any) -> None:
    plant = plant_factory({"max_programs": 10, "max_total_commands": 3})
    with pytest.raises(BadValue, match="programs 0 … 9"):
        plant.set("program.10", ["A10"])
    plant.set("program.1", ["A10", "A20"])
    with pytest.raises(BadValue, match="exceed 3 commands"):
        plant.set("program.2", ["A10", "A20"])
    assert plant.read("programs") == {1: 2}


@pytest.mark.parametrize("command", [("T", 0), ("c", 5, 1), ("N", 20, 100), ("q",), ("o", 2, 50), ("p", 3, 100, 1),
                                     ("p", 1, 100), ("p", 1, 101)])
def test_what_the_point_refuses_a_download_does_not_record(referenced: Plant, command: tuple[Any, ...]) -> None:
    c = referenced.client()
    send(c, "p", 3, 100, 6)
    referenced.advance(FLASH_ERASE)
    send(c, "A", 10)
    c.send_letter(*command)  # (T answers with its read-back, the others with E5h)
    send(c, "A", 20)
    send(c, "p", 3, 101)
    assert referenced.read("program.6") == ["A10", "A20"]
    with pytest.raises(BadValue, match="not a command of a CNC program"):
        referenced.set("program.7", ["A10", text(command), "A20"])
