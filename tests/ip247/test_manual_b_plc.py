"""The manual's PLC chapter walked (manual §6 Standard-Funktionsbausteine FB164 und FB165): what
the module shows the function blocks, driven through the PLC endpoint (TCP, absolute pages from
the S2 base page 0: 0 … 2 the axes, 3 the data channel) in virtual time.  FB164 and FB165
themselves (their parameters, PAFE, data-block work areas) run in the PLC: see deviations.py."""

from __future__ import annotations

import struct
from collections.abc import Iterator
from typing import Any

import msgspec
import pytest
import serial

from devsim.devices.ip247 import program as lang
from devsim.devices.ip247.client import AgClient, PgClient
from devsim.devices.ip247.machine_data import decode, encode
from tests.ip247.test_machine_data import COM247, MANUAL, words

DATA_CHANNEL = 3


class Plc:
    """A module with its PLC endpoint on TCP, and an FB-like client on it."""

    def __init__(self, module: Any) -> None:
        self.module = module
        host, port = module.port_url("ag").removeprefix("socket://").rsplit(":", 1)
        self.ag = AgClient(host, int(port))

    def md(self, axis: int = 1, **changes: object) -> list[int]:
        """COM247's machine data (module 0, binary values) for an axis, with changes."""
        md = decode(words(COM247))
        return encode(msgspec.structs.replace(md, **{"module": 0, "axis": axis, "bcd": False, **changes}))

    def ready(self, axis: int = 1, **changes: object) -> None:
        """Machine data through the axis's page, then "Referenzpunkt setzen"."""
        self.module.set(f"input.ANF{axis}", True)
        self.module.set(f"input.END{axis}", True)
        assert self.ag.write_record(axis - 1, 20, axis, self.md(axis, **changes))[8] == 0
        assert self.ag.operate(axis - 1, 5, "Start", b=1)[4] == 0

    def words(self, answer: bytes) -> tuple[int, ...]:
        return struct.unpack(f">{(len(answer) - 8) // 2}H", answer[8:])


@pytest.fixture
def plc(devsim_device: Any) -> Iterator[Plc]:
    side = Plc(devsim_device("ip247", {}, transport="tcp"))
    yield side
    side.ag.close()


@pytest.mark.manual("§6.2.4", "the operator modes 18 and 19, which FB164 allows, are negatively acknowledged "
                    "by the IP247 on all four pages: they do not exist on the module")
@pytest.mark.manual("§6.2.4", "the observe function 72, which FB164 allows, is negatively acknowledged on all "
                    "pages")
def test_modes_18_19_and_72_are_refused_on_every_page(plc: Plc) -> None:
    for page in range(4):
        for ba in (18, 19, 72):
            assert plc.ag.operate(page, ba, "Start")[0] == 0x80, (page, ba)


@pytest.mark.manual("§6.2.4", "MFKT: in BA8 and BA9 the M functions programmed in the program are given; in every "
                    "other mode M02")
def test_the_m_function_is_m02_outside_automatic(plc: Plc) -> None:
    plc.ready()
    assert plc.ag.operate(0, 7, "Vorwärts", w=1000, dd=1_000)[7] == 2
    plc.module.advance(5)
    plc.ag.write_record(DATA_CHANNEL, 22, 5, lang.record_words(5, "%  5\nN1 X10 F1000 M10\nN2 X20 F1000\nN3 M02\n"))
    plc.ag.operate(0, 8, "Start", b=5)
    plc.module.advance(0.3)
    assert plc.ag.observe(0)[7] == 10
    plc.module.advance(30)
    assert plc.ag.observe(0)[7] == 2  # the program ended with M02
    plc.ag.operate(0, 1, "Vorwärts", w=100)
    assert plc.ag.observe(0)[7] == 2


@pytest.mark.manual("§6.2.4", "RMLD bits 2 … 7: in position, reference synchronous, axis in teach-in, reference "
                    "point missing, machine data missing, job finished (0: job running)")
