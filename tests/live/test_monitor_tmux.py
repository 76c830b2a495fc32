"""`devsim monitor` in a real terminal: tmux runs it against a `devsim run` subprocess; keys go
in with send-keys, the screen comes back with capture-pane."""

from __future__ import annotations

import re
import subprocess
import sys
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path

from tests.support.programs import needs_program

from .run import Proc, ctl
from .tmux import screen_until, terminal, tmux


@contextmanager
def monitor(addr: str) -> Iterator[str]:
    """``devsim monitor --control ADDR`` in a tmux session (its name)."""
    needs_program("tmux")
    with terminal([sys.executable, "-m", "devsim", "monitor", "--control", addr]) as session:
        yield session


_CLOCK = re.compile(r"t = (\d+\.\d{3}) s · (\d\d:\d\d:\d\d)")


def _clock(session: str, after: Callable[[float, str], bool], timeout: float = 20.0) -> tuple[float, str]:
    """The header's clock (device time, wall time) once ``after`` accepts it."""
    deadline = time.monotonic() + timeout
    while True:
        screen = tmux("capture-pane", "-p", "-t", session)
        match = _CLOCK.search(screen)
        if match and after(float(match[1]), match[2]):
            return float(match[1]), match[2]
        if time.monotonic() > deadline:
            raise AssertionError(f"the clock did not get there:\n{screen}")
        time.sleep(0.1)  # polling the screen (bounded by the deadline), not a synchronisation sleep


def test_monitor_clock_ticks_while_nothing_changes(tmp_path: Path) -> None:
    """A real-time SERS at rest after its boot: no point changes, yet the header's device time
    and wall time go on, once a second."""
    sim = Proc("run", "sers", "--tcp", "0", "--control", f"unix:{tmp_path}/ctl.sock")
    try:
        addr = sim.expect(lambda line: line.startswith("control: ")).split()[-1]
        with monitor(addr) as session:
            screen_until(session, "event ready")  # booted (at 2 s): at rest from here on
            first, wall = _clock(session, lambda t, _: t >= 2.0)
            _later, later_wall = _clock(session, lambda t, _: t >= first + 2.0)
            assert later_wall != wall
            assert "event ready" in tmux("capture-pane", "-p", "-t", session)  # still at rest
    finally:
        sim.stop()


def test_monitor_in_tmux(tmp_path: Path) -> None:
    sim = Proc("run", "sers", "--tcp", "0", "--virtual", "--control", f"unix:{tmp_path}/ctl.sock")
    try:
        addr = sim.expect(lambda line: line.startswith("control: ")).split()[-1]
        ctl(addr, "advance", "3")
        with monitor(addr) as session:
            screen_until(session, "axis: pos 0.0")
            screen = screen_until(session, "faults: none")  # (a later pass of the same render, on a busy machine)
            assert "sers (sers)" in screen and "faults: none" in screen
            assert "display: 4   " in screen and '"char"' not in screen  # the 7-segment digit, not its JSON
            tmux("send-keys", "-t", session, "a")  # advance 0.1 s of virtual time
            deadline = time.monotonic() + 20
            while float(ctl(addr, "now").stdout) < 3.1:
                assert time.monotonic() < deadline, "the 'a' key did not advance time"
            tmux("send-keys", "-t", session, "f")
            screen_until(session, "sers: blocked_axis on")
            tmux("send-keys", "-t", session, "Enter")  # the first entry: blocked_axis on
            screen_until(session, "faults: blocked_axis")
            tmux("send-keys", "-t", session, "q")
            deadline = time.monotonic() + 20
            while session in subprocess.run(["tmux", "ls"], capture_output=True, text=True).stdout:
                assert time.monotonic() < deadline, "q did not end the monitor"
                time.sleep(0.1)
    finally:
        sim.stop()


def test_monitor_shows_each_kind_s_display_as_text(tmp_path: Path) -> None:
    """PCD4.H3's DP14 lines and POSELESTA's axis values and screen message, as the fronts show them."""
    plant = tmp_path / "plant.yaml"
    plant.write_text("devices:\n"
                     "  - {name: pcd, kind: pcd4h3, config: {display: {1: {reg1: RActP, reg2: RSetV}}}}\n"
                     "  - {name: cnc, kind: poselesta}\n", encoding="utf-8")
    sim = Proc("up", str(plant), "--virtual", "--control", f"unix:{tmp_path}/ctl.sock")
    try:
        addr = sim.expect(lambda line: line.startswith("control: ")).split()[-1]
        ctl(addr, "advance", "3")
        assert ctl(addr, "fault", "cnc", "monitoring", "on").returncode == 0  # "Fehlermeldung" on its screen
        with monitor(addr) as session:
            screen = screen_until(session, "message: Fehlermeldung")
            assert "display: axis.1 [       /      0]" in screen  # DP14's two lines of six, blanks kept
            assert "display: axis.x 0.000  axis.y 0.000  axis.z 0.000  axis.d 0.000" in screen
            assert '["' not in screen and "panel.message=" not in screen  # no JSON, no message among the values
    finally:
        sim.stop()
