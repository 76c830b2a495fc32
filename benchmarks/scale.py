"""Scale: how many devices one machine serves, each polled at 20 Hz with its axis moving.

Starts ``devsim up`` on a plant of ``--devices`` devices (each on its own TCP port, spread over
``--workers`` processes), sets every axis moving (SERS: ``#ON V=… WR=… E``), then polls every
device with ``#P11?`` at ``--rate`` Hz for ``--seconds``, from ``--pollers`` client processes.
In the same run, in alternating phases, the same pollers poll as many bare asyncio echo
endpoints (answering every CR with a reply of the same length, in one more process), so the
harness's own limit on this machine shows beside the simulator's.

A poll is *missed* when its answer has not arrived by the time the next poll of that device is
due.  Target: ≥ 2,000 devices on 2 cores with p99 < 5 ms and no missed poll.

    python benchmarks/scale.py [--devices 2000] [--workers 2] [--rate 20] [--seconds 10] [--pollers 2]
"""

from __future__ import annotations

import argparse
import asyncio
import json
import os
import signal
import statistics
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
QUERY = b"#P11?\r"
ACK = b"\nok"
MOVE = b"#ON V=30 WR=200000 E\r"  # SERS: a move that outlasts the measurement
REPLY = b"#P11?\r\nP11=0\n\r\nok1\n\r"  # what the echo endpoints answer (a SERS answer's length)


def _env() -> dict[str, str]:
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(p for p in (ROOT, env.get("PYTHONPATH", "")) if p)
    env["DEVSIM_EXTRA_KINDS"] = "stub=benchmarks.stub:StubDevice"
    return env


# -- the echo endpoints (a child process) ------------------------------------------------------
class _Echo(asyncio.Protocol):
    def connection_made(self, transport: asyncio.BaseTransport) -> None:
        self.transport = transport  # type: ignore[assignment]

    def data_received(self, data: bytes) -> None:
        for _ in range(data.count(b"\r")):
            self.transport.write(REPLY)  # type: ignore[attr-defined]


async def echo_servers(count: int) -> None:
    loop = asyncio.get_running_loop()
    servers = [await loop.create_server(_Echo, "127.0.0.1", 0) for _ in range(count)]
    print(json.dumps([s.sockets[0].getsockname()[1] for s in servers]), flush=True)
    await asyncio.Event().wait()


# -- the pollers (child processes) -------------------------------------------------------------
class _Poll(asyncio.Protocol):
    def __init__(self, results: list[float], missed: list[int]) -> None:
        self.results = results
        self.missed = missed
        self.buf = bytearray()
        self.sent_at: float | None = None

    def connection_made(self, transport: asyncio.BaseTransport) -> None:
        self.transport = transport  # type: ignore[assignment]

    def data_received(self, data: bytes) -> None:
        self.buf += data
        at = self.buf.rfind(ACK)
        if at >= 0 and self.buf.find(b"\r", at + len(ACK)) >= 0:
            if self.sent_at is not None:
                self.results.append(time.perf_counter() - self.sent_at)
            self.sent_at = None
            self.buf.clear()

    def poll(self, now: float) -> None:
        if self.sent_at is not None:
            self.missed[0] += 1  # the last answer is not in yet: this poll is missed
            return
        self.sent_at = now
        self.transport.write(QUERY)  # type: ignore[attr-defined]


async def poller(ports: list[int], rate: float, seconds: float, move: bool) -> None:
    loop = asyncio.get_running_loop()
    results: list[float] = []
    missed = [0]
    clients = []
    for port in ports:
        _t, proto = await loop.create_connection(lambda: _Poll(results, missed), "127.0.0.1", port)
        clients.append(proto)
    if move:
        for client in clients:
            client.transport.write(MOVE)
        await asyncio.sleep(0.5)
        for client in clients:
            client.buf.clear()
    period = 1.0 / rate
    start = time.perf_counter() + 0.2
    ticks = int(seconds * rate)
    step = period / max(1, len(clients))
    for k in range(ticks):
        for index, client in enumerate(clients):  # each device at its own phase in the period
            due = start + k * period + index * step
            delay = due - time.perf_counter()
            if delay > 0.0005:
                await asyncio.sleep(delay)
            client.poll(time.perf_counter())
    await asyncio.sleep(0.2)
    results.sort()
    print(json.dumps({"rtts": results, "missed": missed[0], "polls": ticks * len(clients)}), flush=True)


# -- the conductor -----------------------------------------------------------------------------
def _spawn(args: list[str]) -> subprocess.Popen[str]:
    return subprocess.Popen([sys.executable, *args], cwd=ROOT, env=_env(), stdin=subprocess.DEVNULL,
                            stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)