def test_the_attribute_bits_as_the_plc_reads_them(plc: Plc) -> None:
    assert plc.ag.observe(0)[6] & 0xE0 == 0xE0  # no MD, no reference, fertig
    plc.ready()
    assert plc.ag.observe(0)[6] & 0x60 == 0
    plc.ag.operate(0, 7, "Vorwärts", w=1000, dd=2_000)
    assert plc.ag.observe(0)[6] & 0x84 == 0  # running, not in position
    plc.module.advance(5)
    assert plc.ag.observe(0)[6] & 0x84 == 0x84
    plc.ag.operate(0, 10, "Start", b=9)
    assert plc.ag.observe(0)[6] & 0x10
    plc.ag.operate(0, 11, "Start")
    assert not plc.ag.observe(0)[6] & 0x10


@pytest.mark.manual("§6.2.7.2", "BA5: byte parameter 0 drives to the reference point, any other value sets it")
@pytest.mark.manual("§6.2.7.2", "parameters the table does not name for a mode are not evaluated by the IP247")
def test_the_parameter_convention_of_the_axis_data_block(plc: Plc) -> None:
    plc.module.set("input.ANF1", True)
    plc.module.set("input.END1", True)
    plc.ag.write_record(0, 20, 1, plc.md())
    assert plc.ag.operate(0, 5, "Start", b=7, w=0xFFFF, dd=0x1234_5678)[4] == 0
    assert plc.module.read("axis.1.reference_set") is True and plc.module.read("axis.1.position") == 1_000
    assert plc.ag.operate(0, 12, "Start", b=0xAA, w=0x5555, dd=25_000)[4] == 0
    assert plc.module.read("axis.1.position") == 25_000
    assert plc.ag.operate(0, 14, "Start", b=0xAA, w=0x5555, dd=0x7777_7777)[4] == 0
    assert plc.ag.operate(0, 4, "Start", b=0xAA, w=0x5555, dd=0x7777_7777)[4] == 0
    assert plc.module.read("axis.1.position") == 1_000 and plc.module.read("axis.1.running") is False
    plc.module.set("input.BERO1", True)
    assert plc.ag.operate(0, 5, "Start", b=0)[4] == 0  # on the cam: the run leaves it in single steps
    assert plc.module.read("axis.1.reference_set") is False and plc.module.read("axis.1.running") is True


@pytest.mark.manual("§6.2.7.2", "with 'AG BCD-codiert' paths are BCD with the sign in bits 28 … 31: BA6 to "
                    "-120000 µm is F012 0000H, in binary FFFE 2B40H (two's complement)")
@pytest.mark.manual("§6.2.7.2", "a 1 in the byte parameter tells the IP247 to multiply the (BCD) word parameter "
                    "by 10: 1000H with byte 1 is 10000 mm/min")
def test_the_bcd_example_of_the_axis_data_block(plc: Plc) -> None:
    changes = {"limit_begin": -200_000, "gear": 2_000, "reference_velocity": 2_000, "a": 1_000_000}  # 2 µm: 12 m/min
    plc.ready(**changes)
    assert plc.ag.operate(0, 6, "Start", w=0x03E8, dd=0xFFFE_2B40)[4] == 0
    plc.module.advance(30)
    assert plc.module.read("axis.1.position") == -120_000
    plc.ag.delete_record(0, 21, 1)
    plc.ag.write_record(0, 20, 1, plc.md(**changes, bcd=True))
    plc.ag.operate(0, 5, "Start", b=1)
    assert plc.ag.operate(0, 6, "Start", b=1, w=0x1000, dd=0x0012_0000)[4] == 0  # from x_ref = 1 mm
    plc.module.advance(0.4)
    assert plc.module.read("axis.1.velocity") == pytest.approx(10_000 * 1000 / 60)  # µm/s at cruise
    plc.module.advance(30)
    assert plc.module.read("axis.1.position") == 120_000
    assert plc.ag.operate(0, 6, "Start", b=0, w=0x1000, dd=0xF012_0000)[4] == 0
    plc.module.advance(2)
    assert plc.module.read("axis.1.velocity") == pytest.approx(-1000 * 1000 / 60)
    plc.module.advance(30)
    assert plc.module.read("axis.1.position") == -120_000


@pytest.mark.manual("§6.2.9.1", "the Stopp command has the highest priority and may be given with any mode "
                    "(FB164 sends it with BA1 while it observes)")
