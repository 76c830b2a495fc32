"""Control on by default (issue 30): ``devsim run`` and ``devsim up`` serve the control API on a
socket in the user's runtime directory and print it; ``devsim ctl`` and ``devsim monitor`` find
the one running simulator without an address, refuse with a list when several run; ``devsim ps``
lists them.  Everything through the real command line, each test with a runtime directory of
its own (``XDG_RUNTIME_DIR``)."""

from __future__ import annotations

import json
import os
import re
import shlex
import shutil
import socket
import stat
import subprocess
import sys
import tempfile
import time
import uuid
from collections.abc import Iterator
from pathlib import Path

import pytest

from tests.support.process import ROOT, DevsimProcess, devsim_env
from tests.support.programs import needs_program


@pytest.fixture
def runtime(monkeypatch: pytest.MonkeyPatch) -> Iterator[Path]:
    """A fresh XDG_RUNTIME_DIR (short: a socket path holds 107 bytes); its ``devsim`` directory."""
    base = Path(tempfile.mkdtemp(prefix="ds"))
    monkeypatch.setenv("XDG_RUNTIME_DIR", str(base))
    monkeypatch.delenv("DEVSIM_CONTROL", raising=False)
    yield base / "devsim"
    shutil.rmtree(base, ignore_errors=True)


def devsim(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "devsim", *args], cwd=ROOT, env=devsim_env(),
                          capture_output=True, text=True, timeout=60)


def start(*args: str) -> tuple[DevsimProcess, str, list[str]]:
    """``devsim ARGS`` up to its ``control:`` line: the process, the address, the lines before it."""
    sim = DevsimProcess(*args)
    keep: list[str] = []
    line = sim.next_match(sim.out, lambda text: text.startswith("control: "), 30, "the control: line", keep)
    return sim, line.removeprefix("control: "), keep


def test_run_serves_control_in_the_runtime_dir_and_ctl_finds_it(runtime: Path) -> None:
    sim, address, before = start("run", "sers", "--pty")
    try:
        path = Path(address.removeprefix("unix:"))
        assert address.startswith("unix:") and path == runtime / f"sers-{sim.proc.pid}.sock"
        assert re.fullmatch(r"sers: pty /dev/pts/\d+", before[0]), before
        assert stat.S_IMODE(os.lstat(runtime).st_mode) == 0o700
        assert stat.S_ISSOCK(os.lstat(path).st_mode) and stat.S_IMODE(os.lstat(path).st_mode) == 0o600
        read = devsim("ctl", "--json", "read", "sers", "axis.position")  # no address: the one running
        assert read.returncode == 0, read.stderr
        assert float(read.stdout.split()[0]) == 0.0
        by_name = devsim("ctl", "--json", "--control", "sers", "read", "sers", "axis.position")
        assert by_name.returncode == 0 and float(by_name.stdout.split()[0]) == 0.0, by_name.stderr
    finally:
        assert sim.interrupt() == 0
    assert not path.exists()  # removed on the way out
    gone = devsim("ctl", "read", "sers", "axis.position")
    assert gone.returncode == 5  # exits.UNREACHABLE
    assert gone.stderr.strip() == (f"Error: no running simulator found in {runtime} (start one with 'devsim run KIND',"
                                   " or give --control ADDR)")


def test_ps_lists_the_running_simulators(runtime: Path) -> None:
    assert devsim("ps", "--json").stdout.strip() == "[]"
    sim, address, before = start("run", "sers", "--pty", "--drives", "1,2")
    try:
        pty = before[0].split()[-1]
        table = devsim("ps")
        assert table.returncode == 0, table.stderr
        header, row, *rest = table.stdout.splitlines()
        assert header.split() == ["NAME", "KINDS", "PORTS", "CONTROL", "PID", "UPTIME"] and not rest
        assert row.startswith("sers  ") and f"sers1 {pty}, sers2 {pty}" in row and address in row
        assert re.search(rf"\s{sim.proc.pid}\s+\d+[smhd]\S*$", row), row
        (info,) = json.loads(devsim("ps", "--json").stdout)
        assert info["name"] == "sers" and info["kinds"] == ["sers"] and info["pid"] == sim.proc.pid
        assert info["address"] == address and info["ports"] == {"sers1": pty, "sers2": pty}
        assert info["devices"] == ["sers1", "sers2"] and 0 <= info["uptime"] < 60 and info["answering"]
    finally:
        assert sim.interrupt() == 0


