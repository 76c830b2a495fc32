"""The statusword in profile position mode (CiA 402-2, profile position mode: bit 10 "target
reached", bit 12 "set-point acknowledge") and its handshake with the controlword's bits 4 (new
set-point), 5 (change set immediately) and 8 (halt), checked on every kind that is a drive with
canopen as the master on python-can's virtual bus (virtual time).  The standard's definitions, as
the oracle here:

* bit 12 = 1 "previous set-point still in process, set-point overwriting shall be accepted",
  0 "previous set-point already processed, waiting for new set-point"; the drive sets it once it
  has taken (buffered) the data a rising bit 4 validates, and resets it, after the master reset
  bit 4, when it can take new data again (the figure "set-point transmission from a host
  computer");
* bit 5 = 0 "finish the actual positioning and then start the next positioning", 1 "interrupt
  the actual positioning and start the next positioning";
* bit 10 with halt = 0: 1 "target position reached", 0 "not reached"; with halt = 1: 1 "velocity
  of axis is 0", 0 "axis decelerates".
"""

from __future__ import annotations

from typing import Any

import pytest

from tests.facades.test_cia402 import Drive, into_a_following_error
from tests.facades.test_cia402_contract import DRIVES

TARGET_REACHED, ACKNOWLEDGE = 0x0400, 0x1000
NEW, IMMEDIATELY, RELATIVE, HALT = 0x10, 0x20, 0x40, 0x100


def in_profile_position(node: Any, target: int, speed: int) -> int:
    """Operation enabled in profile position mode, 607Ah = ``target``, 6081h = ``speed``; the
    position actual value."""
    for word in (0x06, 0x07, 0x0F):
        node.sdo[0x6040].raw = word
    node.sdo[0x6060].raw = 1
    node.sdo[0x607A].raw = target
    node.sdo[0x6081].raw = speed
    return int(node.sdo[0x6064].raw)


#: Controlwords that leave Operation enabled (CiA 402-2 §8.4.3): disable operation (5), shutdown
#: (8), disable voltage (9), quick stop (11); each with bit 4 released and with it held.
LEAVING = {"disable operation": 0x07, "shutdown": 0x06, "disable voltage": 0x00, "quick stop": 0x03}


@pytest.mark.parametrize("held", [False, True], ids=["bit 4 released", "bit 4 held"])
@pytest.mark.parametrize("leave", sorted(LEAVING))
@pytest.mark.parametrize("kind", DRIVES)
def test_set_point_acknowledge_is_no_set_point_in_process_outside_operation_enabled(kind: str, leave: str,
                                                                                     held: bool) -> None:
    """A set-point taken (bit 12 = 1) and then Operation enabled left: the positioning ends with
    the state, no set-point is in process, so bit 12 is 0 in the state the drive is in (and after
    a quick stop, in Switch on disabled)."""
    with Drive(kind, 9, name=kind, ready=True) as drive:
        node = drive.node
        in_profile_position(node, 1000, 2000)
        node.sdo[0x6040].raw = 0x0F | NEW | IMMEDIATELY | RELATIVE
        assert node.sdo[0x6041].raw & ACKNOWLEDGE
        drive.runtime.advance(0.1)
        node.sdo[0x6040].raw = LEAVING[leave] | (NEW | IMMEDIATELY | RELATIVE if held else 0)
        assert not node.sdo[0x6041].raw & ACKNOWLEDGE, (kind, leave)
        drive.runtime.advance(1.5)  # (the axis stands: a quick stop is over)
        status = node.sdo[0x6041].raw
        assert status & 0x0027 != 0x0027 and not status & ACKNOWLEDGE, (kind, leave, hex(status))


