"""Manual §7.4 (the library's functions) statement by statement, driven by a host over S-Bus on
a real pty: the registers written, the command flags set, the read functions' registers read back."""

from __future__ import annotations

import pytest

from tests.pcd4h3.helpers import Station, load, reg, run

VELOCITY_MODE, FORWARD = 1 << 11, 1 << 12  # MCW and RSigB bits 11, 12 (§7.4 FSelOM, FRdSR)


def signal_register(pcd: Station) -> int:
    run(pcd, "FRdSR")
    return pcd.read_registers(reg("RSigB"))[0]


@pytest.mark.manual("§7.4 FSelOM", "die neu definierte Betriebsart ist erst nach Ausführen des nächsten "
                    "Startbefehls FStart gültig")
@pytest.mark.manual("§7.4 FRdSR", "RSigB Bit 11 (Betriebsart) und Bit 12 (Drehrichtung): Setzen und Rücksetzen "
                    "des Bit erfolgt jeweils erst beim nächsten Startbefehl")
def test_fselom_changes_the_mode_bits_only_with_the_next_start(pcd: Station) -> None:
    assert signal_register(pcd) & (VELOCITY_MODE | FORWARD) == 0  # AxInit with MCW 41Bh: position mode
    load(pcd, MCW=0x041B | VELOCITY_MODE | FORWARD, Veloc=100)
    run(pcd, "FSelOM", "FLdVA")
    assert signal_register(pcd) & (VELOCITY_MODE | FORWARD) == 0  # selected, not yet valid
    assert pcd.sim.read("axis.1.velocity") == 0  # and the axis does not run in velocity mode either
    run(pcd, "FStart")
    assert signal_register(pcd) & (VELOCITY_MODE | FORWARD) == VELOCITY_MODE | FORWARD
    load(pcd, MCW=0x041B)  # back to position mode: still velocity mode until the next start
    run(pcd, "FSelOM")
    assert signal_register(pcd) & (VELOCITY_MODE | FORWARD) == VELOCITY_MODE | FORWARD