def test_stopp_with_any_mode_stops_the_axis(plc: Plc) -> None:
    plc.ready()
    plc.ag.operate(0, 6, "Start", w=1000, dd=300_000)
    plc.module.advance(2)
    assert plc.ag.operate(0, 1, "Stopp")[4] == 0
    plc.module.advance(5)
    assert plc.module.read("axis.1.running") is False and plc.module.read("axis.1.position") < 100_000


@pytest.mark.manual("§6.2.6.2", "TBIT is set by FB164 when it hands a job over and reset after the job is "
                    "executed or aborted")
@pytest.mark.manual("§6.2.6.2", "a program started from the AG: TBIT reset at an interruption, set again by an "
                    "Übernahme from the AG and reset at the next interruption or the end")
@pytest.mark.manual("§6.2.6.2", "a program continued from the PG is treated as started from the PG: TBIT is not "
                    "set")
def test_tbit_over_a_job_and_an_interrupted_program(plc: Plc) -> None:
    plc.ready()
    plc.ag.operate(0, 7, "Vorwärts", w=1000, dd=5_000)
    assert plc.module.read("axis.1.tbit") is True
    plc.module.advance(10)
    assert plc.module.read("axis.1.tbit") is False
    plc.ag.write_record(DATA_CHANNEL, 22, 5, lang.record_words(5, "%  5\nN1 X40 F1000\nN2 X80 F1000\nN3 M02\n"))
    plc.ag.operate(0, 8, "Start", b=5)
    plc.module.advance(0.5)
    assert plc.module.read("axis.1.tbit") is True
    plc.ag.operate(0, 8, "Stopp")
    plc.module.advance(2)
    assert plc.module.read("axis.1.tbit") is False
    plc.ag.operate(0, 8, "Übernahme")
    assert plc.module.read("axis.1.tbit") is True
    plc.module.advance(0.5)
    plc.ag.operate(0, 8, "Stopp")
    plc.module.advance(2)
    assert plc.module.read("axis.1.tbit") is False
    with serial.serial_for_url(plc.module.port_url("pg"), timeout=5) as port:  # the PG port (TCP here)
        assert PgClient(port).operate(1, 8, "Übernahme")[4] == 0
    assert plc.module.read("axis.1.running") is True and plc.module.read("axis.1.tbit") is False


@pytest.mark.manual("§6.3.4", "record modes and the pages they run on: 20, 21, 66 on an axis; 22, 23, 24 on the "
                    "data channel; 64, 65, 68, 69, 70 on all axes and the data channel; on another page the "
                    "IP247 acknowledges negatively")
def test_each_record_mode_on_each_page(plc: Plc) -> None:
    plc.ready()
    plc.ag.write_record(DATA_CHANNEL, 22, 5, lang.record_words(5, "%  5\nN1 M02\n"))
    for page in range(4):
        on_axis = page < DATA_CHANNEL
        for ba in (64, 65, 68, 69, 70):
            assert plc.ag.read_record(page, ba, 5)[0] == 0, (page, ba)
        assert plc.ag.read_record(page, 66)[0] == (0 if on_axis else 0x80)
        assert plc.ag.delete_record(page, 21, 99)[0] == (0 if on_axis else 0x80)
        assert plc.ag.write_record(page, 20, 9, plc.md(axis=min(page + 1, 3)))[0] == (0 if on_axis else 0x80)
        assert plc.ag.write_record(page, 22, 7, lang.record_words(7, "%  7\nN1 M02\n"))[0] == (0x80 if on_axis else 0)
        assert plc.ag.delete_record(page, 23, 7)[0] == (0x80 if on_axis else 0)
        assert plc.ag.write_record(page, 24, 0, [0, 0, 0])[0] == (0x80 if on_axis else 0)


