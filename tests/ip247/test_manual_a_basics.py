"""Walk of manual chapter 1 (Hinweise) and §2.2–§2.5 (the IP247, positioning, machine data),
driven through the PG port on a real pty and the PLC side's TCP endpoint."""

from __future__ import annotations

import struct
from collections.abc import Iterator
from typing import Any

import pytest
import serial

from devsim.devices.ip247 import program as lang
from devsim.devices.ip247.client import AgClient, PgClient
from tests.ip247.helpers import BACKWARD, FORWARD, START, STOP, Make, Module, record
from tests.ip247.test_machine_data import COM247, words


@pytest.fixture
def tcp(devsim_device: Any) -> Iterator[tuple[Any, AgClient]]:
    """A module with its PLC side on TCP (base page 0) and COM247's limit inputs not actuated."""
    module = devsim_device("ip247", {"sys_id": {"module": 11}}, transport="tcp")
    for n in (1, 2):
        module.set(f"input.ANF{n}", True)
        module.set(f"input.END{n}", True)
    host, port = module.port_url("ag").removeprefix("socket://").rsplit(":", 1)
    with AgClient(host, int(port)) as plc:
        yield module, plc


def md_for(axis: int, hex_words: str = COM247, db: int = 0) -> list[int]:
    data = words(hex_words)
    data[3] = (data[3] & 0xFF00) | axis
    if db:
        data[2] = (data[2] & 0xFF00) | db
    return data


@pytest.mark.manual("§1.2", "an axis started from the PG goes on moving when the test screen is left or the PG "
                    "is switched off")
def test_an_axis_moves_on_when_the_pg_goes_away(mod: Module) -> None:
    mod.ready()
    assert mod.operate(1, 7, FORWARD, w=1000, dd=20_000)[4] == 0
    mod.clock.advance(0.5)
    mod.port.close()
    mod.clock.advance(30)
    assert mod.device.read("axis.1.position") == 1_000 + 20_000 and mod.device.read("output.PE1") is True


@pytest.mark.manual("§1.2", "the input external start/stop stops an axis whether it is operated from the PLC or "
                    "from the PG")
def test_external_stop_stops_an_axis_the_plc_started(tcp: tuple[Any, AgClient]) -> None:
    module, plc = tcp
    assert plc.write_record(0, 20, 101, md_for(1))[8] == 0
    assert plc.operate(0, 5, "Start", b=1)[4] == 0
    assert plc.operate(0, 1, "Vorwärts")[4] == 0
    module.advance(1)
    module.set("input.START1", True)
    module.advance(5)
    assert module.read("axis.1.running") is False and module.read("axis.1.error") == 27


@pytest.mark.manual("§2.2", "operator jobs can be given over the PG and the PLC interface at the same time")
@pytest.mark.manual("§2.2", "the IP247 reports its state over both interfaces on request")
def test_pg_and_plc_operate_at_the_same_time(tcp: tuple[Any, AgClient]) -> None:
    module, plc = tcp
    with serial.serial_for_url(module.port_url("pg"), baudrate=9600, parity="E", timeout=5) as port:
        pg = PgClient(port)
        assert pg.write_record(1, 20, 101, md_for(1))[8] == 0
        assert plc.write_record(1, 20, 102, md_for(2))[8] == 0
        assert pg.operate(1, 5, START, b=1)[4] == 0 and plc.operate(1, 5, "Start", b=1)[4] == 0
        assert pg.operate(1, 1, FORWARD)[4] == 0
        assert plc.operate(1, 1, "Rückwärts")[4] == 0
        module.advance(0.3)
        for axis in (1, 2):  # (the PG names pages 1 … 4, the PLC absolute pages from base page 0)
            for answer in (pg.observe(axis), plc.observe(axis - 1)):
                assert answer[0] == 0 and answer[6] & 0x80 == 0  # both sides see both axes "läuft"
        assert struct.unpack(">i", pg.observe(1)[8:12])[0] > 1_000 > struct.unpack(">i", plc.observe(1)[8:12])[0]


@pytest.mark.manual("§2.2", "a traverse program can be entered and deleted over the PG as well as the PLC "
                    "interface")
def test_programs_in_over_one_interface_and_out_over_the_other(tcp: tuple[Any, AgClient]) -> None:
    module, plc = tcp
    text = "%  7 AG\nN1 X10 F1000\nN2 M02\n"
    assert plc.write_record(3, 22, 7, lang.record_words(7, text))[8:] == bytes(4)
    with serial.serial_for_url(module.port_url("pg"), baudrate=9600, parity="E", timeout=5) as port:
        pg = PgClient(port)
        assert pg.read_record(4, 65)[8:] == struct.pack(">2H", 7, len(lang.record_words(7, text)))
        assert pg.delete_record(4, 23, 7)[4] == 0
    assert plc.read_record(3, 65)[8:] == b""


