"""Scale: the largest plant one machine serves, each device polled at 20 Hz with its axis moving.

Starts ``devsim up`` on a plant of ``--most`` devices (each on its own TCP port, spread over
``--workers`` processes) and as many bare asyncio echo endpoints (answering every CR with a reply
of the same length as a SERS answer, in as many processes as devsim has workers). A phase polls
the first N endpoints of one side with ``#P11?`` at ``--rate`` Hz for ``--seconds``; on devsim it
first sets each of their axes moving (SERS: ``#ON V=… WR=… E``). The rest of the plant stays idle
(an idle device costs no CPU). A size *holds* when its p99 is below 5 ms and no poll is missed.

By default the script searches, for devsim and for the echo reference in the same run, the
largest size that holds: doubling from ``--start`` until a size fails (or ``--most`` holds), then
bisecting on a grid of ``--resolution`` devices, at most ``--steps`` phases per side; a size that
misses is measured once more (``--confirm``) before it counts, as a burst of other load may cause
the miss. Phases
alternate between the two sides (devsim's next size, then the echo's), so both see the same
machine. It prints both limits, then the CPU per poll of each at the largest size that held on
both sides, their ratio (target ≤ 1.3), and the capacity ratio devsim / echo last (target ≥ 0.9).
With ``--devices N`` it runs the fixed mode instead: a plant of N, ``--rounds`` pairs of phases.

The pollers are ``benchmarks/poller.c``, compiled with ``cc -O2`` into a temporary directory at
each run (``--poller c``, the default when a C compiler is found), or asyncio processes
(``--poller python``): at 2,000 devices the asyncio pollers need a core of their own.  The C
poller wakes once a millisecond, and times each answer by its kernel receive timestamp.
Device i of the plant is polled at phase i of the period, and device i is served by process
i % workers on both sides (devsim up deals devices round-robin), so every process sees an even
stream of polls.

A poll is *missed* when its answer has not arrived by the time the next poll of that device is
due.

    python benchmarks/scale.py [--start 500] [--most 4000] [--resolution 250] [--steps 10] [--confirm 1] [--seconds 3]
    python benchmarks/scale.py --devices 2000 [--seconds 10] [--rounds 2]
    common: [--workers 2] [--rate 20] [--pollers N] [--poller c|python] [--kind sers|stub]

``--instructions`` counts instead, under valgrind (cachegrind with its cache simulation), what one
server process executes per poll: a plant of ``--devices`` (default 100) in one ``devsim up``
process and as many echo endpoints in one process, each device polled ``--rounds`` times (default
10) one after the other by a blocking client, against the same process polled no time (the same
start, connections and moves). It prints instructions and simulated first-level cache misses
(instruction and data) per poll for both and their ratios, devsim / echo last. The counts do not
depend on the machine's load; each poll here wakes its server alone (no batching of polls per
wake-up), unlike the timed phases.

    python benchmarks/scale.py --instructions [--devices 100] [--rounds 10] [--kind sers|stub]

``--calls`` lists instead the functions the server process calls per poll, the same way (Python
functions by file, line and name; C functions by name; ``sys.setprofile``, as
``benchmarks/latency.py --calls`` counts them): where the instructions go.  ``--opcodes`` counts
the bytecodes each Python function executes per poll (``sys.settrace`` with opcode events): how
much Python a poll runs, a count that does not depend on the machine.

    python benchmarks/scale.py --calls [--devices 20] [--rounds 20] [--kind sers|stub]
    python benchmarks/scale.py --opcodes [--devices 20] [--rounds 20] [--kind sers|stub]

Each phase prints the CPU each side used while it polled (share of one core, and server CPU
seconds per poll sent: a missed poll is not sent): the pollers, devsim's processes, the echo processes, and how long the server
processes were runnable but waited for a CPU (``/proc/PID/schedstat``, seconds per second of the
phase, summed over the processes): answers wait that long too.
"""

from __future__ import annotations

import argparse
import asyncio
import json
import os
import resource
import shutil
import signal
import socket
import statistics
import subprocess
import sys
import tempfile
import time
from array import array
from collections.abc import Callable

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


