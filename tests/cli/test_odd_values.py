"""Odd values of ``devsim run`` / ``up`` options: each is one ``Error:`` line naming the option,
exit status 2, no traceback, nothing served (real subprocesses: the quick command line of
:mod:`devsim.cli.quick` and click both read them)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest
from click.testing import CliRunner

from devsim.cli import cli, exits
from tests.support.process import ROOT, devsim_env

PLANT = str(ROOT / "scenarios/sers/absolute_positioning.yaml")


@pytest.mark.parametrize(
    ("args", "expected"),
    [
        # (click's FloatRange(min=0) takes NaN, and no host was ever idle longer than NaN: "never", unsaid)
        (["run", "sers", "--idle-drop", "nan"], "--idle-drop: must be a number of seconds, not nan"),
        (["run", "sers", "--idle-drop=nan", "--no-control"], "--idle-drop: must be a number of seconds, not nan"),
        (["up", PLANT, "--idle-drop", "nan"], "--idle-drop: must be a number of seconds, not nan"),
        # (ascii_digits then int(): past 4300 digits int() raised, a ValueError traceback)
        (["run", "sers", "--canopen", "9" * 5000], "--canopen: expected NODE"),
        # (the same ValueError said without the option: 'Exceeds the limit (4300 digits) ...')
        (["run", "sers", "--opcua", "9" * 5000], "--opcua: expected [HOST:]PORT"),
        # (int() read the Arabic-Indic digit: the device was served on TCP port 3)
        (["run", "sers", "--tcp", "\u0663"], "--tcp: expected [HOST:]PORT"),
        (["run", "sers", "--rfc2217", "-0"], "--rfc2217: expected [HOST:]PORT"),
        # (parse_address's int() read '٣': the control API or the page was served on port 3)
        (["run", "sers", "--control", "\u0663"], "--control: '\u0663': expected unix:/path/to.sock or [HOST:]PORT"),
        (["scenario", "run", "--virtual", "--control", "\u0663", PLANT],
         "--control: '\u0663': expected unix:/path/to.sock or [HOST:]PORT"),
        (["web", "--listen", "\u0663"], "--listen: '\u0663': expected"),
        (["up", PLANT, "--control", "9" * 5000], "--control: '99"),
        # (inf passed 'rate > 0' / 'period > 0': the facade never sampled the points)
        (["run", "sers", "--mqtt", "mqtt://127.0.0.1:1", "--mqtt-rate", "inf"], "--mqtt-rate: must be a positive, finite"),
        (["run", "sers", "--opcua", "0", "--opcua-period", "1e309"], "--opcua-period: must be positive and finite"),
        # (said as '--mqtt: an MQTT plant name is one topic level ...')
        (["run", "sers", "--mqtt", "mqtt://127.0.0.1:1", "--mqtt-plant", "a/b"], "--mqtt-plant: an MQTT plant name"),
        # (float() and int() read the digits of every script: ran at speed 3, with three workers ...)
        (["run", "sers", "--speed", "\u0663"], "'--speed': '\u0663' is not a number in ASCII digits"),
        (["run", "sers", "--idle-drop", "\u0663"], "'--idle-drop': '\u0663' is not a number in ASCII digits"),
        (["up", PLANT, "--workers", "\u0663"], "'--workers': '\u0663' is not a number in ASCII digits"),
        (["ctl", "--control", "unix:/nonexistent/ctl.sock", "telegrams", "sers", "--count", "\u0663"],
         "'--count': '\u0663' is not a number in ASCII digits"),
        (["ctl", "--control", "unix:/nonexistent/ctl.sock", "line-fault", "sers", "delay", "on", "--delay", "\u0663"],
         "'--delay': '\u0663' is not a number in ASCII digits"),
    ],
)
def test_an_odd_option_value_is_one_error_line(args: list[str], expected: str) -> None:
    done = subprocess.run([sys.executable, "-m", "devsim", *args], cwd=ROOT, env=devsim_env(), capture_output=True,
                          text=True, timeout=60, stdin=subprocess.DEVNULL)
    assert done.returncode == 2, done.stderr
    assert done.stdout == ""
    assert done.stderr.count("\n") == 1, done.stderr
    assert done.stderr.startswith("Error: ") and expected in done.stderr


@pytest.mark.parametrize(
    ("args", "status", "expected"),
    [
        # (mkdir(parents=True) at start: 'cannot create the devices: [Errno 17] File exists', no option named)
        (["run", "sers", "--no-control", "--state-dir", "{file}"], 6, "--state-dir: {file}: not a directory"),
        (["run", "sers", "--no-control", "--state-dir", "{file}/sub"], 6,
         "--state-dir: {file}/sub: {file} is not a directory"),
        (["up", PLANT, "--trace-dir", "{file}"], 6, "--trace-dir: {file}: not a directory"),
        # (scenario run named the scenario file: 'cannot run the scenario: [Errno 17] File exists')
        (["scenario", "run", "--virtual", "--plot", "{file}", PLANT], 6, "--plot: {file}: not a directory"),
        (["scenario", "run", "--virtual", "--state-dir", "{file}", PLANT], 6, "--state-dir: {file}: not a directory"),
        # (an empty one was the current directory)
        (["scenario", "run", "--virtual", "--trace-dir", "", PLANT], 2, "--trace-dir: needs a directory"),
    ],
)
def test_a_directory_option_naming_a_file_is_one_error_line(args: list[str], status: int, expected: str,
                                                            tmp_path: Path) -> None:
    """A file in the way is a file that cannot be written (status 6, docs/cli.md), said naming the option."""
    file = tmp_path / "a file"
    file.write_text("")
    args = [arg.replace("{file}", str(file)) for arg in args]
    done = subprocess.run([sys.executable, "-m", "devsim", *args], cwd=tmp_path, env=devsim_env(), capture_output=True,
                          text=True, timeout=60, stdin=subprocess.DEVNULL)
    assert done.returncode == status, done.stderr
    assert done.stderr.count("\n") == 1, done.stderr
    assert done.stderr.startswith("Error: ") and expected.replace("{file}", str(file)) in done.stderr


@pytest.mark.parametrize(
    ("args", "expected"),
    [
        # (each named only what it was doing: 'cannot open the pty port with its trace {dir}: [Errno 21] ...',
        # 'cannot write the motion log ...', 'cannot start the plant: ...', '{scenario}: cannot run the scenario: ...')
        (["run", "sers", "--no-control", "--pty", "--trace", "{dir}"], "--trace: {dir}: Is a directory"),
        (["run", "sers", "--no-control", "--motion-log", "{dir}/missing/m.csv"],
         "--motion-log: {dir}/missing/m.csv: No such file or directory"),
        (["up", PLANT, "--no-control", "--motion-log", "/proc/devsim-m.csv"],
         "--motion-log: /proc/devsim-m.csv: No such file or directory"),
        (["up", PLANT, "--no-control", "--trace-dir", "/proc/devsim-traces"],
         "--trace-dir: /proc/devsim-traces: No such file or directory"),
        (["scenario", "run", "--virtual", "--motion-log", "{dir}", PLANT], "--motion-log: {dir}: Is a directory"),
        # (a usage error, status 2: "--motion-log: no directory '{dir}/missing'", where run and up give 6)
        (["scenario", "run", "--virtual", "--motion-log", "{dir}/missing/m.csv", PLANT],
         "--motion-log: {dir}/missing/m.csv: No such file or directory"),
        # ('{scenario}: cannot run the scenario: [Errno 2] No such file or directory: ...', no option named)
        (["scenario", "run", "--virtual", "--trace-dir", "/proc/devsim-traces", PLANT],
         "--trace-dir: /proc/devsim-traces: No such file or directory"),
        (["scenario", "run", "--virtual", "--state-dir", "/proc/devsim-state", PLANT],
         "--state-dir: /proc/devsim-state: No such file or directory"),
        (["scenario", "run", "--virtual", "--plot", "/proc/devsim-plots", PLANT],
         "--plot: /proc/devsim-plots: No such file or directory"),
    ],
)
def test_a_file_option_that_cannot_be_written_is_one_error_line(args: list[str], expected: str, tmp_path: Path) -> None:
    """A file that cannot be made (a directory, a missing directory, a file in /proc) is said naming
    the option, the file and why, in one line with status 6 (SYSTEM), as a directory option's."""
    args = [arg.replace("{dir}", str(tmp_path)) for arg in args]
    done = subprocess.run([sys.executable, "-m", "devsim", *args], cwd=tmp_path, env=devsim_env(), capture_output=True,
                          text=True, timeout=60, stdin=subprocess.DEVNULL)
    assert done.returncode == exits.SYSTEM, done.stderr
    assert done.stdout == ""
    assert done.stderr.splitlines()[-1] == "Error: " + expected.replace("{dir}", str(tmp_path)), done.stderr


