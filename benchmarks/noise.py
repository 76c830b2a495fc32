"""Fairness under noise: one port swallows 100 MB of junk while its neighbour is polled.

Starts ``devsim up`` with two devices of ``--kind`` (``sers`` or ``stub``) in one process, each on
its own pty, and a bare asyncio echo server on a pty in another process (the reference).  Then,
in alternating phases, it polls the neighbour device (``#P11?``) and the echo server, first on a
quiet line and then while a writer process pours ``--megabytes`` of noise into the other
device's port.  It prints the neighbour's p50/p99 in each phase, the echo reference's, and how
fast the noise was swallowed (bytes the noisy line received, from the control API, over time).
The same noise is then poured into a bare asyncio pty reader (one read of up to 4 KiB per loop
turn; devsim reads a second in the same turn when the first came full, which does not speed the
bare reader up: 69-77 against 74-83 MB/s in a probe, 2026-11-30) that answers a neighbour's polls on a second pty in the same process, as devsim's
process answers the quiet device's: the neighbour and the echo are polled as before, and its rate
is the reference for the swallow rate (so both processes do the same work; before 2026-11-30 the
bare reader swallowed the noise alone while devsim's process also answered the neighbour).

Noise: random bytes without ``#`` (the SERS line start) by default, so no command lines are
started; ``--raw`` sends plain random bytes.  The noise is 64 KiB of pseudo-random bytes from
``--seed``, repeated, so that runs compare: how much of it a drive answers depends on the
bytes (a ``#`` and this drive's address select it, another address deselects it).  Targets: the neighbour's p99 < 1 ms while the noise
flows, and noise swallowed at ≥ 50 MB/s.  That rate is absolute, so the lines before the last
also say whether the bare reader reaches it in the same run: on a slow day this machine's does not.
The last line is the ratio of the two rates, devsim / the bare reader (issue 31: ≥ 0.9).  The
bare reader's rate swings from run to run far more than devsim's (it waits on the writer and the
kernel's refill, not on its own work): ``--rounds N`` alternates the two phases N times and prints
each round and the medians (the rate target, p99 and the ratio).  ``--alone`` polls nobody while
the noise flows, so that each process swallows it with nothing else to do (no p99 then).  Each
process's CPU time per MB swallowed is printed too (``/proc``): it does not depend on how soon the
machine wakes a sleeping reader, which moves the bare reader's rate most.

    python benchmarks/noise.py [--megabytes 100] [--kind sers] [--raw] [--seed 1] [--rounds 1] [--alone]
"""

from __future__ import annotations

import argparse
import json
import os
import random
import select
import signal
import statistics
import subprocess
import sys
import tempfile
import time

import serial

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

from benchmarks.latency import _spawn, _stop, complete  # noqa: E402
from benchmarks.startup import cpu_of  # noqa: E402

QUERY = b"#P11?\r"
#: What the echo server answers a poll (``latency.py --serve-echo`` with the length given it
#: below), and so the bare reference's neighbour too.
ECHO_LEN = len(QUERY) + 16
ECHO_REPLY = b"x" * (ECHO_LEN - 6) + b"\nok1\n\r"


def _env() -> dict[str, str]:
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(p for p in (ROOT, env.get("PYTHONPATH", "")) if p)
    env["DEVSIM_EXTRA_KINDS"] = "stub=benchmarks.stub:StubDevice"
    return env


def poll(port: serial.Serial, count: int) -> list[float]:
    times = []
    for _ in range(count):
        start = time.perf_counter()
        port.write(QUERY)
        buf = b""
        while not complete(buf):
            buf += port.read(max(1, port.in_waiting))
        times.append(time.perf_counter() - start)
    return times


def writer(path: str, megabytes: float, raw: bool, seed: int) -> None:
    block = bytearray(random.Random(seed).randbytes(1 << 16))  # the same noise in every run
    if not raw:
        block = block.replace(b"#", b"\x00")
    total = int(megabytes * 1e6)
    fd = os.open(path, os.O_WRONLY | os.O_NOCTTY)
    try:
        sent = 0
        while sent < total:
            sent += os.write(fd, block[: min(len(block), total - sent)])
    finally:
        os.close(fd)