@pytest.mark.manual("§6.3.4", "BA67 reads machine data over the data channel only when all DB numbers differ")
def test_machine_data_over_the_data_channel_only_with_distinct_numbers(plc: Plc) -> None:
    plc.module.set("input.ANF2", True)
    plc.module.set("input.END2", True)
    plc.ready()
    assert plc.ag.write_record(1, 20, 1, plc.md(axis=2))[8] == 0  # DB 1 on axes 1 and 2
    assert plc.ag.read_record(DATA_CHANNEL, 67, 1)[0] == 0x80
    assert plc.ag.read_record(1, 67, 1)[0] == 0  # the axis's own page
    plc.ag.delete_record(1, 21, 1)
    plc.ag.write_record(1, 20, 2, plc.md(axis=2))
    answer = plc.ag.read_record(DATA_CHANNEL, 67, 2)
    assert answer[0] == 0 and plc.words(answer)[3] == 0x0002  # module 0, axis 2


@pytest.mark.manual("§6.3.8.1", "the machine-data DB of the manual's example (70 words) is written with BA20 and "
                    "read back with BA67 word for word, DR n+4 the machine-data error")
@pytest.mark.manual("§6.3.4", "the dual/BCD conversion flag (BA = KY x,y with x > 0) is evaluated only with BA66")
def test_the_manuals_machine_data_record_round_trip(plc: Plc) -> None:
    plc.module.set("input.ANF1", True)
    plc.module.set("input.END1", True)
    record = words(MANUAL)
    assert plc.ag.write_record(0, 20, 1, record)[8] == 0
    assert list(plc.words(plc.ag.read_record(0, 67, 1))) == record
    assert list(plc.words(plc.ag.read_record(0, 67, 1, bcd=True))) == record  # the BCD flag is BA66's only


@pytest.mark.manual("§6.3.8.2", "programs are axis-independent: transferred and deleted only over the data "
                    "channel, read over every page")
@pytest.mark.manual("§6.3.8.5", "the program directory lists two words per program (number, length in words) in "
                    "the order the programs are stored on the IP247, not sorted by number")
def test_the_program_directory_in_storage_order(plc: Plc) -> None:
    texts = {78: "%  78\nN1 X1 F100\nN2 M02\n", 1: "%  1 BEISPIEL\nN1 X100 F1000 M10\nN2 M02\n", 165: "%165\nN1 M02\n"}
    for number, text in texts.items():
        assert plc.ag.write_record(DATA_CHANNEL, 22, number, lang.record_words(number, text))[8:] == bytes(4)
    expected = [w for number, text in texts.items() for w in (number, len(lang.record_words(number, text)))]
    assert expected[2:4] == [1, 25]  # "BEISPIEL" is 25 words long (§6.3.8.2)
    for page in range(4):
        assert list(plc.words(plc.ag.read_record(page, 65))) == expected
        assert list(plc.words(plc.ag.read_record(page, 69, 1))) == lang.record_words(1, texts[1])


@pytest.mark.manual("§6.3.8.3", "SYS-ID read (BA70): 9 words, 'IP247 ' and the firmware state 'A02.1 ', then "
                    "module, slot and page number in the right bytes; written (BA24) as 3 words")
@pytest.mark.manual("§6.3.10", "after switching on, module, slot and page number are preset to 0")
def test_the_sys_id_records(plc: Plc) -> None:
    assert plc.words(plc.ag.read_record(DATA_CHANNEL, 70)) == (0x4950, 0x3234, 0x3720, 0x4130, 0x322E, 0x3120,
                                                               0, 0, 0)
    assert plc.ag.write_record(DATA_CHANNEL, 24, 0, [99, 255, 252])[4] == 0
    assert plc.words(plc.ag.read_record(1, 70))[6:] == (99, 255, 252)


@pytest.mark.manual("§6.3.8.4", "the machine-data directory has a constant length of six words, DB number and "
                    "length 70 per axis; zero where an axis has no machine data")
@pytest.mark.manual("§6.3.8.7", "the machine-data overview: 15 words, per axis DB number, module number, axis "
                    "number, length and machine-data error; zero without machine data")
def test_the_machine_data_directory_and_overview(plc: Plc) -> None:
    plc.ready()
    plc.module.set("input.ANF3", True)
    plc.module.set("input.END3", True)
    plc.ag.write_record(2, 20, 7, plc.md(axis=3, backlash=65_000))  # MD error 20
    assert plc.words(plc.ag.read_record(DATA_CHANNEL, 64)) == (1, 70, 0, 0, 7, 70)
    assert plc.words(plc.ag.read_record(0, 68)) == (1, 0, 1, 70, 0, 0, 0, 0, 0, 0, 7, 0, 3, 70, 20)


