"""Fixtures the facade tests share."""

from __future__ import annotations

from collections.abc import Iterator

import pytest

from tests.facades.test_cia402 import Drive


@pytest.fixture
def drive() -> Iterator[Drive]:
    """A PCD4.H3 as CANopen node 3 on a virtual CAN bus, canopen as the master (closed after the test)."""
    d = Drive()
    try:
        yield d
    finally:
        d.close()
