"""CAN for hosts in other processes (issue 13): the socketcand server bridges a python-can virtual
bus, and canopen as the master in another process (python-can's socketcand client) reads the
node's identity and a point over SDO, writes a point, and sees the heartbeat."""

from __future__ import annotations

import subprocess
import sys
import uuid
from pathlib import Path

import can
import canopen

from devsim.core.runtime import Runtime
from devsim.facades.canopen_node import CanopenFacade
from devsim.transports.socketcand import SocketcandServer, frame_text, parse_send

ROOT = Path(__file__).resolve().parents[2]
MASTER = """
import sys, canopen
net = canopen.Network()
net.connect(interface="socketcand", host="127.0.0.1", port=int(sys.argv[1]), channel="can0")
node = net.add_node(5, sys.argv[2])
print(hex(node.sdo[0x1000].raw))
print(node.sdo["quantity.supply_voltage"].raw)
node.sdo["quantity.supply_voltage"].raw = 52.5
node.sdo[0x1017].raw = 100
print(node.nmt.wait_for_heartbeat(5))
net.disconnect()
"""


def test_the_protocol_texts() -> None:
    message = can.Message(arbitration_id=0x605, data=bytes((0x40, 0x00, 0x10, 0x00)), is_extended_id=False)
    message.timestamp = 12.5
    assert frame_text(message) == b"< frame 605 12.500000 40001000 >"
    sent = parse_send("< send 605 4 40 0 10 0 >")
    assert sent is not None and sent.arbitration_id == 0x605 and bytes(sent.data) == bytes((0x40, 0, 0x10, 0))
    assert parse_send("< send 605 9 1 2 >") is None and parse_send("< hi >") is None


def test_canopen_master_in_another_process() -> None:
    channel = f"devsim-{uuid.uuid4().hex}"
    runtime = Runtime().start()
    slave = canopen.Network()
    slave.connect(interface="virtual", channel=channel)
    server = SocketcandServer(channel, port=0)
    try:
        device = runtime.add_device("sers", "sers", {})
        CanopenFacade(device, 5, call=runtime.call).attach(slave)
        runtime.run(server.start())
        done = subprocess.run([sys.executable, "-c", MASTER, str(server.port), str(ROOT / "docs" / "eds" / "sers.eds")],
                              capture_output=True, text=True, timeout=60, stdin=subprocess.DEVNULL, check=False)
        assert done.returncode == 0, done.stderr
        assert done.stdout.split() == ["0x20192", "68.0", "PRE-OPERATIONAL"]
        assert runtime.read("sers", "quantity.supply_voltage") == 52.5
    finally:
        runtime.run(server.close())
        slave.disconnect()
        runtime.stop()


def test_devsim_run_serves_a_canopen_node() -> None:
    from tests.test_cli import Sim

    sim = Sim("sers", "--pty", "--canopen", "7@127.0.0.1:0")
    try:
        seen = sim.read_until("sers.canopen:")
        kind, where, interface, _node, number = seen["sers.canopen"].split()
        assert (kind, interface, number) == ("socketcand", "can0", "7")
        host, _, port = where.rpartition(":")
        network = canopen.Network()
        network.connect(interface="socketcand", host=host, port=int(port), channel="can0")
        try:
            node = network.add_node(7, str(ROOT / "docs" / "eds" / "sers.eds"))
            assert node.sdo[0x1008].raw == "devsim sers"
            assert node.sdo["quantity.supply_voltage"].raw == 68.0
        finally:
            network.disconnect()
    finally:
        sim.stop()


def _vcan0() -> bool:
    """Whether this machine has a SocketCAN interface vcan0 (most CI machines have no PF_CAN)."""
    import socket

    try:
        with socket.socket(socket.PF_CAN, socket.SOCK_RAW, socket.CAN_RAW) as sock:
            sock.bind(("vcan0",))
    except (AttributeError, OSError):
        return False
    return True


def test_devsim_run_on_socketcan_serves_vcan0_or_says_why_not() -> None:
    """``--canopen NODE@socketcan:vcan0``: where vcan0 exists, canopen reads the node's identity
    over SocketCAN; where it does not (this project's CI machine has no PF_CAN), devsim refuses to
    start with one line that names the interface."""
    import subprocess
    import sys

    command = [sys.executable, "-m", "devsim", "run", "sers", "--pty", "--canopen", "8@socketcan:vcan0"]
    if not _vcan0():
        done = subprocess.run(command, capture_output=True, text=True, timeout=60, stdin=subprocess.DEVNULL)
        assert done.returncode != 0
        assert "cannot serve CANopen" in done.stderr and "SocketCAN 'vcan0' cannot be opened here" in done.stderr
        assert "Traceback" not in done.stderr
        return
    from tests.test_cli import Sim

    sim = Sim("sers", "--pty", "--canopen", "8@socketcan:vcan0")
    try:
        assert sim.read_until("sers.canopen:")["sers.canopen"] == "socketcan vcan0 node 8"
        network = canopen.Network()
        network.connect(interface="socketcan", channel="vcan0")
        try:
            node = network.add_node(8, str(ROOT / "docs" / "eds" / "sers.eds"))
            assert node.sdo[0x1008].raw == "devsim sers"
        finally:
            network.disconnect()
    finally:
        sim.stop()
