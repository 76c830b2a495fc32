"""Round trip of the Modbus facade against a bare pymodbus server, interleaved in one run (issue 13).

Each run starts, in a background thread's event loop, (a) a devsim runtime (real clock) with one
``sers`` device whose Modbus facade serves TCP on loopback, and (b) a bare pymodbus 3.16 server
with one ``SimDevice`` holding ten registers and no action; then times ``--n`` reads of a block of
ten holding registers (five 32-bit values: the facade reads them from the device's points) with
pymodbus's synchronous client against each, alternating, and prints p50/p99 and the ratio.

The CANopen half times an SDO upload of a point (REAL64, expedited) through the facade's node against
a bare canopen local node holding the same object in its data store, both on one python-can virtual
bus, canopen's remote nodes as the master, alternating.

Target: p50 ratio facade/bare ≤ 1.3 for both.

    python benchmarks/facades.py [--n 2000] [--runs 5]
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
try:
    import devsim  # noqa: F401
except ImportError:  # running from a source checkout without installing
    sys.path.insert(0, ROOT)

from pymodbus.client import ModbusTcpClient  # noqa: E402
from pymodbus.server import ModbusTcpServer  # noqa: E402
from pymodbus.simulator import DataType, SimData, SimDevice  # noqa: E402

from devsim.facades.modbus import ModbusFacade, serve_tcp  # noqa: E402
from devsim.runtime import Runtime  # noqa: E402

RATIO_TARGET = 1.3
BLOCK = 10


def start_servers() -> tuple[Runtime, int, int, int]:
    """A runtime with the facade and a bare server in the same loop; returns the ports and the
    facade's first holding register of a ten-register block of numbers."""
    runtime = Runtime().start()
    device = runtime.add_device("sers", "sers", {})
    facade = ModbusFacade(device)
    first = facade.map.by_name["quantity.supply_voltage"].address

    async def both() -> tuple[int, int]:
        _server, facade_port = await serve_tcp(facade, port=0)
        bare = ModbusTcpServer(SimDevice(1, simdata=[SimData(first, count=BLOCK, values=7,
                                                             datatype=DataType.REGISTERS)]),
                               address=("127.0.0.1", 0))
        await bare.serve_forever(background=True)
        runtime.add_closer(bare.shutdown)
        runtime.add_closer(_server.shutdown)
        return facade_port, bare.transport.sockets[0].getsockname()[1]

    facade_port, bare_port = runtime.run(both())
    return runtime, facade_port, bare_port, first


def timed(client: ModbusTcpClient, address: int) -> float:
    start = time.perf_counter()
    answer = client.read_holding_registers(address, count=BLOCK, device_id=1)
    elapsed = time.perf_counter() - start
    assert not answer.isError() and len(answer.registers) == BLOCK, answer
    return elapsed


def one_run(n: int) -> tuple[list[float], list[float]]:
    runtime, facade_port, bare_port, first = start_servers()
    try:
        facade = ModbusTcpClient("127.0.0.1", port=facade_port, timeout=5)
        bare = ModbusTcpClient("127.0.0.1", port=bare_port, timeout=5)
        assert facade.connect() and bare.connect()
        for _ in range(50):  # warm up both
            timed(facade, first)
            timed(bare, first)
        ours, theirs = [], []
        for _ in range(n):
            ours.append(timed(facade, first))
            theirs.append(timed(bare, first))
        facade.close()
        bare.close()
        return ours, theirs
    finally:
        runtime.stop()


def sdo_run(n: int) -> tuple[list[float], list[float]]:
    """SDO uploads of quantity.supply_voltage: the facade's node 5 against a bare local node 6."""
    import uuid

    import canopen

    from devsim.facades.canopen_node import CanopenFacade, load_od
    from devsim.facades.canopen_od import eds

    runtime = Runtime().start()
    channel = f"bench-{uuid.uuid4().hex}"
    slave, master = canopen.Network(), canopen.Network()
    slave.connect(interface="virtual", channel=channel)
    master.connect(interface="virtual", channel=channel)
    try:
        device = runtime.add_device("sers", "sers", {})
        facade = CanopenFacade(device, 5, call=runtime.call)
        facade.attach(slave)
        text = eds("sers", device.description, device.points, drive=device.drive is not None)
        bare = canopen.LocalNode(6, load_od(text, 6))
        slave.add_node(bare)
        index = next(i for i, point in facade.objects.items() if point.name == "quantity.supply_voltage")
        bare.sdo[index].raw = 68.0
        ours_node = master.add_node(canopen.RemoteNode(5, load_od(text, 5)))
        bare_node = master.add_node(canopen.RemoteNode(6, load_od(text, 6)))
        for _ in range(50):  # warm up both
            assert ours_node.sdo[index].raw == bare_node.sdo[index].raw
        ours, theirs = [], []
        for _ in range(n):
            start = time.perf_counter()
            assert ours_node.sdo[index].raw == 68.0
            ours.append(time.perf_counter() - start)
            start = time.perf_counter()
            assert bare_node.sdo[index].raw == 68.0
            theirs.append(time.perf_counter() - start)
        return ours, theirs
    finally:
        slave.disconnect()
        master.disconnect()
        runtime.stop()


def p(values: list[float], q: float) -> float:
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, int(q * len(ordered)))] * 1000


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n", 1)[0])
    parser.add_argument("--n", type=int, default=2000)
    parser.add_argument("--runs", type=int, default=5)
    args = parser.parse_args()
    met = 0
    for run in range(1, args.runs + 1):
        ours, theirs = one_run(args.n)
        ratio = statistics.median(ours) / statistics.median(theirs)
        met += ratio <= RATIO_TARGET
        print(f"run {run}: facade p50 {p(ours, 0.5):.3f} ms p99 {p(ours, 0.99):.3f} ms | bare pymodbus "
              f"p50 {p(theirs, 0.5):.3f} ms p99 {p(theirs, 0.99):.3f} ms | p50 ratio {ratio:.2f}")
    print(f"Modbus: p50 ratio ≤ {RATIO_TARGET} in {met} of {args.runs} runs")
    sdo_met = 0
    for run in range(1, args.runs + 1):
        ours, theirs = sdo_run(max(args.n // 4, 100))
        ratio = statistics.median(ours) / statistics.median(theirs)
        sdo_met += ratio <= RATIO_TARGET
        print(f"run {run}: SDO upload facade p50 {p(ours, 0.5):.3f} ms p99 {p(ours, 0.99):.3f} ms | bare local node "
              f"p50 {p(theirs, 0.5):.3f} ms p99 {p(theirs, 0.99):.3f} ms | p50 ratio {ratio:.2f}")
    print(f"CANopen: p50 ratio ≤ {RATIO_TARGET} in {sdo_met} of {args.runs} runs")
    return 0 if met == args.runs and sdo_met == args.runs else 1


if __name__ == "__main__":
    sys.exit(main())
