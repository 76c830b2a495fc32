"""The GMS96's declared names, checked values, declared faults and checked configuration."""

from __future__ import annotations

from pathlib import Path

import pytest

from devsim.core.clock import VirtualClock
from devsim.core.config import ConfigError, load_config
from devsim.core.points import BadValue, ReadOnlyName, UnknownName
from devsim.devices.gms96 import Gms96Device
from devsim.devices.gms96.config import Gms96Config
from devsim.scenario.runner import run_scenario
from devsim.scenario.schema import scenario_from_dict


@pytest.fixture
def card() -> Gms96Device:
    clock = VirtualClock()
    device = Gms96Device(clock=clock, config={"boot_time": 0})
    return device


def test_values_are_checked_before_they_take_effect(card: Gms96Device) -> None:
    card.set("quantity.override_pot", 50)
    for bad in ("hello", float("nan"), 126, "1e400"):
        with pytest.raises(BadValue):
            card.set("quantity.override_pot", bad)
    assert card.read("quantity.override_pot") == 50.0
    with pytest.raises(BadValue, match="param.N20: .* above the maximum 15000"):
        card.set("param.N20", 20000)
    assert card.read("param.n20") == card.read("param.20")


def test_names_read_only_and_suggestions(card: Gms96Device) -> None:
    with pytest.raises(ReadOnlyName, match="status of gms96 is read-only"):
        card.set("status", 0)
    with pytest.raises(UnknownName, match="did you mean following_error"):
        card.read("folowing_error")
    card.set("marker.M41.3", True)
    assert card.read("marker.m41.3") is True and card.read("marker.MB41") == 8
    with pytest.raises(UnknownName):
        card.read("marker.M300.1")


def test_every_declared_fault(card: Gms96Device) -> None:
    assert card.faults.names() == ["blocked_axis", "emergency_stop", "power", "monitoring", "flash_error"]
    card.fault("monitoring", True)
    assert card.read("monitoring") == "dc_undervoltage" and card.read("fault") is True
    card.fault("monitoring", False)
    assert card.read("monitoring") == ""
    card.fault("power", True)
    assert card.read("powered") is False
    card.fault("power", False)
    assert card.read("powered") is True
    card.fault("flash_error", True)  # (what it does: tests/gms96/test_manual_memory.py, test_plc.py)
    card.fault("flash_error", False)


def test_the_monitoring_fault_from_a_scenario() -> None:
    result = run_scenario(
        scenario_from_dict(
            {
                "devices": [{"name": "card", "kind": "gms96", "config": {"boot_time": 0}}],
                "steps": [
                    {"fault": {"device": "card", "kind": "monitoring", "duration": "1s"}},
                    {"expect_state": {"device": "card", "name": "monitoring", "equals": "dc_undervoltage"}},
                    {"after": "2s", "expect_state": {"device": "card", "name": "monitoring", "equals": ""}},
                ],
            }
        ),
        mode="virtual",
    )
    assert result.passed, [s.message for s in result.steps]


def test_configuration_checked_against_the_tables(tmp_path: Path) -> None:
    path = tmp_path / "card.yaml"
    path.write_text("params:\n  N999: 1\n")
    with pytest.raises(ConfigError, match=r"card.yaml:2: params.N999: no such parameter"):
        load_config(path, Gms96Config)
    path.write_text("params:\n  N20: 999999999\n")
    with pytest.raises(ConfigError, match=r"N20: 999999999 is outside 10 … 15000"):
        load_config(path, Gms96Config)
    path.write_text("address: 1\nbaud: 9600\n")
    with pytest.raises(ConfigError, match=r"looks like a SERS configuration \(address, baud\)"):
        load_config(path, Gms96Config)
    path.write_text("i6_mode: level\nquery_units: false\n")  # (the readings a SERS has, G-INFUNC, G-QUERYFMT)
    with pytest.raises(ConfigError, match=r"looks like a SERS configuration \(i6_mode, query_units\)"):
        load_config(path, Gms96Config)


@pytest.mark.parametrize("name", ["marker.mb²", "marker.MB¹2", "marker.MB٣", "marker.M٣.1", "program.٣"])
def test_a_name_s_numbers_are_ascii_digits(card: Gms96Device, name: str) -> None:
    """A marker byte or program number is written in ASCII digits: 'marker.mb²' ended in a ValueError
    (str.isdigit takes the superscript, int() does not) and digits of other scripts, which \\d and
    int() read, named marker byte 3 and program 3."""
    with pytest.raises(UnknownName):
        card.read(name)


def test_a_cnc_program_s_numbers_are_ascii_digits(card: Gms96Device) -> None:
    with pytest.raises(BadValue, match="a command is a letter"):
        card.set("program.1", ["A١٠٠٠"])
    for separator in ("\x1c", "\x1e", "\x85", "\u2028"):  # (str.splitlines split there: two commands)
        with pytest.raises(BadValue, match="a command is a letter"):
            card.set("program.1", f"A1000{separator}A2000")
    card.set("program.1", "A1000\r\nA2000\n")
    assert card.read("program.1") == ["A1000", "A2000"]


def test_a_lone_surrogate_is_a_bad_value(card: Gms96Device) -> None:
    """A choice written with a lone surrogate ('\\udcff': devsim ctl set with an argument byte that is
    no UTF-8) is refused like any other wrong choice; msgspec's conversion raised UnicodeEncodeError."""
    with pytest.raises(BadValue, match="dil.protocol"):
        card.set("dil.protocol", "\udcff")
    assert card.read("dil.protocol") == "S"


@pytest.mark.parametrize("name", ["k\u017fa15-2r", "KSA15-2R\u00a0"])
def test_a_variant_is_named_in_ascii(name: str) -> None:
    """A variant's name is matched in ASCII case: str.upper made 'kſa15-2r' (the long s U+017F)
    KSA15-2R, and str.strip() took the NBSP off 'KSA15-2R\\xa0'."""
    assert Gms96Config.parse({"variant": "g96-ksa15-2r"}).variant == "g96-ksa15-2r"
    with pytest.raises(Exception, match="no such variant"):
        Gms96Config.parse({"variant": name})
