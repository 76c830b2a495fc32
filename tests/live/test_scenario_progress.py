"""`devsim scenario run` progress on stderr: a real-time scenario's steps as they happen (plain
lines without a terminal, a bar on one), and which file of several runs."""

from __future__ import annotations

import os
import pty
import subprocess
import sys
import time
from pathlib import Path

from .run import ROOT, Proc, env

SCENARIO = """\
name: progress
devices:
  - {name: x, kind: sers, config: {address: 1, boot_time: 0.05}}
steps:
  - set: {device: x, values: {input.I1: true}}
  - at: 4s
    expect_state: {device: x, name: input.I1, equals: true}
"""


def _files(tmp_path: Path, count: int = 1) -> list[str]:
    paths = []
    for number in range(count):
        path = tmp_path / f"s{number}.yaml"
        path.write_text(SCENARIO)
        paths.append(str(path))
    return paths


def test_realtime_steps_appear_as_they_happen(tmp_path: Path) -> None:
    run = Proc("scenario", "run", "--realtime", "--speed", "4", *_files(tmp_path))
    try:
        first = run.expect(lambda line: "set x" in line, err=True)
        seen_first = time.monotonic()
        assert first.strip().startswith("[") and first.endswith("ok")
        assert run.proc.poll() is None  # the timeline is still running
        second = run.expect(lambda line: "expect x.input.I1" in line, err=True)
        assert time.monotonic() - seen_first > 0.5  # 4 s of timeline at speed 4: about a second later
        assert "4.0" in second and second.endswith("PASS")
        assert run.proc.wait(timeout=30) == 0
        assert run.expect(lambda line: line.startswith("PASSED")).startswith("PASSED: 1 of 1 checks passed")
    finally:
        run.stop()


def test_several_files_show_which_one_runs(tmp_path: Path) -> None:
    paths = _files(tmp_path, 2)
    done = subprocess.run([sys.executable, "-m", "devsim", "scenario", "run", "--virtual", *paths], cwd=ROOT,
                          env=env(), capture_output=True, text=True, timeout=60, stdin=subprocess.DEVNULL)
    assert done.returncode == 0, done.stderr
    assert done.stderr.splitlines() == [f"[1/2] {paths[0]}", f"[2/2] {paths[1]}"]
    assert done.stdout.rstrip().endswith("2 of 2 scenarios passed")
    assert "[1/2]" not in done.stdout  # the reports on stdout stay as they were


def test_a_terminal_gets_a_bar(tmp_path: Path) -> None:
    master, slave = pty.openpty()
    proc = subprocess.Popen([sys.executable, "-m", "devsim", "scenario", "run", "--realtime", "--speed", "8",
                             *_files(tmp_path, 2)], cwd=ROOT, env=env(), stdin=subprocess.DEVNULL,
                            stdout=subprocess.PIPE, stderr=slave)
    os.close(slave)
    screen = b""
    try:
        while True:
            try:
                chunk = os.read(master, 4096)
            except OSError:  # EIO: the process closed its end
                break
            if not chunk:
                break
            screen += chunk
        assert proc.wait(timeout=30) == 0
    finally:
        os.close(master)
        if proc.poll() is None:
            proc.kill()
            proc.wait()
        assert proc.stdout is not None
        proc.stdout.close()
    text = screen.decode()
    assert "\r\x1b[K[" in text
    assert "step 0/2  file 1/2" in text and "file 2/2" in text
    assert "[" + "#" * 30 + "]" in text and "/4.00 s  step 2/2" in text  # the whole timeline, at the end
    assert "set x input.I1=True  ok" in text
