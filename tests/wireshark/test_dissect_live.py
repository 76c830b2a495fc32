"""Live and decoded: ``devsim wireshark --install`` (the dissectors and the extcap), a running
``devsim run gms96``, and tshark capturing its pty through the extcap interface with devsim's
dissectors loaded from the plugins folder: the fields of a T5;15 query and its answer as the
host sends and receives them."""

from __future__ import annotations

import subprocess
import sys
import time
from pathlib import Path

import serial

from devsim.devices.gms96.client import Gms96Client
from devsim.runtime.client import ControlClient
from tests.support.process import ROOT, devsim_env
from tests.support.programs import needs_program
from tests.test_cli import Sim
from tests.wireshark.test_capture import end_session, tshark_env
from tests.wireshark.test_dissect_gms96 import ADDRESS


def test_a_live_capture_decodes_with_the_installed_dissectors(tmp_path: Path) -> None:
    tshark = needs_program("tshark")
    env = {**tshark_env(tmp_path / "home"), "PYTHONPATH": devsim_env()["PYTHONPATH"]}
    installed = subprocess.run([sys.executable, "-m", "devsim", "wireshark", "--install"], capture_output=True,
                               text=True, timeout=120, env=env, cwd=ROOT, check=False)
    assert installed.returncode == 0, installed.stderr
    sim = Sim("gms96")
    try:
        seen = sim.read_until("control:")
        sim.read_until("gms96: ready")  # booted: a frame before that gets no answer
        pty = seen["gms96"].split()[-1]
        capture = subprocess.Popen([tshark, "-l", "-i", f"devsim-{sim.proc.pid}-gms96", "-c", "2", "-T", "fields",
                                    "-e", "devsim.dir", "-e", "gms96.command", "-e", "gms96.n", "-e", "gms96.value"],
                                   env=env, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                   text=True, start_new_session=True)  # dumpcap and the extcap end with it
        try:
            with ControlClient(seen["control"]) as control:
                deadline = time.monotonic() + 60
                while not control.line("gms96")["capturing"]:
                    assert capture.poll() is None and time.monotonic() < deadline, "the capture never started"
            with serial.Serial(pty, 9600, timeout=5) as port:
                assert Gms96Client(port, ADDRESS, timeout=5).read(5, 15)[1] == 84  # N15's default
            stdout, stderr = capture.communicate(timeout=60)
        finally:
            end_session(capture)
        assert capture.returncode == 0 and "Lua" not in stderr, stderr
    finally:
        code, err = sim.stop()
    assert code == 0, err
    assert [line.split("\t") for line in stdout.splitlines()] == [["0", "T", "15", ""], ["1", "", "15", "84"]]
