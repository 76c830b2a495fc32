"""A serving process whose output nobody reads any more (a supervisor that closed the pipe after
the port line, ``devsim run sers --pty | head -1``) goes on serving as if it were read: its
devices power on completely, its log lines go nowhere, and it ends with status 0.

Before, the ``sers: ready`` line raised ``BrokenPipeError`` in the middle of the drive's power-on
(the model announces ``ready`` to the line's printer), so the rest of it did not run: no
autostart (§3.1.2), no jog function at power-on (§4.8.6.3), and ``ctl advance`` answered
``BrokenPipeError``.

The terminal that started a simulator closing (SIGHUP) stops it as Ctrl-C does, cleanly; under
``nohup`` it goes on."""

from __future__ import annotations

import asyncio
import fcntl
import os
import re
import select
import signal
import struct
import subprocess
import sys
import termios
import threading
import time
from pathlib import Path
from typing import TextIO

import pytest
import serial

from devsim.core.backlog import CAP
from tests.support.process import ROOT, collect_lines, devsim_env, next_match, stop, wait_until
from tests.test_motion_log import rows_of


def ctl(address: str, *args: str) -> str:
    done = subprocess.run([sys.executable, "-m", "devsim", "ctl", "--control", address, *args], cwd=ROOT,
                          env=devsim_env(), capture_output=True, text=True, timeout=60, stdin=subprocess.DEVNULL)
    assert done.returncode == 0, done.stderr
    return done.stdout


COMMANDS = {
    "run": lambda config: ["run", "sers", "--pty", "--config", str(config)],
    "up": lambda config: ["up", str(config.with_name("plant.yaml"))],
    "up --workers 2": lambda config: ["up", str(config.with_name("plant.yaml")), "--workers", "2"],
}
PLANT = """\
devices:
  - {name: sers, kind: sers, config: {autostart: true}}
  - {name: other, kind: sers, config: {address: 2}}
"""


@pytest.mark.manual("§3.1.2", "DIP switch 2 bit 8 ON: a valid EEPROM program starts automatically after a power-on reset")
@pytest.mark.parametrize("command", list(COMMANDS))
@pytest.mark.parametrize("closed", ["stdout", "stdout and stderr"])
def test_a_drive_powers_on_completely_when_nobody_reads_the_output(tmp_path: Path, command: str, closed: str) -> None:
    config = tmp_path / "sers.yaml"
    config.write_text("autostart: true\n")
    (tmp_path / "plant.yaml").write_text(PLANT)
    address = f"unix:{tmp_path}/c.sock"
    with (tmp_path / "err.txt").open("w") as err_file:
        proc = subprocess.Popen(
            [sys.executable, "-m", "devsim", *COMMANDS[command](config), "--virtual", "--control", address,
             "-v"],  # -v: every event logged, from inside the model
            cwd=ROOT, env=devsim_env(), stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
            stderr=subprocess.PIPE if closed == "stdout and stderr" else err_file, text=True,
        )
    try:
        assert proc.stdout is not None
        while not (line := proc.stdout.readline()).startswith("control: "):  # the port lines first
            assert ": pty /dev/" in line, line
        assert line == f"control: {address}\n"
        assert ctl(address, "set", "sers", "program", '["O3=1 PE"]') == "ok\n"  # stored while it boots
        proc.stdout.close()  # nobody reads any more: `sers: ready` finds no reader
        if proc.stderr is not None:
            proc.stderr.close()
        ctl(address, "advance", "2.1")  # the power-on ends (2 s)
        assert ctl(address, "read", "sers", "booting", "output.O3").split() == [
            "name", "value", "unit", "booting", "false", "output.O3", "true"]
        assert ctl(address, "fault", "sers", "blocked_axis", "on") == "ok\n"  # logged (-v): to nobody
        assert ctl(address, "--json", "read", "sers", "output.O3") == "true\n"
    finally:
        status = stop(proc, timeout=15)
    assert status == 0
    if closed == "stdout":
        assert "Traceback" not in (tmp_path / "err.txt").read_text()


