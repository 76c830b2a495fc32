"""Resident memory per device, every kind, against a bare asyncio endpoint set up the same way.

For each kind a fresh process builds a plant of N devices of that kind (each port of each device
served on its own TCP port by devsim's transport, as ``devsim up`` serves them), collects the
garbage and reads its resident set (``VmRSS``); another fresh process does the same with one
device.  A device's share is the difference over N - 1.  The reference, measured in the same
run and alternating with the kinds: a fresh process serving as many bare asyncio TCP echo
endpoints (a listening socket with a reader, a small object per endpoint) as the plant has
ports, against one.  The ratio devsim / reference per port is printed last.

Target (issue 31): a SERS device in a 1,000-device plant < 20 KB.  A single measurement swings
by several per cent (a SERS device 19.0-20.5 KB on the same code, 2026-11-30), so each side is
measured three times by default and the medians are printed.

    python benchmarks/memory.py [--kind sers ...] [--n N] [--rounds 3] [--pty] [--top 0]

``--top K`` prints, for the largest plant of each kind, the K source lines that allocated the
most per device (tracemalloc, a separate process), to find what a device holds.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
KINDS = ("sers", "gms96", "pcd4h3", "ip247", "poselesta")
#: A plant size per kind that a 2-core machine builds in a few seconds (POSELESTA serves three
#: ports per device).
DEFAULT_N = {"sers": 1000, "gms96": 500, "pcd4h3": 200, "ip247": 500, "poselesta": 200}

CHILD = r"""
import asyncio, gc, json, os, resource, sys, tracemalloc
soft, hard = resource.getrlimit(resource.RLIMIT_NOFILE)  # a port is a descriptor (a pty two)
resource.setrlimit(resource.RLIMIT_NOFILE, (hard, hard))
kind, n, pty, top = sys.argv[1], int(sys.argv[2]), sys.argv[3] == "pty", int(sys.argv[4])

def rss_kb():
    with open("/proc/self/status") as status:
        for line in status:
            if line.startswith("VmRSS:"):
                return int(line.split()[1])

async def bare(n):
    loop = asyncio.get_running_loop()
    class Echo(asyncio.Protocol):
        def connection_made(self, transport):
            self.transport = transport
        def data_received(self, data):
            self.transport.write(data)
    if pty:
        endpoints = []
        for _ in range(n):
            master, slave = os.openpty()
            os.set_blocking(master, False)
            loop.add_reader(master, lambda m=master: os.write(m, os.read(m, 4096)))
            endpoints.append((master, slave))
    else:
        endpoints = [await loop.create_server(Echo, "127.0.0.1", 0) for _ in range(n)]
    return endpoints, n

async def plant(n):
    from devsim.runtime import Runtime
    from devsim.transports.pty import PtyTransport
    from devsim.transports.tcp import TcpTransport
    runtime = Runtime()
    await runtime.__aenter__()
    ports = 0
    for i in range(n):
        device = runtime.add_device(kind, f"{kind}{i}")
        for port in device.port_names():
            await runtime.serve(device, PtyTransport() if pty else TcpTransport(), port=port)
            ports += 1
    return runtime, ports

async def main():
    if kind == "bare":
        held = await bare(1)  # what a bare endpoint needs, and nothing of devsim
        held = await bare(n)  # the one of the baseline is made the same way
        ports = n
    else:
        import devsim.runtime, devsim.transports.tcp, devsim.transports.pty  # noqa: F401
        from devsim.core.registry import device_class
        device_class(kind)
        held, _ = await plant(1)  # a first device: the kind's modules and shared tables
        if top:
            gc.collect()
            tracemalloc.start(1)
            before = tracemalloc.take_snapshot()
        if n > 1:
            held2, ports = await plant(n - 1)
            ports += 1
        else:
            ports = len(held.devices[kind + "0"].port_names())
        await asyncio.sleep(0.2)  # boot timers, first reads
        if top:
            gc.collect()
            after = tracemalloc.take_snapshot()
            every = after.compare_to(before, "lineno")
            stats = every[:top]
            total = sum(s.size_diff for s in every) / max(1, n - 1)
            lines = [f"{s.size_diff / max(1, n - 1):9.0f} B/device {s.count_diff / max(1, n - 1):7.1f} blocks "
                     f"{s.traceback[0].filename.replace(os.getcwd() + '/', '')}:{s.traceback[0].lineno}"
                     for s in stats]
            lines.append(f"{total:9.0f} B/device in all (tracemalloc)")
            print(json.dumps({"top": lines}), flush=True)
            return
    gc.collect()
    print(json.dumps({"rss_kb": rss_kb(), "ports": ports}), flush=True)

asyncio.run(main())
"""


def _env() -> dict[str, str]:
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(p for p in (ROOT, env.get("PYTHONPATH", "")) if p)
    return env


def measure(kind: str, n: int, pty: bool, top: int = 0) -> dict:
    """One fresh process: a plant of ``n`` devices of ``kind`` (``bare``: n echo endpoints)."""
    out = subprocess.run([sys.executable, "-c", CHILD, kind, str(n), "pty" if pty else "tcp", str(top)],
                         cwd=ROOT, env=_env(), capture_output=True, text=True, timeout=600)
    if out.returncode != 0:
        raise SystemExit(f"{kind} x {n} failed:\n{out.stderr}")
    return json.loads(out.stdout.strip().splitlines()[-1])


def share(kind: str, n: int, pty: bool) -> tuple[float, int]:
    """KB per device (or per bare endpoint) and ports per device: plant of n against plant of 1."""
    one, many = measure(kind, 1, pty), measure(kind, n, pty)
    ports = many["ports"] / n
    return (many["rss_kb"] - one["rss_kb"]) / (n - 1), round(ports)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--kind", action="append", choices=KINDS, help="a kind (repeatable; default all)")
    parser.add_argument("--n", type=int, default=0, help="devices in the large plant (default per kind)")
    parser.add_argument("--rounds", type=int, default=3, help="measurements of each side (median; default 3)")
    parser.add_argument("--pty", action="store_true", help="serve ptys instead of TCP ports")
    parser.add_argument("--top", type=int, default=0, help="print the K lines allocating most per device")
    args = parser.parse_args(argv)
    kinds = args.kind or list(KINDS)
    rows = []
    for kind in kinds:
        n = args.n or DEFAULT_N[kind]
        dev, ref, ports = [], [], 1
        for _ in range(args.rounds):  # alternate: the kind, then the bare endpoints of as many ports
            kb, ports = share(kind, n, args.pty)
            dev.append(kb)
            ref.append(share("bare", n * ports, args.pty)[0])
        kb, ref_kb = statistics.median(dev), statistics.median(ref)
        rows.append((kind, n, ports, kb, ref_kb))
        print(f"{kind:10} plant of {n:5} against 1: {kb:7.1f} KB per device ({ports} port(s)); "
              f"bare {'pty' if args.pty else 'TCP'} echo endpoint {ref_kb:5.1f} KB", flush=True)
        if args.top:
            for line in measure(kind, n, args.pty, args.top)["top"]:
                print("   ", line)
    print("device / bare endpoints of its ports, per kind:")
    for kind, _n, ports, kb, ref_kb in rows:
        target = "  (target < 20 KB: " + ("met)" if kb < 20 else "missed)") if kind == "sers" else ""
        print(f"  {kind:10} {kb:7.1f} KB / {ports * ref_kb:5.1f} KB = {kb / (ports * ref_kb):5.1f}{target}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