def test_several_simulators_are_listed_and_chosen_by_name(runtime: Path) -> None:
    sers, sers_address, _ = start("run", "sers", "--pty")
    gms, gms_address, _ = start("run", "gms96", "--pty")
    try:
        refused = devsim("ctl", "read", "sers", "axis.position")
        assert refused.returncode == 2 and refused.stdout == ""
        first, *listed = refused.stderr.strip().splitlines()
        assert first == "Error: 2 simulators are running; choose one with --control NAME or --control ADDR:"
        assert [line.split() for line in listed] == [
            ["gms96", "gms96", "pid", str(gms.proc.pid), gms_address],
            ["sers", "sers", "pid", str(sers.proc.pid), sers_address],
        ]
        watch = devsim("ctl", "watch", "sers")
        assert watch.returncode == 2 and watch.stderr == refused.stderr
        monitor = devsim("monitor")
        if "needs textual" not in monitor.stderr:
            assert monitor.returncode == 2 and monitor.stderr == refused.stderr
        chosen = devsim("ctl", "--json", "--control", "gms96", "read", "gms96", "axis.position")
        assert chosen.returncode == 0 and float(chosen.stdout.split()[0]) == 0.0, chosen.stderr
        by_address = devsim("ctl", "--control", sers_address, "read", "sers", "axis.position")
        assert by_address.returncode == 0, by_address.stderr
        unknown = devsim("ctl", "--control", "poselesta", "read", "cnc", "axis.position")
        assert unknown.returncode == 5  # exits.UNREACHABLE
        assert unknown.stderr == ("Error: no running simulator named 'poselesta' (running: gms96, sers;"
                                  " see 'devsim ps')\n")
        assert [row["name"] for row in json.loads(devsim("ps", "--json").stdout)] == ["gms96", "sers"]
    finally:
        assert sers.interrupt() == 0
        assert gms.interrupt() == 0


def test_no_control_opens_none(runtime: Path) -> None:
    sim = DevsimProcess("run", "sers", "--pty", "--no-control")
    try:
        keep: list[str] = []
        sim.next_match(sim.out, lambda line: line == "sers: ready", 30, "sers: ready", keep)
        assert not [line for line in keep if line.startswith("control:")], keep
        assert not list(runtime.glob("*.sock")) if runtime.exists() else True
        assert devsim("ps").stderr == "no running simulators\n"
        assert devsim("ctl", "read", "sers", "axis.position").returncode == 5  # exits.UNREACHABLE
    finally:
        assert sim.interrupt() == 0
    both = devsim("run", "sers", "--pty", "--no-control", "--control", "unix:/tmp/x.sock")
    assert both.returncode == 2 and "--control and --no-control exclude each other" in both.stderr


def test_a_dead_process_socket_is_ignored_and_removed(runtime: Path) -> None:
    runtime.mkdir(mode=0o700)
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True)
    ghost = runtime / f"ghost-{int(dead.stdout)}.sock"
    with socket.socket(socket.AF_UNIX) as sock:  # bound, never listened on: what a killed run leaves
        sock.bind(str(ghost))
    assert ghost.is_socket()
    assert json.loads(devsim("ps", "--json").stdout) == []
    assert not ghost.exists()
    sim, address, _ = start("run", "sers", "--pty")
    try:
        with socket.socket(socket.AF_UNIX) as sock:
            sock.bind(str(ghost))
        read = devsim("ctl", "read", "sers", "axis.position")  # the ghost is no second simulator
        assert read.returncode == 0, read.stderr
        assert not ghost.exists()
    finally:
        assert sim.interrupt() == 0