# -- the echo endpoints (child processes, as many as devsim's workers) -------------------------
class _Echo(asyncio.BufferedProtocol):
    """Reads into one shared buffer, as devsim's TCP sessions do: a plain protocol allocates 256 KiB
    per read, which glibc may serve with an mmap/munmap pair (README, "Performance")."""

    buffer = bytearray(64 * 1024)
    view = memoryview(buffer)

    def connection_made(self, transport: asyncio.BaseTransport) -> None:
        self.transport = transport  # type: ignore[assignment]

    def get_buffer(self, sizehint: int) -> memoryview:
        return self.view

    def buffer_updated(self, nbytes: int) -> None:
        for _ in range(self.buffer.count(b"\r", 0, nbytes)):
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
    print("polling", flush=True)  # the conductor starts its CPU accounts here
    ticks = int(seconds * rate)
    step = period / max(1, len(clients))
    cpu0 = _own_cpu()
    for k in range(ticks):
        for index, client in enumerate(clients):  # each device at its own phase in the period
            due = start + k * period + index * step
            delay = due - time.perf_counter()
            if delay > 0.0005:
                await asyncio.sleep(delay)
            client.poll(time.perf_counter())
    await asyncio.sleep(0.2)
    results.sort()
    print(json.dumps({"rtts": results, "missed": missed[0], "polls": ticks * len(clients), "cpu": _own_cpu() - cpu0,
                      "wall": time.perf_counter() - start + 0.2}), flush=True)


def _own_cpu() -> float:
    usage = resource.getrusage(resource.RUSAGE_SELF)
    return usage.ru_utime + usage.ru_stime


# -- the conductor -----------------------------------------------------------------------------
def _spawn(args: list[str]) -> subprocess.Popen[str]:
    return subprocess.Popen([sys.executable, *args], cwd=ROOT, env=_env(), stdin=subprocess.DEVNULL,
                            stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)


def _compile_poller(tmp: str) -> str | None:
    """``benchmarks/poller.c`` built into ``tmp`` (``None`` when there is no C compiler or it fails)."""
    cc = shutil.which("cc") or shutil.which("gcc")
    if cc is None:
        return None
    binary = os.path.join(tmp, "poller")
    built = subprocess.run([cc, "-O2", "-o", binary, os.path.join(ROOT, "benchmarks", "poller.c")],
                           capture_output=True, text=True)
    if built.returncode:
        print(f"cc failed, using the Python poller:\n{built.stderr}", file=sys.stderr)
        return None
    return binary


def _plant_ports(proc: subprocess.Popen[str], devices: int) -> dict[str, int]:
    """The TCP port of each device of a starting ``devsim up``, read from its lines until every
    device is ready."""
    ports: dict[str, int] = {}
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
            ports[name] = int(value.rsplit(":", 1)[1])
    return ports


def _start_plant(kind: str, devices: int, workers: int, tmp: str) -> tuple[subprocess.Popen[str], list[int]]:
    plant = os.path.join(tmp, "plant.yaml")
    with open(plant, "w") as fh:
        fh.write("devices:\n")
        for i in range(devices):
            fh.write(f"  - {{name: d{i}, kind: {kind}, transport: {{tcp: {{port: 0}}}}}}\n")
    proc = _spawn(["-m", "devsim", "up", plant, "--workers", str(workers)])
    try:
        ports = _plant_ports(proc, devices)
    except BaseException:
        proc.kill()  # (its workers end with it: they watch their parent)
        proc.wait()
        raise
    # in the plant's order, device i at phase i: the workers print their ports one worker after
    # the other, and polling in that order would load each worker at twice the rate for half a period
    return proc, [ports[f"d{i}"] for i in range(devices)]


