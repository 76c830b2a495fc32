"""The manual's COM247 chapter walked (manual §5 Kommunikationssoftware COM247): the simulator plays
the module, not COM247, so these tests check what COM247 relies on at the PG port (AS511 on a real
pty, virtual time): the jobs its screens send and what the module answers."""

from __future__ import annotations

import struct

import pytest

from devsim.devices.ip247 import program as lang
from tests.ip247.helpers import BACKWARD, FORWARD, START, STOP, TAKE_OVER, Make, Module, record
from tests.ip247.test_machine_data import COM247, words


def observe(mod: Module, page: int = 1) -> tuple[int, int, bytes]:
    """OBSERVE: actual value, residual distance and the four pages' errors."""
    answer = mod.call(0x62, bytes((page,)))
    position, residual = struct.unpack(">ii", answer[8:16])
    return position, residual, answer[16:20]


def sys_id(mod: Module) -> tuple[int, int, int]:
    answer = mod.call(0x64, bytes((4, 70, 0, 0)))
    return answer[8 + 13], answer[8 + 15], answer[8 + 17]


@pytest.mark.manual("§5.4", "BEGINN online sends BA24: module, slot and page number; slot and page are only "
                    "documentary and not compared with the switch setting")
@pytest.mark.manual("§5.4", "the values are taken only while no correct machine data are stored, or when the "
                    "module number does not differ from theirs; else 'Baugruppen-Nummer mit korrekten MD nicht "
                    "änderbar' (12)")
def test_the_preset_screens_sys_id(make: Make) -> None:
    mod = make({"base_page": 8})
    assert mod.load_md()[8] == 0  # module 11 in COM247's record and in the SYS-ID
    assert mod.write(4, 24, 0, [11, 5, 100])[4] == 0  # page 100 although S2 says 8
    assert sys_id(mod) == (11, 5, 100)
    assert mod.write(4, 24, 0, [12, 7, 16])[4] == 12
    assert sys_id(mod) == (11, 5, 100)  # nothing of the refused job was taken


@pytest.mark.manual("§5.4", "with only faulty machine data on the module its module number may still change")
def test_faulty_machine_data_do_not_freeze_the_module_number(mod: Module) -> None:
    answer = mod.load_md(record=record(backlash=65_000))
    assert (answer[8], answer[4]) == (20, 15)
    assert mod.write(4, 24, 0, [12, 1, 0])[4] == 0 and sys_id(mod) == (12, 1, 0)


@pytest.mark.manual("§5.1", "COM247's error line shows the module errors of axes 1 … 3 and the data channel "
                    "(e.g. F8A F00 F00 F00: axis 1 has error 8AH - 80H = 10, the others none)")
def test_the_four_pages_errors(mod: Module) -> None:
    assert observe(mod)[2] == bytes((8, 8, 8, 8))  # after power-up
    mod.operate(4, 17, START)
    mod.load_md()
    assert mod.operate(1, 6, START, w=1000, dd=5_000)[4] == 10
    assert observe(mod, 2)[2] == bytes((10, 0, 0, 0))


@pytest.mark.manual("§5.6.1.1", "zero offsets and tool offsets are reset by every input of new machine data")
def test_new_machine_data_reset_the_offsets(mod: Module) -> None:
    mod.ready()
    mod.operate(1, 12, START, dd=20_000)  # actual value 20 mm
    mod.operate(1, 15, FORWARD, dd=3_000)
    shifted = observe(mod)[0]
    assert mod.call(0x65, bytes((1, 21, 101)))[4] == 0
    assert mod.load_md()[8] == 0
    mod.operate(1, 5, START, b=1)  # x_ref = 1 mm again, now without any shift
    assert shifted != 1_000 and observe(mod)[0] == 1_000
    mod.operate(1, 7, FORWARD, w=1000, dd=2_000)
    mod.clock.advance(10)
    assert observe(mod)[0] == 3_000


@pytest.mark.manual("§5.6.1.2", "rotary axis: the range end is physically the range start; the actual value jumps "
                    "from the end value to the start value")
