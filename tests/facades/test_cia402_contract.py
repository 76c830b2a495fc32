"""Every kind that declares drive actions passes the CiA 402 flow through canopen (issue 13, the
kit's contract for drives): from Switch on disabled to Operation enabled, a relative profile-
position move of 1 000 units that ends there with "target reached", and back to Switch on
disabled; enabled again, an NMT reset node disables the drive as disable voltage does (issue 29).  Kinds without drive actions are CANopen nodes without the 402 objects."""

from __future__ import annotations

from pathlib import Path

import canopen
import pytest

from devsim.core.registry import device_class, kinds
from devsim.facades.canopen_node import load_od
from devsim.facades.canopen_od import eds
from tests.facades.test_cia402 import Drive

ROOT = Path(__file__).resolve().parents[2]
DRIVES = sorted(k for k in kinds() if device_class(k).drive is not None)


def test_the_drives() -> None:
    assert {"sers", "gms96", "poselesta", "ip247", "pcd4h3"} <= set(DRIVES)


@pytest.mark.parametrize("kind", DRIVES)
def test_a_drive_runs_the_402_flow(kind: str) -> None:
    drive = Drive(kind, 9, name=kind, ready=True)
    runtime, device, node = drive.runtime, drive.device, drive.node
    try:
        for word, state in ((0x06, 0x21), (0x07, 0x23), (0x0F, 0x27)):
            node.sdo[0x6040].raw = word
            assert node.sdo[0x6041].raw & 0x6F == state, (kind, hex(word))
        start = node.sdo[0x6064].raw
        node.sdo[0x6060].raw = 1
        node.sdo[0x607A].raw = 1000
        node.sdo[0x6081].raw = 2000
        node.sdo[0x6040].raw = 0x5F  # new set-point, relative
        assert node.sdo[0x6041].raw & 0x1000
        assert runtime.run_until(lambda: not device.drive.moving(device.model), 30.0)
        runtime.advance(1.0)
        assert abs(node.sdo[0x6064].raw - (start + 1000)) <= 3
        assert node.sdo[0x6041].raw & 0x0400
        node.sdo[0x6040].raw = 0x00  # disable voltage
        assert node.sdo[0x6041].raw & 0x4F == 0x40
        disabled = runtime.call(device.drive.enabled, device.model)  # (the IP247 has no power stage to switch)
        for word in (0x06, 0x07, 0x0F):
            node.sdo[0x6040].raw = word
        assert runtime.call(device.drive.enabled, device.model)
        node.nmt.send_command(0x81)  # NMT reset node (CiA 301): the drive disabled, Switch on disabled
        assert node.sdo[0x6041].raw & 0x4F == 0x40
        assert runtime.call(device.drive.enabled, device.model) == disabled
    finally:
        drive.close()


def test_a_kind_without_drive_actions_has_no_402_objects() -> None:
    """Every built-in kind is a drive now; the test kit's echo device is not."""
    from tests.support.echo import EchoDevice

    assert EchoDevice.drive is None
    od = load_od(eds(EchoDevice.kind, EchoDevice.description, EchoDevice.points, drive=False), 1)
    assert 0x6040 not in od and 0x6041 not in od and 0x1000 in od
    for kind in DRIVES:
        assert 0x6040 in canopen.import_od(str(ROOT / "docs" / "eds" / f"{kind}.eds"))
