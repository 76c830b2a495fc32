"""CAN for hosts in other processes (issue 13): the socketcand server bridges a python-can virtual
bus, and canopen as the master in another process (python-can's socketcand client) reads the
node's identity and a point over SDO, writes a point, and sees the heartbeat."""

from __future__ import annotations

import contextlib
import itertools
import socket
import subprocess
import sys
import time
import uuid
from pathlib import Path

import can
import canopen

from devsim.facades.canopen_node import CanopenFacade
from devsim.runtime import Runtime
from devsim.transports.socketcand import SocketcandServer, frame_text, parse_send, split_commands
from tests.support.can import network as can_network

ROOT = Path(__file__).resolve().parents[2]
MASTER = """
import sys, canopen
net = canopen.Network()
net.NOTIFIER_CYCLE = 0.01  # (disconnect returns within 10 ms: tests/support/can.py)
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


def test_a_client_s_text_is_cut_into_commands_and_a_run_without_end_is_not_kept() -> None:
    """A client that sends text without a closing ``>`` costs at most 4,096 characters (the server
    kept all of it, and scanned all of it again for every chunk)."""
    assert split_commands("junk< open can0 >< rawmode >< se") == (["< open can0 >", "< rawmode >"], "< se")
    commands, rest = split_commands("x" * 1_000_000)
    assert commands == [] and rest == "x" * 4096
    assert split_commands(rest + "< send 605 0 >") == (["< send 605 0 >"], "")
    assert split_commands("< open" + "x" * 5000) == ([], "x" * 4096)  # (a command that long is none)


def test_canopen_master_in_another_process() -> None:
    channel = f"devsim-{uuid.uuid4().hex}"
    runtime = Runtime().start()
    slave = can_network()
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
        network = can_network()
        network.connect(interface="socketcand", host=host, port=int(port), channel="can0")
        try:
            node = network.add_node(7, str(ROOT / "docs" / "eds" / "sers.eds"))
            assert node.sdo[0x1008].raw == "devsim sers"
            assert node.sdo["quantity.supply_voltage"].raw == 68.0
        finally:
            network.disconnect()
    finally:
        sim.stop()


def test_a_client_still_connected_when_the_simulator_stops_leaves_no_traceback() -> None:
    """The server's close cancels the sessions still open; a session ends quietly.  (Before:
    asyncio's stream callback asked the cancelled task for its exception, and every client still
    connected left an 'Exception in callback ... CancelledError' traceback on stderr.)"""
    import socket

    from tests.test_cli import Sim

    sim = Sim("sers", "--pty", "--canopen", "7@127.0.0.1:0")
    try:
        seen = sim.read_until("sers.canopen:")
        host, _, port = seen["sers.canopen"].split()[1].rpartition(":")
        client = socket.create_connection((host, int(port)), timeout=5)
        assert client.recv(100) == b"< hi >"
        client.sendall(b"< open can0 >")
        assert client.recv(100) == b"< ok >"
        client.sendall(b"< rawmode >")
        assert client.recv(100).startswith(b"< ok >")
    finally:
        status, err = sim.stop()
    client.close()
    assert "Traceback" not in err and status == 0, err


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
        network = can_network()
        network.connect(interface="socketcan", channel="vcan0")
        try:
            node = network.add_node(8, str(ROOT / "docs" / "eds" / "sers.eds"))
            assert node.sdo[0x1008].raw == "devsim sers"
        finally:
            network.disconnect()
    finally:
        sim.stop()


def test_the_402_flow_with_the_master_in_another_process_under_virtual_time() -> None:
    """The issue's end-to-end check: ``devsim run pcd4h3 --virtual`` serves node 3 over socketcand,
    and this process is the master (canopen over python-can's socketcand client): it resets the
    node and sees the boot-up, reads the identity, drives 402 from Switch on disabled to Operation
    enabled, runs a profile-position move that completes at the LM628 triangle's closed-form 6.34 s
    (spec pcd4h3 §5.2; virtual time advanced through the control API), blocks the axis and sees
    EMCY 8611h and the Fault state, and resets the fault."""
    from devsim.runtime.client import ControlClient
    from tests.test_cli import Sim

    sim = Sim("pcd4h3", "--virtual", "--control", "127.0.0.1:0", "--canopen", "3@127.0.0.1:0",
              "--port", "ether_udp=udp:0", "--port", "ether_tcp=tcp:0")  # no fixed port 5050
    network = can_network()
    try:
        seen = sim.read_until("control:")
        kind, where, _, _, number = seen["pcd4h3.canopen"].split()
        assert (kind, number) == ("socketcand", "3")
        host, _, port = where.rpartition(":")
        network.connect(interface="socketcand", host=host, port=int(port), channel="can0")
        node = network.add_node(3, str(ROOT / "docs" / "eds" / "pcd4h3.eds"))
        with ControlClient(seen["control"]) as control:
            import queue

            bootups: queue.Queue[bytes] = queue.Queue()
            network.subscribe(0x703, lambda can_id, data, timestamp: bootups.put(bytes(data)))
            node.nmt.send_command(0x81)  # reset node
            assert bootups.get(timeout=5) == b"\x00"  # the boot-up message
            identity = canopen.import_od(str(ROOT / "docs" / "eds" / "pcd4h3.eds"))[0x1018]
            assert node.sdo[0x1018][2].raw == identity[2].default != 0  # product code, as the EDS says
            assert node.sdo[0x1018][3].raw == identity[3].default  # revision
            assert node.sdo[0x1008].raw == "devsim pcd4h3"
            assert node.sdo[0x6041].raw & 0x4F == 0x40  # Switch on disabled
            for word, state in ((0x06, 0x21), (0x07, 0x23), (0x0F, 0x27)):
                node.sdo[0x6040].raw = word
                assert node.sdo[0x6041].raw & 0x6F == state
            node.sdo[0x6060].raw = 1
            node.sdo[0x607A].raw = 100_000  # counts: 100 mm with k = 100
            node.sdo[0x6081].raw = 50_000  # counts/s: the 6.34 s triangle
            node.sdo[0x6040].raw = 0x1F
            node.sdo[0x6040].raw = 0x0F
            control.advance(6.30)  # the closed form: 6.34 s
            assert not control.read("pcd4h3", "axis.1.status") & 0x04  # trajectory not yet complete
            control.advance(0.08)
            assert control.read("pcd4h3", "axis.1.status") & 0x04
            control.advance(0.5)
            assert node.sdo[0x6041].raw & 0x0400 and abs(node.sdo[0x6064].raw - 100_000) <= 3
            node.sdo[0x607A].raw = 0
            node.sdo[0x6040].raw = 0x1F
            control.advance(1.0)
            control.fault("pcd4h3", "blocked_1", True)
            control.advance(3.0)
            deadline = time.monotonic() + 5
            while not [e for e in node.emcy.log if e.code == 0x8611] and time.monotonic() < deadline:
                node.emcy.wait(0x8611, timeout=0.05)
            assert [e for e in node.emcy.log if e.code == 0x8611]
            assert node.sdo[0x6041].raw & 0x4F == 0x08  # Fault
            control.fault("pcd4h3", "blocked_1", False)
            node.sdo[0x6040].raw = 0x80  # fault reset
            assert node.sdo[0x6041].raw & 0x4F == 0x40
    finally:
        network.disconnect()
        sim.stop()


def test_resets_and_short_sdo_requests_neither_stop_the_node_nor_flood_stderr() -> None:
    """Clients that send junk and reset the connection, then 300 SDO requests shorter than eight
    bytes: each reset used to end the socketcand session in an unhandled ConnectionResetError (a
    14-line traceback), and canopen logged a traceback for each short request.  Now stderr gets
    one line per kind of message every ten seconds, and the node still answers the next upload."""
    import socket
    import struct

    from tests.support.process import DevsimProcess

    sim = DevsimProcess("run", "sers", "--pty", "--canopen", "7@127.0.0.1:0")
    try:
        line = sim.next_match(sim.out, lambda text: text.startswith("sers.canopen:"), 30, "the CANopen line")
        host, _, port = line.split()[2].rpartition(":")
        for _ in range(20):
            client = socket.create_connection((host, int(port)), timeout=5)
            client.sendall(b"junk <<< >")
            client.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))
            client.close()  # (with linger 0: a reset)
        with socket.create_connection((host, int(port)), timeout=5) as raw:
            received = b""
            for command, reply in ((b"", b"< hi >"), (b"< open can0 >", b"< ok >"), (b"< rawmode >", b"< ok >")):
                raw.sendall(command)
                while reply not in received:
                    received += raw.recv(4096)
                received = b""
            raw.sendall(b"< send 607 1 40 >" * 150 + b"< send 607 2 40 00 >" * 150)
            raw.sendall(b"< send 607 8 40 00 10 00 00 00 00 00 >")  # upload 1000h: the device type
            while b"< frame 587" not in received or b" 43001000" not in received:
                chunk = raw.recv(65536)
                assert chunk, "the server closed the connection"
                received += chunk
    finally:
        sim.interrupt()
    errors = sim.rest_of_err()
    assert not any("Traceback" in text for text in errors), errors[:20]
    assert sum("canopen:" in text for text in errors) <= 4, errors


def _raw_client(port: int, receive_buffer: int | None = None) -> socket.socket:
    """A TCP client of the socketcand server in raw mode (``receive_buffer``: its SO_RCVBUF)."""
    client = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    if receive_buffer is not None:
        client.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, receive_buffer)
    client.settimeout(10)
    client.connect(("127.0.0.1", port))
    received = b""
    for command, reply in ((b"", b"< hi >"), (b"< open can0 >", b"< ok >"), (b"< rawmode >", b"< ok >")):
        client.sendall(command)
        while reply not in received:
            received += client.recv(100)
        received = b""
    return client


def test_a_client_that_does_not_read_costs_a_bounded_queue_and_a_reader_gets_every_frame() -> None:
    """One raw-mode client never reads, another floods 20,000 frames, a third reads them: the
    frames kept for the one that does not read never exceed its queue's limit (the rest are dropped
    for it alone), and the reader receives every frame in order.  (Before: the session kept every
    frame for a client that does not read, in an unbounded queue: devsim run sers --canopen grew
    from 37 to 173 MB in 25 s.)  The flood goes in chunks of 100, each sent when the reader has the
    one before, so the reader is never slow."""
    import re

    channel = f"devsim-{uuid.uuid4().hex}"
    runtime = Runtime().start()
    slave = can_network()
    slave.connect(interface="virtual", channel=channel)
    server = SocketcandServer(channel, port=0, client_queue=100)
    clients: list[socket.socket] = []
    try:
        CanopenFacade(runtime.add_device("sers", "sers", {}), 5, call=runtime.call).attach(slave)
        runtime.run(server.start())
        idle = _raw_client(server.port, receive_buffer=4096)
        reader, flooder = _raw_client(server.port), _raw_client(server.port)
        clients += [idle, reader, flooder]
        idle_queue = server.queues[0]
        frame = re.compile(rb"< frame 123 \d+\.\d+ ([0-9A-F]{8}) >")
        seen: list[int] = []
        text = b""
        for start in range(0, 20_000, 100):
            flooder.sendall(b"".join(b"< send 123 4 %X %X %X %X >" % tuple(n.to_bytes(4, "big"))
                                     for n in range(start, start + 100)))
            while len(seen) < start + 100:
                chunk = reader.recv(65536)
                assert chunk, "the server closed the reader's connection"
                text += chunk
                frames = frame.findall(text)
                seen += [int(data, 16) for data in frames]
                text = text[text.rfind(b">") + 1:] if frames else text
        assert seen == list(range(20_000))
        assert idle_queue.peak <= 100 and len(idle_queue) <= 100
        assert idle_queue.dropped > 0  # (it did fill up: more came than the idle client's socket takes)
        assert server.queues[1].dropped == 0, idle_queue.dropped
        reader.sendall(b"< send 605 8 40 00 10 00 00 00 00 00 >")  # the node still answers: device type
        while b"< frame 585 " not in text or b" 43001000" not in text:
            chunk = reader.recv(65536)
            assert chunk, "the server closed the reader's connection"
            text += chunk
    finally:
        for client in clients:
            client.close()
        runtime.run(server.close())
        slave.disconnect()
        runtime.stop()


def test_a_client_that_sends_faster_than_the_node_answers_is_held_back_and_gets_every_answer() -> None:
    """A raw-mode client sends 4,000 SDO uploads at once: the node's queue on the bus never holds
    more than BUS_BACKLOG frames and one read's worth (the session stops reading the client while
    it is longer), and the client gets an answer for every request, in order.  (Before: the
    session put every frame on the bus as it came, and the node's queue grew without bound: 18,896
    frames after 10 s of such a flood.)  4,000 answers fit the client's own queue even if it read
    none of them before the last request."""
    import re
    import threading

    from devsim.transports.socketcand import BUS_BACKLOG, CLIENT_QUEUE

    requests = 4_000
    assert requests <= CLIENT_QUEUE
    channel = f"devsim-{uuid.uuid4().hex}"
    runtime = Runtime().start()
    slave = can_network()
    slave.connect(interface="virtual", channel=channel)
    server = SocketcandServer(channel, port=0)
    client: socket.socket | None = None
    try:
        CanopenFacade(runtime.add_device("sers", "sers", {}), 5, call=runtime.call).attach(slave)
        runtime.run(server.start())
        client = _raw_client(server.port)
        request = b"< send 605 8 40 %X 10 00 00 00 00 00 >"  # upload 1000h (device type), then 1001h
        flood = b"".join(request % (n % 2) for n in range(requests))
        sender = threading.Thread(target=client.sendall, args=(flood,))
        sender.start()
        answer = re.compile(rb"< frame 585 \d+\.\d+ ([0-9A-F]+) >")
        answers: list[bytes] = []
        text = b""
        while len(answers) < requests:
            chunk = client.recv(65536)
            assert chunk, "the server closed the connection"
            text += chunk
            found = answer.findall(text)
            answers += found
            text = text[text.rfind(b">") + 1:] if found else text
        sender.join()
        assert answers == [b"4300100092010200", b"4F01100000000000"] * (requests // 2)
        read = 4096 // len(request % 0) + 1  # the requests in one read of the session (and one begun before)
        assert server.backlog_peak <= BUS_BACKLOG + read, server.backlog_peak
    finally:
        if client is not None:
            client.close()
        runtime.run(server.close())
        slave.disconnect()
        runtime.stop()


def test_sigterm_during_a_flood_stops_the_simulator() -> None:
    """``devsim run --canopen`` with a raw-mode client that does not read and one that floods: a
    SIGTERM sent during the flood stops it, status 0, no traceback.  (Before: every frame woke the
    event loop through its self-pipe, the pipe was full, and the signal's byte was lost: 'Exception
    ignored when trying to write to the signal wakeup fd: BlockingIOError', and the simulator ran
    on.)"""
    import signal
    import threading

    from tests.support.process import DevsimProcess, stop

    sim = DevsimProcess("run", "sers", "--pty", "--canopen", "7@127.0.0.1:0")
    clients: list[socket.socket] = []
    flooded = threading.Event()

    def flood(client: socket.socket) -> None:
        chunk = b"< send 123 8 01 02 03 04 05 06 07 08 >" * 1000
        with contextlib.suppress(OSError):
            for sent in itertools.count(1000, 1000):
                client.sendall(chunk)
                if sent >= 100_000:
                    flooded.set()
        flooded.set()

    try:
        line = sim.next_match(sim.out, lambda text: text.startswith("sers.canopen:"), 30, "the CANopen line")
        port = int(line.split()[2].rpartition(":")[2])
        clients += [_raw_client(port, receive_buffer=4096), _raw_client(port)]
        flooder = threading.Thread(target=flood, args=(clients[1],), daemon=True)
        flooder.start()
        assert flooded.wait(60)
        status = stop(sim.proc, signal.SIGTERM, 30)
    finally:
        stop(sim.proc, signal.SIGKILL)
        for client in clients:
            client.close()
    errors = sim.rest_of_err()
    assert status == 0, errors[-10:]
    assert not any("Traceback" in text or "Exception ignored" in text for text in errors), errors[:20]
