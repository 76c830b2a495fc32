"""Out of file descriptors: one line per cause, refused hosts told at once, the rest served.

Each test runs devsim in a child process with a low ``ulimit -n`` (RLIMIT_NOFILE)."""

from __future__ import annotations

import json
import os
import queue
import resource
import select
import socket
import subprocess
import sys
from pathlib import Path

import pytest

from devsim.transports import fdlimit
from tests.support.process import collect_lines, next_match, wait_until

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
    assert fdlimit.capacity(1024) == (1024 - fdlimit.BASE_FDS - 256) // 2  # (the control clients' share kept)
    assert fdlimit.capacity(1024, control=False) == (1024 - fdlimit.BASE_FDS) // 2
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


def test_up_promises_no_port_that_the_control_clients_take(tmp_path: Path) -> None:
    """Under ``ulimit -n 256`` ``devsim up`` serves the ports it says fit beside the control
    server's bound of clients (a quarter of the limit, 64): with every one of those clients
    connected, a host on every port is served.  Before, the port budget did not keep that share:
    108 ports opened, and with 64 idle clients the hosts of 32 of them were refused (or, hosts
    first, 32 clients)."""
    limit = 256
    plant = tmp_path / "plant.yaml"
    plant.write_text(
        "devices:\n" + "".join(f"  - {{name: e{i}, kind: echo, transport: {{tcp: {{port: 0}}}}}}\n" for i in range(120))
    )
    control = tmp_path / "c.sock"
    proc = subprocess.Popen(
        [sys.executable, "-m", "devsim", "up", str(plant), "--control", f"unix:{control}"],
        cwd=ROOT, env=_env(), stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
        text=True, preexec_fn=_limit(limit),
    )
    out, err = collect_lines(proc.stdout), collect_lines(proc.stderr)
    bound = fdlimit.client_bound(limit)
    clients: list[socket.socket] = []
    hosts: list[socket.socket] = []
    try:
        said = next_match(err, lambda text: "allows about" in text, 30, "the limit line")
        assert said == f"devsim: the file descriptor limit {limit} allows about {fdlimit.capacity(limit)} ports"
        ports: list[str] = []
        while not (line := next_match(out, lambda text: ": tcp " in text or text.startswith("control: "), 30,
                                      "the port lines")).startswith("control: "):
            ports.append(line.split()[-1].removeprefix("socket://"))
        assert 0 < len(ports) <= fdlimit.capacity(limit) < 120
        for _ in range(bound):  # every control client the server serves, each answered and kept
            client = socket.socket(socket.AF_UNIX)
            client.settimeout(5)
            client.connect(str(control))
            clients.append(client)
            client.sendall(b'{"id": 1, "op": "now"}\n')
            assert json.loads(client.makefile("rb").readline())["ok"] is True
        echoed = 0
        for where in ports:  # and a host on every port it opened
            host, port = where.rsplit(":", 1)
            device = socket.create_connection((host, int(port)), timeout=5)
            hosts.append(device)
            try:
                device.sendall(b"ping")
                echoed += device.recv(4) == b"ping"
            except ConnectionResetError:
                pass  # (refused: out of descriptors)
        assert echoed == len(ports)
    finally:
        for sock in clients + hosts:
            sock.close()
        proc.terminate()
        proc.wait(20)
    rest = []
    while (text := err.get(timeout=10)) is not None:
        rest.append(text)
    assert not [text for text in rest if "descriptors" in text and "not opened" not in text], rest


def _echo_under_limit(control: Path, limit: int) -> tuple[subprocess.Popen[str], queue.Queue[str | None], queue.Queue[str | None]]:
    """``devsim run echo --tcp 0`` with its control server at ``control`` and at most ``limit``
    descriptors, and its stdout and stderr lines."""
    proc = subprocess.Popen(
        [sys.executable, "-m", "devsim", "run", "echo", "--tcp", "0", "--control", f"unix:{control}"],
        cwd=ROOT, env=_env(), stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
        text=True, preexec_fn=_limit(limit),
    )
    return proc, collect_lines(proc.stdout), collect_lines(proc.stderr)


