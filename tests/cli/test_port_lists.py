"""``--port`` of ``devsim ctl line``, ``line-fault``, ``telegrams`` and ``capture``: a port the
device does not have is one error line listing every port the command takes, the Modbus RTU
line ``modbus`` among them when the device serves one (it listed the device's own ports only).
Real subprocesses: ``devsim run sers --modbus rtu`` and ``devsim ctl``."""

from __future__ import annotations

import tempfile

import pytest

from tests.test_cli import Sim, ctl

COMMANDS = [["line", "sers"], ["line-fault", "sers", "noise", "on", "--rate", "10"], ["telegrams", "sers"],
            ["capture", "sers"]]


@pytest.mark.parametrize("modbus", [True, False])
def test_an_unknown_port_names_every_port_the_command_takes(modbus: bool) -> None:
    sockdir = tempfile.TemporaryDirectory(prefix="dsl")  # a unix socket's path is short
    addr = f"unix:{sockdir.name}/ctl.sock"
    sim = Sim("sers", "--pty", *(["--modbus", "rtu"] if modbus else []), "--control", addr)
    try:
        sim.read_until("control:")
        for command in COMMANDS:
            done = ctl(addr, *command, "--port", "nope")
            assert done.returncode == 4, done.stderr
            assert done.stderr.count("\n") == 1, done.stderr
            ports = "main, modbus" if modbus else "main"
            assert done.stderr.endswith(f"sers has no port 'nope' (ports: {ports})\n"), (command, done.stderr)
            if modbus:  # (and the port it names is one the command takes)
                taken = ctl(addr, *command[:2], "--port", "modbus", *command[2:]) if command[0] != "capture" else None
                assert taken is None or taken.returncode == 0, (command, taken.stderr)
    finally:
        sim.stop()
        sockdir.cleanup()
