"""Walk of manual §2.7 (axis attributes), §2.8 (digital inputs and outputs: limit switches,
external start/stop) and §2.9 (BASP), driven through the PG port on a real pty."""

from __future__ import annotations

import pytest

from tests.ip247.helpers import BACKWARD, FORWARD, START, STOP, TAKE_OVER, Make, Module, record

REF_SYNC, TEACH_IN, REF_MISSING = 0x08, 0x10, 0x20  # §2.7 attribute bits 3, 4, 5


def attributes(mod: Module, page: int = 1) -> int:
    return mod.call(0x62, bytes((page,)))[6]


@pytest.mark.parametrize(("unit", "bits"), [(1, 0b10), (2, 0b00), (3, 0b01)], ids=["metric", "inch", "degree"])
@pytest.mark.manual("§2.7", "attribute bits 0 and 1 give the unit: metric 0/1, inch 0/0, degree 1/0")
def test_the_unit_bits(make: Make, unit: int, bits: int) -> None:
    mod = make()
    assert mod.load_md(record=record(unit=unit))[8] == 0
    assert attributes(mod) & 0x03 == bits


@pytest.mark.manual("§2.7.5", "the attribute Referenzpunkt synchron mirrors the machine data")
def test_the_sync_attribute_follows_the_machine_data(make: Make) -> None:
    mod = make()
    assert mod.load_md(record=record(reference_sync=0, patterns=4))[8] == 0
    assert attributes(mod) & REF_SYNC
    other = make()
    assert other.load_md(record=record(reference_sync=1))[8] == 0
    assert not attributes(other) & REF_SYNC


@pytest.mark.manual("§2.7.3", "moves to an absolute target are possible only once BA5 has fixed the coordinate "
                    "system; then the attribute Referenzpunkt fehlt is reset")
def test_absolute_moves_need_the_reference_point(mod: Module) -> None:
    assert mod.load_md()[8] == 0
    assert attributes(mod) & REF_MISSING
    assert mod.operate(1, 6, START, dd=5_000)[4] == 10
    assert mod.operate(1, 5, START, b=1)[4] == 0
    assert not attributes(mod) & REF_MISSING
    assert mod.operate(1, 6, START, dd=5_000)[4] == 0


@pytest.mark.manual("§2.7.4", "teach-in is switched on with BA10 and off with BA11; the attribute Teach-In ein "
                    "shows it")
def test_the_teach_in_attribute(mod: Module) -> None:
    mod.ready()
    assert mod.operate(1, 10, START, b=30)[4] == 0
    assert attributes(mod) & TEACH_IN
    assert mod.operate(1, 11, START, b=30)[4] == 0
    assert not attributes(mod) & TEACH_IN


@pytest.mark.manual("§2.7.7", "a positioning aborted before its target does not set position reached")
def test_an_aborted_positioning_does_not_set_position_reached(mod: Module) -> None:
    mod.ready()
    mod.operate(1, 6, START, w=1000, dd=50_000)
    mod.clock.advance(1)
    mod.operate(1, 6, STOP)
    mod.clock.advance(5)
    assert not attributes(mod) & 0x04 and mod.device.read("output.PE1") is False


@pytest.mark.manual("§2.8.3", "a detected limit switch aborts the move; travel towards it stays locked until the "
                    "module has seen the switch left in the opposite direction")
def test_limit_switch_lock_and_release(make: Make) -> None:
    mod = make({"axes": {1: {"end": 20_000.0}}})
    mod.ready()
    mod.operate(1, 1, FORWARD, w=1000)
    mod.clock.advance(10)
    assert mod.device.read("axis.1.error") == 26
    assert mod.operate(1, 7, FORWARD, w=1000, dd=100)[4] == 26
    mod.operate(1, 7, BACKWARD, w=1000, dd=5_000)
    mod.clock.advance(10)
    assert mod.operate(1, 7, FORWARD, w=1000, dd=100)[4] == 0


@pytest.mark.manual("§2.8.3", "a locked direction is also released when the reference cam (Vorkontakt) is passed")
def test_passing_the_cam_releases_a_locked_direction(make: Make) -> None:
    mod = make({"axes": {1: {"end": 20_000.0, "cam": [5_000.0, 6_000.0]}}})
    mod.ready()
    mod.operate(1, 1, FORWARD, w=1000)
    mod.clock.advance(10)
    assert mod.device.read("axis.1.error") == 26
    mod.device.set("input.END1", True)  # (the switch is released by hand: no edge seen while standing)
    assert mod.operate(1, 1, FORWARD, w=1000)[4] == 26
    mod.operate(1, 7, BACKWARD, w=1000, dd=14_000)  # over the cam at 5 … 6 mm
    mod.clock.advance(20)
    assert mod.operate(1, 7, FORWARD, w=1000, dd=100)[4] == 0


@pytest.mark.manual("§2.8.3", "the hardware limit switches are evaluated whatever the axis type, on a rotary axis "
                    "too")