def test_back_in_operation_enabled_the_handshake_starts_anew(drive: Drive) -> None:
    """After disable operation with bit 4 held, Operation enabled again with bit 4 still held:
    nothing in process, bit 12 = 0; bit 4 released and raised again is a new set-point, taken and
    acknowledged, and bit 12 falls with bit 4."""
    node = drive.node
    in_profile_position(node, 1000, 2000)
    node.sdo[0x6040].raw = 0x0F | NEW | RELATIVE
    assert node.sdo[0x6041].raw & ACKNOWLEDGE
    node.sdo[0x6040].raw = 0x07 | NEW | RELATIVE  # disable operation
    drive.runtime.advance(1.0)
    node.sdo[0x6040].raw = 0x0F | NEW | RELATIVE
    assert node.sdo[0x6041].raw & (0x6F | ACKNOWLEDGE) == 0x27
    node.sdo[0x6040].raw = 0x0F | RELATIVE
    assert not node.sdo[0x6041].raw & ACKNOWLEDGE
    start = node.sdo[0x6064].raw
    node.sdo[0x6040].raw = 0x0F | NEW | RELATIVE
    assert node.sdo[0x6041].raw & (ACKNOWLEDGE | TARGET_REACHED) == ACKNOWLEDGE
    node.sdo[0x6040].raw = 0x0F | RELATIVE
    assert not node.sdo[0x6041].raw & ACKNOWLEDGE
    assert drive.runtime.run_until(lambda: not drive.device.drive.moving(drive.device.model), 5.0)
    drive.runtime.advance(0.5)
    assert abs(node.sdo[0x6064].raw - (start + 1000)) <= 3 and node.sdo[0x6041].raw & TARGET_REACHED


def test_no_set_point_is_in_process_in_the_fault_state(drive: Drive) -> None:
    """A PCD4.H3 following error while a set-point runs with bit 4 held (transition 13, the drive's
    fault): in Fault bit 12 is 0; after the fault reset and back in Operation enabled the held bit
    4 is no new set-point."""
    into_a_following_error(drive)
    status = drive.status
    assert status & 0x4F == 0x08 and not status & ACKNOWLEDGE, hex(status)
    drive.runtime.fault("pcd", "blocked_1", False)
    for word in (0x80, 0x06, 0x07, 0x0F):  # fault reset, shutdown, switch on, enable operation
        drive.control(word | NEW)
    assert drive.status & (0x6F | ACKNOWLEDGE) == 0x27

@pytest.mark.parametrize("kind", DRIVES)
def test_a_set_point_with_bit_5_at_0_waits_for_the_positioning_before_it(kind: str) -> None:
    """Bit 5 = 0, "finish the actual positioning and then start the next positioning": a second
    set-point (relative 1 000, validated while the first relative 1 000 runs) is taken into the
    buffer, acknowledged, and bit 12 stays 1 after bit 4 falls while it waits (the drive cannot
    take new data); the axis first arrives at the first target, then the second set-point starts
    (bit 12 falls) and the axis ends at 2 000 from the start with bit 10 = 1; bit 10 is 0 all the
    while a set-point waits."""
    with Drive(kind, 9, name=kind, ready=True) as drive:
        runtime, node = drive.runtime, drive.node
        moving = drive.moving
        start = in_profile_position(node, 1000, 2000)
        node.sdo[0x6040].raw = 0x0F | NEW | RELATIVE
        assert node.sdo[0x6041].raw & (ACKNOWLEDGE | TARGET_REACHED) == ACKNOWLEDGE, kind
        node.sdo[0x6040].raw = 0x0F | RELATIVE
        assert not node.sdo[0x6041].raw & ACKNOWLEDGE, kind  # nothing waits: it can take new data
        runtime.advance(0.1)
        assert moving(), kind
        node.sdo[0x6040].raw = 0x0F | NEW | RELATIVE  # the second set-point, validated mid-move
        assert node.sdo[0x6041].raw & ACKNOWLEDGE, kind
        node.sdo[0x6040].raw = 0x0F | RELATIVE
        waited = []
        for _ in range(1000):
            status, position = node.sdo[0x6041].raw, node.sdo[0x6064].raw
            if not status & ACKNOWLEDGE:
                break
            assert not status & TARGET_REACHED, (kind, position)
            waited.append(position)
            runtime.advance(0.002)
        else:
            raise AssertionError(f"{kind}: the second set-point never started")
        assert waited, f"{kind}: bit 12 fell with bit 4 while the set-point waited"
        assert abs(waited[-1] - (start + 1000)) <= 5, (kind, waited[-5:])  # it finished the first
        assert max(waited) <= start + 1005, kind  # and did not head for the second before
        assert runtime.run_until(lambda: not moving(), 5.0), kind
        runtime.advance(1.0)
        assert abs(node.sdo[0x6064].raw - (start + 2000)) <= 5, kind
        assert node.sdo[0x6041].raw & (ACKNOWLEDGE | TARGET_REACHED) == TARGET_REACHED, kind


