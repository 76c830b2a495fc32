"""Fixtures of the PCD4.H3 tests: ``make(config)`` gives a :class:`~tests.pcd4h3.helpers.Station`
on a real pty (virtual time), ``pcd`` one with the manual's example installation."""

from __future__ import annotations

from collections.abc import Callable, Iterator
from typing import Any

import pytest

from tests.pcd4h3.helpers import EXAMPLE, Station


@pytest.fixture
def make(devsim_device: Any) -> Iterator[Callable[..., Station]]:
    opened: list[Station] = []

    def factory(config: dict | None = None) -> Station:
        merged = {**EXAMPLE, **(config or {})}
        opened.append(Station(devsim_device("pcd4h3", merged)))
        return opened[-1]

    yield factory
    for station in opened:
        station.close()


@pytest.fixture
def pcd(make: Callable[..., Station]) -> Station:
    return make()
