"""Manual §2.3.1 T3;4 (memory status), p (downloads), s (EEPROM), r (reset), d/c (static data),
§2.5 (CNC programs): driven through the card's pty with the :class:`Gms96Client`."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from devsim.devices.gms96.client import Gms96Client
from tests.gms96.conftest import Plant
from tests.gms96.test_motion_reference import send

CNC_STORAGE_ERROR = 0x10  # T3;4 I.4 (manual §2.3.1 T)
FLASH_ERASE = 5.0  # manual §2.3.1 p: "2 bis 5 Sekunden nicht ansprechbar"


def memory_status(c: Gms96Client) -> int:
    """T3;4: the identifier is the memory status byte (manual §2.3.1 T, P1=3 P2=4)."""
    return c.read(3, 4)[0]


def download(plant: Plant, c: Gms96Client, number: int, *commands: tuple[Any, ...]) -> None:
    """p3;100;number, the commands, p3;101 (manual §2.3.1 p, §2.5)."""
    send(c, "p", 3, 100, number)
    plant.advance(FLASH_ERASE)
    for command in commands:
        send(c, *command)
    send(c, "p", 3, 101)


@pytest.mark.manual("§2.3.1 T", "T3;4 I.4: CNC program storage error")
@pytest.mark.parametrize("wipe", [False, True])
def test_cnc_storage_error_is_gone_after_power_on(plant_factory: Any, wipe: bool) -> None:
    plant = plant_factory({"max_total_commands": 2})
    c = plant.client()
    assert memory_status(c) & CNC_STORAGE_ERROR == 0
    download(plant, c, 0, ("A", 1000), ("A", 0), ("A", 500))  # 3 commands: does not fit
    assert memory_status(c) & CNC_STORAGE_ERROR
    plant.runtime.power_cycle(plant.name, wipe=wipe)
    plant.advance(0.6)
    assert memory_status(c) & CNC_STORAGE_ERROR == 0


@pytest.mark.manual("§2.3.1 T", "T3;4 I.4: CNC program storage error (a download that fits stores the program)")
def test_cnc_storage_error_ends_with_a_download_that_fits(plant_factory: Any) -> None:
    plant = plant_factory({"max_total_commands": 2})
    c = plant.client()
    download(plant, c, 0, ("A", 1000), ("A", 0), ("A", 500))
    assert memory_status(c) & CNC_STORAGE_ERROR
    assert plant.read("programs") == {}
    download(plant, c, 0, ("A", 1000), ("A", 0))
    assert plant.read("programs") == {0: 2}
    assert memory_status(c) & CNC_STORAGE_ERROR == 0


@pytest.mark.manual("§2.3.1 p", "the download of program 0 rebuilds the program structure: all programs before are "
                    "deleted (so they take no room from the new program 0)")
def test_a_new_program_0_has_the_room_of_the_programs_it_deletes(plant_factory: Any) -> None:
    plant = plant_factory({"max_total_commands": 3})
    c = plant.client()
    download(plant, c, 0, ("A", 1000))
    download(plant, c, 1, ("A", 0), ("A", 500))  # the memory is full: 3 commands
    assert plant.read("programs") == {0: 1, 1: 2}
    download(plant, c, 0, ("A", 10), ("A", 20), ("A", 30))  # fits once 0 and 1 are gone
    assert memory_status(c) & CNC_STORAGE_ERROR == 0
    assert plant.read("programs") == {0: 3}


FLASH_ERROR = 0x04  # T3;4 I.2 (manual §2.3.1 T)


@pytest.mark.manual("§2.3.1 T", "T3;4 I.2: 'Programmier-/Löschfehler des Flash-Speichers (z.B. nach Download)'")
def test_a_cnc_download_into_a_defective_flash_is_a_flash_error(plant_factory: Any) -> None:
    plant = plant_factory({})
    c = plant.client()
    download(plant, c, 0, ("A", 1000))
    assert plant.read("programs") == {0: 1} and memory_status(c) & FLASH_ERROR == 0
    plant.runtime.fault(plant.name, "flash_error", True)
    download(plant, c, 1, ("A", 0), ("A", 500))
    assert memory_status(c) & FLASH_ERROR
    assert memory_status(c) & CNC_STORAGE_ERROR == 0  # it would have fitted
    assert plant.read("programs") == {0: 1}  # the FLASH stays as it was
    plant.runtime.fault(plant.name, "flash_error", False)
    assert memory_status(c) & FLASH_ERROR  # until a download succeeds
    download(plant, c, 1, ("A", 0), ("A", 500))
    assert plant.read("programs") == {0: 1, 1: 2}
    assert memory_status(c) & FLASH_ERROR == 0


@pytest.mark.manual("§2.3.1 T", "T3;4 I.2: FLASH programming/erase error (e.g. after a download)")
def test_a_flash_error_is_gone_after_power_on(plant_factory: Any) -> None:
    plant = plant_factory({})
    c = plant.client()
    plant.runtime.fault(plant.name, "flash_error", True)
    download(plant, c, 0, ("A", 1000))
    assert memory_status(c) & FLASH_ERROR and plant.read("programs") == {}
    plant.runtime.fault(plant.name, "flash_error", False)
    plant.runtime.power_cycle(plant.name)
    plant.advance(0.6)
    assert memory_status(c) & FLASH_ERROR == 0


NV_ERROR = 0x60  # T3;4 I.5 NV memory (power-stage parameters), I.6 EEPROM defective (manual §2.3.1 T)
IDXOFF, POSITION_CONTROL = 0x08, 0x20  # T3;0 I.3; M0.5 (manual §2.4.1)


def unreadable_memory(plant_factory: Any, state_dir: Path) -> tuple[Plant, Gms96Client]:
    """A card started on a state file it cannot read: its parameter memory failed at the start."""
    (state_dir / "gms96.nvram.json").write_text("{not a memory image", "utf-8")
    plant = plant_factory({}, state_dir=state_dir)
    return plant, plant.client()


@pytest.mark.manual("§2.3.1 T", "T3;4 I.5: error of the NV memory (power-stage parameters): the power stage does "
                    "not go into control")
@pytest.mark.manual("§2.3.1 T", "T3;0 I.3 IDXOFF: 0 = indexer ok (moves can be carried out)")
@pytest.mark.parametrize("reference", [(0,), (3,), (8, 3, 1000)])
def test_the_nv_error_keeps_the_power_stage_out_of_control(plant_factory: Any, tmp_path: Path,
                                                           reference: tuple[int, ...]) -> None:
    plant, c = unreadable_memory(plant_factory, tmp_path)
    assert memory_status(c) & NV_ERROR == NV_ERROR
    assert c.read(1, 3, 0)[2][0] & POSITION_CONTROL == 0
    assert plant.read("fault") is True and plant.read("ready") is False  # (the machine side's view)
    start = plant.read("axis.physical")
    send(c, "Q", *reference)  # a reference run, Q3 (controller on), the spindle simulation Q8
    plant.advance(30.0)
    assert plant.read("axis.physical") == start  # no motor motion without control
    assert c.read(3, 0)[0] & IDXOFF  # nor a ready indexer
    assert c.read(1, 3, 0)[2][0] & POSITION_CONTROL == 0


@pytest.mark.manual("§2.3.1 s", "s85;170 saves the parameters in the EEPROM; they are active at the next start "
                    "(which clears the NV error of T3;4 I.5/I.6)")
def test_the_nv_error_ends_with_the_parameters_saved_again(plant_factory: Any, tmp_path: Path) -> None:
    plant, c = unreadable_memory(plant_factory, tmp_path)
    plant.runtime.power_cycle(plant.name)  # (a start writes nothing to the EEPROM)
    plant.advance(0.6)
    assert memory_status(c) & NV_ERROR == NV_ERROR
    send(c, "N", 300, 10)
    send(c, "s", 85, 170)
    plant.advance(0.5)
    plant.runtime.power_cycle(plant.name)
    plant.advance(0.6)
    assert memory_status(c) & NV_ERROR == 0
    assert c.read(1, 3, 0)[2][0] & POSITION_CONTROL  # in control after the start (manual §4.3)
    assert plant.read("fault") is False and plant.read("ready") is True
    assert int.from_bytes(c.read(5, 10)[2], "little") == 300
