"""CiA 402 homing mode (6060h = 6) over each kind's own reference run, with canopen as the master
on python-can's virtual bus (virtual time).  The standard's definitions as the oracle (CiA 402-2 /
IEC 61800-7-201, homing mode):

* 6502h bit 5: homing mode supported; 6098h the homing method (its numbers, e.g. 17/18 the
  negative/positive limit switch, 19/21 the positive/negative home switch, 33/34 the index pulse
  in the negative/positive direction);
* controlword bit 4 "homing operation start" (0 → 1 start, 1 → 0 interrupt), bit 8 halt;
* statusword bits 13, 12, 10: 0 0 0 homing procedure in progress, 0 0 1 interrupted or not
  started, 0 1 1 homing procedure completed successfully, 1 0 x homing error (bit 10: velocity 0);
* 607Ch home offset: "once the homing is completed, the zero position is offset from the home
  position by adding the home offset to the home position": the home position reads −607Ch.
"""

from __future__ import annotations

import contextlib
import queue
from collections.abc import Iterator
from typing import Any

import pytest
from canopen.sdo.exceptions import SdoAbortedError

from tests.facades.test_cia402 import Drive, mapped
from tests.facades.test_cia402_contract import DRIVES

TARGET_REACHED, ATTAINED, ERROR = 0x0400, 0x1000, 0x2000
BITS = TARGET_REACHED | ATTAINED | ERROR
START, HALT = 0x10, 0x100
VALUE_RANGE_EXCEEDED = 0x06090030

#: The kinds with a reference run of their own: a config that puts its switch or mark somewhere
#: the method finds it, the method, and where the home position is in the drive's units
#: (``None``: not checked).
HOMING: dict[str, tuple[dict[str, Any], int]] = {
    "sers": ({"axis": {"reference_low": 3000}}, 19),
    "gms96": ({}, 21),  # (the card's default cam: [-20000, -15000], on the negative side)
    "poselesta": ({}, 33),  # (the default mark of X at -10 mm, homing in the negative direction)
    "ip247": ({"axes": {1: {"cam": [3000.0, 6000.0]}}}, 19),  # (SETUP's machine data: R backward, asynchronous)
}
#: Methods no kind's reference run performs (the homing on a hard stop, -1; 35, the current
#: position; an out-of-range number).
FOREIGN = (35, 37, 1, 2, 7, 100)


@contextlib.contextmanager
def homing_drive(kind: str) -> Iterator[tuple[Drive, int]]:
    """A ready drive of ``kind`` (node 9) configured for its reference run, and the run's method."""
    config, method = HOMING[kind]
    with Drive(kind, 9, name=kind, ready=True, config=config) as drive:
        yield drive, method


def in_homing(drive: Drive, method: int) -> None:
    node = drive.node
    for word in (0x06, 0x07, 0x0F):
        node.sdo[0x6040].raw = word
    node.sdo[0x6060].raw = 6
    node.sdo[0x6098].raw = method


def run_home(drive: Drive, seconds: float = 120.0) -> int:
    """Start (rising bit 4) and run on until bit 12 or 13 is set or ``seconds`` passed."""
    drive.control(0x0F | START)
    for _ in range(int(seconds * 10)):
        if drive.status & (ATTAINED | ERROR):
            break
        drive.runtime.advance(0.1)
    return drive.status


@pytest.mark.parametrize("kind", DRIVES)
def test_6502h_lists_homing_mode_exactly_for_the_kinds_with_a_reference_run(kind: str) -> None:
    drive = Drive(kind, 9, name=kind, ready=True)
    try:
        node = drive.node
        supported = node.sdo[0x6502].raw
        assert bool(supported & 0x20) == (kind in HOMING), (kind, hex(supported))
        for word in (0x06, 0x07, 0x0F):
            node.sdo[0x6040].raw = word
        if kind in HOMING:
            node.sdo[0x6060].raw = 6
            assert node.sdo[0x6061].raw == 6
        else:
            with pytest.raises(SdoAbortedError):
                node.sdo[0x6060].raw = 6
            assert node.sdo[0x6061].raw != 6
    finally:
        drive.close()


@pytest.mark.parametrize("kind", sorted(HOMING))
def test_6098h_takes_the_methods_of_the_reference_run_and_refuses_others(kind: str) -> None:
    with homing_drive(kind) as (drive, method):
        node = drive.node
        assert node.sdo[0x6098].raw == 0
        node.sdo[0x6098].raw = method
        assert node.sdo[0x6098].raw == method
        for other in FOREIGN:
            with pytest.raises(SdoAbortedError) as refused:
                node.sdo[0x6098].raw = other
            assert refused.value.code == VALUE_RANGE_EXCEEDED
            assert node.sdo[0x6098].raw == method