def test_limit_switches_on_a_rotary_axis(make: Make) -> None:
    mod = make({"axes": {1: {"end": 20_000.0}}})
    assert mod.load_md(record=record(rotary=True, limit_begin=0, limit_end=360_000, reference=0, backlash=0))[8] == 0
    mod.operate(1, 5, START, b=1)
    mod.operate(1, 1, FORWARD, w=1000)
    mod.clock.advance(10)
    assert mod.device.read("axis.1.error") == 26 and mod.device.read("axis.1.running") is False


@pytest.mark.manual("§2.8.3", "the IP247 begins to brake only when the software limit switch is reached (jog: error "
                    "29 Software-Endschalter Ende, the axis stands beyond it)")
def test_jog_brakes_from_the_sw_limit(make: Make) -> None:
    mod = make()
    assert mod.load_md(record=record(limit_end=20_000))[8] == 0
    mod.operate(1, 5, START, b=1)
    mod.operate(1, 1, FORWARD, w=6000)
    mod.clock.advance(20)
    assert mod.device.read("axis.1.error") == 29 and mod.device.read("axis.1.running") is False
    assert mod.device.read("axis.1.position") > 20_000


@pytest.mark.manual("§2.8.4", "during the wait for external start a further operator command deletes the waiting "
                    "job; a command other than Stopp gives error 2")
def test_a_command_during_the_external_start_wait(mod: Module) -> None:
    mod.ready()
    mod.device.set("input.START1", True)
    assert mod.operate(1, 7, FORWARD, w=1000, dd=5_000)[4] == 6
    assert mod.operate(1, 7, FORWARD, w=1000, dd=5_000)[4] == 2
    assert mod.device.read("axis.1.waiting_start") is False
    mod.device.set("input.START1", False)
    mod.clock.advance(5)
    assert mod.device.read("axis.1.position") == 1_000  # the waiting job is gone


@pytest.mark.manual("§2.8.4", "with 1 at the input before BA8 Start the program runs up to its first traverse or "
                    "dwell, which waits (Motor wartet auf externen Start); the falling edge releases it")
@pytest.mark.parametrize("g", ["", "G10 "], ids=["traverse", "flying change"])
def test_external_start_in_automatic(mod: Module, g: str) -> None:
    mod.ready()
    assert mod.store(3, f"%  3\nN1 G91\nN2 {g}X5 F1000 M10\nN3 X5 F1000\nN4 M02\n")[4] == 0
    mod.device.set("input.START1", True)
    assert mod.operate(1, 8, START, b=3)[4] == 6
    mod.clock.advance(2)
    assert mod.device.read("axis.1.position") == 1_000
    mod.device.set("input.START1", False)
    mod.clock.advance(10)
    assert mod.device.read("axis.1.position") == 11_000 and mod.device.read("axis.1.error") == 0


@pytest.mark.manual("§2.8.1", "without the power unit's ready signal BB a program's traverse is refused (53 "
                    "'Leistungsteil einschalten'): the program ends and the axis is fertig")
@pytest.mark.parametrize("g", ["", "G10 "], ids=["traverse", "flying change"])
def test_a_program_without_the_ready_signal(mod: Module, g: str) -> None:
    mod.ready()
    assert mod.store(3, f"%  3\nN1 {g}X5 F1000 M10\nN2 X10 F1000\nN3 M02\n")[4] == 0
    mod.device.set("input.BB1", False)
    assert mod.operate(1, 8, START, b=3)[4] == 53
    mod.clock.advance(2)
    assert mod.device.read("axis.1.running") is False and mod.device.read("axis.1.position") == 1_000
    assert mod.m.units[0].automatic is None


@pytest.mark.manual("§2.8.4", "an external stop during a program interrupts the program: Übernahme continues it")
def test_external_stop_interrupts_a_program(mod: Module) -> None:
    mod.ready()
    assert mod.store(3, "%  3\nN1 X30 F1000 M10\nN2 M02\n")[4] == 0
    mod.operate(1, 8, START, b=3)
    mod.clock.advance(1)
    mod.device.set("input.START1", True)
    mod.clock.advance(5)
    assert mod.device.read("axis.1.error") == 27 and mod.device.read("axis.1.running") is False
    mod.device.set("input.START1", False)
    assert mod.operate(1, 8, TAKE_OVER, b=3)[4] == 0
    mod.clock.advance(30)
    assert mod.device.read("axis.1.position") == 30_000


@pytest.mark.manual("§2.9", "whether BASP is evaluated is set by a jumper: with X21 1-2 it is ignored")
def test_basp_ignored_with_x21_1_2(make: Make) -> None:
    mod = make({"x21": "1-2"})
    mod.ready()
    mod.operate(1, 1, FORWARD, w=1000)
    mod.device.set("input.BASP", True)
    mod.clock.advance(1)
    assert mod.device.read("axis.1.running") is True and mod.device.read("axis.1.error") == 0
