"""``devsim ctl line-fault`` requests in a row (docs/control.md): a fault turned on again replaces
the one of its kind and direction, so a line does not gather faults without bound; they piled
up, and every noise tick and byte walked them all (800 ``noise on`` took the whole CPU).
Real subprocesses: ``devsim run sers`` and its control socket."""

from __future__ import annotations

import json
import tempfile

from devsim.runtime.client import ControlClient
from tests.test_cli import Sim, ctl


def test_line_fault_requests_in_a_row_keep_one_fault_per_kind_and_direction() -> None:
    sockdir = tempfile.TemporaryDirectory(prefix="dsl")  # a unix socket's path is short
    addr = f"unix:{sockdir.name}/ctl.sock"
    sim = Sim("sers", "--pty", "--control", addr)
    try:
        sim.read_until("control:")
        with ControlClient(addr) as client:
            for rate in range(1, 201):
                client.line_fault("sers", "noise", True, rate=float(rate))
                client.line_fault("sers", "corrupt", True, count=1, direction="to_device")
            client.line_fault("sers", "noise", True, rate=3.0, direction="to_host")
        line = json.loads(ctl(addr, "--json", "line", "sers").stdout)
        assert sorted(line["faults"]) == ["corrupt", "noise", "noise"]
        done = ctl(addr, "line-fault", "sers", "noise", "off")
        assert done.returncode == 0, done.stderr
        line = json.loads(ctl(addr, "--json", "line", "sers").stdout)
        assert line["faults"] == ["corrupt"]
    finally:
        sim.stop()
        sockdir.cleanup()