@pytest.mark.parametrize("offset", [0, 250])
@pytest.mark.parametrize("kind", sorted(HOMING))
def test_a_homing_completes_at_the_home_position_less_the_home_offset(kind: str, offset: int) -> None:
    with homing_drive(kind) as (drive, method):
        node = drive.node
        in_homing(drive, method)
        node.sdo[0x607C].raw = offset
        assert drive.status & BITS == TARGET_REACHED  # not started
        drive.control(0x0F | START)
        drive.runtime.advance(0.05)
        assert drive.status & BITS == 0  # in progress
        status = run_home(drive)
        drive.runtime.advance(0.5)
        status = drive.status
        assert status & BITS == ATTAINED | TARGET_REACHED, hex(status)
        assert node.sdo[0x6064].raw == -offset


@pytest.mark.parametrize("how", ["halt", "bit 4 released"])
@pytest.mark.parametrize("kind", sorted(HOMING))
def test_a_halt_or_a_falling_bit_4_interrupts_the_homing(kind: str, how: str) -> None:
    """Bit 8 = 1 or bit 4 1 → 0 during the run: the axis stops with the ramp, no home is
    attained, and once it stands the statusword says "interrupted or not started" (0 0 1)."""
    with homing_drive(kind) as (drive, method):
        in_homing(drive, method)
        drive.control(0x0F | START)
        drive.runtime.advance(0.3)
        assert drive.status & BITS == 0  # in progress
        drive.control(0x0F | START | HALT if how == "halt" else 0x0F)
        drive.runtime.advance(10.0)
        status = drive.status
        assert status & BITS == TARGET_REACHED, (kind, how, hex(status))
        assert not drive.moving()


@pytest.mark.parametrize("kind", sorted(HOMING))
def test_leaving_operation_enabled_interrupts_the_homing(kind: str) -> None:
    with homing_drive(kind) as (drive, method):
        in_homing(drive, method)
        drive.control(0x0F | START)
        drive.runtime.advance(0.3)
        drive.control(0x07)  # disable operation
        drive.runtime.advance(10.0)
        drive.control(0x0F)  # back in Operation enabled: no home was attained
        assert drive.status & BITS == TARGET_REACHED, hex(drive.status)


def test_a_start_with_no_method_is_a_homing_error() -> None:
    """6098h = 0, its power-on value, names no method: the start is a homing error (1 0 1)."""
    drive = Drive("sers", 9, name="sers", ready=True)
    try:
        in_homing(drive, 0)
        drive.control(0x0F | START)
        assert drive.status & BITS == ERROR | TARGET_REACHED
    finally:
        drive.close()


def test_a_method_the_machine_data_do_not_name_is_a_homing_error_on_the_ip247() -> None:
    """The IP247's reference direction is machine data (MD n+26, here backward: 19): 21, the
    forward run, is refused at the start, a homing error, and nothing moves."""
    drive = Drive("ip247", 9, name="ip247", ready=True)
    try:
        in_homing(drive, 21)
        here = drive.node.sdo[0x6064].raw
        drive.control(0x0F | START)
        drive.runtime.advance(0.5)
        assert drive.status & BITS == ERROR | TARGET_REACHED
        assert drive.node.sdo[0x6064].raw == here
    finally:
        drive.close()


def test_a_drive_error_during_the_homing_is_a_homing_error() -> None:
    """The SERS's limit switch in the search direction (a drive error: the right limit, no
    reference cam before it) ends the run with bit 13, and the drive is in Fault."""
    drive = Drive("sers", 9, name="sers", ready=True, config={"axis": {"limit_right": 2000}})
    try:
        in_homing(drive, 19)
        status = run_home(drive, 20.0)
        assert status & ERROR and not status & ATTAINED, hex(status)
    finally:
        drive.close()


def test_the_sers_takes_the_homing_speeds_and_acceleration_into_its_parameters() -> None:
    """6099h sub 1 → P41 (speed of the search), sub 2 → P1003 (the creep back), 609Ah → P42,
    written when the run starts (manual §4.8.4.5); 0 leaves them as set."""
    drive = Drive("sers", 9, name="sers", ready=True, config={"axis": {"reference_low": 3000}})
    try:
        node = drive.node
        in_homing(drive, 19)
        node.sdo[0x6099][1].raw = 4000
        node.sdo[0x6099][2].raw = 500
        node.sdo[0x609A].raw = 20000
        assert (node.sdo[0x6099][1].raw, node.sdo[0x6099][2].raw) == (4000, 500)
        drive.control(0x0F | START)
        params = drive.device.model.params  # (P41, P1003 in inc/s, P42 in inc/s²)
        assert drive.runtime.call(lambda: (round(float(params.homing_velocity)), round(float(params.homing_velocity_slow)),
                                           round(float(params.homing_acceleration)))) == (4000, 500, 20000)
        assert run_home(drive) & BITS == ATTAINED | TARGET_REACHED
    finally:
        drive.close()


def test_a_drive_without_a_reference_run_has_no_homing_objects() -> None:
    """The PCD4.H3 has no reference run of its own (the user program watches the switches):
    its EDS and object dictionary have no 607Ch, 6098h, 6099h, 609Ah."""
    drive = Drive("pcd4h3", 9, name="pcd4h3", ready=True)
    try:
        for index in (0x607C, 0x6098, 0x6099, 0x609A):
            assert index not in drive.node.object_dictionary
            assert index not in drive.facade.od
    finally:
        drive.close()