@pytest.mark.manual("§2.5", "the machine-data blocks of the axes may have the same DB number")
def test_the_axes_machine_data_may_share_a_db_number(mod: Module) -> None:
    for axis in (1, 2, 3):
        mod.device.set(f"input.ANF{axis}", True)
        mod.device.set(f"input.END{axis}", True)
        assert mod.write(axis, 20, 1, md_for(axis))[8] == 0
    listing = mod.client.read_record(4, 64)[8:]
    assert struct.unpack(">6H", listing) == (1, 70, 1, 70, 1, 70)


@pytest.mark.manual("§2.5.6", "an error the firmware finds at input is entered into the record's error variable "
                    "and the message 'Fehlerhafte Maschinendaten' (15) is given")
def test_the_md_error_is_entered_into_the_record(make: Make) -> None:
    mod = make({"sys_id": {"module": 5}})  # COM247's record names module 11: MD error 12
    answer = mod.load_md()
    assert answer[4] == 15
    stored = mod.client.read_record(1, 67, 101)[8:]
    assert struct.unpack(">70H", stored)[4] & 0xFF == 12  # DR n+4


@pytest.mark.parametrize(("polarity", "forward_level"), [(0x40, True), (0x00, False)],
                         ids=["positive edge", "negative edge"])
@pytest.mark.manual("§2.5.1.1", "the polarity machine datum also fixes the direction signal's level for forward "
                    "and backward")
def test_the_direction_output_follows_the_polarity(make: Make, polarity: int, forward_level: bool) -> None:
    mod = make()
    assert mod.load_md(record=record(pulse_polarity=polarity))[8] == 0
    mod.operate(1, 5, START, b=1)
    mod.operate(1, 1, FORWARD)
    mod.clock.advance(0.1)
    assert mod.device.read("output.RP1") is forward_level
    mod.operate(1, 1, STOP)
    mod.clock.advance(5)
    mod.operate(1, 1, BACKWARD)
    mod.clock.advance(0.1)
    assert mod.device.read("output.RP1") is (not forward_level)


@pytest.mark.manual("§2.5.3.2", "the software limit switches of a linear axis are effective only once a reference "
                    "point exists")
def test_sw_limits_act_only_with_a_reference_point(make: Make) -> None:
    mod = make()
    assert mod.load_md(record=record(limit_end=10_000, reference=1_000))[8] == 0
    mod.operate(1, 1, FORWARD, w=6000)  # no reference point: jog runs past x_E = 10 mm
    mod.clock.advance(3)
    assert mod.device.read("axis.1.running") is True and mod.device.read("axis.1.position") > 10_000
    assert mod.device.read("axis.1.error") == 0


@pytest.mark.manual("§2.5.3.2", "on an axis set up as rotary by mistake, the range values are no limit switches: "
                    "the drive is not braked when they are passed")
@pytest.mark.manual("§2.5.3.3", "when the actual value passes the range end it is set to the range start")
def test_rotary_range_is_no_limit_and_the_actual_value_wraps(make: Make) -> None:
    mod = make()
    assert mod.load_md(record=record(rotary=True, limit_begin=0, limit_end=10_000, reference=0, backlash=0))[8] == 0
    mod.operate(1, 5, START, b=1)
    mod.operate(1, 1, FORWARD, w=1000)
    mod.clock.advance(0.9)
    assert 0 < mod.device.read("axis.1.position") < 10_000
    mod.clock.advance(0.3)  # 1000 mm/min: past 10 mm after 0.6 s of cruise and the ramp
    assert mod.device.read("axis.1.running") is True and mod.device.read("axis.1.error") == 0
    assert mod.device.read("axis.1.machine_position") > 10_000 and 0 <= mod.device.read("axis.1.position") < 10_000


@pytest.mark.manual("§2.5.5.1", "with a tool offset the software limits are checked without it: the holder can use "
                    "the same range")
def test_sw_limits_are_checked_on_the_holder(make: Make) -> None:
    mod = make()
    assert mod.load_md(record=record(limit_end=50_000, backlash=0))[8] == 0
    mod.operate(1, 5, START, b=1)
    assert mod.operate(1, 15, FORWARD, dd=5_000)[4] == 0
    assert mod.operate(1, 6, START, w=6000, dd=50_000 + 5_000)[4] == 0  # the holder goes to x_E
    mod.clock.advance(30)
    assert mod.device.read("axis.1.position") == 55_000
    assert mod.operate(1, 6, START, w=6000, dd=50_000 + 5_001)[4] == 23