def test_a_rotary_axis_wraps_its_actual_value(mod: Module) -> None:
    rotary = record(rotary=True, unit=3, limit_begin=0, limit_end=360_000, reference=0)
    assert mod.load_md(record=rotary)[8] == 0
    mod.operate(1, 5, START, b=1)
    mod.operate(1, 7, FORWARD, w=1000, dd=350_000)
    mod.clock.advance(60)
    assert observe(mod)[0] == 350_000
    mod.operate(1, 7, FORWARD, w=1000, dd=20_000)
    mod.clock.advance(60)
    assert observe(mod)[0] == 10_000


@pytest.mark.manual("§5.6.2.1", "a program is at most 1023 characters long; program numbers 0 … 255")
def test_program_length_and_numbers(mod: Module) -> None:
    def program(number: int, length: int) -> str:
        """A valid program of ``length`` characters: traverses, then an end block padded with blanks."""
        text, k = f"%{number:3d}\n", 1
        while len(text) + len(f"N{k} X{k} F100\n") + len("N999 M02\n") + 20 <= length:
            text += f"N{k} X{k} F100\n"
            k += 1
        return text + "N999" + " " * (length - len(text) - len("N999M02\n")) + "M02\n"

    assert len(program(0, 1023)) == 1023
    answer = mod.store(0, program(0, 1023))
    assert answer[4] == 0 and answer[8:12] == bytes(4)
    answer = mod.store(255, program(255, 1024))
    assert answer[4] == 48 and struct.unpack(">H", answer[8:10])[0] == 1  # "Text zu lang"


@pytest.mark.manual("§5.6.2.3", "the block types '/N' (skippable) and ':N' (main block) are allowed but mean "
                    "nothing: every block is a normal block")
@pytest.mark.manual("§5.6.2.4", "block numbers have up to three digits and need not ascend: blocks run in the order "
                    "they were entered")
def test_block_types_and_numbers(mod: Module) -> None:
    mod.ready()
    text = "%  5\n/N7 X10 F1000 M11\n:N2 X30 F1000 M12\nN999 X20 F1000 M13\nN0 M02\n"
    assert mod.store(5, text)[8:12] == bytes(4)
    mod.operate(1, 9, START, b=5)  # single block: one traverse per Übernahme
    seen = []
    for _ in range(3):
        mod.operate(1, 9, TAKE_OVER)
        mod.clock.advance(10)
        seen.append((observe(mod)[0], mod.device.read("axis.1.m_function")))
    assert seen == [(10_000, 11), (30_000, 12), (20_000, 13)]


@pytest.mark.manual("§5.6.2.3", "ABSPEICHERN with a program of that number already on the module asks whether "
                    "to overwrite it")
def test_storing_over_an_existing_program_asks_first(mod: Module) -> None:
    old, new = "%  5\nN1 X10 F1000\nN2 M02\n", "%  5\nN1 X20 F1000\nN2 M02\n"
    mod.store(5, old)
    assert mod.store(5, new)[4] == 20  # "Verfahrprogramm überschreiben ?"
    assert mod.device.read("program.5") == old
    assert mod.write(4, 22, 5, lang.record_words(5, new), flags=1)[4] == 0  # confirmed
    assert mod.device.read("program.5") == new


@pytest.mark.manual("§5.8.2", "without correct machine data only the modes 4 (Achse aus) and 17 (Fehler löschen) "
                    "run, besides the input and output of data")
def test_without_machine_data_only_ba4_and_ba17(mod: Module) -> None:
    assert mod.load_md(record=record(backlash=65_000))[8] == 20  # faulty machine data
    for ba, cmd in ((1, FORWARD), (2, BACKWARD), (5, START), (6, START), (7, FORWARD), (8, START), (9, START),
                    (10, START), (11, START), (12, START), (13, FORWARD), (14, START), (15, FORWARD), (16, START)):
        assert mod.operate(1, ba, cmd, b=1)[4] == 14, ba
    assert mod.operate(1, 4, START)[4] == 0 and mod.operate(1, 17, START)[4] == 0
    assert mod.call(0x64, bytes((1, 67, 101, 0)))[0] == 0