@pytest.mark.parametrize("kind", sorted(HOMING))
def test_after_homing_absolute_moves_count_from_the_new_zero(kind: str) -> None:
    """607Ch = 400: the home position reads −400; a profile position move to 607Ah = 600 then
    travels 1000 units from home and stands at 6064h = 600."""
    with homing_drive(kind) as (drive, method):
        node = drive.node
        in_homing(drive, method)
        node.sdo[0x607C].raw = 400
        assert run_home(drive) & ATTAINED
        drive.runtime.advance(1.0)
        home = drive.runtime.call(lambda: drive.device.drive.position(drive.device.model))
        assert node.sdo[0x6064].raw == -400
        node.sdo[0x6060].raw = 1
        node.sdo[0x607A].raw = 600
        node.sdo[0x6081].raw = 2000
        drive.control(0x0F)  # (bit 4 released: it was the homing's start)
        drive.control(0x0F | 0x10 | 0x20)  # new set-point
        drive.runtime.advance(30.0)
        assert node.sdo[0x6064].raw == 600
        moved = drive.runtime.call(lambda: drive.device.drive.position(drive.device.model)) - home
        assert round(moved) == 1000, (kind, moved)


def test_a_reset_node_restores_the_homing_objects_power_on_values() -> None:
    """CiA 301 NMT reset node: 607Ch, 6098h, 6099h, 609Ah back to their power-on values (the
    EDS's DefaultValue, 0) and no homing attained (bits 13, 12, 10 = 0 0 1 in homing mode)."""
    drive = Drive("sers", 9, name="sers", ready=True, config={"axis": {"reference_low": 3000}})
    try:
        node = drive.node
        in_homing(drive, 19)
        node.sdo[0x607C].raw = 7
        node.sdo[0x6099][1].raw = 3000
        node.sdo[0x609A].raw = 9000
        assert run_home(drive) & ATTAINED
        node.nmt.send_command(0x81)
        assert [node.sdo[i].raw for i in (0x607C, 0x6098, 0x609A)] == [0, 0, 0]
        assert (node.sdo[0x6099][1].raw, node.sdo[0x6099][2].raw) == (0, 0)
        for word in (0x06, 0x07, 0x0F):
            node.sdo[0x6040].raw = word
        node.sdo[0x6060].raw = 6
        assert drive.status & BITS == TARGET_REACHED
    finally:
        drive.close()


#: More methods of the kinds' runs, each where its switch or mark is found: (kind, config, method).
MORE = [
    ("sers", {"axis": {"reference_low": -6000, "reference_high": -3000}}, 21),
    ("sers", {"axis": {"limit_left": -2500}}, 17),
    ("sers", {"axis": {"limit_right": 2500}}, 18),
    ("sers", {}, 34),
    ("sers", {}, 33),
    ("gms96", {}, 33),
    ("gms96", {}, 6),
]


@pytest.mark.parametrize(("kind", "config", "method"), MORE, ids=[f"{k}-{m}" for k, _c, m in MORE])
def test_more_methods_complete(kind: str, config: dict[str, Any], method: int) -> None:
    drive = Drive(kind, 9, name=kind, ready=True, config=config)
    try:
        in_homing(drive, method)
        status = run_home(drive)
        drive.runtime.advance(1.0)
        assert drive.status & BITS == ATTAINED | TARGET_REACHED, hex(status)
        assert drive.node.sdo[0x6064].raw == 0
    finally:
        drive.close()


def test_a_home_offset_at_the_least_integer32_rolls_6064h_over() -> None:
    """607Ch = -2^31 (INTEGER32's least value, taken like any other): after the homing the home
    position is +2^31, one past 6064h's range, so the position actual value rolls over to -2^31
    as a drive's 32-bit counter does ([SIM-CHOICE]); an SDO upload answers it (it was aborted 0800
    0000h with a traceback in the log) and so does an event-driven TPDO that maps it."""
    with homing_drive("gms96") as (drive, method):
        node = drive.node
        in_homing(drive, method)
        node.sdo[0x607C].raw = -2**31
        assert run_home(drive) & BITS == ATTAINED | TARGET_REACHED
        assert node.sdo[0x6064].raw == -2**31
        node.tpdo.read()
        tpdo = mapped(node.tpdo[1], 0x6064, 0x60F4, trans_type=255, event_timer=10)
        node.tpdo.save()
        arrived: queue.Queue[int] = queue.Queue()
        tpdo.add_callback(lambda m: arrived.put(m["Position actual value"].raw))
        node.nmt.state = "OPERATIONAL"
        assert node.sdo[0x1017].raw == 0  # (an SDO round trip: the NMT command was handled before it)
        drive.runtime.advance(0.05)
        assert arrived.get(timeout=5) == -2**31
