"""Manual §2.5 (CNC sequence programs), §1.5 (programming mode), §2.3.1 p (p3 program control):
driven through the card's pty with the :class:`Gms96Client`."""

from __future__ import annotations

from typing import Any

import pytest

from devsim.devices.gms96.client import Gms96Client
from devsim.devices.gms96.codec import LongFrame
from tests.gms96.conftest import Plant
from tests.gms96.test_motion_reference import send

FLASH_ERASE = 5.0  # manual §2.3.1 p: 2 to 5 s
SETO, RESO, WAIT = 16, 17, 14


def download(plant: Plant, c: Gms96Client, number: int, *commands: tuple[Any, ...]) -> None:
    send(c, "p", 3, 100, number)
    plant.advance(FLASH_ERASE)
    for command in commands:
        send(c, *command)
    send(c, "p", 3, 101)


def output(c: Gms96Client, n: int) -> bool:
    byte, bit = divmod(n, 8)
    return bool(c.read(1, 2, byte)[2][0] >> bit & 1)


def mb(c: Gms96Client, byte: int) -> int:
    return c.read(1, 3, byte)[2][0]


@pytest.mark.manual("§2.5", "a program may start further programs (subprogram calls), nested up to 8")
def test_programs_nest_up_to_8(referenced: Plant) -> None:
    c = referenced.client()
    for k in range(8):  # program k calls k + 1; program 7 sets A0.5
        download(referenced, c, k, ("p", 3, 1, k + 1) if k < 7 else ("p", 10, SETO, 5))
    send(c, "p", 3, 1, 0)
    referenced.idle()
    assert output(c, 5)


@pytest.mark.manual("§2.3.1 p", "p3;100 for program 0 rebuilds the program structure: all programs before are deleted")
def test_download_of_program_0_deletes_all_programs(referenced: Plant) -> None:
    c = referenced.client()
    download(referenced, c, 0, ("A", 10))
    download(referenced, c, 1, ("A", 20))
    download(referenced, c, 5, ("A", 30))
    assert referenced.read("programs") == {0: 1, 1: 1, 5: 1}
    download(referenced, c, 0, ("A", 40))
    assert referenced.read("programs") == {0: 1}


@pytest.mark.manual("§2.3.1 p", "p3;2 stops the program (inside a sequence program)")
def test_p3_2_stops_the_program(referenced: Plant) -> None:
    c = referenced.client()
    download(referenced, c, 0, ("p", 10, SETO, 6), ("p", 3, 2), ("p", 10, SETO, 7))
    send(c, "p", 3, 1, 0)
    referenced.idle()
    assert output(c, 6) and not output(c, 7)


@pytest.mark.manual("§2.5", "the running CNC program can be aborted with the break command (#0)")
@pytest.mark.manual("§2.4.1", "M0.2 r: a CNC program runs (0 once it is aborted)")
def test_break_aborts_the_running_program(referenced: Plant) -> None:
    c = referenced.client()
    download(referenced, c, 0, ("p", 10, WAIT, 50), ("p", 10, SETO, 8))
    send(c, "p", 3, 1, 0)
    referenced.advance(1.0)
    assert mb(c, 0) & 0x04  # running
    c.abort()
    referenced.advance(6.0)
    assert not output(c, 8)
    assert mb(c, 0) & 0x04 == 0 and mb(c, 1) & 0x01 == 0  # not running, not ended successfully


@pytest.mark.manual("§2.5", "T commands are not allowed in a program: a T during a download is answered, not recorded")
def test_t_is_not_recorded_in_a_program(referenced: Plant) -> None:
    c = referenced.client()
    send(c, "p", 3, 100, 0)
    referenced.advance(FLASH_ERASE)
    send(c, "A", 100)
    reply = c.send_letter("T", 0)
    assert isinstance(reply, LongFrame) and reply.data[0] == ord("@")
    send(c, "p", 3, 101)
    assert referenced.read("programs") == {0: 1}


@pytest.mark.manual("§2.5", "100 different CNC programs can be loaded")
@pytest.mark.manual("§1.5", "up to 100 CNC programs are kept in the FLASH and are there after power-on")
def test_a_hundred_programs_survive_power_on(plant_factory: Any, tmp_path: Any) -> None:
    plant = plant_factory({}, state_dir=tmp_path)
    c = plant.client()
    download(plant, c, 0, ("p", 10, SETO, 2))
    download(plant, c, 99, ("p", 10, SETO, 3))
    plant.runtime.power_cycle(plant.name)
    plant.advance(0.6)
    send(c, "p", 3, 1, 99)
    plant.idle()
    assert output(c, 3) and not output(c, 2)


@pytest.mark.manual("§2.3.2 #0", "#0 aborts the CNC program input (a running download)")
def test_break_aborts_a_download(referenced: Plant) -> None:
    c = referenced.client()
    send(c, "p", 3, 100, 0)
    referenced.advance(FLASH_ERASE)
    send(c, "p", 10, SETO, 4)
    c.abort()
    send(c, "p", 10, SETO, 5)  # executed now, not recorded
    referenced.advance(0.01)
    assert output(c, 5)
    send(c, "p", 3, 101)
    assert referenced.read("programs") == {}


@pytest.mark.manual("§1.5", "up to 100 CNC programs are loaded into the FLASH; online and programmed operation may be mixed")
@pytest.mark.manual("§2.5", "100 CNC programs can be loaded into the memory of the GMS and run")
def test_a_long_running_program_does_not_fill_the_host_command_queue(referenced: Plant) -> None:
    c = referenced.client()
    download(referenced, c, 0, *[("p", 10, WAIT, 1)] * 100)  # 100 rows: more than the 64 queue slots
    send(c, "p", 3, 1, 0)
    referenced.advance(0.05)
    send(c, "p", 10, SETO, 4)  # a host command is acknowledged at once and queued behind the program
    referenced.advance(5.0)
    assert not output(c, 4) and mb(c, 0) & 0x04  # the program still runs
    referenced.idle()
    assert output(c, 4) and mb(c, 1) & 0x01


@pytest.mark.manual("§2.3.1 p", "p3;2 stops the program; it is meaningful only inside a sequence program")
def test_p3_2_outside_a_program_drops_no_host_command(referenced: Plant) -> None:
    c = referenced.client()
    send(c, "p", 10, WAIT, 10)
    send(c, "p", 3, 2)  # no program runs: nothing to stop
    send(c, "p", 10, SETO, 3)
    send(c, "A", 1000)
    referenced.idle()
    assert output(c, 3) and c.read(0)[1] == 1000


@pytest.mark.manual("§2.5", "subprogram calls: nesting up to 8 (deeper: the manual is silent; spec §4.9 [R] aborts the program)")
def test_a_ninth_nested_call_aborts_the_programs(referenced: Plant) -> None:
    c = referenced.client()
    for k in range(9):  # program k calls k + 1, then sets output k + 1 (A0.0 is the brake output)
        download(referenced, c, k, *([("p", 3, 1, k + 1)] if k < 8 else []), ("p", 10, SETO, k + 1))
    send(c, "p", 3, 1, 0)
    send(c, "p", 10, SETO, 10)  # the host's command queued behind the program
    referenced.idle()
    assert [n for n in range(1, 10) if output(c, n)] == []  # no row of any nested program runs on
    assert output(c, 10)  # the host's own command is not part of the program
    assert mb(c, 0) & 0x04 == 0 and mb(c, 1) & 0x01 == 0  # not running, not ended successfully