def test_up_takes_its_workers_lines_when_nobody_reads_its_own() -> None:
    """`devsim up --workers` passes each worker's lines on: with its own reader gone it still takes
    them all, or a worker would block once its pipe is full."""
    from devsim.scenario.workers import _forward

    read_end, write_end = os.pipe()
    os.close(read_end)

    async def forward_all(out: TextIO) -> asyncio.StreamReader:
        lines = asyncio.StreamReader()
        for n in range(5000):  # (more than a pipe holds)
            lines.feed_data(f"w{n}: ready\n".encode())
        lines.feed_data(b"control: unix:/worker.sock\n")
        lines.feed_eof()
        seen = asyncio.Event()
        await _forward(lines, seen, out)
        assert seen.is_set()
        return lines

    with open(write_end, "w") as out:
        assert asyncio.run(forward_all(out)).at_eof()


def test_a_slow_reader_gets_every_line_in_order_without_the_writer_waiting() -> None:
    """Lines a full pipe does not take wait and go out as the reader reads, in order, while the
    writer never waits (here a pipe someone set non-blocking, and one left blocking); before,
    a line the pipe did not take at once was dropped."""
    from devsim.core.console import say

    async def write_then_read(blocking: bool) -> bytes:
        read_end, write_end = os.pipe()
        os.set_blocking(write_end, blocking)
        with open(write_end, "w") as out:
            for n in range(2000):  # (200 kB: three times what the pipe holds; nobody reads yet)
                say(f"{n:04d}" + "x" * 95, out)
            say("after", out)
            got = b""
            loop = asyncio.get_running_loop()
            while not got.endswith(b"after\n"):  # the loop sends what waited as the reader takes it
                readable = asyncio.Event()
                loop.add_reader(read_end, readable.set)
                await asyncio.wait_for(readable.wait(), 10)
                loop.remove_reader(read_end)
                got += os.read(read_end, 1 << 16)
        os.close(read_end)
        return got

    for blocking in (False, True):
        lines = asyncio.run(write_then_read(blocking)).decode().splitlines()
        assert lines == [f"{n:04d}" + "x" * 95 for n in range(2000)] + ["after"]


def test_a_harness_a_little_behind_gets_every_port_line_of_a_big_plant(tmp_path: Path) -> None:
    """`devsim up` of 300 devices in two workers prints 600 lines (about 14 kB) into a pipe of two
    pages (``F_SETPIPE_SZ``: full, as the default 64 KiB pipe is, for a plant a tenth the size);
    a harness that reads them only once the pipe is full gets every one.
    Before, a line the full pipe did not take at once was dropped: benchmarks/scale.py lost port
    lines of its 6,000-device plant (KeyError)."""
    devices = 300
    plant = tmp_path / "plant.yaml"
    plant.write_text("devices:\n" + "".join(f"  - {{name: d{i}, kind: sers, transport: {{tcp: {{port: 0}}}}}}\n"
                                            for i in range(devices)))
    out, into = os.pipe()
    fcntl.fcntl(into, fcntl.F_SETPIPE_SZ, 8192)
    full = fcntl.fcntl(into, fcntl.F_GETPIPE_SZ) - 4096  # (a write fills a page of the pipe's ring, or waits)
    try:
        proc = subprocess.Popen([sys.executable, "-m", "devsim", "up", str(plant), "--workers", "2", "--control",
                                 f"unix:{tmp_path}/c.sock"], cwd=ROOT, env=devsim_env(), stdin=subprocess.DEVNULL,
                                stdout=into, stderr=subprocess.DEVNULL)
    finally:
        os.close(into)
    try:
        wait_until(lambda: _in_pipe(out) >= full, "a full pipe", timeout=60)  # the plant writes on meanwhile
        os.set_blocking(out, False)
        text = _read_until(out, f"d{devices - 1}: ready\n".encode(), timeout=60)  # (the workers print one after the other)
        while b"dropped" not in text and text.count(b": ready\n") < devices:
            text += _read_until(out, b": ready\n", timeout=60)
    finally:
        status = stop(proc, timeout=15)
        os.close(out)
    assert status == 0
    lines = text.decode().splitlines()
    assert not [line for line in lines if "dropped" in line]
    ports = {line.split(":")[0] for line in lines if ": tcp socket://127.0.0.1:" in line}
    ready = {line.split(":")[0] for line in lines if line.endswith(": ready")}
    assert ports == ready == {f"d{i}" for i in range(devices)}