def _start_plant(kind: str, devices: int, workers: int, tmp: str) -> tuple[subprocess.Popen[str], list[int]]:
    plant = os.path.join(tmp, "plant.yaml")
    with open(plant, "w") as fh:
        fh.write("devices:\n")
        for i in range(devices):
            fh.write(f"  - {{name: d{i}, kind: {kind}, transport: {{tcp: {{port: 0}}}}}}\n")
    proc = _spawn(["-m", "devsim", "up", plant, "--workers", str(workers)])
    ports: list[int] = []
    ready = 0
    assert proc.stdout is not None
    while ready < devices:
        line = proc.stdout.readline()
        if not line:
            raise SystemExit("devsim up ended early")
        name, _, value = line.strip().partition(": ")
        if value == "ready":
            ready += 1
        elif value.startswith("tcp "):
            ports.append(int(value.rsplit(":", 1)[1]))
    return proc, ports


def _percentile(values: list[float], q: float) -> float:
    return values[min(len(values) - 1, int(q * len(values)))] if values else float("nan")


def _collect(procs: list[subprocess.Popen[str]]) -> tuple[list[float], int, int]:
    rtts: list[float] = []
    missed = polls = 0
    for proc in procs:
        out, _ = proc.communicate(timeout=600)
        data = json.loads(out.strip().splitlines()[-1])
        rtts += data["rtts"]
        missed += data["missed"]
        polls += data["polls"]
    rtts.sort()
    return rtts, missed, polls


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--devices", type=int, default=2000)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--rate", type=float, default=20.0)
    parser.add_argument("--seconds", type=float, default=10.0)
    parser.add_argument("--pollers", type=int, default=2)
    parser.add_argument("--kind", default="sers")
    parser.add_argument("--rounds", type=int, default=2, help="simulator/echo phase pairs (default 2)")
    parser.add_argument("--echo-servers", type=int, help=argparse.SUPPRESS)
    parser.add_argument("--poll", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.echo_servers is not None:
        asyncio.run(echo_servers(args.echo_servers))
        return 0
    if args.poll is not None:
        spec = json.loads(args.poll)
        asyncio.run(poller(spec["ports"], args.rate, args.seconds, spec["move"]))
        return 0

    with tempfile.TemporaryDirectory() as tmp:
        plant, ports = _start_plant(args.kind, args.devices, args.workers, tmp)
        echo = _spawn([__file__, "--echo-servers", str(args.devices)])
        assert echo.stdout is not None
        echo_ports = json.loads(echo.stdout.readline())
        try:
            def pollers(targets: list[int], move: bool) -> list[subprocess.Popen[str]]:
                shares = [targets[i :: args.pollers] for i in range(args.pollers)]
                return [
                    _spawn([__file__, "--poll", json.dumps({"ports": share, "move": move}), "--rate", str(args.rate),
                            "--seconds", str(args.seconds)])
                    for share in shares if share
                ]

            # alternating phases, simulator then reference, so both see the same machine
            sim, ref = [], []
            sim_missed = sim_polls = ref_missed = ref_polls = 0
            for phase in range(2 * args.rounds):
                if phase % 2 == 0:
                    rtts, missed, polls = _collect(pollers(ports, args.kind == "sers" and phase == 0))
                    sim += rtts
                    sim_missed += missed
                    sim_polls += polls
                else:
                    rtts, missed, polls = _collect(pollers(echo_ports, False))
                    ref += rtts
                    ref_missed += missed
                    ref_polls += polls
            sim.sort()
            ref.sort()
        finally:
            plant.send_signal(signal.SIGINT)
            echo.kill()
            plant.wait(timeout=60)
            echo.wait()
    for label, rtts, missed, polls in (("devsim", sim, sim_missed, sim_polls), ("echo", ref, ref_missed, ref_polls)):
        print(f"{label:>6}: {args.devices} endpoints at {args.rate:g} Hz for {args.seconds:g} s: "
              f"p50 {_percentile(rtts, 0.5) * 1e3:.2f} ms, p99 {_percentile(rtts, 0.99) * 1e3:.2f} ms, "
              f"missed {missed} of {polls} polls")
    ok = _percentile(sim, 0.99) < 0.005 and sim_missed == 0
    print(f"target (p99 < 5 ms, no missed poll) with {args.devices} devices on {args.workers} workers: "
          f"{'met' if ok else 'missed'}; median ratio devsim/echo "
          f"{statistics.median(sim) / statistics.median(ref):.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
