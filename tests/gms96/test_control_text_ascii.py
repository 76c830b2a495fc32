"""A CNC program set through the control socket (``program.<n>``, manual §2.5): its commands as
the manual writes them, with only the control blanks (space, TAB, CR; core.points.strip_blanks)
around and inside them."""

from __future__ import annotations

import tempfile
from collections.abc import Iterator
from typing import Any

import pytest

from devsim.runtime.client import ControlClient, ControlError
from devsim.runtime.control import ControlServer


@pytest.fixture
def ctl(devsim_device: Any) -> Iterator[tuple[ControlClient, str]]:
    card = devsim_device("gms96", {})
    with tempfile.TemporaryDirectory(prefix="dsc") as path:  # (Unix socket paths are short)
        server = ControlServer(card.runtime, f"unix:{path}/ctl.sock")
        bound = server.start_sync()
        try:
            with ControlClient(str(bound)) as client:
                yield client, card.name
        finally:
            server.close_sync()


@pytest.mark.parametrize("program", ["A\x0b1000", "\x0cA1000", "A1000\x0b", "p10;\x0c16;2",
                                     "A1000\n\x1c\nA2000", "A1000\n\xa0\nA2000", "A1000\n\u3000\nA2000",
                                     "A1000\n\x85\nA2000"])
def test_a_program_has_only_the_control_blanks(ctl: tuple[ControlClient, str], program: str) -> None:
    """The command pattern's \\s (re.ASCII) took VT and FF as blanks ('A\\x0b1000' stored A1000), and a
    line of FS, NBSP, U+3000 or NEL was skipped as empty (str.strip) where it is no command."""
    client, card = ctl
    with pytest.raises(ControlError, match="a command is a letter|not a command of a CNC program"):
        client.set(card, "program.1", program)
    assert client.read(card, "program.1") == []
    client.set(card, "program.1", " A1000 \r\n\tp10 ; 16;2\n\n")
    assert client.read(card, "program.1") == ["A1000", "p10;16;2"]