def _tree_cpu(root: int) -> tuple[float, float]:
    """CPU seconds used so far by process ``root`` and its living descendants, and the seconds
    they spent runnable but waiting for a CPU, summed over their threads (``schedstat``: in
    nanoseconds, where ``stat``'s user and system times count in ticks of 10 ms)."""
    stats: dict[int, tuple[int, float, float]] = {}
    for entry in os.listdir("/proc"):
        if entry.isdigit():
            try:
                with open(f"/proc/{entry}/stat") as fh:
                    fields = fh.read().rsplit(")", 1)[1].split()
                cpu = waited = 0.0
                for task in os.listdir(f"/proc/{entry}/task"):
                    with open(f"/proc/{entry}/task/{task}/schedstat") as fh:
                        ran, wait = fh.read().split()[:2]
                    cpu, waited = cpu + int(ran) / 1e9, waited + int(wait) / 1e9
            except (OSError, IndexError, ValueError):
                continue
            stats[int(entry)] = (int(fields[1]), cpu, waited)
    tree = {root}
    for pid in sorted(stats):  # a child's pid is almost always above its parent's; look twice to be sure
        if stats[pid][0] in tree:
            tree.add(pid)
    for pid in sorted(stats):
        if stats[pid][0] in tree:
            tree.add(pid)
    found = [stats[pid] for pid in tree if pid in stats]
    return sum(cpu for _, cpu, _ in found), sum(waited for _, _, waited in found)


def _trees(roots: list[int]) -> tuple[float, float]:
    totals = [_tree_cpu(root) for root in roots]
    return sum(cpu for cpu, _ in totals), sum(waited for _, waited in totals)


def _percentile(values: list[float], q: float) -> float:
    return values[min(len(values) - 1, int(q * len(values)))] if values else float("nan")


class _Side:
    """What one side (devsim or echo) gathered over one or more phases."""

    def __init__(self, devices: int = 0) -> None:
        self.devices = devices
        self.rtts: list[float] = []
        self.missed = self.polls = 0
        self.poller_cpu = self.server_cpu = self.server_wait = self.wall = self.poller_wall = 0.0

    def collect(self, procs: list[tuple[subprocess.Popen[str], str]], servers: list[int]) -> None:
        for proc, _ in procs:  # the servers' CPU is counted over the polls only (not the connects, the move)
            assert proc.stdout is not None
            if proc.stdout.readline().strip() != "polling":
                raise SystemExit("a poller ended before polling")
        before, began = _trees(servers), time.monotonic()
        walls = []
        for proc, out in procs:
            text, _ = proc.communicate(timeout=600)
            data = json.loads(text.strip().splitlines()[-1])
            if "rtts" in data:
                self.rtts += data["rtts"]
            else:  # the C poller's round trips, float64 in a file
                samples = array("d")
                with open(out, "rb") as fh:
                    samples.fromfile(fh, data["samples"])
                self.rtts += samples.tolist()
            self.missed += data["missed"]
            self.polls += data["polls"]
            self.poller_cpu += data["cpu"]
            walls.append(data["wall"])
        after = _trees(servers)
        self.server_cpu += after[0] - before[0]
        self.server_wait += after[1] - before[1]
        self.wall += time.monotonic() - began
        self.poller_wall += max(walls)  # the pollers' measurement; wall: the whole phase

    @property
    def held(self) -> bool:
        """The target: p99 below 5 ms and no missed poll."""
        self.rtts.sort()
        return bool(self.rtts) and _percentile(self.rtts, 0.99) < 0.005 and self.missed == 0

    @property
    def cpu_per_poll(self) -> float:
        """Server CPU seconds per poll (the processes' CPU over the phase, polls included only),
        per poll sent: a missed poll is not sent (the pollers wait for the last answer), so
        dividing by every poll due would make a server that falls behind look cheaper."""
        sent = self.polls - self.missed
        return self.server_cpu / sent if sent > 0 else float("nan")

    def line(self, label: str, rate: float, seconds: float) -> str:
        self.rtts.sort()
        return (f"{label:>6}: {self.devices} endpoints at {rate:g} Hz for {seconds:g} s: "
                f"p50 {_percentile(self.rtts, 0.5) * 1e3:.2f} ms, p99 {_percentile(self.rtts, 0.99) * 1e3:.2f} ms, "
                f"missed {self.missed} of {self.polls} polls; CPU (cores): pollers "
                f"{self.poller_cpu / self.poller_wall:.2f}, {label} {self.server_cpu / self.wall:.2f} "
                f"({self.cpu_per_poll * 1e6:.1f} µs per poll); waited for a CPU "
                f"{self.server_wait / self.wall:.2f} s per second")


