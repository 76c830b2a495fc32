"""Walk of manual §4.3.11–§4.3.23 (machine data, programs and SYS-ID as records: BA20–BA24,
BA64–BA70), driven through the PG port on a real pty and the PLC side's TCP endpoint."""

from __future__ import annotations

import struct
from collections.abc import Iterator
from typing import Any

import pytest

from devsim.devices.ip247 import program as lang
from devsim.devices.ip247.client import AgClient
from tests.ip247.helpers import FORWARD, START, Module
from tests.ip247.test_machine_data import COM247, words


def md_for(axis: int, db: int) -> list[int]:
    data = words(COM247)
    data[3] = (data[3] & 0xFF00) | axis
    data[2] = (data[2] & 0xFF00) | db
    return data


def load(mod: Module, axis: int, db: int) -> bytes:
    mod.device.set(f"input.ANF{axis}", True)
    mod.device.set(f"input.END{axis}", True)
    return mod.write(axis, 20, db, md_for(axis, db))


@pytest.fixture
def tcp(devsim_device: Any) -> Iterator[tuple[Any, AgClient]]:
    module = devsim_device("ip247", {"sys_id": {"module": 11}}, transport="tcp")
    host, port = module.port_url("ag").removeprefix("socket://").rsplit(":", 1)
    with AgClient(host, int(port)) as plc:
        yield module, plc


@pytest.mark.manual("§4.3.12", "a machine-data record can be transferred only over the page of its axis")
def test_md_only_over_the_axis_page(mod: Module) -> None:
    mod.device.set("input.ANF2", True)
    mod.device.set("input.END2", True)
    answer = mod.write(2, 20, 101, md_for(1, 101))  # axis 1's record on page 2
    assert answer[0] == 0x80 and answer[4] == 46
    answer = mod.write(4, 20, 101, md_for(1, 101))
    assert answer[0] == 0x80 and answer[4] == 46


@pytest.mark.manual("§4.3.12", "machine data can be entered only while the axis is fertig")
@pytest.mark.manual("§4.3.13", "BA21 deletes machine data only while the axis is fertig")
def test_md_input_and_delete_need_a_fertig_axis(mod: Module) -> None:
    mod.ready()
    mod.operate(1, 1, FORWARD)
    mod.clock.advance(0.2)
    assert mod.write(1, 20, 101, md_for(1, 101), flags=1)[4] == 4
    assert mod.client.delete_record(1, 21, 101)[4] == 4


@pytest.mark.manual("§4.3.12", "machine data can be entered only when the record's module number equals the "
                    "SYS-ID's; after BA24 with that number they are accepted")
def test_md_input_after_the_sys_id(devsim_device: Any) -> None:
    import serial

    from devsim.devices.ip247.client import PgClient
    module = devsim_device("ip247", {})
    module.set("input.ANF1", True)
    module.set("input.END1", True)
    with serial.serial_for_url(module.port_url("pg"), baudrate=9600, parity="E", timeout=5) as port:
        pg = PgClient(port)
        assert pg.write_record(1, 20, 101, md_for(1, 101))[8] == 12  # SYS-ID module 0, the record 11
        assert pg.write_record(4, 24, 0, [11, 1, 0])[4] == 0
        assert pg.write_record(1, 20, 101, md_for(1, 101), overwrite=True)[8] == 0


@pytest.mark.manual("§4.3.14", "BA64 lists the machine-data records of all three axes at once")
@pytest.mark.manual("§4.3.16", "BA68 gives for all three axes the MD number, module, axis, length in words and the "
                    "MD error")
def test_directory_and_overview(mod: Module) -> None:
    assert load(mod, 1, 101)[8] == 0
    assert load(mod, 3, 103)[8] == 0
    assert struct.unpack(">6H", mod.client.read_record(2, 64)[8:]) == (101, 70, 0, 0, 103, 70)
    overview = struct.unpack(">15H", mod.client.read_record(2, 68)[8:])
    assert overview == (101, 11, 1, 70, 0, 0, 0, 0, 0, 0, 103, 11, 3, 70, 0)


@pytest.mark.manual("§4.3.15", "with different DB numbers a machine-data record can be read over any page")
def test_md_read_over_any_page_when_numbers_differ(mod: Module) -> None:
    assert load(mod, 1, 101)[8] == 0
    assert load(mod, 2, 102)[8] == 0
    for page in (1, 3, 4):
        answer = mod.client.read_record(page, 67, 102)
        assert answer[0] == 0 and answer[4] == 0, page
        assert struct.unpack(">70H", answer[8:])[3] & 0xFF == 2  # axis 2's record