def test_a_run_out_of_descriptors_by_control_clients_says_so_in_one_line(tmp_path: Path) -> None:
    """Idle control clients take every descriptor of a plain ``devsim run`` (which has not asked
    its limit at start): the accept that fails is reported in one line, and when they leave the
    port serves again.  Before, the report's ``import resource`` could not open its file either:
    'Unhandled error in exception handler', an ImportError traceback for every failed accept
    (1.4 MB of stderr in four seconds)."""
    control = tmp_path / "c.sock"
    proc, out, err = _echo_under_limit(control, 48)
    clients: list[socket.socket] = []
    seen: list[str] = []
    try:
        line = next_match(out, lambda text: ": tcp " in text, 30, "the port line")
        host, port = line.split()[-1].removeprefix("socket://").rsplit(":", 1)
        for _ in range(60):  # more than the limit leaves (they wait in the listen backlog)
            client = socket.socket(socket.AF_UNIX)
            client.settimeout(5)
            client.connect(str(control))
            clients.append(client)
        said = next_match(err, lambda text: "descriptors" in text or "Traceback" in text or "rror" in text, 10,
                          "the report", seen)
        assert said.startswith("devsim: out of file descriptors (limit 48)"), said
        for client in clients:
            client.close()

        def echoes() -> bool:
            with socket.create_connection((host, int(port)), timeout=5) as device:
                try:
                    device.sendall(b"ping")
                    return device.recv(4) == b"ping"
                except ConnectionResetError:
                    return False  # refused (shed) while the closes are still being seen

        wait_until(echoes, "the port serving again", 10.0, 0.1)
    finally:
        for client in clients:
            client.close()
        proc.terminate()
        proc.wait(20)
    while (rest := err.get(timeout=10)) is not None:
        seen.append(rest)
    assert not [text for text in seen if "Traceback" in text or "Unhandled" in text]
    assert len("\n".join(seen)) < 2000


def test_idle_control_clients_leave_the_device_its_descriptors(tmp_path: Path) -> None:
    """Under ``ulimit -n 128`` the control server serves a quarter of the limit at once (32,
    docs/control.md); the next client gets the one ``Busy`` line, and the device's TCP port still
    serves a host.  Before, the bound was 256 whatever the limit: idle clients were served until
    the descriptors ran out, and the device's hosts were refused."""
    control = tmp_path / "c.sock"
    proc, out, err = _echo_under_limit(control, 128)
    clients: list[socket.socket] = []
    try:
        line = next_match(out, lambda text: ": tcp " in text, 30, "the port line")
        host, port = line.split()[-1].removeprefix("socket://").rsplit(":", 1)
        next_match(out, lambda text: text.startswith("control: "), 30, "the control line")
        answer = b""
        while len(clients) <= 128:  # each client asks once and stays; until one is not served
            client = socket.socket(socket.AF_UNIX)
            client.settimeout(5)
            client.connect(str(control))
            clients.append(client)
            client.sendall(b'{"id": 1, "op": "now"}\n')
            try:
                answer = client.makefile("rb").readline()
            except TimeoutError:  # (not even accepted: the descriptors ran out)
                answer = b""
            if not answer or json.loads(answer)["ok"] is not True:
                break
        assert len(clients) == 33, answer
        assert json.loads(answer) == {"id": None, "ok": False, "type": "Busy",
                                      "error": "the simulator serves at most 32 control connections at once"}
        with socket.create_connection((host, int(port)), timeout=10) as device:  # the port's host
            device.sendall(b"ping")
            assert device.recv(4) == b"ping"
    finally:
        for client in clients:
            client.close()
        proc.terminate()
        proc.wait(20)
    said = []
    while (rest := err.get(timeout=10)) is not None:
        said.append(rest)
    assert [text for text in said if "control" in text] == [
        f"devsim: control unix:{control}: refused a connection, 32 are open"], said
