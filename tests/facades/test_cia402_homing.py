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

from typing import Any

import pytest
from canopen.sdo.exceptions import SdoAbortedError

from tests.facades.test_cia402 import Drive
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
    config, method = HOMING[kind]
    drive = Drive(kind, 9, name=kind, ready=True, config=config)
    try:
        node = drive.node
        assert node.sdo[0x6098].raw == 0
        node.sdo[0x6098].raw = method
        assert node.sdo[0x6098].raw == method
        for other in FOREIGN:
            with pytest.raises(SdoAbortedError) as refused:
                node.sdo[0x6098].raw = other
            assert refused.value.code == VALUE_RANGE_EXCEEDED
            assert node.sdo[0x6098].raw == method
    finally:
        drive.close()


@pytest.mark.parametrize("offset", [0, 250])
@pytest.mark.parametrize("kind", sorted(HOMING))
def test_a_homing_completes_at_the_home_position_less_the_home_offset(kind: str, offset: int) -> None:
    config, method = HOMING[kind]
    drive = Drive(kind, 9, name=kind, ready=True, config=config)
    try:
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
    finally:
        drive.close()