SINK = """
import asyncio, os, sys, tty
total, reply = int(sys.argv[1]), sys.argv[2].encode()
async def main():
    master, slave = os.openpty()
    tty.setraw(slave)  # as devsim's pty: no output processing adds bytes
    os.set_blocking(master, False)
    loop = asyncio.get_running_loop()
    done = asyncio.Event()
    got = 0
    def readable():
        nonlocal got
        try:
            got += len(os.read(master, 4096))
        except BlockingIOError:
            return
        if got >= total:
            done.set()
    loop.add_reader(master, readable)
    # the neighbour: a bare answer to every CR-terminated poll, on a pty of its own
    neighbour, neighbour_slave = os.openpty()
    tty.setraw(neighbour_slave)
    os.set_blocking(neighbour, False)
    pending = bytearray()
    def poll():
        try:
            pending.extend(os.read(neighbour, 4096))
        except BlockingIOError:
            return
        while (end := pending.find(13)) >= 0:
            del pending[:end + 1]
            os.write(neighbour, reply)
    loop.add_reader(neighbour, poll)
    print(os.ttyname(slave), os.ttyname(neighbour_slave), flush=True)
    await done.wait()
    print("done", flush=True)
    await asyncio.Event().wait()  # (the neighbour answers until the benchmark ends the process)
asyncio.run(main())
"""


def _writer(path: str, megabytes: float, raw: bool, seed: int) -> subprocess.Popen[bytes]:
    return subprocess.Popen([sys.executable, __file__, "--writer", path, str(megabytes), "--seed", str(seed),
                             *(["--raw"] if raw else [])], env=_env())


def bare_rate(megabytes: float, raw: bool, seed: int, echo: serial.Serial, reply: bytes,
              alone: bool = False) -> tuple[float, float]:
    """MB/s a bare asyncio pty reader swallows the same noise at while its neighbour (a bare
    answer ``reply`` on a second pty in the same process) and the echo are polled in turn, as
    devsim's quiet device and the echo are while devsim swallows it (``alone``: not polled);
    and its process's CPU seconds meanwhile."""
    sink = subprocess.Popen([sys.executable, "-c", SINK, str(int(megabytes * 1e6)), reply.decode()],
                            stdout=subprocess.PIPE, text=True)
    assert sink.stdout is not None
    path, neighbour_path = sink.stdout.readline().split()
    with serial.Serial(neighbour_path, 9600, timeout=2) as neighbour:
        poll(neighbour, 200)
        started, cpu = time.perf_counter(), cpu_of(sink.pid)
        noise = _writer(path, megabytes, raw, seed)
        while not select.select([sink.stdout], [], [], 1.0 if alone else 0)[0]:  # (until it has swallowed it all)
            if alone:
                continue
            poll(neighbour, 50)
            poll(echo, 50)
        assert sink.stdout.readline().strip() == "done"
        elapsed, cpu = time.perf_counter() - started, cpu_of(sink.pid) - cpu
    noise.wait(timeout=10)
    sink.kill()
    sink.wait(timeout=10)
    return megabytes / elapsed, cpu


