"""The control server's bound on connections (docs/control.md, ``MAX_CLIENTS``, fewer under a low
descriptor limit: ``client_bound``, tests/transports/test_fd_limit.py): idle clients
cannot take every descriptor the device's ports need; one more is one ``Busy`` error line.
Real subprocesses: ``devsim run sers`` and its control socket, ``devsim ctl``."""

from __future__ import annotations

import json
import socket
import tempfile

from devsim.runtime.client import ControlClient, ControlError
from devsim.runtime.control import client_bound
from tests.support.process import wait_until
from tests.test_cli import Sim, ctl


def _now(sock: socket.socket, reader: object) -> dict[str, object]:
    sock.sendall(b'{"id": 1, "op": "now"}\n')
    return json.loads(reader.readline())  # type: ignore[attr-defined]


def test_one_connection_more_than_max_clients_is_one_busy_line() -> None:
    bound = client_bound()  # (256 under the default limit of 1,024 descriptors; the simulator inherits ours)
    sockdir = tempfile.TemporaryDirectory(prefix="dsl")  # a unix socket's path is short
    addr = f"unix:{sockdir.name}/ctl.sock"
    sim = Sim("sers", "--pty", "--control", addr)
    held: list[socket.socket] = []
    err = ""
    try:
        sim.read_until("control:")
        for _ in range(bound):  # each one served (an answer on each)
            sock = socket.socket(socket.AF_UNIX)
            sock.connect(f"{sockdir.name}/ctl.sock")
            held.append(sock)
            assert _now(sock, sock.makefile("rb"))["ok"] is True
        try:
            with ControlClient(addr) as client:
                client.now()
            raise AssertionError("one connection more was served")
        except ControlError as exc:
            assert exc.type == "Busy"
            assert str(exc) == f"Busy: the simulator serves at most {bound} control connections at once"
        done = ctl(addr, "now")
        assert done.returncode == 5
        assert done.stderr == f"Error: Busy: the simulator serves at most {bound} control connections at once\n"
        held.pop().close()

        def served() -> bool:
            try:
                with ControlClient(addr) as client:
                    client.now()
            except ControlError:
                return False
            return True

        wait_until(served, "a connection served once one closed", timeout=10)
    finally:
        for sock in held:
            sock.close()
        _, err = sim.stop()
        sockdir.cleanup()
    refusals = [line for line in err.splitlines() if f"refused a connection, {bound} are open" in line]
    assert len(refusals) == 1, err  # (the second refusal within seconds is counted, not printed)
    assert "Traceback" not in err
