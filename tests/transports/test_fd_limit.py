"""Out of file descriptors: one line per cause, refused hosts told at once, the rest served.

Each test runs devsim in a child process with a low ``ulimit -n`` (RLIMIT_NOFILE)."""

from __future__ import annotations

import os
import resource
import select
import socket
import subprocess
import sys
from pathlib import Path

import pytest

from devsim.transports import fdlimit

ROOT = Path(__file__).resolve().parents[2]
pytestmark = pytest.mark.skipif(os.name != "posix", reason="rlimits")


def _limit(n: int):  # noqa: ANN202 - a preexec_fn
    def apply() -> None:
        _soft, hard = resource.getrlimit(resource.RLIMIT_NOFILE)
        resource.setrlimit(resource.RLIMIT_NOFILE, (n, hard))

    return apply


def _env() -> dict[str, str]:
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(p for p in (str(ROOT), env.get("PYTHONPATH", "")) if p)
    env["DEVSIM_EXTRA_KINDS"] = "echo=tests.support.echo:EchoDevice"
    return env


def test_capacity_and_rate_limited_reports(capsys: pytest.CaptureFixture[str]) -> None:
    assert fdlimit.capacity(1024) == (1024 - fdlimit.BASE_FDS) // 2
    assert fdlimit.report("test-cause", "first")
    assert not fdlimit.report("test-cause", "second")  # within ten seconds: counted, not printed
    assert not fdlimit.report("test-cause", "third")
    assert capsys.readouterr().err == "devsim: first\n"


def test_up_serves_what_fits_and_says_what_does_not(tmp_path: Path) -> None:
    count = 80
    plant = tmp_path / "plant.yaml"
    plant.write_text(
        "devices:\n" + "".join(f"  - {{name: e{i}, kind: echo, transport: {{tcp: {{port: 0}}}}}}\n" for i in range(count))
    )
    proc = subprocess.Popen(
        [sys.executable, "-m", "devsim", "up", str(plant)],
        cwd=ROOT, env=_env(), stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
        text=True, preexec_fn=_limit(64),
    )
    try:
        assert proc.stdout is not None and proc.stderr is not None
        first = proc.stderr.readline()
        assert first == f"devsim: the file descriptor limit 64 allows about {fdlimit.capacity(64)} ports\n"
        refused = proc.stderr.readline()
        assert refused.startswith("devsim: ") and "ports not opened (not enough file descriptors left; ulimit -n 64)" in refused
        served = []
        while len(served) < 3:
            line = proc.stdout.readline()
            assert line, proc.stderr.read()
            if ": tcp " in line:
                served.append(line.split()[-1])
        host, port = served[0].removeprefix("socket://").rsplit(":", 1)
        hosts = []
        for _ in range(64):  # more hosts than descriptors are left: the surplus is refused at once
            hosts.append(socket.create_connection((host, int(port)), timeout=5))
        hosts[0].sendall(b"ping")
        assert hosts[0].recv(4) == b"ping"  # the first host is served
        # refused hosts see their connection closed instead of hanging (the others wait their
        # turn behind the first host, as on a serial port)
        readable, _, _ = select.select(hosts[1:], [], [], 10)
        assert readable and all(sock.recv(1) == b"" for sock in readable)
        for sock in hosts:
            sock.close()
    finally:
        proc.terminate()
        _out, err = proc.communicate(timeout=20)
    assert "Traceback" not in err and len(err) < 2000