def _in_pipe(fd: int) -> int:
    """Bytes waiting in the pipe ``fd`` reads (FIONREAD)."""
    return struct.unpack("i", fcntl.ioctl(fd, termios.FIONREAD, b"\0\0\0\0"))[0]


#: ``python -c HUP ARGS``: ``python -m devsim ARGS`` with SIGHUP ignored, as ``nohup`` starts it
#: (HUP % "SIG_IGN"), or not (HUP % "SIG_DFL": also when the test run itself runs under nohup).
HUP = ("import os, signal, sys\n"
       "signal.signal(signal.SIGHUP, signal.%s)\n"
       "os.execv(sys.executable, [sys.executable, '-m', 'devsim', *sys.argv[1:]])\n")


def catches_sighup(pid: int) -> bool:
    """Whether process ``pid`` has a handler of its own for SIGHUP (``SigCgt`` of /proc/PID/status)."""
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("SigCgt:"):
            return bool(int(line.split()[1], 16) >> (signal.SIGHUP - 1) & 1)
    raise AssertionError("no SigCgt in /proc/PID/status")


@pytest.mark.parametrize("nohup", [False, True])
def test_the_terminal_closing_stops_a_simulator_cleanly_unless_nohup(tmp_path: Path, nohup: bool) -> None:
    """SIGHUP: the motion log gets its last rows and the control socket goes, status 0, as with
    Ctrl-C (before, SIGHUP killed the process: a log cut short in its buffer, a socket left).
    Under nohup the simulator goes on, until Ctrl-C."""
    address, log = f"unix:{tmp_path}/c.sock", tmp_path / "motion.csv"
    command = ["run", "sers", "--pty", "--virtual", "--control", address, "--motion-log", str(log),
               "--motion-resolution", "0.001"]
    proc = subprocess.Popen([sys.executable, "-c", HUP % ("SIG_IGN" if nohup else "SIG_DFL"), *command], cwd=ROOT,
                            env=devsim_env(), stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL,
                            text=True)
    out = collect_lines(proc.stdout)
    try:
        pty = next_match(out, lambda line: line.startswith("sers: pty "), 30, "the port line").split()[-1]
        next_match(out, lambda line: line.startswith("control: "), 30, "the control line")
        assert catches_sighup(proc.pid) is not nohup
        ctl(address, "advance", "2.1")  # the power-on
        with serial.Serial(pty, 9600, timeout=5) as port:
            port.write(b"#1 ON V=60 A=100 WR=90 E\r")  # 3,200 steps, logged every millisecond
            assert port.read_until(b"ok0\n\r").endswith(b"ok0\n\r")
            ctl(address, "advance", "60")
            proc.send_signal(signal.SIGHUP)
            if nohup:
                port.write(b"#1 P1050?\r")
                assert port.read_until(b"ok1\n\r").endswith(b"P1050=1\n\r\nok1\n\r")
                assert float(ctl(address, "--json", "now")) > 60  # still serving
                proc.send_signal(signal.SIGINT)
            status = proc.wait(timeout=15)
    finally:
        stop(proc)
    assert status == 0
    assert not Path(address.removeprefix("unix:")).exists()
    rows = rows_of(log)
    assert [row["event"] for row in rows if row["event"].startswith("move_")] == ["move_start", "move_end"]
    assert float(rows[-1]["position"]) == 3200.0


