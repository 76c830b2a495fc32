"""kill -9 in the middle of a DNC download leaves the stored programs intact (issue: "kill -9
during a download leaves the stored programs intact"), and the blocks committed before it
(spec §3.5.3: blocks read before a failure stay)."""

from __future__ import annotations

import signal
import time
from pathlib import Path

import serial

from devsim.devices.poselesta.codes import encode
from devsim.runtime.client import ControlClient
from tests.test_cli import Sim


def _start(state: Path, sock: Path) -> tuple[Sim, dict[str, str]]:
    sim = Sim("poselesta", "--pty", "--state-dir", str(state), "--control", f"unix:{sock}",
              "--config", str(state.parent / "fast.yaml"))
    return sim, sim.read_until("poselesta: ready")


def test_kill_during_a_download(tmp_path: Path) -> None:
    state, sock = tmp_path / "state", tmp_path / "ctl.sock"
    state.mkdir()
    (tmp_path / "fast.yaml").write_text("boot_time: 0\n")
    sim, seen = _start(state, sock)
    try:
        ctl = ControlClient(f"unix:{sock}")
        ctl.set("poselesta", "program.P01", "N1 X1\nN2 Y2")
        ctl.set("poselesta", "panel.mode", "EXTERNAL_OPERATION")
        ctl.set("poselesta", "panel.program", 5)
        ctl.set("poselesta", "v7.transfer", "input")
        with serial.Serial(seen["poselesta.v7"].split()[1], 1200, stopbits=2, timeout=5) as dnc:
            dnc.write(encode("%\r\n" + "".join(f"N{n} X{n}\r\n" for n in range(1, 41)), iso=True))
            deadline = time.monotonic() + 10
            while ctl.read("poselesta", "v7.blocks") < 40:
                assert time.monotonic() < deadline, "the blocks arrive"
            ctl.close()
            sim.proc.send_signal(signal.SIGKILL)  # mid-transfer: no M30 yet
            sim.proc.wait(timeout=15)
    finally:
        sim.stop()
    sim, _ = _start(state, sock)
    try:
        ctl = ControlClient(f"unix:{sock}")
        assert ctl.read("poselesta", "program.P01") == "N 1 X 1.000\nN 2 Y 2.000"
        assert ctl.read("poselesta", "programs") == [1, 5]
        assert ctl.read("poselesta", "program.P05").count("\n") == 39  # the 40 committed blocks
        ctl.close()
    finally:
        code, err = sim.stop()
    assert code == 0 and "Traceback" not in err