@pytest.mark.parametrize("kind", DRIVES)
def test_target_reached_with_halt_and_after_it(kind: str) -> None:
    """Bit 10 in profile position mode: 0 while the axis runs to its target; with halt set, 0 while
    the axis decelerates and 1 once it stands ("velocity of axis is 0"); halt released, the axis
    standing, 1 only if it stands at the target ("target position reached": a halt that stopped
    the positioning short leaves it 0, the positioning is not resumed); a new set-point then runs
    to its target and sets it again."""
    with Drive(kind, 9, name=kind, ready=True) as drive:
        runtime, node = drive.runtime, drive.node
        moving = drive.moving
        start = in_profile_position(node, 5000, 2000)
        node.sdo[0x6040].raw = 0x0F | NEW | RELATIVE
        runtime.advance(0.3)
        assert not node.sdo[0x6041].raw & TARGET_REACHED, kind
        node.sdo[0x6040].raw = 0x0F | NEW | RELATIVE | HALT
        deadline = runtime.now() + 5.0
        while moving():
            assert not node.sdo[0x6041].raw & TARGET_REACHED, kind  # (decelerates)
            runtime.advance(0.05)
            assert runtime.now() < deadline, kind
        runtime.advance(0.5)
        stood = node.sdo[0x6064].raw
        assert node.sdo[0x6041].raw & TARGET_REACHED, kind  # halted: the axis stands
        node.sdo[0x6040].raw = 0x0F | RELATIVE
        runtime.advance(0.5)
        assert not moving(), kind
        at_target = abs(stood - (start + 5000)) <= 3
        assert bool(node.sdo[0x6041].raw & TARGET_REACHED) == at_target, (kind, stood)
        node.sdo[0x607A].raw = 500
        node.sdo[0x6040].raw = 0x0F | NEW | RELATIVE
        assert runtime.run_until(lambda: not moving(), 5.0), kind
        runtime.advance(1.0)
        assert abs(node.sdo[0x6064].raw - (stood + 500)) <= 5, kind
        assert node.sdo[0x6041].raw & TARGET_REACHED, kind


@pytest.mark.parametrize("kind", DRIVES)
def test_halt_stops_a_positioning_short_of_its_target_on_every_drive(kind: str) -> None:
    """Controlword bit 8 in profile position mode, "1: axis shall be stopped" (CiA 402-2 pp
    controlword): a relative 50 000 at 20 000 units/s halted after 0.5 s stands well short of its
    target and stays there, in Operation enabled."""
    with Drive(kind, 9, name=kind, ready=True) as drive:
        runtime, node = drive.runtime, drive.node
        start = in_profile_position(node, 50_000, 20_000)
        node.sdo[0x6040].raw = 0x0F | NEW | RELATIVE
        runtime.advance(0.5)
        node.sdo[0x6040].raw = 0x0F | NEW | RELATIVE | HALT
        assert runtime.run_until(lambda: not runtime.call(drive.device.drive.moving, drive.device.model), 5.0), kind
        runtime.advance(0.5)
        stood = node.sdo[0x6064].raw
        assert start < stood < start + 40_000, (kind, stood - start)
        runtime.advance(2.0)
        assert node.sdo[0x6064].raw == stood, kind
        assert node.sdo[0x6041].raw & (0x6F | TARGET_REACHED) == 0x27 | TARGET_REACHED, kind


@pytest.mark.parametrize("kind", DRIVES)
def test_disable_operation_mid_move_and_enable_operation_again(kind: str) -> None:
    """Transition 5 (disable operation) while a positioning runs, then 4 (enable operation): the
    drive is in Operation enabled again, with no set-point in process (bit 12 = 0), and a new
    set-point runs to its target."""
    with Drive(kind, 9, name=kind, ready=True) as drive:
        runtime, node = drive.runtime, drive.node
        moving = drive.moving
        in_profile_position(node, 1000, 2000)
        node.sdo[0x6040].raw = 0x0F | NEW | RELATIVE
        runtime.advance(0.1)
        node.sdo[0x6040].raw = 0x07
        runtime.advance(1.5)
        node.sdo[0x6040].raw = 0x0F
        runtime.advance(0.1)
        assert node.sdo[0x6041].raw & (0x6F | ACKNOWLEDGE) == 0x27, kind
        start = node.sdo[0x6064].raw
        node.sdo[0x6040].raw = 0x0F | NEW | RELATIVE
        runtime.advance(0.1)
        assert runtime.run_until(lambda: not moving(), 5.0), kind
        runtime.advance(1.0)
        assert abs(node.sdo[0x6064].raw - (start + 1000)) <= 5, kind
        assert node.sdo[0x6041].raw & (0x6F | TARGET_REACHED) == 0x27 | TARGET_REACHED, kind
