"""A file a run writes as it goes (a wire trace, text or pcap; a motion log; the session of
`devsim record`) that the file system stops taking: the file ends there with one line on stderr,
and the device goes on answering.

The file system is made to refuse as a full disk would, without a disk: the simulator runs
under a file size limit (``RLIMIT_FSIZE``; Python ignores SIGXFSZ, so a write beyond it fails
with ``EFBIG``, "File too large").  Before, the trace's refusal was raised in the line's feed, so
the drive never saw another byte and answered nothing."""

from __future__ import annotations

import resource
import signal
import subprocess
import sys
from pathlib import Path

import pytest
import serial

from devsim.runtime.client import ControlClient
from tests.support.process import ROOT, DevsimProcess, collect_lines, devsim_env, next_match, stop

LIMIT = 2048  # bytes a file of the simulator may grow to



def limited(limit: int = LIMIT) -> str:
    """``python -c limited() ARGS``: ``python -m devsim ARGS`` with every file it writes limited to
    ``limit`` bytes (a soft limit: the test may lift it while the simulator runs, as when space is
    freed on a full disk)."""
    return ("import os, resource, sys\n"
            f"resource.setrlimit(resource.RLIMIT_FSIZE, ({limit}, resource.RLIM_INFINITY))\n"
            "os.execv(sys.executable, [sys.executable, '-m', 'devsim', *sys.argv[1:]])\n")


QUERY, ANSWER = b"#1 P1050?\r", b"#1 P1050?\rP1050=1\n\r\nok1\n\r"


@pytest.mark.parametrize(("option", "name"), [("--trace", "line.trace"), ("--trace", "line.pcap"),
                                              ("--motion-log", "motion.csv")])
def test_a_file_the_disk_stops_taking_ends_and_the_drive_goes_on(tmp_path: Path, option: str, name: str) -> None:
    address = f"unix:{tmp_path}/c.sock"
    written = tmp_path / name
    proc = subprocess.Popen(
        [sys.executable, "-c", limited(), "run", "sers", "--pty", "--virtual", "--control", address,
         option, str(written), "--motion-resolution", "0.001"],
        cwd=ROOT, env=devsim_env(), stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )
    out, err = collect_lines(proc.stdout), collect_lines(proc.stderr)
    try:
        pty = next_match(out, lambda line: line.startswith("sers: pty "), 30, "the port line").split()[-1]
        next_match(out, lambda line: line.startswith("control: "), 30, "the control line")
        with ControlClient(address) as client, serial.Serial(pty, 9600, timeout=5) as port:
            client.request("advance", seconds=3.0)  # the power-on
            port.write(b"#1 ON V=60 A=100 WR=90 E\r")  # a move of 3,200 steps: the motion log's rows
            assert port.read_until(b"ok0\n\r").endswith(b"ok0\n\r")
            client.request("advance", seconds=60.0)
            for n in range(60):  # about 100 bytes of text trace each, 80 of pcap
                port.write(QUERY)
                assert port.read_until(ANSWER) == ANSWER, f"poll {n}"
            assert client.read("sers", "axis.position") == 3200
    finally:
        status = stop(proc, timeout=15)
    assert status == 0
    lines = []
    while (line := err.get(timeout=15)) is not None:
        lines.append(line)
    ended = [line for line in lines if "it ends here" in line]
    what = "motion log" if option == "--motion-log" else "trace"
    assert ended == [f"devsim: {what} {written}: File too large; it ends here"], lines
    assert not any("Traceback" in line for line in lines), lines
    assert 0 < written.stat().st_size <= LIMIT


