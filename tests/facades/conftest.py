"""Fixtures the facade tests share.

canopen's SDO client gives a server 0.3 s to answer (then asks once more and fails): a bound
meant for a real bus, which a simulator in a test process on a loaded two-core machine can miss
(the likely cause of a CiA 402 test failing once under ``pytest -n 3`` with the whole suite, which
passed 40 of 40 alone; its message was not kept).  The tests' masters wait up to 5 s; nothing here
tests the SDO timeout itself.
"""

from __future__ import annotations

from collections.abc import Iterator

import pytest
from canopen.sdo.client import SdoClient

from tests.facades.test_cia402 import Drive

SdoClient.RESPONSE_TIMEOUT = 5.0  # (see above; a class attribute each client reads when it waits)


@pytest.fixture
def drive() -> Iterator[Drive]:
    """A PCD4.H3 as CANopen node 3 on a virtual CAN bus, canopen as the master (closed after the test)."""
    d = Drive()
    try:
        yield d
    finally:
        d.close()