@pytest.mark.manual("§6.3.8.6", "BA66 reads actual value and residual distance in 6 words (position, 2 words "
                    "unused, residual), 32-bit binary, negative values in two's complement")
@pytest.mark.manual("§6.3.8.6", "with BCD conversion (KY 255,66) seven decades and a sign; a value beyond "
                    "±9999999 stays binary")
def test_actual_values_binary_and_bcd(plc: Plc) -> None:
    plc.ready(limit_begin=-20_000_000, limit_end=20_000_000)
    plc.ag.operate(0, 12, "Start", dd=47_287)
    assert plc.words(plc.ag.read_record(0, 66)) == (0, 0xB8B7, 0, 0, 0, 0)
    plc.ag.operate(0, 7, "Rückwärts", w=6000, dd=12_602)
    plc.module.advance(0.05)
    answer = plc.ag.read_record(0, 66)
    residual = struct.unpack(">i", answer[16:20])[0]  # backward: negative
    assert -12_602 < residual < 0 and plc.module.read("axis.1.residual") == residual
    plc.module.advance(5)
    assert plc.words(plc.ag.read_record(0, 66)) == (0, 34_685, 0, 0, 0, 0)
    plc.ag.operate(0, 12, "Start", dd=-47_287)
    assert plc.words(plc.ag.read_record(0, 66)) == (0xFFFF, 0x10000 - 47_287, 0, 0, 0, 0)
    assert plc.words(plc.ag.read_record(0, 66, bcd=True)) == (0xF004, 0x7287, 0, 0, 0, 0)
    plc.ag.operate(0, 12, "Start", dd=12_345_678)
    assert plc.words(plc.ag.read_record(0, 66, bcd=True))[:2] == (12_345_678 >> 16, 12_345_678 & 0xFFFF)


@pytest.mark.manual("§6.3.10", "machine data are accepted only when their module number equals the SYS-ID's")
@pytest.mark.manual("§6.3.10", "with valid machine data jog and relative incremental moves work at once; "
                    "absolute targets only after BA5")
@pytest.mark.manual("§6.3.10", "there is no overwrite mode for machine data: delete the old set (BA21), then "
                    "transfer the new one (BA20)")
def test_commissioning_over_the_plc_interface(plc: Plc) -> None:
    plc.module.set("input.ANF1", True)
    plc.module.set("input.END1", True)
    answer = plc.ag.write_record(0, 20, 1, plc.md(module=11))
    assert (answer[8], answer[4]) == (12, 15)
    plc.ag.delete_record(0, 21, 1)
    plc.ag.write_record(DATA_CHANNEL, 24, 0, [11, 0, 0])
    assert plc.ag.write_record(0, 20, 1, plc.md(module=11))[8] == 0
    assert plc.ag.operate(0, 1, "Vorwärts", w=1000)[4] == 0
    plc.ag.operate(0, 1, "Stopp")
    plc.module.advance(2)
    assert plc.ag.operate(0, 7, "Vorwärts", w=1000, dd=1_000)[4] == 0
    plc.module.advance(2)
    assert plc.ag.operate(0, 6, "Start", w=1000, dd=1_000)[4] == 10
    assert plc.ag.write_record(0, 20, 1, plc.md(module=11, jog1=2000), overwrite=True)[4] == 17
    assert plc.ag.delete_record(0, 21, 1)[4] == 0
    assert plc.ag.write_record(0, 20, 1, plc.md(module=11, jog1=2000))[8] == 0


@pytest.mark.manual("§6.3.10", "any DB number 0 … 255 may name a machine-data set; the three axes may each have a "
                    "set with the same DB number, told apart by the axis number")
def test_machine_data_numbers(plc: Plc) -> None:
    for axis in (1, 2, 3):
        plc.module.set(f"input.ANF{axis}", True)
        plc.module.set(f"input.END{axis}", True)
        assert plc.ag.write_record(axis - 1, 20, 0 if axis < 3 else 255, plc.md(axis=axis))[8] == 0
    assert plc.words(plc.ag.read_record(DATA_CHANNEL, 64)) == (0, 70, 0, 70, 255, 70)