def test_a_recording_the_disk_stops_taking_ends_and_the_host_is_still_served(tmp_path: Path) -> None:
    """`devsim record` between a host and a device: its session file ends, the traffic goes on."""
    session, config = tmp_path / "drive.devsim", tmp_path / "sers.yaml"
    config.write_text("boot_time: 0\n")
    device = DevsimProcess("run", "sers", "--pty", "--config", str(config))
    recorder: subprocess.Popen[str] | None = None
    try:
        device_pty = device.next_match(device.out, lambda line: line.startswith("sers: pty "), 30, "the port").split()[-1]
        device.next_match(device.out, lambda line: line == "sers: ready", 30, "ready")
        recorder = subprocess.Popen(
            [sys.executable, "-c", limited(), "record", "--port", device_pty, "--out", str(session), "--kind", "sers"],
            cwd=ROOT, env=devsim_env(), stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
            text=True,
        )
        out, err = collect_lines(recorder.stdout), collect_lines(recorder.stderr)
        host_pty = next_match(out, lambda line: line.startswith("record: pty "), 30, "the host's port").split()[-1]
        with serial.Serial(host_pty, 9600, timeout=5) as port:
            for n in range(40):  # about 150 bytes of session each
                port.write(QUERY)
                assert port.read_until(ANSWER) == ANSWER, f"poll {n}"
    finally:
        statuses = [stop(recorder, signal.SIGINT, 15)] if recorder is not None else []
        statuses.append(device.interrupt())  # (both stopped before either is judged)
    assert statuses == [0, 0]
    lines = []
    while (line := err.get(timeout=15)) is not None:
        lines.append(line)
    assert [line for line in lines if "it ends here" in line] == [
        f"devsim: session {session}: File too large; it ends here"], lines
    held = sum(1 for line in session.read_text().splitlines() if line.startswith('{"t"') and '"dir"' in line
               and line.endswith("}"))  # the whole chunk lines (not the header, the settings, the last cut short)
    assert lines[-1] == f"record: {held} chunks in {session}"  # what the file holds, not all 80
    cut = len(session.read_text().splitlines())
    replay = DevsimProcess("replay", str(session), "--pty")  # what was recorded replays
    try:
        replay.next_match(replay.err, lambda line: line == f"replay: {session}:{cut}: the last line is cut short"
                          " (the recorder stopped writing there); the recording ends before it", 30, "the cut")
        host_pty = replay.next_match(replay.out, lambda line: line.startswith("replay: pty "), 30, "the port").split()[-1]
        with serial.Serial(host_pty, 9600, timeout=5) as port:
            port.write(QUERY)
            assert port.read_until(ANSWER) == ANSWER
    finally:
        assert replay.interrupt() == 0
    assert 0 < session.stat().st_size <= LIMIT


MEMORY_LIMIT = 1024  # (the SERS's image of its parameters is about 1.6 kB)


def test_a_save_the_disk_refuses_is_kept_and_written_once_the_disk_takes_it(tmp_path: Path) -> None:
    """P1004=2 (RAM parameters to EEPROM, §4.8.2) on a full disk: the drive answers as having saved
    and keeps the image; the state file gets it once the disk takes it again (here: at the end)."""
    address, state = f"unix:{tmp_path}/c.sock", tmp_path / "state"
    proc = subprocess.Popen(
        [sys.executable, "-c", limited(MEMORY_LIMIT), "run", "sers", "--pty", "--virtual", "--control", address,
         "--state-dir", str(state)],
        cwd=ROOT, env=devsim_env(), stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )
    out, err = collect_lines(proc.stdout), collect_lines(proc.stderr)
    memory = state / "sers.nvram.json"
    try:
        pty = next_match(out, lambda line: line.startswith("sers: pty "), 30, "the port line").split()[-1]
        next_match(out, lambda line: line.startswith("control: "), 30, "the control line")
        with ControlClient(address) as client, serial.Serial(pty, 9600, timeout=5) as port:
            client.request("advance", seconds=3.0)  # the power-on
            for request, answer in ((b"#1 P41=700\r", b"#1 P41=700\r\nok1\n\r"),
                                    (b"#1 P1004=2\r", b"#1 P1004=2\r\nok1\n\r"),  # the save: refused
                                    (b"#1 P41?\r", b"#1 P41?\rP41=700U/min\n\r\nok1\n\r")):
                port.write(request)
                assert port.read_until(answer) == answer
        next_match(err, lambda line: line == f"devsim: memory {memory}: File too large; kept in memory until a write"
                   " succeeds", 15, "the memory's line")
        assert not memory.exists() or memory.stat().st_size <= MEMORY_LIMIT
        resource.prlimit(proc.pid, resource.RLIMIT_FSIZE, (resource.RLIM_INFINITY, resource.RLIM_INFINITY))
    finally:
        status = stop(proc, signal.SIGINT, timeout=15)
    assert status == 0
    next_match(err, lambda line: line == f"devsim: memory {memory}: saved again", 15, "the save at the end")
    again = DevsimProcess("run", "sers", "--pty", "--virtual", "--control", address, "--state-dir", str(state))
    try:
        again.next_match(again.out, lambda line: line.startswith("control: "), 30, "the control line")
        with ControlClient(address) as client:
            client.request("advance", seconds=3.0)
            assert client.read("sers", "param.P41") == 700  # the EEPROM image the first run kept
    finally:
        assert again.interrupt() == 0
