"""A CNC program set through the control socket (``program.<n>``, manual §2.5): its commands as
the manual writes them, with only the control blanks (space, TAB, CR; core.points.strip_blanks)
around and inside them."""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import pytest

from devsim.runtime.client import ControlClient, ControlError
from tests.support.control import control_client


@pytest.fixture
def ctl(devsim_device: Any) -> Iterator[tuple[ControlClient, str]]:
    card = devsim_device("gms96", {})
    with control_client(card.runtime) as client:
        yield client, card.name


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


@pytest.mark.parametrize("name", ["marker.M7.0\x0b", "marker.\x0cM7.0", "marker.m7.0\x0c",
                                  "marker.M7.0\n"])
def test_a_marker_bit_is_named_with_only_space_or_tab(ctl: tuple[ControlClient, str], name: str) -> None:
    """image.parse_bit's \\s took VT and FF around the parts of a bit address (and its $ a final LF):
    'marker.M7.0\\x0b' was the marker bit M7.0, 'input.E2.1\\x0b' was refused."""
    client, card = ctl
    with pytest.raises(ControlError, match="UnknownName"):
        client.read(card, name)
    with pytest.raises(ControlError, match="UnknownName"):
        client.set(card, name, True)
    assert client.read(card, "marker.M7.0") is False and client.read(card, "marker.m 7.0") is False
