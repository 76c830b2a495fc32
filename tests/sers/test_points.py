"""The SERS's declared names, checked values and declared faults (the device kit)."""

from __future__ import annotations

import math
import re
from pathlib import Path

import pytest

from devsim.core.clock import VirtualClock
from devsim.core.config import ConfigError, load_config
from devsim.core.points import BadValue, ReadOnlyName, UnknownName
from devsim.devices.sers import SersDevice
from devsim.devices.sers.config import SersConfig


@pytest.fixture
def sers() -> SersDevice:
    clock = VirtualClock()
    device = SersDevice(clock=clock, config={"boot_time": 0})
    device.clock = clock
    return device


@pytest.mark.parametrize("bad", ["hello", math.nan, math.inf, "1e400", True])
def test_a_bad_quantity_is_refused_and_the_old_value_stays(sers: SersDevice, bad: object) -> None:
    sers.set("quantity.supply_voltage", 40)
    with pytest.raises(BadValue, match="quantity.supply_voltage"):
        sers.set("quantity.supply_voltage", bad)
    assert sers.read("quantity.supply_voltage") == 40.0


@pytest.mark.parametrize(("text", "value"), [("False", False), ("off", False), ("0", False), ("true", True),
                                             ("ON", True), (1, True)])
def test_booleans_by_their_declared_type(sers: SersDevice, text: object, value: bool) -> None:
    sers.set("input.limit_right", not value)
    sers.set("input.limit_right", text)
    assert sers.read("input.limit_right") is value
    with pytest.raises(BadValue, match="true/false/1/0/on/off/yes/no"):
        sers.set("input.limit_right", "False!")


def test_read_only_and_unknown_names(sers: SersDevice) -> None:
    with pytest.raises(ReadOnlyName, match="output.O1 of sers is read-only"):
        sers.set("output.O1", True)
    with pytest.raises(UnknownName, match=r"did you mean axis.position"):
        sers.read("axis.positon")
    assert sers.read("param.V") == sers.read("param.P91") == sers.read("param.91")


def test_parameter_writes_keep_the_drive_s_own_check(sers: SersDevice) -> None:
    before = sers.read("param.V")
    with pytest.raises(BadValue, match="P91: errno 1"):
        sers.set("param.V", 1e9)
    assert sers.read("param.V") == before
    with pytest.raises(BadValue, match="finite"):
        sers.set("param.V", "NaN")
    assert sers.read("param.V") == before


def test_every_declared_fault(sers: SersDevice) -> None:
    assert sers.faults.names() == ["blocked_axis", "emergency_stop", "power"]
    sers.fault("emergency_stop", True)
    assert sers.read("input.stop") is True
    sers.fault("emergency_stop", "off")
    assert sers.read("input.stop") is False
    sers.fault("blocked_axis", True)
    assert sers.read("quantity.stall") is True
    sers.fault("blocked_axis", False)
    sers.fault("power", True)
    assert sers.read("powered") is False
    sers.fault("power", False)
    assert sers.read("powered") is True


def test_a_program_in_the_initial_state_is_checked_first(sers: SersDevice) -> None:
    sers.apply_state({"program": ["ON", "W=360 E"]})
    assert sers.read("program") == [["ON"], ["W=360", "E"]]
    with pytest.raises(BadValue, match="program line"):
        sers.apply_state({"program": ["ON", "GARBAGE?!"]})
    assert sers.read("program") == [["ON"], ["W=360", "E"]]  # nothing of the bad download was stored


@pytest.mark.parametrize(("bad", "match"), [
    (["ON", "LIST"], "'LIST': programming mode does not store it"),
    (["ON", "QUIT"], "'QUIT': programming mode does not store it"),
    (["L1 ON", "L1"], "label bereits definiert: L1"),
])
def test_a_program_in_the_initial_state_is_stored_as_programming_mode_stores_it(sers: SersDevice, bad: list,
                                                                                 match: str) -> None:
    """Typed in programming mode, a comment is not stored, ``LIST`` or ``QUIT`` runs instead and a
    label is defined once (§4.2, §4.6.2): a program downloaded as the initial state is the same, so
    the drive's next start loads it (before: ``// loop`` was stored as a statement, and so were
    ``LIST`` and a second ``L1``: a program the drive could never have written)."""
    sers.apply_state({"program": ["L1 O1=1 // loop", "GT1"]})
    assert sers.read("program") == [["L1", "O1=1"], ["GT1"]]
    with pytest.raises(BadValue, match=re.escape(match)):
        sers.apply_state({"program": bad})
    assert sers.read("program") == [["L1", "O1=1"], ["GT1"]]  # nothing of the bad download was stored


@pytest.mark.parametrize("number", [123, 103])
def test_a_range_above_zero_refuses_zero(sers: SersDevice, number: int) -> None:
    """P123 (feed constant) and P103 (modulo) take values > 0 (spec §5 table: ">0"): 0 is "zu
    klein" on the line and through the control API, and the position stays readable.  (Found by
    fuzzing: P123=0 was taken, and every read of the position then raised.)"""
    out = bytearray()
    sers.attach(out.extend)
    before = sers.read(f"param.P{number}")
    sers.feed(f"#P{number}=0\r".encode())
    assert bytes(out) == f"#P{number}=0\r\n*zu klein\n\r".encode()
    with pytest.raises(BadValue, match=f"P{number}: errno 2: zu klein"):
        sers.set(f"param.P{number}", 0)
    assert sers.read(f"param.P{number}") == before
    assert sers.read("axis.position") == 0


def test_config_parameters_are_checked_against_the_table(tmp_path: Path) -> None:
    path = tmp_path / "sers.yaml"
    path.write_text("address: 1\nparams:\n  P9999: 1\n")
    with pytest.raises(ConfigError, match=r"sers.yaml:3: params.P9999: no such parameter"):
        load_config(path, SersConfig)
    path.write_text("params:\n  V: 1e12\n")
    with pytest.raises(ConfigError, match=r"V: 1e\+12 is above the maximum"):
        load_config(path, SersConfig)
    path.write_text("params:\n  P123: 0\n")
    with pytest.raises(ConfigError, match=r"P123: 0 must be above 0"):
        load_config(path, SersConfig)
    path.write_text("params:\n  P123: 0.00001\n")  # (0.0000 on the drive's grid of four decimals)
    with pytest.raises(ConfigError, match=r"P123: 1e-05 must be above 0"):
        load_config(path, SersConfig)
    path.write_text("params:\n  P1017: 2\n  V: 500\n  '1028': 3\n")
    assert load_config(path, SersConfig).params == {"P1017": 2, "V": 500, "1028": 3}