def test_a_socket_whose_name_ends_in_no_ascii_number_is_no_simulator(runtime: Path) -> None:
    """A stray socket ``x-².sock`` in the directory: ``str.isdigit`` takes '²' and ``int`` does
    not, so ``devsim ps`` ended in a ValueError traceback."""
    runtime.mkdir(mode=0o700)
    with socket.socket(socket.AF_UNIX) as sock:
        sock.bind(str(runtime / "x-\u00b2.sock"))
        listed = devsim("ps", "--json")
    assert listed.returncode == 0 and "Traceback" not in listed.stderr, listed.stderr
    assert json.loads(listed.stdout) == []


def test_an_unsafe_runtime_dir_is_refused(runtime: Path, tmp_path: Path) -> None:
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir(mode=0o700)
    runtime.symlink_to(elsewhere)
    for args in (("run", "sers", "--pty"), ("ps",), ("ctl", "read", "sers", "axis.position")):
        done = devsim(*args)
        assert done.returncode == 6, (args, done.stderr)  # exits.SYSTEM
        assert f"the runtime directory {runtime} is a symlink; remove it" in done.stderr
    assert not list(elsewhere.iterdir())
    runtime.unlink()
    runtime.mkdir(mode=0o755)
    os.chmod(runtime, 0o755)
    done = devsim("run", "sers", "--pty")
    assert done.returncode == 6 and f"{runtime} is open to others (mode 755); chmod 700 it" in done.stderr


def test_without_xdg_the_runtime_dir_is_named_with_the_uid(monkeypatch: pytest.MonkeyPatch) -> None:
    base = Path(tempfile.mkdtemp(prefix="ds"))
    monkeypatch.delenv("XDG_RUNTIME_DIR")
    monkeypatch.setenv("TMPDIR", str(base))
    try:
        sim, address, _ = start("run", "sers", "--pty")
        try:
            assert address == f"unix:{base}/devsim-{os.getuid()}/sers-{sim.proc.pid}.sock"
            assert stat.S_IMODE(os.lstat(base / f"devsim-{os.getuid()}").st_mode) == 0o700
        finally:
            assert sim.interrupt() == 0
    finally:
        shutil.rmtree(base, ignore_errors=True)


@pytest.mark.parametrize("xdg", ["gone", "another user's"])
def test_an_xdg_runtime_dir_not_yours_is_as_none(monkeypatch: pytest.MonkeyPatch, xdg: str) -> None:
    """After `su` the variable may name the first user's directory, or one that is gone: the
    simulator and its clients use devsim-UID in TMPDIR, as without it (before: status 6)."""
    base = Path(tempfile.mkdtemp(prefix="ds"))
    monkeypatch.setenv("TMPDIR", str(base))
    if xdg == "gone":
        monkeypatch.setenv("XDG_RUNTIME_DIR", "/nonexistent/run/user/1000")
    elif os.getuid() != 0:
        monkeypatch.setenv("XDG_RUNTIME_DIR", "/")  # (root's)
    else:  # (root may enter every directory: one of nobody's)
        (base / "other").mkdir(mode=0o700)
        os.chown(base / "other", 65534, 65534)
        monkeypatch.setenv("XDG_RUNTIME_DIR", str(base / "other"))
    try:
        sim, address, _ = start("run", "sers", "--pty")
        try:
            assert address == f"unix:{base}/devsim-{os.getuid()}/sers-{sim.proc.pid}.sock"
            (info,) = json.loads(devsim("ps", "--json").stdout)  # the clients look there too
            assert info["pid"] == sim.proc.pid
        finally:
            assert sim.interrupt() == 0
    finally:
        shutil.rmtree(base, ignore_errors=True)


def test_up_names_its_socket_after_the_plant_inside_the_dir(runtime: Path, tmp_path: Path) -> None:
    plant = tmp_path / "plant.yaml"
    plant.write_text("name: ../../line 7\ndevices:\n  - {name: x, kind: sers, config: {boot_time: 0}}\n")
    sim, address, _ = start("up", str(plant))
    try:
        assert address == f"unix:{runtime}/line_7-{sim.proc.pid}.sock"
        (info,) = json.loads(devsim("ps", "--json").stdout)
        assert info["name"] == "../../line 7" and info["devices"] == ["x"]
        by_device = devsim("ctl", "--control", "x", "read", "x", "axis.position")  # a device names its simulator
        assert by_device.returncode == 0, by_device.stderr
    finally:
        assert sim.interrupt() == 0