@pytest.mark.manual("§5.8.2", "the residual distance is shown only in BA6, BA7, BA8 and BA9")
def test_no_residual_distance_while_jogging(mod: Module) -> None:
    mod.ready()
    mod.operate(1, 1, FORWARD, w=1000)
    mod.clock.advance(1)
    assert observe(mod)[1] == 0
    mod.operate(1, 1, STOP)
    mod.clock.advance(2)
    mod.operate(1, 7, FORWARD, w=1000, dd=20_000)
    mod.clock.advance(1)
    assert observe(mod)[1] > 0


@pytest.mark.manual("§5.8.2", "velocity 0 means the value in the machine data; a velocity above the maximum is "
                    "taken as the maximum")
def test_velocity_zero_and_too_high(mod: Module) -> None:
    mod.ready()  # COM247's MD: step velocity 1000 mm/min; 1.1 µm per pulse at 100 kHz: 6600 mm/min
    mod.operate(1, 7, FORWARD, w=0, dd=50_000)
    mod.clock.advance(2)
    assert mod.device.read("axis.1.velocity") == pytest.approx(1000 * 1000 / 60)
    mod.clock.advance(60)
    mod.operate(1, 1, FORWARD, w=60_000)
    mod.clock.advance(3.5)  # the ramp reaches f_max after 2.84 s
    assert mod.device.read("axis.1.velocity") == pytest.approx(6600 * 1000 / 60)


@pytest.mark.manual("§5.8.2", "Vorwärts and Rückwärts with BA6 only on a rotary axis; Start not with the jog "
                    "modes, BA7, BA13 and BA15")
def test_the_commands_each_mode_takes(mod: Module) -> None:
    mod.ready()
    for ba, cmd in ((6, FORWARD), (6, BACKWARD), (1, START), (2, START), (7, START), (13, START), (15, START)):
        assert mod.operate(1, ba, cmd)[4] == 2, (ba, cmd)
    assert mod.load_md(axis=2, record=record(rotary=True, unit=3, limit_begin=0, limit_end=360_000,
                                              reference=0))[8] == 0
    mod.operate(2, 5, START, b=1)
    assert mod.operate(2, 6, BACKWARD, w=1000, dd=90_000)[4] == 0
    mod.clock.advance(60)
    assert observe(mod, 2)[0] == 90_000


@pytest.mark.manual("§5.8.2", "Übernahme: in BA8 it acknowledges a programmed halt (M00); in BA8 and BA9 it "
                    "continues an interrupted program")
def test_take_over_after_a_halt_and_an_interruption(mod: Module) -> None:
    mod.ready()
    mod.store(5, "%  5\nN1 X10 F1000 M00\nN2 X40 F1000\nN3 M02\n")
    mod.operate(1, 8, START, b=5)
    mod.clock.advance(10)
    assert observe(mod)[0] == 10_000 and mod.device.read("axis.1.running") is False  # held after N1 (§2.6.9)
    mod.operate(1, 8, TAKE_OVER)
    mod.clock.advance(0.5)
    assert mod.operate(1, 8, STOP)[4] == 65
    mod.clock.advance(2)
    assert 10_000 < observe(mod)[0] < 40_000
    mod.operate(1, 8, TAKE_OVER)
    mod.clock.advance(10)
    assert observe(mod)[:2] == (40_000, 0) and mod.device.read("axis.1.m_function") == 2


@pytest.mark.manual("§5.9", "transferring machine data COM247 may change the axis number of the target set; "
                    "the set then goes to that axis")
def test_machine_data_moved_to_another_axis(mod: Module) -> None:
    mod.load_md()
    stored = list(struct.unpack(">70H", mod.call(0x64, bytes((1, 67, 101, 0)))[8:]))
    stored[3] = (stored[3] & 0xFF00) | 2
    mod.device.set("input.ANF2", True)
    mod.device.set("input.END2", True)
    assert mod.write(2, 20, 101, stored)[8] == 0
    assert mod.call(0x64, bytes((4, 64, 0, 0)))[8:] == struct.pack(">6H", 101, 70, 101, 70, 0, 0)
    assert words(COM247)[5:70] == list(struct.unpack(">70H", mod.call(0x64, bytes((2, 67, 101, 0)))[8:]))[5:70]
