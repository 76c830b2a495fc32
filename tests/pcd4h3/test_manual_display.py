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


def shown(pcd: Station, axis: int = 1, **registers: int) -> list[str]:
    load(pcd, axis, **registers)
    pcd.sim.advance(0.02)  # the next PLC cycle's DP14
    return pcd.sim.read(f"axis.{axis}.display")


@pytest.mark.manual("§7.4 DP14", "2·6 Digits: 0 ≤ w ≤ 999 999: v = MSD; w > 999 999: v = 'A'; 0 > w ≥ −99 999: v = '-'; "
                    "w < −99 999: v = 'U'; Anzeigebereich −99 999 … +999 999")
@pytest.mark.manual("§7.4 DP14", "das Flag DPLM bestimmt die Art der Anzeige: DPLM = 1 → 2·6 Digits")
def test_two_values_of_six_digits(make: Callable[..., Station]) -> None:
    pcd = make(SHOWN)
    assert pcd.write_flags(flag("DplM"), 1) == b"\x00\x00"
    assert shown(pcd, DestP=999_999, Veloc=0) == ["999999", "     0"]
    assert shown(pcd, DestP=1_234_567, Veloc=-99_999) == ["A34567", "-99999"]
    assert shown(pcd, DestP=-100_000, Veloc=-7) == ["U00000", "-    7"]


@pytest.mark.manual("§7.4 DP14", "1·10 Digits (1 Register): oben 'b v 1 2 3 4', unten '5 6 7 8 9 10', b blank, v blank "
                    "oder '-'; Anzeigebereich ±2 147 483 647")
@pytest.mark.manual("§7.4 DP14", "das Flag DPLM bestimmt die Art der Anzeige: DPLM = 0 → 1·10 Digits")
def test_one_value_of_ten_digits(make: Callable[..., Station]) -> None:
    pcd = make(SHOWN)
    assert pcd.write_flags(flag("DplM"), 0) == b"\x00\x00"
    assert shown(pcd, DestP=-2_147_483_647) == [" -2147", "483647"]
    assert shown(pcd, DestP=2_147_483_647) == ["  2147", "483647"]
    assert shown(pcd, DestP=12) == ["      ", "    12"]


@pytest.mark.manual("§7.4 DP14", "mit dem Modul PCD4.H320 können 2 Anzeigemodule betrieben werden")
def test_a_two_axis_module_drives_two_displays(make: Callable[..., Station]) -> None:
    pcd = make({"h3def": {"fmah3": 48, "bar": 200, "baf": 200, "mna": 2},
                "display": {1: {"reg1": "DestP", "reg2": "Veloc"}, 2: {"reg1": "DestP", "reg2": "Veloc"}}})
    pcd.write_flags(flag("DplM", 1), 1)
    pcd.write_flags(flag("DplM", 2), 1)
    assert shown(pcd, 1, DestP=11) == ["    11", "   500"]
    assert shown(pcd, 2, DestP=22, Veloc=33) == ["    22", "    33"]
    assert pcd.sim.read("axis.1.display") == ["    11", "   500"]
