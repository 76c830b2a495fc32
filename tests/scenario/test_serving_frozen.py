"""`devsim run` and `devsim up` keep what they built before serving out of the garbage
collector's scans (``gc.freeze``): unfrozen, a full collection in a 1,000-device worker took
about 70 ms, during which every device of the worker missed its poll (benchmarks/scale.py)."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
from pathlib import Path

import pytest

from tests.support.process import ROOT, collect_lines, devsim_env, next_match, stop

# Loaded by the child's interpreter at start (a sitecustomize on its PYTHONPATH): at exit it
# says how many objects were frozen.
REPORTER = """
import atexit, gc, sys
atexit.register(lambda: print(f"frozen objects: {gc.get_freeze_count()}", file=sys.stderr, flush=True))
"""


@pytest.mark.parametrize("command", ["run", "up"])
def test_the_objects_built_before_serving_are_frozen(command: str, tmp_path: Path) -> None:
    (tmp_path / "sitecustomize.py").write_text(REPORTER)
    plant = tmp_path / "plant.yaml"
    plant.write_text("devices:\n  - {name: d1, kind: sers, transport: {tcp: {port: 0}}}\n")
    args = ["run", "sers", "--tcp", "0"] if command == "run" else ["up", str(plant)]
    env = devsim_env()
    env["PYTHONPATH"] = os.pathsep.join((str(tmp_path), env["PYTHONPATH"]))
    proc = subprocess.Popen([sys.executable, "-m", "devsim", *args], cwd=ROOT, env=env, stdin=subprocess.DEVNULL,
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    try:
        err = collect_lines(proc.stderr)
        next_match(err, lambda line: "Ctrl-C to stop" in line, 60, "the serving line")
    finally:
        assert stop(proc, signal.SIGINT, 15) in (0, 130)
    report = next_match(err, lambda line: line.startswith("frozen objects:"), 10, "the exit report")
    assert int(report.split(":")[1]) > 10_000  # the modules, tables and the device
