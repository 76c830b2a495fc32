"""Restarting after a crash: ``kill -9`` of a simulator that served a ``--link`` (and kept its
EEPROM in a state dir), then the same command again (issue 32, item 1).

The kernel gives the new pty the lowest free number – usually the dead simulator's – so the link
it left points at a pseudo-terminal that exists again.  The owner record next to the link
(:mod:`devsim.transports.ptylink`) says its holder is gone, and the link is replaced; a link held
by a live simulator is refused, naming it."""

from __future__ import annotations

import json
import os
import select
import signal
import tempfile
from pathlib import Path

import pytest
import serial

from devsim.cli import exits
from devsim.transports.ptylink import owner_record_path
from tests.support.process import DevsimProcess

pytestmark = pytest.mark.skipif(not hasattr(os, "openpty"), reason="needs POSIX ptys")

PLANT = """\
devices:
  - name: axis
    kind: sers
    config: {{address: 1, boot_time: 0}}
    transport: {{pty: {{link: {link}}}}}
"""


def ask(link: Path, text: str) -> bytes:
    """One SERS exchange through the link (a host opening the stable name)."""
    with serial.Serial(str(link), 9600, timeout=5) as port:
        port.write(text.encode("ascii"))
        return bytes(port.read_until(b"\n\r\nok1\n\r" if "?" in text else b"ok1\n\r"))


def serving(*args: str, ready: str | tuple[str, ...]) -> DevsimProcess:
    """``devsim ARGS`` once it printed a line starting with ``ready`` (each of them, any order)."""
    sim = DevsimProcess(*args)
    waiting = {ready} if isinstance(ready, str) else set(ready)
    try:
        while waiting:
            prefixes = tuple(waiting)
            line = sim.next_match(sim.out, lambda line, p=prefixes: line.startswith(p), 30, repr(waiting))
            waiting = {prefix for prefix in waiting if not line.startswith(prefix)}
    except BaseException:
        sim.interrupt()
        raise
    return sim


def kill_9(sim: DevsimProcess) -> None:
    os.kill(sim.proc.pid, signal.SIGKILL)
    assert sim.proc.wait(timeout=15) == -signal.SIGKILL


def test_run_with_a_link_and_a_state_dir_restarts_after_kill_9(tmp_path: Path) -> None:
    link, state = tmp_path / "ttyA", tmp_path / "state"
    config = tmp_path / "sers.yaml"
    config.write_text("address: 1\nboot_time: 0\n")
    command = ("run", "sers", "--pty", "--link", str(link), "--config", str(config), "--state-dir", str(state))
    first = serving(*command, ready="sers: link")
    try:
        assert ask(link, "#P1019=45 PSAVE\r").endswith(b"ok1\n\r")
        dead_pty = os.readlink(link)
    finally:
        kill_9(first)
    assert os.readlink(link) == dead_pty  # the crash left the link (and its owner record) behind
    assert json.loads(owner_record_path(str(link)).read_text())["pid"] == first.proc.pid
    for _ in range(2):  # and the restart is not a one-off: kill it too, start again
        again = serving(*command, ready="sers: link")
        try:
            assert ask(link, "#P1019?\r") == b"#P1019?\rP1019=45U/min\n\r\nok1\n\r"
        finally:
            kill_9(again)
    final = serving(*command, ready="sers: link")
    assert final.interrupt() == exits.OK
    assert not os.path.lexists(link) and not owner_record_path(str(link)).exists()  # a clean stop tidies


def test_up_with_links_and_a_state_dir_restarts_after_kill_9(tmp_path: Path) -> None:
    link, state = tmp_path / "ttyP", tmp_path / "state"
    plant = tmp_path / "plant.yaml"
    plant.write_text(PLANT.format(link=link))
    command = ("up", str(plant), "--state-dir", str(state))
    first = serving(*command, ready="axis: ready")
    try:
        assert ask(link, "#P1019=52 PSAVE\r").endswith(b"ok1\n\r")
    finally:
        kill_9(first)
    again = serving(*command, ready="axis: ready")
    try:
        assert ask(link, "#P1019?\r") == b"#P1019?\rP1019=52U/min\n\r\nok1\n\r"
    finally:
        assert again.interrupt() == exits.OK


def test_a_link_held_by_a_live_simulator_is_refused_naming_it(tmp_path: Path) -> None:
    link = tmp_path / "ttyA"
    config = tmp_path / "sers.yaml"
    config.write_text("address: 1\nboot_time: 0\n")
    holder = serving("run", "sers", "--pty", "--link", str(link), "--config", str(config), ready="sers: link")
    try:
        held = os.readlink(link)
        second = DevsimProcess("run", "sers", "--pty", "--link", str(link))
        error = second.next_match(second.err, lambda line: "Error" in line, 30, "the refusal")
        assert second.proc.wait(timeout=15) == exits.SYSTEM
        assert f"held by a live process, pid {holder.proc.pid} (devsim run sers --pty --link {link}" in error
        assert os.readlink(link) == held  # untouched: the holder still serves it
        assert ask(link, "#P1050?\r") == b"#P1050?\rP1050=1\n\r\nok1\n\r"
    finally:
        assert holder.interrupt() == exits.OK


def wait_gone(pid: int, timeout: float) -> bool:
    """Whether process ``pid`` (not our child) ends within ``timeout`` s (a pidfd says when)."""
    try:
        fd = os.pidfd_open(pid)
    except ProcessLookupError:
        return True
    try:
        return bool(select.select([fd], [], [], timeout)[0])
    finally:
        os.close(fd)


@pytest.mark.skipif(not hasattr(os, "pidfd_open"), reason="needs pidfd_open (Linux 5.3)")
def test_up_with_workers_restarts_after_kill_9_of_its_process(tmp_path: Path) -> None:
    """kill -9 of ``devsim up --workers 2``: its workers end with it (tidily: links removed), and
    the same command starts again with what they stored."""
    links = [tmp_path / "ttyW0", tmp_path / "ttyW1"]
    plant = tmp_path / "plant.yaml"
    plant.write_text("devices:\n" + "".join(
        PLANT.format(link=link).split("\n", 1)[1].replace("name: axis", f"name: axis{n}") for n, link in enumerate(links)))
    command = ("up", str(plant), "--workers", "2", "--state-dir", str(tmp_path / "state"))
    first = serving(*command, ready=("axis0: ready", "axis1: ready"))
    try:
        for n, link in enumerate(links):
            assert ask(link, f"#P1019={60 + n} PSAVE\r").endswith(b"ok1\n\r")
        workers = [json.loads(owner_record_path(str(link)).read_text())["pid"] for link in links]
        assert first.proc.pid not in workers
    finally:
        kill_9(first)
    outlived = [pid for pid in workers if not wait_gone(pid, 15)]
    for pid in outlived:  # (leave no process behind)
        os.kill(pid, signal.SIGTERM)
    assert not outlived, "a worker outlived its devsim up"
    assert not any(os.path.lexists(link) for link in links)  # they stopped as on Ctrl-C
    left = list(Path(tempfile.gettempdir()).glob(f"devsim-workers-{first.proc.pid}-*"))
    assert left  # (the workers' plant files: nobody could remove them at the kill)
    again = serving(*command, ready=("axis0: ready", "axis1: ready"))
    assert not any(path.exists() for path in left)  # the next start swept them
    try:
        for n, link in enumerate(links):
            assert ask(link, "#P1019?\r") == f"#P1019?\rP1019={60 + n}U/min\n\r\nok1\n\r".encode()
    finally:
        assert again.interrupt() == exits.OK
