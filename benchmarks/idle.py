"""CPU use of an idle simulator: one device on a pty, real clock, nobody talking.

Starts a :class:`~devsim.runtime.Runtime` in a thread with one device of ``--kind``
(default ``sers``) on a :class:`~devsim.transports.pty.PtyTransport`, lets it settle, then
measures the process's CPU time (user + system, all threads) over ``--seconds`` of wall time and
prints it as a percentage of one core.  With ``--open`` a pyserial host holds the port open
meanwhile (still sending nothing).

Target: < 0.1 % of one core.

    python benchmarks/idle.py [--seconds 10] [--kind sers|stub] [--open]
"""

from __future__ import annotations

import argparse
import contextlib
import os
import resource
import sys
import time

import serial

# the checkout, for benchmarks.stub (and devsim itself when it is not installed)
sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def cpu_seconds() -> float:
    usage = resource.getrusage(resource.RUSAGE_SELF)
    return usage.ru_utime + usage.ru_stime


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=10.0, help="measuring time (default 10 s)")
    parser.add_argument("--settle", type=float, default=3.0, help="wait before measuring (default 3 s)")
    parser.add_argument("--kind", default="sers", help="device kind (default sers; 'stub' = stand-in)")
    parser.add_argument("--open", action="store_true", help="keep the port open by a pyserial host")
    args = parser.parse_args(argv)

    if args.kind == "stub":
        os.environ["DEVSIM_EXTRA_KINDS"] = "stub=benchmarks.stub:StubDevice"
    from devsim.runtime import Runtime
    from devsim.transports.pty import PtyTransport

    runtime = Runtime().start()
    try:
        device = runtime.add_device(args.kind)
        port = device.port_names()[0]  # the kind's first serial port (main, sbus, pg, v6 ...)
        transport = PtyTransport()
        runtime.serve_sync(device, transport, port=port)
        baud = runtime.call(lambda: device.port(port).serial_settings.baudrate)
        with contextlib.ExitStack() as stack:
            if args.open:
                stack.enter_context(serial.Serial(transport.address, baud))
            time.sleep(args.settle)  # boot display, first timers
            cpu0, wall0 = cpu_seconds(), time.monotonic()
            time.sleep(args.seconds)
            cpu1, wall1 = cpu_seconds(), time.monotonic()
    finally:
        runtime.stop()

    cpu = cpu1 - cpu0
    wall = wall1 - wall0
    percent = 100.0 * cpu / wall
    print(f"idle: one {args.kind}, port {port} on a pty ({transport.address}), real clock,"
          f" host {'open' if args.open else 'absent'}")
    print(f"  wall     {wall:8.2f} s")
    print(f"  cpu      {cpu * 1e3:8.2f} ms (user + system, whole process)")
    print(f"  load     {percent:8.4f} % of one core (target < 0.1 %): {'PASS' if percent < 0.1 else 'MISS'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