class _Search:
    """The largest plant that holds the target, for one side: doubling from ``start`` until a size
    fails (or ``most`` holds), then bisecting until the bracket is ``resolution`` wide, in at most
    ``steps`` phases."""

    def __init__(self, start: int, most: int, resolution: int, steps: int, confirm: int = 1) -> None:
        self.most, self.resolution, self.steps_left, self.confirm = most, resolution, steps, confirm
        self.held = 0  # the largest size that held
        self.failed: int | None = None  # the smallest size that failed
        self.next: int | None = min(start, most)
        self.phases: dict[int, _Side] = {}
        self._tries: dict[int, int] = {}

    def record(self, side: _Side) -> None:
        size = side.devices
        self.steps_left -= 1
        tries = self._tries[size] = self._tries.get(size, 0) + 1
        if size not in self.phases or side.held:
            self.phases[size] = side  # (a size that held once is shown by the phase that held)
        if side.held:
            self.held = max(self.held, size)
        elif tries <= self.confirm and self.steps_left > 0:
            self.next = size  # a miss is measured again before it counts (a burst of other load)
            return
        else:
            self.failed = size if self.failed is None else min(self.failed, size)
        self.next = self._choose()

    def _choose(self) -> int | None:
        if self.steps_left <= 0 or self.held >= self.most:
            return None
        if self.failed is None:
            return min(2 * self.held, self.most)
        if self.failed - self.held <= self.resolution:
            return None
        middle = (self.held + self.failed) // 2
        middle -= middle % self.resolution  # sizes on the resolution's grid
        return middle if self.held < middle < self.failed else None

    def limit(self) -> str:
        if self.held >= self.most:
            return f"≥ {self.held} (every size held up to --most)"
        return f"{self.held} ({self.failed} missed)" if self.failed else f"{self.held}"


def _build_pollers(binary: str | None, count: int, tmp: str, rate: float,
                   seconds: float) -> Callable[[list[int], bool], list[tuple[subprocess.Popen[str], str]]]:
    def pollers(targets: list[int], move: bool) -> list[tuple[subprocess.Popen[str], str]]:
        shares = [targets[i :: count] for i in range(count)]
        started = []
        for i, share in enumerate(share for share in shares if share):
            out = os.path.join(tmp, f"rtts{i}")
            if binary:
                cmd = [binary, str(rate), str(seconds), str(int(move)), out, *map(str, share)]
                started.append((subprocess.Popen(cmd, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                                                 text=True), out))
            else:
                started.append((_spawn([__file__, "--poll", json.dumps({"ports": share, "move": move}),
                                        "--rate", str(rate), "--seconds", str(seconds)]), out))
        return started
    return pollers


def _ask(sock: socket.socket, query: bytes) -> None:
    """Send ``query`` and read until its answer is complete (``\nok`` and a CR after it)."""
    sock.sendall(query)
    got = b""
    while True:
        chunk = sock.recv(4096)
        if not chunk:
            raise SystemExit("the server closed a connection")
        got += chunk
        at = got.rfind(ACK)
        if at >= 0 and got.find(b"\r", at + len(ACK)) >= 0:
            return


def _polled(command: list[str], server: list[str], kind: str, devices: int, rounds: int) -> None:
    """Run ``command`` (the process ``server``, a plant or the echo endpoints, under a counter), poll
    each of its ``devices`` endpoints ``rounds`` times one after the other, then stop it."""
    env = dict(_env(), PYTHONHASHSEED="0")
    proc = subprocess.Popen(command, cwd=ROOT, env=env, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                            stderr=subprocess.DEVNULL, text=True)
    assert proc.stdout is not None
    try:
        if server[0] == "-m":  # devsim up: its port lines, then every device ready
            ports = _plant_ports(proc, devices)
            order = [ports[f"d{i}"] for i in range(devices)]
        else:
            order = json.loads(proc.stdout.readline())
        socks = [socket.create_connection(("127.0.0.1", port)) for port in order]
        for sock in socks:  # the same start on both sides: a move on devsim, a first poll on the echo
            _ask(sock, MOVE if server[0] == "-m" and kind == "sers" else QUERY)
        for _ in range(rounds):
            for sock in socks:
                _ask(sock, QUERY)
        for sock in socks:
            sock.close()
    finally:  # devsim up ends cleanly on Ctrl-C; the echo dies of SIGTERM (valgrind still writes its counts),
        # or of Ctrl-C under the call counter (which writes its counts at exit)
        proc.send_signal(signal.SIGINT if server[0] == "-m" or command[0] != "valgrind" else signal.SIGTERM)
        proc.wait(600)