@pytest.mark.manual("§6.3.10", "a machine-data set is assigned to an axis by the axis number in the set (DR n+3) "
                    "and is transferred over that axis's page")
def test_machine_data_for_another_axis_are_refused(plc: Plc) -> None:
    plc.module.set("input.ANF1", True)
    plc.module.set("input.END1", True)
    answer = plc.ag.write_record(0, 20, 2, plc.md(axis=2))
    assert answer[0] == 0x80 and answer[4] == 46
    assert plc.module.read("axis.1.md_error") == -1 and plc.module.read("axis.2.md_error") == -1


@pytest.mark.manual("§6.3.10", "a stored program cannot be overwritten from the AG: read it (BA69), delete it "
                    "(BA23), transfer the changed one (BA22)")
@pytest.mark.manual("§6.3.10", "all three axes may execute the same program at the same time; it can be deleted "
                    "only when no axis executes it")
def test_programs_over_the_plc_interface(plc: Plc) -> None:
    for axis in (1, 2, 3):
        plc.ready(axis)
    old, new = "%  5\nN1 X10 F1000\nN2 M02\n", "%  5\nN1 X20 F1000\nN2 M02\n"
    plc.ag.write_record(DATA_CHANNEL, 22, 5, lang.record_words(5, old))
    assert plc.ag.write_record(DATA_CHANNEL, 22, 5, lang.record_words(5, new), overwrite=True)[4] == 49
    assert list(plc.words(plc.ag.read_record(DATA_CHANNEL, 69, 5))) == lang.record_words(5, old)
    for axis in (1, 2, 3):
        assert plc.ag.operate(axis - 1, 8, "Start", b=5)[4] == 0
    plc.module.advance(0.5)
    assert [plc.module.read(f"axis.{n}.running") for n in (1, 2, 3)] == [True] * 3
    assert plc.ag.delete_record(DATA_CHANNEL, 23, 5)[4] == 51
    plc.module.advance(30)
    assert [plc.module.read(f"axis.{n}.position") for n in (1, 2, 3)] == [10_000] * 3
    assert plc.ag.delete_record(DATA_CHANNEL, 23, 5)[4] == 0
    assert plc.ag.write_record(DATA_CHANNEL, 22, 5, lang.record_words(5, new))[4] == 0


@pytest.mark.manual("§6.2.7.2", "BA1/BA2 in BCD: the word parameter is the velocity in BCD, the byte parameter 1 "
                    "multiplies it by 10 (0: as it is)")
def test_a_bcd_jog_velocity(plc: Plc) -> None:
    plc.ready(bcd=True)  # COM247's MD: 1.1 µm per pulse, at most 6600 mm/min
    plc.ag.operate(0, 1, "Vorwärts", b=1, w=0x0500)
    plc.module.advance(3)
    assert plc.module.read("axis.1.velocity") == pytest.approx(5000 * 1000 / 60)
    plc.ag.operate(0, 1, "Stopp")
    plc.module.advance(3)
    plc.ag.operate(0, 1, "Rückwärts", b=0, w=0x0500)
    plc.module.advance(3)
    assert plc.module.read("axis.1.velocity") == pytest.approx(-500 * 1000 / 60)


@pytest.mark.manual("§5.6.1.2", "'AG BCD-codiert' yes: every coordinate the AG sends (targets, increments, zero "
                    "offsets, tool offsets) is read as BCD, within ±9999999")
def test_bcd_offsets_and_increments_from_the_plc(plc: Plc) -> None:
    plc.ready(bcd=True)
    assert plc.ag.operate(0, 12, "Start", dd=0x0002_5000)[4] == 0  # BA12: actual value 25 mm
    assert plc.module.read("axis.1.position") == 25_000
    assert plc.ag.operate(0, 13, "Vorwärts", dd=0x0000_5000)[4] == 0  # BA13: 5 mm forward
    assert plc.module.read("axis.1.position") == 20_000
    assert plc.ag.operate(0, 15, "Vorwärts", dd=0x0000_3000)[4] == 0  # BA15: tool 3 mm
    assert plc.module.read("axis.1.position") == 23_000
    assert plc.ag.operate(0, 7, "Rückwärts", w=0x1000, dd=0x0001_0000)[4] == 0  # BA7: 10 mm back
    plc.module.advance(10)
    assert plc.module.read("axis.1.position") == 13_000
    assert plc.ag.operate(0, 12, "Start", dd=0x0002_500A)[4] == 66
    assert plc.ag.operate(0, 15, "Vorwärts", dd=0x0000_30F0)[4] == 66


