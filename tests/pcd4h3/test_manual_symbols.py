"""Manual §7.1.3 and §7.1.5: the installation's symbols and where an axis's registers and flags
live, checked over S-Bus on a real pty against the addresses the manual gives."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pytest

from devsim.core.config import ConfigError, load_config
from devsim.core.points import BadValue
from devsim.devices.pcd4h3.config import Pcd4h3Config
from tests.pcd4h3.helpers import Station, flag, reg, run


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


@pytest.mark.manual("§7.1.3", "H3DEF.SRC voreingestellt: FMAH3 EQU 0, IMode EQU 6, MNA EQU 2, BAF EQU 2000, "
                    "BAR EQU 2000")
@pytest.mark.manual("§7.2 AxInit", "RAi = (i − 1) · 20 (NoRfeA), FAi = (i − 1) · 35 (NoFfeA)")
def test_the_h3def_defaults(make: Callable[..., Station]) -> None:
    pcd = make({"h3def": {}})  # H3DEF.SRC as shipped
    assert pcd.read_registers(2000, 20)[:6] == pcd.read_registers(2020, 20)[:6] == [150, 50, 50, 500, 15, -939524025]
    pcd.write_registers(2020 + 7, 300)  # DestP + RA2
    pcd.write_flags(2035 + 7, 1)  # FLdDA + FA2
    pcd.write_flags(2035 + 28, 1)  # FStart + FA2
    assert pcd.sim.run_until(lambda d: d.read("axis.2.OnDest") and d.read("axis.2.position") > 29_990, 20.0)
    assert pcd.sim.read("axis.1.position") == 0
    assert pcd.read_flags(9, 2, command=0x03) == [1, 1]  # FMAH3 0: the first module's LS1x, LS2x at I 9, 10
    pcd.write_flags(2027, 1)  # FRdSR + FA1
    pcd.sim.advance(0.05)
    assert not pcd.read_registers(2019)[0] & 0x100  # IMode 6: the ±10 V port (RSigB bit 8 = 0)


@pytest.mark.manual("§7.1.3", "IMode: Module H310, 311, 320, 321: 6; Module H316, 317, 326, 327: 5")
@pytest.mark.manual("§7.4 FRdSR", "Bit 8: 1 wenn der Ausgang mit AxInit als PWM-Ausgang definiert wird, 0 als ±10 V "
                    "Analogausgang")
def test_imode_follows_the_output_of_the_variant(make: Callable[..., Station]) -> None:
    for variant, pwm in (("H310", 0), ("H321", 0), ("H316", 1), ("H327", 1)):
        pcd = make({"variant": variant})
        run(pcd, "FRdSR")
        assert pcd.read_registers(reg("RSigB"))[0] >> 8 & 1 == pwm, variant


@pytest.mark.manual("§7.1.5", "Belegung der Register: BAR+RAi+0 KProp … +19 RSigB; der Flag: BAF+FAi+0 OnDest, +1 IPuls, "
                    "+2 WrapOc, +3 ExcPEr, +4 BrkPos, +5 DplM, +6 FLdDR, +7 FLdDA, +8 FLdVR, +9 FLdVA, +34 FBackw")
@pytest.mark.manual("§7.1.5", "LD R DestP+RA3 / SET F FLdDA+FA3: die Zielposition der Achse 3 ins H3-Modul laden; STH F "
                    "OnDest+FA3 fragt ab, ob sie erreicht ist")
def test_axis_3_by_its_register_block_and_flag_field(make: Callable[..., Station]) -> None:
    pcd = make({"modules": 2, "h3def": {"fmah3": 48, "bar": 200, "baf": 200, "mna": 3}})
    ra3, fa3 = 200 + 2 * 20, 200 + 2 * 35
    assert pcd.write_registers(ra3 + 7, 250) == b"\x00\x00"  # DestP
    assert pcd.write_registers(ra3 + 9, 1000) == b"\x00\x00"  # Veloc
    pcd.write_flags(fa3 + 9, 1)  # FLdVA
    pcd.write_flags(fa3 + 7, 1)  # FLdDA
    pcd.sim.advance(0.05)
    assert pcd.read_flags(fa3 + 7, 3) == [0, 0, 0]  # run and cleared
    assert pcd.sim.read("axis.3.position") == 0  # loaded, not started
    pcd.write_flags(fa3 + 28, 1)  # FStart
    pcd.sim.advance(0.05)
    assert pcd.read_flags(fa3, 1) == [0]  # OnDest: moving
    assert pcd.sim.run_until(lambda d: d.read("axis.3.OnDest"), 10.0)
    assert pcd.read_flags(fa3, 1) == [1]
    pcd.write_flags(fa3 + 34, 1)  # FBackw at the field's last offset
    pcd.sim.advance(0.5)
    assert pcd.sim.read("axis.3.velocity") < 0
    pcd.write_flags(flag("FRdAP", 3), 1)  # FRdAP (offset 21: the reconstruction, G-1)
    pcd.sim.advance(0.05)
    assert pcd.read_registers(ra3 + 13)[0] < 250  # RActP


@pytest.mark.manual("§7.1.3", "MNA definiert die Anzahl der eingesetzten Achsen; entsprechend werden die Speichermedien "
                    "(Register, Flag) reserviert")
def test_only_mna_axes_have_a_block(make: Callable[..., Station]) -> None:
    pcd = make()  # the example installation: MNA 1 on a two-axis module
    after = 200 + 35  # where axis 2's flag field would be
    pcd.write_flags(after + 28, 1)
    pcd.sim.advance(0.1)
    assert pcd.read_flags(after + 28) == [1]  # an ordinary flag: no AxHndlg processes it
    assert pcd.write_registers(220 + 7, 999) == b"\x00\x00"
    assert pcd.read_registers(220 + 7) == [999]
    with pytest.raises(BadValue, match="1 axes"):
        pcd.sim.read("axis.2.DestP")


@pytest.mark.manual("§7.1.3", "MNA: Definiert die Anzahl der eingesetzten Achsen. Entsprechend dieser Angabe werden "
                    "die benötigten Speichermedien (Register, Flag) reserviert (from BAR and BAF, within the PCD's "
                    "R 0 … 4095 and F 0 … 8191)")
def test_axis_blocks_that_leave_the_media_are_refused(tmp_path: Path) -> None:
    path = tmp_path / "pcd.yaml"
    path.write_text("h3def:\n  mna: 2\n  bar: 4090\n", encoding="utf-8")
    with pytest.raises(ConfigError) as info:
        load_config(path, Pcd4h3Config)
    assert str(info.value) == f"{path}:1: h3def: BAR 4090 with MNA 2: the axis blocks R 4090 … 4129 pass R 4095"
    path.write_text("h3def:\n  baf: 8180\n", encoding="utf-8")
    with pytest.raises(ConfigError, match="the axis fields F 8180 … 8249 pass F 8191"):
        load_config(path, Pcd4h3Config)
    path.write_text("h3def:\n  mna: 2\n  bar: 4056\n  baf: 8122\n", encoding="utf-8")  # the last that fit
    assert load_config(path, Pcd4h3Config).h3def.bar == 4056


@pytest.mark.manual("§7.1.3", "MNA: Entsprechend dieser Angabe werden die benötigten Speichermedien (Register, Flag) "
                    "reserviert (the axes' own: the simulator's diagnostics block, spec §9.6.3, lies apart from them)")
def test_axis_blocks_over_the_diagnostics_block_are_refused(tmp_path: Path) -> None:
    """The simulator's read-only diagnostics block (16 registers and 8 flags per axis from
    ``diagnostics``, default R 4000 and F 8000) over an axis block or flag field shadowed the axis's
    registers or flags there (a read gave the diagnostics, a write got NAK); it was accepted."""
    path = tmp_path / "pcd.yaml"
    refused = {
        "h3def:\n  mna: 2\n  bar: 3990\n":
            "diagnostics: the diagnostics block R 4000 … 4031 overlaps the axis blocks R 3990 … 4029 (BAR 3990, MNA 2): move it",
        "h3def:\n  baf: 7990\n":
            "diagnostics: the diagnostics flags F 8000 … 8015 overlap the axis fields F 7990 … 8059 (BAF 7990, MNA 2): move it",
        "diagnostics: [2039, 100]\n":
            "diagnostics: the diagnostics block R 2039 … 2070 overlaps the axis blocks R 2000 … 2039 (BAR 2000, MNA 2): move it",
        "diagnostics: [100, 1995]\nh3def: {mna: 1}\n":
            "diagnostics: the diagnostics flags F 1995 … 2002 overlap the axis fields F 2000 … 2034 (BAF 2000, MNA 1): move it",
    }
    for text, message in refused.items():
        path.write_text(text, encoding="utf-8")
        with pytest.raises(ConfigError) as info:
            load_config(path, Pcd4h3Config)
        assert str(info.value) == f"{path}:1: {message}", text
    for text in ("h3def:\n  mna: 2\n  bar: 3960\n  baf: 7930\n",  # the axes end where the diagnostics begin
                 "diagnostics: [2040, 2070]\n",  # the diagnostics begin where the axes end
                 "diagnostics: [1968, 1984]\n"):  # the diagnostics end where the axes begin
        path.write_text(text, encoding="utf-8")
        load_config(path, Pcd4h3Config)


def test_a_symbol_in_any_case_is_in_ascii(make: Callable[..., Station]) -> None:
    """Upper and lower case are the assembler's, ASCII: the Kelvin sign U+212A, which Python lower-cases
    to k, does not spell KProp, and an axis is numbered in ASCII digits (not Arabic-Indic ١)."""
    from devsim.core.points import UnknownName

    pcd = make()
    assert pcd.sim.read("axis.1.kprop") == pcd.sim.read("axis.1.KProp")
    for name in ("axis.1.\u212aProp", "axis.\u0661.KProp"):
        with pytest.raises(UnknownName):
            pcd.sim.read(name)


@pytest.mark.parametrize("init", [{1: {"\u212aProp": 5}}, {"axis\u0661": {"KProp": 5}}, {" 1": {"KProp": 5}},
                                  {"1_0": {"KProp": 5}}, {"\u00b2": {"KProp": 5}}])
def test_the_configuration_s_symbols_and_axes_are_ascii(init: dict) -> None:
    """The configuration reads symbols in ASCII case and axes in ASCII digits: the Kelvin sign (which
    str.lower makes k) spelled KProp, 'axis١' (Arabic-Indic), ' 1' and '1_0' (which int() reads) were
    axes 1 and 10, and '²' gave int()'s own message."""
    with pytest.raises(Exception, match="not a load register|an axis is 1"):
        Pcd4h3Config.parse({"init": init})