@pytest.mark.parametrize(
    ("period", "expected"),
    [
        ("nan", "'--period': nan is not a finite number"),
        ("inf", "'--period': inf is not a finite number"),
        ("1e309", "'--period': inf is not a finite number"),
        ("-1", "'--period': -1.0 is not in the range x>=0.001"),
        ("0", "'--period': 0.0 is not in the range x>=0.001"),
        ("0.0001", "'--period': 0.0001 is not in the range x>=0.001"),
        ("\u0663", "'--period': '\u0663' is not a number in ASCII digits"),
    ],
)
def test_ctl_watch_names_its_period_option(period: str, expected: str) -> None:
    """``devsim ctl watch --period`` is checked as the option it is (in process: click reads it before
    any connection; the address leads nowhere).  Before, click's FLOAT took nan, inf, 0 and -1 and
    the control server refused them in its own words: "BadRequest: 'period' must be a number of
    seconds from 0.001 on", status 4 (REFUSED) for a command-line mistake."""
    result = CliRunner().invoke(cli, ["ctl", "--control", "unix:/nonexistent/ctl.sock", "watch", "sers",
                                      "--period", period], prog_name="devsim")
    assert result.exit_code == exits.USAGE, result.output
    assert result.stdout == ""
    assert result.stderr.count("\n") == 1, result.stderr
    assert result.stderr.startswith("Error: ") and expected in result.stderr