def _counted(server: list[str], tmp: str, kind: str, devices: int, rounds: int) -> dict[str, int]:
    """Instructions and simulated L1 misses of the process ``server`` (a plant, or the echo
    endpoints) in all, its ``devices`` endpoints polled ``rounds`` times each, then stopped."""
    log = os.path.join(tmp, f"valgrind-{len(os.listdir(tmp))}.log")
    _polled(["valgrind", "--tool=cachegrind", "--cache-sim=yes", "--cachegrind-out-file=/dev/null",
             f"--log-file={log}", sys.executable, *server], server, kind, devices, rounds)
    with open(log) as fh:
        text = fh.read()
    counts = {}
    for key, label in (("I", "I   refs"), ("I1", "I1  misses"), ("D1", "D1  misses")):
        at = text.find(label + ":")
        if at < 0:
            raise SystemExit(f"no {label} in valgrind's log for {server}")
        counts[key] = int(text[at + len(label) + 1 :].split()[0].replace(",", ""))
    return counts


def _servers(tmp: str, kind: str, devices: int) -> dict[str, list[str]]:
    """The two servers counted: a plant of ``devices`` in one ``devsim up``, as many echo endpoints."""
    plant = os.path.join(tmp, "plant.yaml")
    with open(plant, "w") as fh:
        fh.write("devices:\n")
        for i in range(devices):
            fh.write(f"  - {{name: d{i}, kind: {kind}, transport: {{tcp: {{port: 0}}}}}}\n")
    return {"devsim": ["-m", "devsim", "up", plant], "echo": [os.path.abspath(__file__), "--echo-servers", str(devices)]}


def _calls(args: argparse.Namespace) -> None:
    """Per poll, counted with sys.setprofile: the functions each server calls (N polls against none);
    with ``--opcodes``, counted with sys.settrace: the bytecodes each function executes."""
    if ROOT not in sys.path:
        sys.path.insert(0, ROOT)
    from benchmarks.latency import COUNTER

    devices, rounds = args.devices or 20, args.rounds_given or 20
    mode = ["--opcodes"] if args.opcodes else []

    def counts(server: list[str], tmp: str, polls: int) -> dict[str, int]:
        out = os.path.join(tmp, f"calls-{len(os.listdir(tmp))}.tsv")
        _polled([sys.executable, "-c", COUNTER, out, *mode, *server], server, args.kind, devices, polls)
        with open(out) as fh:
            return {name: int(count) for count, name in (line.rstrip("\n").split("\t", 1) for line in fh)}

    with tempfile.TemporaryDirectory() as tmp:
        for label, server in _servers(tmp, args.kind, devices).items():
            polled, idle = counts(server, tmp, rounds), counts(server, tmp, 0)
            per_poll = {call: (count - idle.get(call, 0)) / (devices * rounds) for call, count in polled.items()}
            shown = sorted(((count, call) for call, count in per_poll.items() if count >= 0.5), reverse=True)
            python = sum(count for count, call in shown if not call.startswith("(C)"))
            what = "opcodes per poll, by function" if args.opcodes else "calls per poll"
            total = f"{python:.0f} opcodes" if args.opcodes else f"{python:.0f} Python functions"
            print(f"{label}: {what} ({devices} endpoints polled {rounds} times each, against none): {total}")
            for count, call in shown:
                print(f"  {count:7.2f}  {call}")


