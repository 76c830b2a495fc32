"""Tests that need a program outside Python: skipped where it is missing, with one summary line at
the end of the run naming it and the command that installs it; a failure under CI=true.

Each case runs a small pytest in a subprocess with this suite's conftest, PATH set to a directory
of our choosing (empty: no tshark; with an executable ``tshark`` in it: found)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

from tests.support.process import ROOT

TEST = '''
from tests.support.programs import needs_program


def test_decodes_with_tshark():
    path = needs_program("tshark")
    assert path.endswith("/tshark")


def test_runs_a_node_client():
    needs_program("node", "npm")


def test_needs_nothing():
    pass
'''


def run_pytest(tmp_path: Path, path: Path, ci: str | None) -> subprocess.CompletedProcess[str]:
    (tmp_path / "test_inner.py").write_text(TEST)
    environ = {key: value for key, value in os.environ.items() if key not in ("CI", "PYTEST_ADDOPTS")}
    environ.update(PATH=str(path), PYTHONPATH=str(ROOT))
    if ci is not None:
        environ["CI"] = ci
    return subprocess.run([sys.executable, "-m", "pytest", "-p", "tests.conftest", "-p", "no:cacheprovider",
                           "-q", "test_inner.py"], cwd=tmp_path, env=environ, capture_output=True, text=True,
                          timeout=120)


def empty_path(tmp_path: Path) -> Path:
    path = tmp_path / "bin"
    path.mkdir()
    return path


def test_a_missing_program_skips_with_one_summary_line(tmp_path: Path) -> None:
    done = run_pytest(tmp_path, empty_path(tmp_path), ci=None)
    assert done.returncode == 0, done.stdout + done.stderr
    lines = done.stdout.splitlines()
    summary = [line for line in lines if "not installed here" in line]
    assert summary == ["2 tests skipped: tshark, node, npm not installed here"
                       " (install: sudo apt-get install tshark nodejs npm;"
                       " CI=true makes these skips failures)"], done.stdout
    assert "1 passed, 2 skipped" in lines[-1]
    assert lines.index(summary[0]) >= len(lines) - 3, done.stdout  # at the end of the run


def test_under_ci_a_missing_program_is_a_failure(tmp_path: Path) -> None:
    done = run_pytest(tmp_path, empty_path(tmp_path), ci="true")
    assert done.returncode == 1, done.stdout + done.stderr
    assert "1 passed" in done.stdout and "2 failed" in done.stdout
    assert "not installed here: tshark (CI=true: a missing program is a failure; sudo apt-get install tshark)" \
        in done.stdout
    assert "tests skipped" not in done.stdout


def test_a_program_on_the_path_is_found(tmp_path: Path) -> None:
    path = empty_path(tmp_path)
    for name in ("tshark", "node", "npm"):
        (path / name).write_text("#!/bin/sh\n")
        (path / name).chmod(0o755)
    done = run_pytest(tmp_path, path, ci="true")
    assert done.returncode == 0, done.stdout + done.stderr
    assert "3 passed" in done.stdout and "not installed" not in done.stdout
