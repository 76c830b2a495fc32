"""Axis 1 as a CiA 402 drive (the kind's drive actions) with targets the PCD cannot take, driven
by canopen's master over a virtual CAN bus: refused with an SDO abort, DestP and Veloc untouched,
the axis where it was; manual §7.4 FLdDA (the position range) and §7.1.5 (32-bit registers)."""

from __future__ import annotations

from collections.abc import Iterator

import pytest
from canopen.sdo.exceptions import SdoAbortedError

from devsim.core.words import signed32
from devsim.devices.pcd4h3.units import ffp_encode
from tests.facades.test_cia402 import Drive, enable

LIMIT = 1 << 30  # the LM628's position range: −2^30 … 2^30 − 1 counts (§7.4 FLdDA, DestP)


@pytest.fixture
def drive() -> Iterator[Drive]:
    d = Drive()
    try:
        yield d
    finally:
        d.close()


def registers(drive: Drive) -> tuple[int, int]:
    return drive.runtime.read("pcd", "axis.1.DestP"), drive.runtime.read("pcd", "axis.1.Veloc")


@pytest.mark.manual("§7.4 FLdDA", "DestP Wert: [−2^30 … +(2^30 − 1)] / k: a target beyond the position range is not "
                    "taken")
def test_a_relative_target_beyond_the_position_range_is_refused(drive: Drive) -> None:
    enable(drive)
    drive.runtime.set("pcd", "axis.1.position", LIMIT - 500)
    before = registers(drive)
    drive.node.sdo[0x6060].raw = 1  # profile position
    drive.node.sdo[0x607A].raw = 1_000  # relative: 2^30 + 500 counts
    with pytest.raises(SdoAbortedError):
        drive.control(0x5F)  # new set-point, relative
    assert registers(drive) == before
    drive.runtime.advance(1.0)
    assert drive.runtime.read("pcd", "axis.1.position") == LIMIT - 500
    assert drive.runtime.read("pcd", "axis.1.comers") == 0  # nothing reached the chip


@pytest.mark.manual("§7.1.5", "die Achsenparameter stehen in den Registern des PCD4.R2 (32 Bit): a target that "
                    "needs more than 32 bits in MCFac's unit is refused, not wrapped")
def test_a_target_the_register_cannot_hold_is_refused_not_wrapped(drive: Drive) -> None:
    drive.runtime.set("pcd", "axis.1.MCFac", signed32(ffp_encode(0.001)))  # k = 0.001 counts per unit
    enable(drive)
    before = registers(drive)
    drive.node.sdo[0x6060].raw = 1
    drive.node.sdo[0x607A].raw = 5_000_000  # counts, in range for the chip; 5·10^9 units: not 32 bits
    with pytest.raises(SdoAbortedError):
        drive.control(0x1F)
    assert registers(drive) == before
    drive.runtime.advance(1.0)
    assert abs(drive.runtime.read("pcd", "axis.1.position")) < 10