def test_up_with_workers_is_one_simulator(runtime: Path, tmp_path: Path) -> None:
    plant = tmp_path / "cell.yaml"
    plant.write_text("devices:\n  - {name: a, kind: sers, config: {boot_time: 0}}\n"
                     "  - {name: b, kind: gms96}\n")
    sim, address, before = start("up", str(plant), "--workers", "2")
    try:
        assert address == f"unix:{runtime}/cell-{sim.proc.pid}.sock"
        assert [path.name for path in runtime.iterdir()] == [f"cell-{sim.proc.pid}.sock"]  # no worker's
        (info,) = json.loads(devsim("ps", "--json").stdout)
        assert info["name"] == "cell" and info["pid"] == sim.proc.pid and info["kinds"] == ["gms96", "sers"]
        assert sorted(info["devices"]) == ["a", "b"]
        assert info["ports"] == {row.split(": ")[0]: row.split()[-1] for row in before if ": pty " in row}
        read = devsim("ctl", "read", "b", "axis.position")
        assert read.returncode == 0, read.stderr
    finally:
        assert sim.interrupt() == 0


def test_monitor_without_an_address_attaches_to_the_one_running(runtime: Path) -> None:
    """In a real terminal (tmux): ``devsim monitor`` alone shows the one simulator running."""
    needs_program("tmux")
    sim, _address, _ = start("run", "sers", "--tcp", "0", "--virtual")
    session = f"devsim-{uuid.uuid4().hex[:8]}"
    environ = devsim_env()
    command = " ".join(shlex.quote(part) for part in (
        "env", f"PYTHONPATH={environ['PYTHONPATH']}", f"XDG_RUNTIME_DIR={environ['XDG_RUNTIME_DIR']}",
        "TERM=xterm-256color", sys.executable, "-m", "devsim", "monitor")) + "; sleep 30"  # an error stays visible
    try:
        subprocess.run(["tmux", "new-session", "-d", "-s", session, "-x", "160", "-y", "50", "-c", str(ROOT),
                        "sh", "-c", command], check=True, timeout=10)
        deadline = time.monotonic() + 30
        while "sers (sers)" not in (screen := _capture(session)):
            assert "Error" not in screen and time.monotonic() < deadline, screen
            time.sleep(0.1)  # polling the screen (bounded by the deadline), not a synchronisation sleep
    finally:
        subprocess.run(["tmux", "kill-session", "-t", session], capture_output=True)
        assert sim.interrupt() == 0


def _capture(session: str) -> str:
    return subprocess.run(["tmux", "capture-pane", "-p", "-t", session], capture_output=True, text=True,
                          timeout=10, check=True).stdout


def test_names_of_a_kind_while_a_simulator_of_another_runs(runtime: Path) -> None:
    """`devsim ctl names KIND` where the running simulators serve no device of that name: the
    kind's names (before: 'no device named gms96' with one running, 'choose one' with two)."""
    sers, _address, _ = start("run", "sers", "--pty")
    try:
        done = devsim("ctl", "names", "gms96")
        assert done.returncode == 0, done.stderr
        assert "\n160 names in " in done.stdout and "\nalso by pattern:\n" in done.stdout
        done = devsim("ctl", "--json", "names", "sers")  # the running device's own
        assert done.returncode == 0 and json.loads(done.stdout)[0]["name"] == "axis.position", done.stderr
        gms, _address, _ = start("run", "gms96", "--pty")
        try:
            done = devsim("ctl", "names", "pcd4h3")
            assert done.returncode == 0 and "\n42 names in " in done.stdout, done.stderr
            assert done.stdout.splitlines()[-1].startswith("  O.<n>"), done.stdout  # its patterns last
            refused = devsim("ctl", "names", "nokind")
            assert refused.returncode == 2 and "2 simulators are running" in refused.stderr
        finally:
            assert gms.interrupt() == 0
    finally:
        assert sers.interrupt() == 0
