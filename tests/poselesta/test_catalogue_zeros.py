"""After a parameter catalogue read-in (P99) that does not carry every parameter: the manual clears
the whole catalogue before the read-in (§2.6.2.3, §2.6.3), so the parameters the tape leaves out
stand at 0, values `ctl set` would refuse (P30 1 … 99, P76 1/2/4).  The control then does what
such parameters say, and its values stay numbers: no gain is no position loop, no increments per
detent is a handwheel that moves nothing.  (The probe saw ZeroDivisionError and ValueError come
out of the control API.)"""

from __future__ import annotations

import math
from typing import Any

import pytest

from devsim.core.points import UnknownName
from devsim.devices.poselesta.codes import encode
from tests.poselesta.test_ports import open_port, until


@pytest.fixture
def zeroed(devsim_device):  # noqa: ANN001, ANN201
    """A POSELESTA III whose catalogue was read in from a tape that carries P70 alone."""
    cnc = devsim_device("poselesta", {"input_rise_ms": 0, "input_fall_ms": 0})
    cnc.set("input.key_switch", True)  # (H: the catalogue may be read in)
    cnc.set("panel.mode", "EXTERNAL_OPERATION")
    cnc.set("panel.program", 99)
    cnc.set("v7.transfer", "input")
    tape = encode("%\r\nN70P3\r\nM30\r\n", iso=True)
    with open_port(cnc, "v7") as host:
        host.write(tape)
        until(lambda: cnc.read("v7.state") in ("done", "failed"), "the read-in has ended")
    assert cnc.read("v7.state") == "done"
    assert [cnc.read(f"param.P{n}") for n in (30, 70, 76)] == [0, 3, 0]
    return cnc


@pytest.mark.manual("§2.6.2.3", "vor dem Einlesen wird der gesamte Parameterkatalog P 99 inkl. P 68 und P 69 "
                    "gelöscht … somit die Parameter auf \"0\" stehen")
def test_every_value_is_a_number_with_the_catalogue_at_zero(zeroed: Any) -> None:
    numbers = {}
    for name in zeroed.names():
        try:
            value = zeroed.read(name)
        except UnknownName:
            continue  # (a name to set only)
        if isinstance(value, float):
            numbers[name] = value
    assert "axis.x.following_error" in numbers and "axis.x.analog_out" in numbers
    assert all(math.isfinite(value) for value in numbers.values()), numbers


def test_without_a_gain_the_following_error_is_none(zeroed: Any) -> None:
    """P30 = 0: Kv = 0, no position loop to lag behind (as in open loop, spec §5.2)."""
    zeroed.set("panel.mode", "MANUAL")
    zeroed.set("input.rapid", True)
    zeroed.set("input.jog_pos_x", True)
    assert zeroed.run_until(lambda device: device.model.axes["x"].moving, 5)
    assert zeroed.read("axis.x.following_error") == 0.0


def test_a_handwheel_of_no_increments_per_detent_moves_nothing(zeroed: Any) -> None:
    """P76 = 0: a detent is 0 increments (manual §2.2.3: P76 increments a detent)."""
    zeroed.set("panel.mode", "MANUAL")
    zeroed.set("input.handwheel_x", True)
    before = zeroed.read("axis.x.position")
    zeroed.set("handwheel.turn", 50)
    zeroed.advance(1)
    assert zeroed.read("axis.x.position") == before
