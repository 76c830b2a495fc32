"""The operator's panel actions through the control socket (spec §3.2.2): a key or a program
number with only the control API's blanks around it (space, TAB, LF, CR, as every control value;
core.points.strip_blanks), not the Unicode ones str.strip() also takes."""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import pytest

from devsim.runtime.client import ControlClient, ControlError
from tests.support.control import control_client

D = "poselesta"
UNICODE_BLANKS = ["\u3000", "\xa0", "\x1c", "\x1f", "\x85", "\u2028", "\x0b", "\x0c"]


@pytest.fixture
def cnc(devsim_device: Any) -> Any:
    sim = devsim_device("poselesta", {"input_rise_ms": 0, "input_fall_ms": 0, "v8_keymap": {"48": "P"}})
    sim.advance(0.1)  # past the boot
    sim.set("panel.mode", "PROGRAM_ENTRY")
    return sim


@pytest.fixture
def ctl(cnc: Any) -> Iterator[ControlClient]:
    with control_client(cnc.runtime) as client:
        yield client


@pytest.mark.parametrize("blank", UNICODE_BLANKS)
def test_a_key_has_only_the_control_blanks_around_it(cnc: Any, ctl: ControlClient, blank: str) -> None:
    """panel.key stripped with str.strip(): '\\u3000P', 'P\\x1c', '\\xa048' pressed the key P (48h)."""
    for key in (f"{blank}P", f"P{blank}", f"{blank}48", f"48{blank}"):
        with pytest.raises(ControlError, match="no key"):
            ctl.set(D, "panel.key", key)
    assert ctl.read(D, "keyboard.last_key") == -1  # (none pressed)
    ctl.set(D, "panel.key", " P\t")  # the control blanks
    assert ctl.read(D, "keyboard.last_key") == 0x48


@pytest.mark.parametrize("blank", UNICODE_BLANKS)
def test_a_program_number_has_only_the_control_blanks_around_it(cnc: Any, ctl: ControlClient, blank: str) -> None:
    """panel.edit_block's program number stripped with str.strip(): '\\u300020: N5 X10' stored N5 in P20."""
    for text in (f"{blank}20: N5 X10", f"20{blank}: N5 X10", f"{blank}P20: N5 X10"):
        with pytest.raises(ControlError, match="expected 'program: block'"):
            ctl.set(D, "panel.edit_block", text)
    assert ctl.read(D, "programs") == []
    ctl.set(D, "panel.edit_block", " 20 : N5 X10")
    assert ctl.read(D, "program.P20") == "N 5 X 10.000"


@pytest.mark.parametrize("blank", UNICODE_BLANKS)
def test_a_parameter_name_has_only_the_control_blanks_around_it(cnc: Any, ctl: ControlClient, blank: str) -> None:
    """ParameterTable.find stripped the key with str.strip(): 'param.\\u3000P67' and 'param.67\\u2028'
    read and set P67 (the buzzer switch) on every kind with parameters."""
    for name in (f"param.{blank}P67", f"param.P67{blank}", f"param.{blank}67", f"param.67{blank}"):
        with pytest.raises(ControlError, match="UnknownName"):
            ctl.read(D, name)
        with pytest.raises(ControlError, match="UnknownName"):
            ctl.set(D, name, 1)
    assert ctl.read(D, "param.P67") == 0
    assert ctl.read(D, "param. P67\t") == ctl.read(D, "param.67") == 0  # the control blanks, the bare number
