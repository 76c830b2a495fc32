"""Manual §7.1.3 and §7.1.5: the installation's symbols and where an axis's registers and flags
live, checked over S-Bus on a real pty against the addresses the manual gives."""

from __future__ import annotations

from collections.abc import Callable

import pytest

from tests.pcd4h3.helpers import Station, flag, reg


@pytest.mark.manual("§7.1.5", "da der PCD-Assembler zwischen Gross- und Kleinschrift nicht unterscheidet, können die "
                    "Namen beliebig, gross oder klein geschrieben werden")
def test_symbols_in_any_case(make: Callable[..., Station]) -> None:
    pcd = make({"init": {1: {"destp": 777}}, "flag_map": {"fstart": 28}})
    assert pcd.read_registers(reg("DestP")) == [777]  # the configuration's lower-case key
    pcd.sim.set("axis.1.VELOC", 321)
    assert pcd.read_registers(reg("Veloc")) == [321]
    assert pcd.sim.read("axis.1.veloc") == 321 and pcd.sim.read("axis.1.Veloc") == 321
    pcd.write_flags(flag("DplM"), 1)
    assert pcd.sim.read("axis.1.dplm") is True and pcd.sim.read("axis.1.DPLM") is True
