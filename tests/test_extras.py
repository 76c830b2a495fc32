"""A missing extra names the install command that fits where devsim runs: the checkout's own
extra (``pip install '.[plot]'``) inside a source tree, the distribution's from an installed copy."""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from devsim.cli import exits
from tests.support.process import ROOT, devsim_env


@pytest.fixture
def no_matplotlib(tmp_path: Path) -> Path:
    """A directory that, first on the import path, makes ``import matplotlib`` fail."""
    shadow = tmp_path / "shadow" / "matplotlib"
    shadow.mkdir(parents=True)
    (shadow / "__init__.py").write_text("raise ImportError('matplotlib hidden by the test')\n")
    return shadow.parent


def plot_hint(path: list[Path], cwd: Path, tmp_path: Path) -> str:
    """stderr of ``devsim scenario run … --plot DIR`` run with ``path`` as PYTHONPATH."""
    environ = devsim_env()
    environ["PYTHONPATH"] = ":".join(map(str, path))
    done = subprocess.run([sys.executable, "-m", "devsim", "scenario", "run", str(ROOT / "scenarios" / "x.yaml"),
                           "--plot", str(tmp_path / "plots")], cwd=cwd, env=environ, capture_output=True, text=True,
                          timeout=60)
    assert done.returncode == exits.SYSTEM, done.stderr  # a missing extra
    assert not (tmp_path / "plots").exists()
    return done.stderr.strip()


def test_inside_the_checkout_the_hint_installs_the_checkouts_extra(no_matplotlib: Path, tmp_path: Path) -> None:
    assert plot_hint([no_matplotlib, ROOT], ROOT, tmp_path) == (
        "Error: devsim plot needs matplotlib: pip install '.[plot]'")
    # elsewhere, the checkout's path
    assert plot_hint([no_matplotlib, ROOT], tmp_path, tmp_path) == (
        f"Error: devsim plot needs matplotlib: pip install '{ROOT}[plot]'")


def test_an_installed_copy_names_the_distribution(no_matplotlib: Path, tmp_path: Path) -> None:
    site = tmp_path / "site"
    shutil.copytree(ROOT / "devsim", site / "devsim", ignore=shutil.ignore_patterns("__pycache__"))
    assert plot_hint([no_matplotlib, site], tmp_path, tmp_path) == (
        "Error: devsim plot needs matplotlib: pip install 'devsim-motion[plot]'")


def test_a_copy_installed_from_a_checkout_names_the_checkout(no_matplotlib: Path, tmp_path: Path) -> None:
    """``pip install .`` copies the package out of the checkout and records where it came from
    (direct_url.json): the checkout's own extra is still the one to install."""
    site = tmp_path / "site"
    shutil.copytree(ROOT / "devsim", site / "devsim", ignore=shutil.ignore_patterns("__pycache__"))
    info = site / "devsim_motion-0.1.0.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: devsim-motion\nVersion: 0.1.0\n")
    (info / "direct_url.json").write_text(f'{{"url": "{ROOT.as_uri()}", "dir_info": {{}}}}')
    assert plot_hint([no_matplotlib, site], tmp_path, tmp_path) == (
        f"Error: devsim plot needs matplotlib: pip install '{ROOT}[plot]'")
    (info / "direct_url.json").unlink()  # installed from an index: no record of a source
    assert plot_hint([no_matplotlib, site], tmp_path, tmp_path) == (
        "Error: devsim plot needs matplotlib: pip install 'devsim-motion[plot]'")