@pytest.mark.manual("§6.3.8.5", "programs are listed in the order they are stored: a program transferred again "
                    "after a delete comes last")
def test_the_directory_order_after_a_delete(plc: Plc) -> None:
    for number in (3, 1, 2):
        plc.ag.write_record(DATA_CHANNEL, 22, number, lang.record_words(number, f"%{number:3d}\nN1 M02\n"))
    plc.ag.delete_record(DATA_CHANNEL, 23, 3)
    plc.ag.write_record(DATA_CHANNEL, 22, 3, lang.record_words(3, "%  3\nN1 X1 F100\nN2 M02\n"))
    assert plc.words(plc.ag.read_record(DATA_CHANNEL, 65))[::2] == (1, 2, 3)


@pytest.mark.manual("§6.3.8.2", "program DB header: DW n length in words, DW n+1 00H 'D', DW n+2 'B' and the "
                    "number, DW n+3 the program error, DW n+4 the faulty block, the text from DW n+5")
def test_the_header_of_a_faulty_program(plc: Plc) -> None:
    text = "%  9 FEHLER\nN1 X10 F1000\nN2 X10 Q5\nN3 M02\n"
    answer = plc.ag.write_record(DATA_CHANNEL, 22, 9, lang.record_words(9, text))
    assert answer[4] == 48
    read = plc.words(plc.ag.read_record(1, 69, 9))
    assert read[:5] == (5 + (len(text) + 1) // 2, 0x0044, 0x4209, 16, 2)  # 16: function unknown, block 2
    assert b"".join(struct.pack(">H", w) for w in read[5:])[: len(text)] == text.encode()


@pytest.mark.manual("§6.4.6.1", "the machine-data DB104 in the AG is transferred (BA20, Z-DB 10) as DB10 in the "
                    "IP247's memory, read back (BA67, Q-DB 10) and deleted (BA21) under that number")
def test_the_target_db_number_names_the_stored_set(plc: Plc) -> None:
    plc.module.set("input.ANF1", True)
    plc.module.set("input.END1", True)
    md = plc.md()
    md[2] = 0x4200 | 104  # the AG's DB104
    assert plc.ag.write_record(0, 20, 10, md)[8] == 0
    assert plc.words(plc.ag.read_record(0, 64))[:2] == (10, 70)
    read = plc.words(plc.ag.read_record(0, 67, 10))
    assert read[2] == 0x4200 | 10 and read[5:] == tuple(md[5:])
    assert plc.ag.read_record(0, 67, 104)[4] == 13  # no set of that number
    assert plc.ag.delete_record(0, 21, 10)[4] == 0 and plc.words(plc.ag.read_record(0, 64)) == (0,) * 6


@pytest.mark.manual("§6.2.6.2", "BA9: each Übernahme starts the next block of the program (traverse or dwell); "
                    "TBIT is set with it and reset when the block is done")
def test_tbit_in_single_block(plc: Plc) -> None:
    plc.ready()
    plc.ag.write_record(DATA_CHANNEL, 22, 5, lang.record_words(5, "%  5\nN1 X10 F1000\nN2 G04 F10\nN3 X20 F1000\n"
                                                                   "N4 M02\n"))
    plc.ag.operate(0, 9, "Start", b=5)
    plc.module.advance(5)
    positions = []
    for _ in range(3):
        plc.ag.operate(0, 9, "Übernahme")
        assert plc.module.read("axis.1.tbit") is True
        plc.module.advance(10)
        assert plc.module.read("axis.1.tbit") is False
        positions.append(plc.module.read("axis.1.position"))
    assert positions == [10_000, 10_000, 20_000]


@pytest.mark.manual("§4.4", "Beobachtbetriebsarten sind: 66, 71, 73, 74 Beobachtung ausschalten (FB164); sie lassen "
                    "die eingestellte Bedienbetriebsart unbeeinflusst und können jederzeit und unabhängig vom "
                    "Zustand einer Achse ausgeführt werden")
@pytest.mark.manual("§6.2.4", "BA 74 Beobachten ausschalten is a mode FB164 hands over; only 72 (all pages) and 71, 73 "
                    "(data channel) are negatively acknowledged")
def test_observation_off_leaves_the_axis_and_its_error_alone(plc: Plc) -> None:
    plc.ready()
    assert plc.ag.operate(0, 6, "Start", w=1000, dd=900_000)[4] == 23  # beyond the SW limit: pending
    answer = plc.ag.operate(0, 74, "Start")
    assert answer[0] == 0 and answer[4] == 23 and plc.ag.observe(0)[4] == 23
    assert plc.ag.operate(0, 7, "Vorwärts", w=1000, dd=20_000)[4] == 0
    plc.module.advance(0.5)
    for cmd in ("Start", "Stopp"):
        answer = plc.ag.operate(0, 74, cmd)
        assert answer[0] == 0 and answer[4] == 0 and answer[5] == 7, cmd
    assert plc.module.read("axis.1.running") is True
    plc.module.advance(5)
    assert plc.module.read("axis.1.position") == 21_000 and plc.ag.observe(0)[4] == 0
    assert plc.ag.operate(DATA_CHANNEL, 74, "Start")[0] == 0


@pytest.mark.manual("§6.2.4", "Auf dem Datenkanal werden zusätzlich auch die Betriebsarten 1-16 negativ quittiert")
@pytest.mark.manual("§7.2.2", "error 46 also when one of the operator modes 1 … 17 other than 17 is tried on the "
                    "data channel (axis 4)")
def test_every_mode_1_to_16_is_refused_on_the_data_channel(plc: Plc) -> None:
    """BA3 ("frei", an undefined mode, error 2 on an axis page) is one of them."""
    assert plc.ag.operate(0, 3, "Start")[:1] + plc.ag.operate(0, 3, "Start")[4:5] == bytes((0, 2))
    for ba in range(1, 17):
        answer = plc.ag.operate(DATA_CHANNEL, ba, "Start")
        assert answer[0] == 0x80 and answer[4] == 46, ba
    assert plc.ag.operate(DATA_CHANNEL, 17, "Start")[0] == 0


@pytest.mark.manual("§4.3.10", "Sie können im Achszustand 'fertig' einen anstehenden Fehler auf allen Achsen und dem "
                    "Datenkanal mit dem Kommando 'Fehler löschen', 'Start' rücksetzen")
@pytest.mark.manual("§6.2.7.2", "BA17 Fehler löschen: zulässiger Befehl Start")
@pytest.mark.manual("§7.2.2", "error 2: the job was senseless at this point, e.g. starting an axis that runs; the "
                    "running mode is aborted and the error shown")
def test_clearing_errors_needs_a_finished_axis_and_start(plc: Plc) -> None:
    plc.ready()
    plc.ready(2)
    assert plc.ag.operate(1, 6, "Start", w=1000, dd=900_000)[4] == 23  # axis 2: error pending
    assert plc.ag.operate(0, 7, "Vorwärts", w=1000, dd=50_000)[4] == 0
    plc.module.advance(0.3)
    answer = plc.ag.operate(0, 17, "Start")  # on the page of the axis that runs
    assert answer[4] == 2 and answer[5] == 7
    plc.module.advance(3)
    assert plc.module.read("axis.1.running") is False and plc.module.read("axis.1.position") < 51_000 - 10_000
    assert plc.ag.observe(1)[4] == 23  # nothing cleared
    for cmd in ("Stopp", "Vorwärts", "Übernahme"):
        answer = plc.ag.operate(0, 17, cmd)
        assert answer[4] == 2 and plc.ag.observe(1)[4] == 23, cmd
    assert plc.ag.operate(0, 17, "Start")[4] == 0 and list(plc.ag.observe(1)[16:20]) == [0, 0, 0, 0]