@pytest.mark.parametrize("closed", [1, 2])
def test_a_simulator_started_with_its_output_closed_serves(tmp_path: Path, closed: int) -> None:
    """`devsim run sers --pty >&-` (or `2>&-`): Python then has no sys.stdout (sys.stderr); the
    port line raised AttributeError and the simulator ended with a traceback before it served."""
    address = f"unix:{tmp_path}/c.sock"
    start = (f"import os, sys\nos.close({closed})\n"
             "os.execv(sys.executable, [sys.executable, '-m', 'devsim', *sys.argv[1:]])\n")
    proc = subprocess.Popen([sys.executable, "-c", start, "run", "sers", "--pty", "--virtual", "--control", address],
                            cwd=ROOT, env=devsim_env(), stdin=subprocess.DEVNULL,
                            stdout=subprocess.PIPE if closed == 2 else None, stderr=subprocess.PIPE if closed == 1 else None)
    try:
        wait_until(lambda: Path(f"{tmp_path}/c.sock").exists() or proc.poll() is not None, "the control socket", 30)
        assert proc.poll() is None, proc.communicate()
        assert ctl(address, "advance", "2.1") == "ok, time 2.1 s\n"  # the power-on ends, "ready" to nobody
        assert ctl(address, "read", "sers", "booting").split()[-1] == "false"
    finally:
        status = stop(proc, timeout=15)
    assert status == 0
    if closed == 2:  # what goes to stderr goes nowhere, not to stdout
        assert proc.stdout is not None
        lines = proc.stdout.read().decode().splitlines()
        assert lines[0].startswith("sers: pty /dev/") and lines[1:] == [f"control: {address}", "sers: ready"]


def test_a_scenario_run_with_stderr_closed_reports_its_result() -> None:
    """`devsim scenario run FILE 2>&-`: the progress has no stderr to go to (it raised
    AttributeError, and the run ended with 1 and no word)."""
    start = "import os, sys\nos.close(2)\nos.execv(sys.executable, [sys.executable, '-m', 'devsim', *sys.argv[1:]])\n"
    done = subprocess.run([sys.executable, "-c", start, "scenario", "run", "scenarios/gms96/power_on_status.yaml"],
                          cwd=ROOT, env=devsim_env(), stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, text=True,
                          timeout=60)
    assert done.returncode == 0 and done.stdout.splitlines()[-1].startswith("PASSED: 14 of 14 checks passed")


def test_a_real_time_scenario_whose_reader_goes_away_runs_to_its_result() -> None:
    """`devsim scenario run --realtime FILE | head -1`: the plant's port lines are a serving
    process's (docs/connect.md: a reader gone, what follows goes nowhere); the scenario runs and
    its status is its result.  Before, the port line's EPIPE was said as the run's failure, 'Error:
    FILE: cannot run the scenario: [Errno 32] Broken pipe', status 6, and no step ran."""
    with subprocess.Popen([sys.executable, "-m", "devsim", "scenario", "run", "--realtime", "--speed", "100",
                           "scenarios/gms96/power_on_status.yaml"], cwd=ROOT, env=devsim_env(),
                          stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True) as proc:
        assert proc.stdout is not None and proc.stderr is not None
        proc.stdout.close()  # (before the port line)
        err = proc.stderr.read()
    assert proc.returncode == 0, err
    assert err.splitlines()[-1].endswith("line 36: expect card.plc.running == False  PASS")  # (the progress)


