"""A CANopen node that conforms (issue 29), checked with canopen as the master on python-can's
virtual bus: CiA 402's modes of operation (6060h takes only a mode 6502h lists, 6061h never shows
another), CiA 301's NMT resets (reset communication restores 1000h … 1FFFh, reset node the 402
objects too, one boot-up each), and SDO aborts that name the request they answer."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import canopen
import pytest

from tests.facades.test_cia402 import Drive

ROOT = Path(__file__).resolve().parents[2]
VALUE_RANGE_EXCEEDED = 0x06090030  # CiA 301 SDO abort: value range of parameter exceeded

#: CiA 402-2, 6502h "supported drive modes": the bit of each mode of operation (6060h value).
MODE_BITS = {1: 0, 2: 1, 3: 2, 4: 3, 6: 5, 7: 6, 8: 7, 9: 8, 10: 9}


@pytest.fixture
def drive() -> Iterator[Drive]:
    d = Drive()
    try:
        yield d
    finally:
        d.close()


def test_6060h_takes_only_the_modes_6502h_lists_and_6061h_shows_no_other(drive: Drive) -> None:
    node = drive.node
    supported = node.sdo[0x6502].raw
    assert supported & (1 << MODE_BITS[1]) and supported & (1 << MODE_BITS[3])  # pp and pv: every drive here
    assert not supported & (1 << MODE_BITS[6])  # no homing mode
    shown = node.sdo[0x6061].raw
    for mode in (-1, 0, *range(1, 11), 127):
        bit = MODE_BITS.get(mode)
        if bit is not None and supported >> bit & 1:
            node.sdo[0x6060].raw = mode
            shown = mode
        else:
            with pytest.raises(canopen.SdoAbortedError) as refused:
                node.sdo[0x6060].raw = mode
            assert refused.value.code == VALUE_RANGE_EXCEEDED, mode
        assert node.sdo[0x6061].raw == shown, mode
    node.sdo[0x6060].raw = 1
    # an RPDO carrying an unsupported mode changes nothing either
    node.rpdo.read()
    rpdo = node.rpdo[1]
    rpdo.clear()
    rpdo.add_variable(0x6060)
    rpdo.trans_type, rpdo.enabled = 255, True
    node.rpdo.save()
    node.nmt.state = "OPERATIONAL"
    rpdo["Modes of operation"].raw = 3
    rpdo.transmit()
    assert node.sdo[0x6061].raw == 3  # (frames on the bus are handled in order: the RPDO before the SDO)
    rpdo["Modes of operation"].raw = 6
    rpdo.transmit()
    assert node.sdo[0x6061].raw == 3
    assert node.sdo[0x6060].raw == 3
