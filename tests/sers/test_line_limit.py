"""The SERS's line limit through the real pty (§4.1: at most 60 characters in a line, ``#`` and
address included; §4.8.3.1: beyond it, P12 1024 "RS232 Pufferüberlauf", errno 124): a line of 60
characters is carried out in full, one of 61 is cut and reported."""

from __future__ import annotations

import pytest

from devsim.devices.sers.codec import MAX_LINE
from tests.sers.conftest import Plant

OVERFLOW = "*RS232 Pufferüberlauf".encode("latin-1")


def _line(length: int) -> str:
    """``#V=1 V=1 ... W=NN`` of exactly ``length`` characters, the last statement W=nn."""
    body = "V=1 " * ((length - 1 - 4) // 4)
    pad = length - 1 - len(body) - 2
    return "#" + body + "W=" + "1" * pad


@pytest.mark.manual("§4.1", "at most 60 characters in a line")
def test_a_line_of_60_characters_is_carried_out_in_full(sers: Plant) -> None:
    line = _line(MAX_LINE)
    assert len(line) == 60 == MAX_LINE
    reply = sers.host.ask(line + "\r")
    assert OVERFLOW not in reply
    assert not sers.read("P12") & 1024
    assert sers.read("param.W") == int(line.rpartition("W=")[2])  # the last statement, whole


@pytest.mark.manual("§4.8.3.1", "P12 1024 RS232 buffer overflow; errno 124")
def test_a_line_of_61_characters_is_reported_as_an_overflow(sers: Plant) -> None:
    line = _line(MAX_LINE + 1)
    assert len(line) == 61
    before = sers.read("param.W")
    reply = sers.host.ask(line + "\r")
    assert reply.endswith(b"\n" + OVERFLOW + b"\n\r")  # errno 124, and no other error before it
    assert sers.read("P12") & 1024 and sers.read("param.P1137") == 124
    assert sers.read("param.W") == before  # the statement the limit cut is not carried out with a cut value


@pytest.mark.manual("§4.1", "several commands in a line, 'jedoch maximal 60 Zeichen in einer Zeile'")
def test_a_statement_cut_by_the_limit_is_reported_as_the_overflow_not_as_its_syntax(sers: Plant) -> None:
    line = "#1 " + "V=1 " * 14 + "V=2"  # 62 characters: the limit falls on the last V
    reply = sers.host.ask(line + "\r")
    assert reply.endswith(b"\n" + OVERFLOW + b"\n\r") and b"erwartet" not in reply  # not '*= oder ? erwartet'
    assert sers.read("param.P1137") == 124
    assert sers.read("param.V") == 1  # the statements within the 60 characters ran
