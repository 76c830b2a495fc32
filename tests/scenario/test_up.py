"""`devsim up PLANT.yaml`: every device of a plant served, every port printed, clean Ctrl-C."""

from __future__ import annotations

import re
import signal
import subprocess
import sys
from pathlib import Path

import pytest
import serial

from devsim.cli import exits
from tests.support.process import DevsimProcess, stop

PLANT = """\
devices:
  - name: left
    kind: sers
    config: {address: 1, boot_time: 0}
    transport: {bus: line}
  - name: right
    kind: sers
    config: {address: 2, boot_time: 0}
    transport: {bus: line}
  - name: lift
    kind: sers
    config: {address: 5, boot_time: 0}
    transport: {tcp: {port: 0}}
buses:
  - name: line
"""


def test_devsim_up_serves_the_plant(tmp_path: Path) -> None:
    plant = tmp_path / "plant.yaml"
    plant.write_text(PLANT)
    proc = subprocess.Popen(
        [sys.executable, "-m", "devsim", "up", str(plant)],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )
    try:
        assert proc.stdout is not None
        rows = [proc.stdout.readline().strip() for _ in range(2)]
        assert re.fullmatch(r"lift: tcp socket://127\.0\.0\.1:\d+", rows[0]), rows
        assert re.fullmatch(r"line \(left, right\): pty /dev/pts/\d+", rows[1]), rows
        with serial.Serial(rows[1].split()[-1], 9600, timeout=2) as port:
            port.write(b"#2 P1050?\r")
            assert port.read_until(b"ok1\n\r") == b"#2 P1050?\rP1050=2\n\r\nok1\n\r"
        with serial.serial_for_url(rows[0].split()[-1], timeout=2) as port:
            port.write(b"#5 P1050?\r")
            assert port.read_until(b"ok1\n\r") == b"#5 P1050?\rP1050=5\n\r\nok1\n\r"
    finally:
        proc.send_signal(signal.SIGINT)
        _out, err = proc.communicate(timeout=10)
    assert proc.returncode == 0, err
    assert "Traceback" not in err


def test_devsim_up_reports_a_bad_plant_file(tmp_path: Path) -> None:
    plant = tmp_path / "plant.yaml"
    plant.write_text(PLANT.replace("address: 5", "address: 500"))
    done = subprocess.run([sys.executable, "-m", "devsim", "up", str(plant)], capture_output=True, text=True)
    assert done.returncode != 0
    assert done.stderr.strip() == f"Error: {plant}:12: devices.3.config.address: Input should be less than or equal to 127"


@pytest.mark.parametrize("memory", ['{"devsim-kind": "gms96"}', '{"params": {"41": NaN}}'])
def test_up_and_scenario_run_refuse_a_state_file_they_cannot_use_in_one_line(tmp_path: Path, memory: str) -> None:
    """(Fuzzed: a state file of the wrong shape or holding NaN ended `devsim up` and `devsim
    scenario run` in a traceback, where `devsim run` says one line.)  The file stays as it was.
    (The fuzzed shape was a program of "x": a SERS now starts on it without a valid program, as on
    any program it could not have written; a file of another kind is refused as that one was.)"""
    from tests.support.process import ROOT, devsim_env

    state = tmp_path / "state"
    state.mkdir()
    (state / "x.nvram.json").write_text(memory)
    plant = tmp_path / "plant.yaml"
    plant.write_text("devices:\n  - {name: x, kind: sers}\n")
    scenario = tmp_path / "scenario.yaml"
    scenario.write_text("devices:\n  - {name: x, kind: sers}\nsteps:\n  - wait: 1s\n")
    for command, said in ((["up", str(plant), "--virtual", "--no-control", "-q"], "Error: cannot start the plant: "),
                          (["scenario", "run", str(scenario)], f"Error: {scenario}: cannot run the scenario: ")):
        done = subprocess.run([sys.executable, "-m", "devsim", *command, "--state-dir", str(state)], cwd=ROOT,
                              env=devsim_env(), capture_output=True, text=True, timeout=60)
        assert done.returncode == exits.SYSTEM, done.stderr
        assert done.stderr.startswith(said + str(state / "x.nvram.json")) and done.stderr.count("\n") == 1, done.stderr
    assert (state / "x.nvram.json").read_text() == memory


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGHUP, signal.SIGINT], ids=["TERM", "HUP", "INT"])
def test_a_scenario_run_stopped_by_a_signal_says_so_and_cleans_up(tmp_path: Path, sig: signal.Signals) -> None:
    """SIGTERM and SIGHUP ended the process at once (status 143 or 129, no word, the pty link
    left behind); Ctrl-C left a 'Task was destroyed but it is pending!' dump."""
    link = tmp_path / "ttyX"
    scenario = tmp_path / "long.yaml"
    scenario.write_text(f"devices:\n  - {{name: x, kind: sers, transport: {{pty: {{link: {link}}}}}}}\n"
                        "time: realtime\nsteps:\n  - wait: 60s\n")
    sim = DevsimProcess("scenario", "run", str(scenario))
    sim.next_match(sim.out, lambda line: line == f"x: pty {link}", 30, "the port line")
    assert link.is_symlink()
    assert stop(sim.proc, sig, 15) == exits.INTERRUPTED
    err = sim.rest_of_err(timeout=5)
    assert err == ["devsim: scenario run interrupted"]
    assert not link.exists() and not link.is_symlink()