def _percentiles(times: list[float]) -> str:
    times = sorted(times)
    return f"p50 {statistics.median(times) * 1e3:.3f} ms, p99 {times[int(0.99 * (len(times) - 1))] * 1e3:.3f} ms"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--megabytes", type=float, default=100.0)
    parser.add_argument("--kind", default="sers")
    parser.add_argument("--raw", action="store_true", help="noise may contain '#'")
    parser.add_argument("--seed", type=int, default=1, help="the noise: 64 KiB from this seed, repeated (default 1)")
    parser.add_argument("--rounds", type=int, default=1,
                        help="rounds of the two noise phases, devsim's then the bare reader's; the medians are printed")
    parser.add_argument("--alone", action="store_true",
                        help="poll nobody while the noise flows: each process swallows it with nothing else to do")
    parser.add_argument("--writer", nargs=2, help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.writer:
        writer(args.writer[0], float(args.writer[1]), args.raw, args.seed)
        return 0
    from devsim.runtime.client import ControlClient

    with tempfile.TemporaryDirectory() as tmp:
        plant = os.path.join(tmp, "plant.yaml")
        with open(plant, "w") as fh:
            fh.write(f"devices:\n  - {{name: noisy, kind: {args.kind}}}\n  - {{name: quiet, kind: {args.kind}}}\n")
        sock = f"unix:{tmp}/ctl.sock"
        proc = subprocess.Popen([sys.executable, "-m", "devsim", "up", plant, "--control", sock], cwd=ROOT, env=_env(),
                                stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
        ports: dict[str, str] = {}
        ready = 0
        assert proc.stdout is not None
        while ready < 2:
            name, _, value = proc.stdout.readline().strip().partition(": ")
            if value == "ready":
                ready += 1
            elif value.startswith("pty "):
                ports[name] = value.split()[1]
        rates: list[float] = []
        references: list[float] = []
        cpus: list[float] = []  # each process's CPU seconds during its noise phase
        bare_cpus: list[float] = []
        echo_proc, echo_path = _spawn([sys.executable, os.path.join(ROOT, "benchmarks", "latency.py"), "--serve-echo",
                                       str(ECHO_LEN)])
        try:
            with serial.Serial(ports["quiet"], 9600, timeout=2) as quiet, serial.Serial(echo_path, 9600, timeout=2) as echo, \
                    ControlClient(sock) as control:
                poll(quiet, 200)
                quiet_times, echo_quiet = poll(quiet, 2000), poll(echo, 2000)
                noisy_times: list[float] = []
                echo_noisy: list[float] = []
                for _ in range(args.rounds):  # devsim, then the bare reader: alternating phases
                    before = control.line("noisy")["bytes_in"]
                    started, cpu = time.perf_counter(), cpu_of(proc.pid)
                    noise = _writer(ports["noisy"], args.megabytes, args.raw, args.seed)
                    while noise.poll() is None and not args.alone:
                        noisy_times += poll(quiet, 50)
                        echo_noisy += poll(echo, 50)
                    noise.wait()
                    target = before + int(args.megabytes * 1e6)
                    while control.line("noisy")["bytes_in"] < target:
                        if args.alone:
                            time.sleep(0.001)  # (a look a millisecond, not a poll: nothing else to do)
                        else:
                            noisy_times += poll(quiet, 10)
                    rates.append(args.megabytes / (time.perf_counter() - started))
                    cpus.append(cpu_of(proc.pid) - cpu)
                    reference, bare_cpu = bare_rate(args.megabytes, args.raw, args.seed, echo, ECHO_REPLY, args.alone)
                    references.append(reference)
                    bare_cpus.append(bare_cpu)
        finally:
            _stop(echo_proc)
            proc.send_signal(signal.SIGINT)
            proc.wait(timeout=30)
    ratios = [devsim / bare for devsim, bare in zip(rates, references, strict=True)]
    rate, reference, ratio = (statistics.median(values) for values in (rates, references, ratios))
    print(f"neighbour, quiet line:    {_percentiles(quiet_times)}   (echo reference {_percentiles(echo_quiet)})")
    if args.alone:
        print("neighbour, during noise:  not polled (--alone)")
    else:
        print(f"neighbour, during noise:  {_percentiles(noisy_times)}   (echo reference {_percentiles(echo_noisy)})")
    for devsim, bare in zip(rates, references, strict=True):
        print(f"noise swallowed: {args.megabytes:g} MB at {devsim:.0f} MB/s "
              f"(a bare asyncio pty reader: {bare:.0f} MB/s; ratio {devsim / bare:.2f})")
    # CPU per MB swallowed: what each process spends, whatever the machine's wake-ups cost in time
    devsim_ms, bare_ms = (statistics.median(c) / args.megabytes * 1e3 for c in (cpus, bare_cpus))
    print(f"CPU per MB swallowed (medians): devsim {devsim_ms:.1f} ms, bare pty reader {bare_ms:.1f} ms; "
          f"bare / devsim {bare_ms / devsim_ms:.2f} (information: the ratio of record is the rates', last)")
    p99 = sorted(noisy_times)[int(0.99 * (len(noisy_times) - 1))] if noisy_times else float("nan")
    met, bare_reaches = p99 < 0.001 and rate >= 50, reference >= 50
    # the rate target is absolute, so say whether this machine's bare reader reaches it at all
    if args.alone:
        print(f"target noise at >= 50 MB/s: {'met' if rate >= 50 else 'missed'} (the neighbour's p99 < 1 ms: not "
              f"measured, --alone); the bare reader {'reaches' if bare_reaches else 'does not reach'} 50 MB/s")
    else:
        print(f"targets (neighbour p99 < 1 ms, noise at >= 50 MB/s): {'met' if met else 'missed'}; "
              f"the bare reader {'reaches' if bare_reaches else 'does not reach'} 50 MB/s in this run")
    print(json.dumps({"p99_ms": round(p99 * 1e3, 3) if noisy_times else None, "mb_per_s": round(rate, 1), "bare_mb_per_s": round(reference, 1),
                      "targets_met": met, "bare_reaches_rate": bare_reaches}))
    print(f"noise swallowed, devsim / bare pty reader: {ratio:.2f}"
          f"{f' (median of {len(ratios)} rounds)' if len(ratios) > 1 else ''} (target >= 0.9)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
