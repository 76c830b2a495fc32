"""The longest AS511 parameter block through the real PG pty (spec ip247.md §3.6.5: a parameter
block longer than 1100 bytes after DLE removal gets DLE NAK at the next acknowledgement point, the
transaction ends, nothing is executed): 1100 bytes are a request the module answers; 1101 are
refused, and the module answers the next transaction."""

from __future__ import annotations

import pytest

from devsim.devices.ip247.client import As511Error
from devsim.devices.ip247.pg_profile import MAX_PARAMETERS
from tests.ip247.helpers import Module


def _write(size: int) -> bytes:
    """A WRITE_REC of a program record (page 4, BA22, program 7) of ``size`` parameter bytes, full
    of 10H (each sent doubled: the limit counts bytes after DLE removal)."""
    return bytes((4, 22, 7, 0)) + b"\x10" * (size - 4)


def test_a_block_of_1100_bytes_is_answered(mod: Module) -> None:
    assert MAX_PARAMETERS == 1100
    answer = mod.call(0x63, _write(MAX_PARAMETERS))
    assert answer[0] == 0x00 and answer[1:3] == bytes((4, 22))  # taken; the record's own error follows
    assert answer[4] != 0  # (a record of 10H words is no program: an error, not a refusal)


def test_a_block_of_1101_bytes_is_refused_with_dle_nak(mod: Module) -> None:
    with pytest.raises(As511Error, match="DLE NAK"):
        mod.call(0x63, _write(MAX_PARAMETERS + 1))
    assert mod.client.read_record(4, 65)[0] == 0x00  # the next transaction is served
    assert mod.client.read_record(4, 65)[8:] == b""  # nothing stored