@pytest.mark.manual("§4.3.15", "with equal DB numbers a record must be read over its axis's page")
def test_md_read_over_the_axis_page_when_numbers_are_equal(mod: Module) -> None:
    assert load(mod, 1, 7)[8] == 0
    assert load(mod, 2, 7)[8] == 0
    assert struct.unpack(">70H", mod.client.read_record(2, 67, 7)[8:])[3] & 0xFF == 2
    assert mod.client.read_record(4, 67, 7)[0] == 0x80


@pytest.mark.manual("§4.3.18", "from the PLC side a program number already on the IP247 cannot be overwritten (49)")
@pytest.mark.manual("§4.3.20", "BA65 lists the programs in the order they were entered, with their lengths in words")
def test_program_input_from_the_plc_and_the_directory(tcp: tuple[Any, AgClient]) -> None:
    _, plc = tcp
    first = lang.record_words(9, "%  9\nN1 M02\n")
    second = lang.record_words(3, "%  3\nN1 X1 F100\nN2 M02\n")
    assert plc.write_record(3, 22, 9, first)[4] == 0
    assert plc.write_record(3, 22, 3, second)[4] == 0
    assert plc.write_record(3, 22, 9, first)[4] == 49
    assert struct.unpack(">4H", plc.read_record(0, 65)[8:]) == (9, len(first), 3, len(second))


@pytest.mark.manual("§4.3.18", "a program from the CPU is checked by the firmware; a faulty one is stored marked "
                    "faulty: module error 48, the program error in the header")
@pytest.mark.manual("§4.3.21", "BA69 reads a program over any page, with a header of its length in words, its "
                    "number, the program error and the faulty block")
def test_faulty_program_from_the_plc_and_read_back(tcp: tuple[Any, AgClient]) -> None:
    _, plc = tcp
    text = "%  4\nN1 X10\nN2 M02\n"  # X without F: error 6 in block 1
    answer = plc.write_record(3, 22, 4, lang.record_words(4, text))
    assert answer[4] == 48 and answer[8:12] == struct.pack(">2H", 6, 1)
    for page in (0, 1, 2, 3):
        record = struct.unpack(">5H", plc.read_record(page, 69, 4)[8:18])
        assert record[0] == len(lang.record_words(4, text)) and record[2] & 0xFF == 4, page
        assert record[3:] == (6, 1)


@pytest.mark.manual("§4.3.19", "deleting a program while another one runs leaves a gap: 'Verfahrprogramm ist nur "
                    "aus dem Directory gelöscht' (61)")
def test_delete_while_another_program_runs(mod: Module) -> None:
    mod.ready()
    assert mod.store(1, "%  1\nN1 X100 F1000\nN2 M02\n")[4] == 0
    assert mod.store(2, "%  2\nN1 M02\n")[4] == 0
    mod.operate(1, 8, START, b=1)
    mod.clock.advance(0.5)
    assert mod.client.delete_record(4, 23, 2)[4] == 61
    assert struct.unpack(">2H", mod.client.read_record(4, 65)[8:])[0] == 1


@pytest.mark.manual("§4.3.22", "BA24 enters module number, slot and page; type IP247 and the firmware version "
                    "cannot be changed")
@pytest.mark.manual("§4.3.23", "BA70 reads the SYS-ID over every page")
def test_sys_id_in_and_out(devsim_device: Any) -> None:
    import serial

    from devsim.devices.ip247.client import PgClient
    module = devsim_device("ip247", {})
    with serial.serial_for_url(module.port_url("pg"), baudrate=9600, parity="E", timeout=5) as port:
        pg = PgClient(port)
        assert pg.write_record(4, 24, 0, [42, 200, 252])[4] == 0
        for page in (1, 2, 3, 4):
            answer = pg.read_record(page, 70)
            assert answer[8:20] == b"IP247 A02.1 " and answer[20:26] == bytes((0, 42, 0, 200, 0, 252)), page


@pytest.mark.manual("§4.3.22", "the module number cannot be changed once correct machine data are on the module "
                    "(12)")
def test_module_number_frozen_by_correct_md(mod: Module) -> None:
    mod.ready()
    assert mod.write(4, 24, 0, [12, 1, 0])[4] == 12
    assert mod.write(4, 24, 0, [11, 5, 9])[4] == 0  # the same number: slot and page change


@pytest.mark.manual("§4.3.18", "at most 255 programs can be stored (18 'Max. Programmzahl erreicht')")
def test_at_most_255_programs(mod: Module) -> None:
    for number in range(255):
        assert mod.store(number, f"%{number:3d}\nN1 M02\n")[4] == 0, number
    answer = mod.client.delete_record(4, 23, 7)
    assert answer[4] == 0
    assert mod.store(7, "%  7\nN1 M02\n")[4] == 0
    assert mod.store(255, "%255\nN1 M02\n")[4] == 18


