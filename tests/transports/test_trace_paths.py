"""Trace files and names from plant files stay where they belong."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from devsim.cli import exits
from devsim.core.config import ConfigError
from devsim.scenario.schema import load_plant
from devsim.transports.trace import Tracer
from tests.support.process import ROOT, devsim_env


def test_a_trace_never_truncates_through_a_symlink(tmp_path: Path) -> None:
    precious = tmp_path / "precious.txt"
    precious.write_text("keep me\n")
    (tmp_path / "sers.trace").symlink_to(precious)
    with pytest.raises(OSError, match="refusing to write a trace through the symlink"):
        Tracer(tmp_path / "sers.trace")
    assert precious.read_text() == "keep me\n"


def test_devsim_run_says_which_file_it_cannot_trace_to(tmp_path: Path) -> None:
    """The one error line names the option and its trace, not only the port it was opening (status 6,
    SYSTEM)."""
    precious = tmp_path / "precious.txt"
    precious.write_text("keep me\n")
    (tmp_path / "sers.pcap").symlink_to(precious)
    done = subprocess.run([sys.executable, "-m", "devsim", "run", "sers", "--pty", "--trace", str(tmp_path / "sers.pcap")],
                          cwd=ROOT, env=devsim_env(), capture_output=True, text=True, timeout=60, stdin=subprocess.DEVNULL)
    assert done.returncode == exits.SYSTEM
    assert done.stderr.splitlines()[-1] == (f"Error: --trace: {tmp_path / 'sers.pcap'}: "
                                            "refusing to write a trace through the symlink")
    assert precious.read_text() == "keep me\n"


def test_devsim_run_says_which_link_it_cannot_make(tmp_path: Path) -> None:
    """A --link in a directory that is not there: the error names the link (it named a temporary
    file beside it, ``.tty.owner.PID.tmp``)."""
    link = tmp_path / "missing" / "ttySERS"
    done = subprocess.run([sys.executable, "-m", "devsim", "run", "sers", "--link", str(link)],
                          cwd=ROOT, env=devsim_env(), capture_output=True, text=True, timeout=60, stdin=subprocess.DEVNULL)
    assert done.returncode == exits.SYSTEM
    assert done.stderr.splitlines()[-1] == (f"Error: cannot open the pty port: [Errno 2] cannot make the link {link}: "
                                            "No such file or directory")
    assert not (tmp_path / "missing").exists()


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
