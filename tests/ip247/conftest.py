"""Fixtures of the IP247 tests: ``make(config)`` gives a :class:`~tests.ip247.helpers.Module` on a
real pty (virtual time), ``mod`` one with the default configuration."""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import pytest

from tests.ip247.helpers import Make, Module


@pytest.fixture
def make(devsim_device: Any) -> Iterator[Make]:
    opened: list[Module] = []

    def factory(config: dict | None = None) -> Module:
        sim = devsim_device("ip247", {"sys_id": {"module": 11, "slot": 1}, **(config or {})})
        opened.append(Module(sim))
        return opened[-1]

    yield factory
    for module in opened:
        module.port.close()


@pytest.fixture
def mod(make: Make) -> Module:
    return make()


