"""The PCD's media by address through the control socket (``R.<n>``, ``F.<n>``, ``I.<n>``,
``O.<n>``; manual §9.5): the address is ASCII digits, and what a name writes is what S-Bus reads
on the real pty."""

from __future__ import annotations

from collections.abc import Iterator

import pytest

from devsim.runtime.client import ControlClient, ControlError
from tests.pcd4h3.helpers import Station
from tests.support.control import control_client


@pytest.fixture
def ctl(pcd: Station) -> Iterator[ControlClient]:
    """A client on a control socket served for the ``pcd`` fixture's runtime."""
    with control_client(pcd.sim.runtime) as client:
        yield client


@pytest.mark.parametrize("name", ["R.\u0663\u0660\u0662", "R.\uff13\uff10\uff12", "F.\u0665", "I.\u0669", "O.\u0661"])
def test_a_medium_address_is_ascii_digits(pcd: Station, ctl: ControlClient, name: str) -> None:
    """Without re.ASCII the family's \\d took the digits of other scripts, which int() reads: the
    Arabic-Indic 'R.٣٠٢' and the full-width 'R.３０２' were register 302, 'F.٥' flag 5."""
    device = pcd.sim.name
    ctl.set(device, "R.302", 7)
    assert pcd.read_registers(302) == [7]
    with pytest.raises(ControlError, match="UnknownName"):
        ctl.read(device, name)
    with pytest.raises(ControlError, match="UnknownName"):
        ctl.set(device, name, 1)
    assert pcd.read_registers(302) == [7]  # S-Bus on the pty: unchanged
    assert pcd.read_flags(5) == [0]
