"""Fixtures for the transport tests."""

from __future__ import annotations

import pytest

from tests.transports.transport_helpers import Recorder


@pytest.fixture
def recorder() -> Recorder:
    return Recorder()


@pytest.fixture
def echo() -> Recorder:
    return Recorder(echo=True)