@pytest.mark.manual("§4.3.19", "deleting a program while no program runs frees its memory (the memory is "
                    "compacted); a gap left while a program ran stays until then")
def test_deleting_frees_memory_unless_a_program_runs(mod: Module) -> None:
    mod.ready()
    block = "N1 G04 F1" + " " * 39 + "\n"
    big = "%{:3d}\n" + block * 19 + "N2 M02\n"
    count = 6000 // len(big.format(1))
    for number in range(1, count + 1):
        assert mod.store(number, big.format(number))[4] == 0
    assert mod.store(200, big.format(200))[4] == 24
    mod.operate(1, 8, START, b=1)  # program 1 dwells 19 × 0.1 s
    assert mod.client.delete_record(4, 23, 2)[4] == 61
    assert mod.store(200, big.format(200))[4] == 24  # the gap is not free yet
    mod.clock.advance(10)
    assert mod.client.delete_record(4, 23, 3)[4] == 0  # compacts, closing the gap too
    assert mod.store(200, big.format(200))[4] == 0
    assert mod.store(201, big.format(201))[4] == 0


@pytest.mark.manual("§4.3.18", "the PG may overwrite a program after asking ('Verfahrprogramm überschreiben ?'): "
                    "the old one is deleted and the new one stored in one step (spec §3.6.6)")
def test_an_overwrite_that_does_not_fit_keeps_the_old_program(mod: Module) -> None:
    def program(number: int) -> bytes:  # BA69 over the PG: the record as stored
        return mod.client.read_record(1, 69, number)[8:]

    def words(number: int, text: str) -> bytes:
        record = lang.record_words(number, text)
        return struct.pack(f">{len(record)}H", *record)

    block = "N1 G04 F1" + " " * 39 + "\n"
    big = "%{:3d}\n" + block * 19 + "N2 M02\n"
    old, fits = "%  5\nN1 M02\n", "%  5\nN1 G04 F2\nN2 M02\n"
    assert mod.store(5, old)[4] == 0
    number = 10
    while mod.store(number, big.format(number))[4] == 0:  # fill the 6000 characters
        number += 1
    assert mod.store(number, big.format(number))[4] == 24
    directory = mod.client.read_record(0, 65)[8:]  # BA65: number and length of each, in storage order
    larger = big.format(5) + block * 2  # more than program 5 and the room left together
    assert mod.write(4, 22, 5, lang.record_words(5, larger), flags=1)[4] == 24
    assert mod.client.read_record(0, 65)[8:] == directory and program(5) == words(5, old)  # as it was
    assert mod.write(4, 22, 5, lang.record_words(5, fits), flags=1)[4] == 0
    assert program(5) == words(5, fits)


@pytest.mark.manual("§4.3.12", "a machine-data record can be transferred only over the page of its axis (46)")
def test_setting_a_record_the_module_refuses_says_so_and_keeps_the_old_one(mod: Module) -> None:
    assert mod.load_md(1)[8] == 0
    stored = mod.device.read("axis.1.machine_data")
    with pytest.raises(Exception, match="machine data not stored: module error 46"):
        mod.device.set("axis.1.machine_data", md_for(2, 101))  # a record of axis 2 set on axis 1
    assert mod.device.read("axis.1.machine_data") == stored


@pytest.mark.parametrize("change", [
    lambda texts: ["0x" + texts[0], *texts[1:]],  # int(text, 16) read a prefix,
    lambda texts: [*texts[:-1], "-1"],  # a sign (stored as FFFF),
    lambda texts: ["\u0660" + texts[0], *texts[1:]],  # an Arabic-Indic digit,
    lambda texts: ["\u00a0".join(texts)],  # and str.split() split at NBSP
], ids=["prefix", "sign", "arabic-indic", "nbsp"])
def test_machine_data_in_one_string_are_hex_words(mod: Module, change: Any) -> None:
    """The machine-data point's one-string form is 70 words of 1 to 4 hex digits with blanks between."""
    assert mod.load_md(1)[8] == 0
    stored = mod.device.read("axis.1.machine_data")
    with pytest.raises(Exception, match="are hex words"):
        mod.device.set("axis.1.machine_data", " ".join(change(COM247.split())))
    assert mod.device.read("axis.1.machine_data") == stored
    mod.device.set("axis.1.machine_data", COM247)  # (lines and blanks between the words as they come)