def _instructions(args: argparse.Namespace) -> None:
    """Per poll, under cachegrind: instructions and L1 misses of devsim and of the echo."""
    devices, rounds = args.devices or 100, args.rounds_given or 10
    per_poll: dict[str, dict[str, float]] = {}
    with tempfile.TemporaryDirectory() as tmp:
        servers = _servers(tmp, args.kind, devices)
        for label, server in servers.items():
            idle = _counted(server, tmp, args.kind, devices, 0)
            polled = _counted(server, tmp, args.kind, devices, rounds)
            per_poll[label] = {key: (polled[key] - idle[key]) / (devices * rounds) for key in idle}
            print(f"{label:>6}: {devices} endpoints polled {rounds} times each: "
                  f"{per_poll[label]['I'] / 1e3:.1f} k instructions, {per_poll[label]['I1']:.0f} instruction "
                  f"and {per_poll[label]['D1']:.0f} data L1 misses per poll", flush=True)
    sim, ref = per_poll["devsim"], per_poll["echo"]
    print(f"per poll devsim/echo: L1 misses instruction {sim['I1'] / ref['I1']:.2f}, data {sim['D1'] / ref['D1']:.2f}; "
          f"instructions {sim['I'] / ref['I']:.2f}")


def _fixed(args: argparse.Namespace, run: Callable[[str, int, bool], _Side]) -> None:
    """The old mode: one plant size, ``--rounds`` pairs of phases."""
    sim, ref = _Side(args.devices), _Side(args.devices)
    for phase in range(2 * args.rounds):
        side = run("devsim" if phase % 2 == 0 else "echo", args.devices, args.kind == "sers" and phase == 0)
        into = sim if phase % 2 == 0 else ref
        into.rtts += side.rtts
        for name in ("missed", "polls", "poller_cpu", "server_cpu", "server_wait", "wall", "poller_wall"):
            setattr(into, name, getattr(into, name) + getattr(side, name))
    print(sim.line("devsim", args.rate, args.seconds))
    print(ref.line("echo", args.rate, args.seconds))
    # the target is absolute, so say whether the bare echo meets it on this machine in this run
    print(f"target (p99 < 5 ms, no missed poll) with {args.devices} devices on {args.workers} workers: "
          f"{'met' if sim.held else 'missed'} (the echo reference: {'met' if ref.held else 'missed'}); "
          f"CPU per poll devsim/echo {sim.cpu_per_poll / ref.cpu_per_poll:.2f}; median ratio devsim/echo "
          f"{statistics.median(sim.rtts) / statistics.median(ref.rtts):.2f}")


