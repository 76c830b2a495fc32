"""Trace files and names from plant files stay where they belong."""

from __future__ import annotations

from pathlib import Path

import pytest

from devsim.core.config import ConfigError
from devsim.scenario.schema import load_plant
from devsim.transports.trace import Tracer


def test_a_trace_never_truncates_through_a_symlink(tmp_path: Path) -> None:
    precious = tmp_path / "precious.txt"
    precious.write_text("keep me\n")
    (tmp_path / "sers.trace").symlink_to(precious)
    with pytest.raises(OSError, match="refusing to write a trace through the symlink"):
        Tracer(tmp_path / "sers.trace")
    assert precious.read_text() == "keep me\n"


def test_a_plain_trace_file_is_truncated(tmp_path: Path) -> None:
    old = tmp_path / "x.trace"
    old.write_text("old run\n")
    Tracer(old).close()
    assert "old run" not in old.read_text()


@pytest.mark.parametrize("name", ["../escaped_bus", "a/b", ".hidden"])
def test_bus_names_cannot_leave_the_trace_dir(tmp_path: Path, name: str) -> None:
    plant = tmp_path / "plant.yaml"
    plant.write_text(
        "devices:\n  - {name: a, kind: sers, transport: {bus: b1}}\n"
        f"buses:\n  - name: '{name}'\n    transport: {{pty: {{}}}}\n"
    )
    with pytest.raises(ConfigError, match=r"plant.yaml:4: buses.1.name: String should match pattern"):
        load_plant(plant)