def test_a_command_whose_reader_goes_away_ends_quietly_with_1() -> None:
    """`devsim list | head -1`: click ends a command on EPIPE with status 1 and nothing on stderr
    (docs/cli.md, FAILED)."""
    with subprocess.Popen([sys.executable, "-m", "devsim", "list"], cwd=ROOT, env=devsim_env(), stdin=subprocess.DEVNULL,
                          stdout=subprocess.PIPE, stderr=subprocess.PIPE) as proc:
        assert proc.stdout is not None and proc.stderr is not None
        proc.stdout.close()  # (before the first line: every write finds no reader)
        err = proc.stderr.read()
    assert proc.returncode == 1 and err == b""


def test_a_simulator_whose_log_nobody_reads_keeps_answering(tmp_path: Path) -> None:
    """A harness that starts a simulator with ``stderr=PIPE`` and never reads it: with ``-v`` every
    telegram is logged, and once the pipe was full (64 KiB, about 400 SERS requests) the simulator
    stopped in the middle of a log line: its host got no answer and SIGTERM did not stop it.  Now
    what the pipe does not take waits, up to 1 MiB; beyond that a line is dropped, and the next
    line that goes out counts the lost."""
    address, link = f"unix:{tmp_path}/c.sock", str(tmp_path / "ttySERS")
    proc = subprocess.Popen(
        [sys.executable, "-m", "devsim", "run", "sers", "--link", link, "--virtual", "--control", address, "-v"],
        cwd=ROOT, env=devsim_env(), stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
    )
    try:
        assert proc.stdout is not None and proc.stderr is not None
        while not (line := proc.stdout.readline()).startswith(b"control: "):
            assert line, "the simulator ended before its control line"
        ctl(address, "advance", "2.1")  # the power-on ends (2 s)
        with serial.Serial(link, 9600, timeout=5, write_timeout=5) as host:
            for n in range(600):  # a 4 kB line the drive ignores: 4 kB of log each, nobody reading them
                host.write(b"x" * 4000 + b"\r#P134?\r")
                assert host.read_until(b"ok1\n\r") == b"#P134?\rP134=0\n\r\nok1\n\r", f"no answer to request {n}"
            log = bytearray()
            reader = threading.Thread(target=_read_into, args=(proc.stderr.fileno(), log), daemon=True)
            reader.start()  # someone reads at last: what waited goes out, then the lines after
            # Until the reader has taken more than the pipe held, the backlog may still be full and
            # the next request's log line dropped (its write first sends what waits, but only into
            # room the reader made): a loaded machine ran the request before the reader's thread.
            wait_until(lambda: len(log) >= CAP + select.PIPE_BUF, "the waiting lines going out", timeout=30)
            host.write(b"#P134!\r")
            assert host.read_until(b"\n\r").endswith(b"\n\r")
            wait_until(lambda: b'main \xe2\x86\x92 "#P134!\\r"' in log, "the last request's log line", timeout=30)
        notes = list(re.finditer(rb"devsim: (\d+) lines? of output dropped here: nobody read them\n", log))
        assert notes and notes[0].start() > 1 << 20  # what the pipe and the backlog held came before any drop
        assert sum(int(note[1]) for note in notes) > 500
    finally:
        status = stop(proc, timeout=15)
    assert status == 0


def _read_into(fd: int, into: bytearray) -> None:
    while chunk := os.read(fd, 1 << 16):
        into += chunk


def _read_now(fd: int) -> bytes:
    try:
        return os.read(fd, 1 << 16)
    except BlockingIOError:
        return b""


def _read_until(fd: int, needle: bytes, timeout: float) -> bytes:
    """What a non-blocking ``fd`` gives until ``needle`` is in it (an AssertionError after ``timeout``)."""
    deadline = time.monotonic() + timeout
    got = b""
    while needle not in got:
        left = deadline - time.monotonic()
        assert left > 0, f"no {needle!r} within {timeout} s: {got[-300:]!r}"
        if select.select([fd], [], [], left)[0]:
            chunk = _read_now(fd)
            assert chunk or got, "the output ended"
            got += chunk
    return got
