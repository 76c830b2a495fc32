"""Manual §7.4 DP14/DPB14 and §9.2 (Example 2's cyclic part): what the PCA2.D14 shows, the
registers written by a host over S-Bus on a real pty, the display read as the machine shows it."""

from __future__ import annotations

from collections.abc import Callable

import pytest

from tests.pcd4h3.helpers import Station, flag, load

SHOWN = {"display": {1: {"reg1": "DestP", "reg2": "Veloc"}}}  # DP14 of two load registers every cycle


@pytest.mark.manual("§9.2", "im COB 0 (zyklische Achsenbearbeitung) werden die Werte mit dem Funktionsblock DP14 "
                    "auf dem Displaymodul PCA2.D14 angezeigt: jeder Zyklus, auch wenn die Achse steht")
def test_the_display_follows_its_registers_while_the_axis_is_idle(make: Callable[..., Station]) -> None:
    pcd = make(SHOWN)
    assert pcd.write_flags(flag("DplM"), 1) == b"\x00\x00"  # 2 × 6 digits
    pcd.sim.advance(0.05)
    assert pcd.sim.read("axis.1.display") == ["  1000", "   500"]  # Example 1's DestP and Veloc
    load(pcd, DestP=1234)  # nothing moves, no command flag: only the register changes
    pcd.sim.advance(0.05)
    assert pcd.sim.read("axis.1.display") == ["  1234", "   500"]
    load(pcd, Veloc=-42)
    pcd.sim.advance(0.05)
    assert pcd.sim.read("axis.1.display") == ["  1234", "-   42"]