def _search(args: argparse.Namespace, run: Callable[[str, int, bool], _Side]) -> None:
    """Both limits in one run: a step runs devsim's next size, then the echo's, until both are found."""
    searches = {label: _Search(args.start, args.most, args.resolution, args.steps, args.confirm)
                for label in ("devsim", "echo")}
    while any(search.next is not None for search in searches.values()):
        for label, search in searches.items():
            if search.next is not None:
                side = run(label, search.next, label == "devsim" and args.kind == "sers")
                print(side.line(label, args.rate, args.seconds) + f": {'held' if side.held else 'MISSED'}",
                      flush=True)
                search.record(side)
    sim, ref = searches["devsim"], searches["echo"]
    common = [n for n in sim.phases if n in ref.phases]
    both = [n for n in common if sim.phases[n].held and ref.phases[n].held] or common
    print(f"limit (p99 < 5 ms, no missed poll at {args.rate:g} Hz, {args.workers} workers): "
          f"devsim {sim.limit()}, echo {ref.limit()}")
    if both:
        at = max(both)
        d_cpu, e_cpu = sim.phases[at].cpu_per_poll, ref.phases[at].cpu_per_poll
        cpu = f"CPU per poll at {at} devices devsim/echo {d_cpu / e_cpu:.2f} ({d_cpu * 1e6:.1f} / {e_cpu * 1e6:.1f} µs)"
    else:
        cpu = "CPU per poll: no size measured on both sides"
    ratio = sim.held / ref.held if ref.held else float("nan")
    print(f"{cpu} (target ≤ 1.3); capacity devsim/echo {ratio:.2f} (target ≥ 0.9)")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--devices", type=int, help="one plant size (the fixed mode); without it: search")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--rate", type=float, default=20.0)
    parser.add_argument("--seconds", type=float, help="per phase (default: 10 fixed, 3 in the search)")
    parser.add_argument("--pollers", type=int, help="poller processes (default: 1 in C, 2 in Python)")
    parser.add_argument("--poller", choices=("c", "python"), help="default: c when a C compiler is found")
    parser.add_argument("--kind", default="sers")
    parser.add_argument("--rounds", type=int, help="fixed mode: simulator/echo phase pairs (default 2); "
                        "--instructions: polls per device (default 10)")
    parser.add_argument("--instructions", action="store_true",
                        help="count instructions and L1 misses per poll under valgrind instead of timing")
    parser.add_argument("--start", type=int, default=500, help="search: the first size (default 500)")
    parser.add_argument("--most", type=int, default=4000, help="search: the plant's size, the largest tried")
    parser.add_argument("--resolution", type=int, default=250, help="search: sizes are multiples of it")
    parser.add_argument("--steps", type=int, default=10, help="search: phases per side at most (default 10)")
    parser.add_argument("--confirm", type=int, default=1,
                        help="search: a size that missed is measured again this many times before it counts")
    parser.add_argument("--calls", action="store_true",
                        help="list the functions called per poll (sys.setprofile) instead of timing")
    parser.add_argument("--opcodes", action="store_true",
                        help="count the bytecodes each function executes per poll (sys.settrace) instead of timing")
    parser.add_argument("--echo-servers", type=int, help=argparse.SUPPRESS)
    parser.add_argument("--poll", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    args.rounds_given, args.rounds = args.rounds, args.rounds or 2
    if args.instructions:
        _instructions(args)
        return 0
    if args.calls or args.opcodes:
        _calls(args)
        return 0
    if args.seconds is None:
        args.seconds = 10.0 if args.devices else 3.0
    if args.echo_servers is not None:
        asyncio.run(echo_servers(args.echo_servers))
        return 0
    if args.poll is not None:
        spec = json.loads(args.poll)
        asyncio.run(poller(spec["ports"], args.rate, args.seconds, spec["move"]))
        return 0

    size = args.devices or args.most
    with tempfile.TemporaryDirectory() as tmp:
        binary = _compile_poller(tmp) if args.poller != "python" else None
        if args.poller == "c" and binary is None:
            raise SystemExit("--poller c: no C compiler (cc) that builds benchmarks/poller.c")
        count = args.pollers or (1 if binary else 2)
        print(f"pollers: {count} {'C (benchmarks/poller.c, cc -O2)' if binary else 'asyncio'} "
              f"process{'es' if count > 1 else ''}; plant of {size} {args.kind} devices", flush=True)
        plant, ports = _start_plant(args.kind, size, args.workers, tmp)
        echoes: list[subprocess.Popen[str]] = []
        try:
            echoes += [_spawn([__file__, "--echo-servers", str(len(range(i, size, args.workers)))])
                       for i in range(args.workers)]
            # device i served by echo process i % workers, as devsim up deals devices out to its workers
            shares = [json.loads(echo.stdout.readline()) for echo in echoes]  # type: ignore[union-attr]
        except BaseException:
            _stop(plant, echoes)
            raise
        echo_ports = [shares[i % args.workers][i // args.workers] for i in range(size)]
        pollers = _build_pollers(binary, count, tmp, args.rate, args.seconds)

        def run(label: str, devices: int, move: bool) -> _Side:
            """One phase: the first ``devices`` endpoints of one side polled (devices i < n are dealt
            evenly over the processes on both sides); the rest of the plant stays idle."""
            side = _Side(devices)
            if label == "devsim":
                side.collect(pollers(ports[:devices], move), [plant.pid])
            else:
                side.collect(pollers(echo_ports[:devices], False), [echo.pid for echo in echoes])
            return side

        try:
            (_fixed if args.devices else _search)(args, run)
        finally:
            _stop(plant, echoes)
    return 0


def _stop(plant: subprocess.Popen[str], echoes: list[subprocess.Popen[str]]) -> None:
    plant.send_signal(signal.SIGINT)
    for echo in echoes:
        echo.kill()
        echo.wait()
    plant.wait(timeout=60)


if __name__ == "__main__":
    sys.exit(main())
