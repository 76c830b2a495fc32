"""Fleet: many devices in several devsim processes through mosquitto.

Starts a mosquitto (``$SYS`` every second) and a plant of ``--devices`` SERS devices in
``--processes`` parts, each part a ``devsim up PLANT --part pN`` process.  Two measurements
(``--measure``, default both):

* ``states``: the parts publish their devices with the MQTT facade (the plant's ``mqtt:``
  section, points sampled every ``1/--rate`` s); one client sets ``quantity.adc_volts`` of
  every device ``--rate`` times a second (a new value each time) through
  ``…/set/quantity.adc_volts`` and takes the ``…/state/quantity.adc_volts`` each device
  publishes: state messages delivered per second, and the end-to-end time from the command to
  the published state (command → broker → devsim → broker → subscriber).  The client speaks
  through devsim's own MQTT link, which is not the bottleneck (an aiomqtt client was).  The bare
  reference, in the same run: aiomqtt processes that answer each command with its state at once
  (``benchmarks/fleet_bare.py states``), no device, no sampling.
* ``requests``: the parts join a fleet (``--fleet URL``); one fleet client
  (:class:`devsim.fleet.client.AsyncFleetClient`) reads ``input.I1`` of every device ``--rate``
  times a second: every round trip is two messages through the broker.  Then, in the same run
  and on the same broker, the bare reference: as many aiomqtt responders
  (``benchmarks/fleet_bare.py``) serving the same device names, read the same way.  Phases
  alternate ``--rounds`` times (for both measurements).  CPU per request (per command) is the servers' CPU over the measured window
  (``/proc/PID/stat``) over the requests they answered in it; printed last: devsim's, the bare
  responders', and their ratio (medians over the rounds).

``--instructions`` counts instead the instructions one server process (``--devices /
--processes`` devices) executes per request, devsim's member and the bare aiomqtt responder
(valgrind's cachegrind, ``PYTHONHASHSEED=0``): ``--warmup + --requests`` reads against
``--warmup`` alone, each request sent after the last one's answer, so that each is a loop turn of
its own, as at the benchmark's rate (one request every 4 ms per process).  A count the load of
the machine does not move; the timed figures on a shared two-core machine swing by a third.
``--profile N`` runs the devsim member the same way under callgrind and prints its N costliest
functions per request (C functions: the interpreter's, msgspec's, the socket's), self and
inclusive; ``--profile-dir`` keeps callgrind's files for ``callgrind_annotate``.

Reports: round trips answered per second and the broker's own count of messages sent per second
(``$SYS/broker/messages/sent``), round-trip p50/p99/max, late requests (an answer that had not
arrived when the device's next read was due), and the CPU of mosquitto, of each server process
and of the client (% of one core).

    python benchmarks/fleet.py [--devices 100] [--processes 4] [--rate 10] [--seconds 10]
                               [--measure states|requests|both] [--rounds 1]
    python benchmarks/fleet.py --instructions [--requests 5000] [--warmup 200]
    python benchmarks/fleet.py --profile 40 [--requests 5000] [--warmup 200]
"""

from __future__ import annotations

import argparse
import asyncio
import os
import re
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from devsim.fleet.client import AsyncFleetClient  # noqa: E402
from tests.support.broker import Broker  # noqa: E402

TICK = os.sysconf("SC_CLK_TCK")


def cpu_seconds(pid: int) -> float:
    """utime + stime of a process, in seconds."""
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / TICK


def start_members(url: str, devices: int, processes: int, tmp: Path, *, states: float | None = None,
                  wrapper: tuple[str, ...] = ()) -> list[tuple[subprocess.Popen[str], str]]:
    """The parts as ``devsim up`` processes: fleet members, or (``states``: the MQTT facade's
    sampling period) publishing their devices on the broker; ``wrapper``: the command that runs
    each (valgrind)."""
    plant = tmp / "plant.yaml"
    mqtt = f"mqtt: {{url: '{url}', rate: {states}}}\n" if states is not None else ""
    plant.write_text(f"name: bench\n{mqtt}devices:\n" + "".join(
        f"  - {{name: d{i:03d}, kind: sers, part: p{i % processes}}}\n" for i in range(devices)))
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    members = []
    for part in range(processes):
        extra = [] if states is not None else ["--fleet", url]
        proc = subprocess.Popen([*wrapper, sys.executable, "-m", "devsim", "up", str(plant), "--part", f"p{part}", *extra],
                                cwd=ROOT, env=env, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                                stderr=subprocess.DEVNULL, text=True)
        members.append(proc)
    joined = []
    for part, proc in enumerate(members):
        assert proc.stdout is not None
        for line in proc.stdout:  # bounded by the member's own start-up (it exits on failure)
            if states is None and line.startswith("fleet: "):
                joined.append((proc, line.rsplit(" as ", 1)[1].strip()))
                break
            if states is not None and line.startswith("mqtt: topics"):
                joined.append((proc, f"p{part}"))
                break
        else:
            raise SystemExit(f"a devsim process ended before joining: {proc.args}")
    return joined


async def sys_counter(url: str, topic: str) -> asyncio.Queue[tuple[float, int]]:
    """The broker's $SYS counter ``topic`` as (arrival time, value) in a queue."""
    import aiomqtt

    from devsim.fleet.topics import parse_fleet_url

    queue: asyncio.Queue[tuple[float, int]] = asyncio.Queue()
    fleet = parse_fleet_url(url)

    async def watch() -> None:
        async with aiomqtt.Client(fleet.host, fleet.port) as client:
            await client.subscribe(topic)
            async for message in client.messages:
                queue.put_nowait((asyncio.get_running_loop().time(), int(bytes(message.payload))))  # type: ignore[arg-type]

    _watchers.add(asyncio.ensure_future(watch()))
    return queue


_watchers: set[asyncio.Task[None]] = set()


async def measure(url: str, devices: list[str], rate: float, seconds: float, client_pid: int,
                  servers: dict[str, int] | None = None) -> dict[str, Any]:
    """Read ``input.I1`` of every device ``rate`` times a second through the fleet; ``servers``
    (process -> pid): whose CPU to take over the measured window, with the requests each answered."""
    counter = await sys_counter(url, "$SYS/broker/messages/sent")
    async with AsyncFleetClient(url, timeout=5.0) as fleet:
        await fleet.wait_for_devices(devices, timeout=30)
        where = {name: fleet.serving(name) for name in devices}
        period = 1.0 / rate
        latencies: list[float] = []
        late = [0]
        failed = [0]
        loop = asyncio.get_running_loop()
        warm_end = loop.time() + 1.0
        end = warm_end + seconds
        samples: list[tuple[float, int]] = []
        answered = dict.fromkeys(where.values(), 0)

        async def poll(index: int, name: str) -> None:
            due = loop.time() + period * index / len(devices)
            while due < end:
                await asyncio.sleep(max(0.0, due - loop.time()))
                sent = time.perf_counter()
                try:
                    await fleet.ask(where[name], "read", device=name, name="input.I1")
                except Exception:
                    failed[0] += 1 if due >= warm_end else 0
                    due += period
                    continue
                took = time.perf_counter() - sent
                if due >= warm_end:
                    answered[where[name]] += 1
                    latencies.append(took)
                    if loop.time() > due + period:
                        late[0] += 1
                due += period

        async def count() -> None:
            while True:
                samples.append(await counter.get())

        counting = asyncio.ensure_future(count())
        polls = asyncio.gather(*(poll(i, name) for i, name in enumerate(devices)))
        await asyncio.sleep(max(0.0, warm_end - loop.time()))
        pids = servers or {}
        cpu0 = loop.time(), cpu_seconds(client_pid)
        served0 = {process: cpu_seconds(pid) for process, pid in pids.items()}
        await asyncio.sleep(max(0.0, end - loop.time()))
        served1 = {process: cpu_seconds(pid) for process, pid in pids.items()}
        cpu1 = loop.time(), cpu_seconds(client_pid)
        await polls
        counting.cancel()
    inside = [sample for sample in samples if warm_end <= sample[0] <= end]
    first, last = (inside[0], inside[-1]) if len(inside) > 1 else ((0.0, 0), (1.0, 0))  # $SYS: once a second
    latencies.sort()
    return {
        "answered_per_s": len(latencies) / seconds,
        "broker_sent_per_s": (last[1] - first[1]) / (last[0] - first[0]),
        "p50_ms": 1000 * statistics.median(latencies),
        "p99_ms": 1000 * latencies[int(0.99 * (len(latencies) - 1))],
        "max_ms": 1000 * latencies[-1],
        "late": late[0],
        "failed": failed[0],
        "requests": len(latencies),
        "client_cpu": 100 * (cpu1[1] - cpu0[1]) / (cpu1[0] - cpu0[0]),
        "server_cpu": {process: served1[process] - served0[process] for process in pids},
        "answered": answered,
    }


async def measure_states(url: str, devices: list[str], rate: float, seconds: float, client_pid: int,
                         servers: dict[str, int] | None = None) -> dict[str, Any]:
    """Set ``quantity.adc_volts`` of every device to a new value ``rate`` times a second over
    MQTT and time each published state from its command (every value is matched, however late).
    The commands go out and the states come in on devsim's own MQTT link
    (:mod:`devsim.facades.mqtt_link`): an aiomqtt client here was the slowest part of the chain."""
    from devsim.facades.mqtt_link import open_link
    from devsim.facades.mqtt_wire import Publish
    from devsim.fleet.topics import parse_fleet_url

    broker = parse_fleet_url(url)
    counter = await sys_counter(url, "$SYS/broker/messages/sent")
    loop = asyncio.get_running_loop()
    pending: dict[tuple[str, float], tuple[float, bool]] = {}  # (device, volts) -> (sent at, in the window)
    latencies: list[float] = []
    delivered = [0]
    sent = [0]
    window = [float("inf"), float("inf")]  # warm-up end, end: set once the births are in
    online: set[str] = set()
    all_online = asyncio.Event()
    samples: list[tuple[float, int]] = []

    def receive(message: Publish) -> None:
        topic = message.topic
        device = topic.split("/")[2]
        if topic.endswith("/status"):
            (online.add if message.payload == b"online" else online.discard)(device)
            if len(online) == len(devices):
                all_online.set()
            return
        counted = window[0] <= loop.time() <= window[1]
        delivered[0] += counted
        if topic.endswith("/quantity.adc_volts"):
            sent_at, timed = pending.pop((device, float(message.payload)), (0.0, False))
            if timed:
                latencies.append(time.perf_counter() - sent_at)

    link = await open_link(broker.host, broker.port, f"bench-{os.getpid()}")
    link.on_message = receive
    try:
        await link.subscribe("devsim/bench/+/state/#")
        await link.subscribe("devsim/bench/+/status")

        async def command(index: int, name: str) -> None:
            period = 1.0 / rate
            due = loop.time() + period * index / len(devices)
            number = 0
            while due < window[1]:
                await asyncio.sleep(max(0.0, due - loop.time()))
                number += 1
                volts = (number % 500) / 100  # 0.01 … 4.99 V: a new value each time
                pending[(name, volts)] = time.perf_counter(), due >= window[0]
                link.publish(f"devsim/bench/{name}/set/quantity.adc_volts", str(volts).encode())
                if due >= window[0]:
                    sent[0] += 1
                due += period

        async def count() -> None:
            while True:
                samples.append(await counter.get())

        counting = asyncio.ensure_future(count())
        await asyncio.wait_for(all_online.wait(), 60)  # every device born and subscribed to its commands
        await asyncio.sleep(1.0)  # the births' retained states drain before the window
        window[:] = [loop.time() + 1.0, loop.time() + 1.0 + seconds]
        warm_end, end = window
        commands = asyncio.gather(*(command(i, name) for i, name in enumerate(devices)))
        await asyncio.sleep(max(0.0, warm_end - loop.time()))
        pids = servers or {}
        cpu0 = loop.time(), cpu_seconds(client_pid)
        served0 = {process: cpu_seconds(pid) for process, pid in pids.items()}
        await commands
        served1 = {process: cpu_seconds(pid) for process, pid in pids.items()}
        cpu1 = loop.time(), cpu_seconds(client_pid)
        await asyncio.sleep(1.0)  # the last states
        counting.cancel()
    finally:
        await link.disconnect()
    inside = [sample for sample in samples if warm_end <= sample[0] <= end]
    first, last = (inside[0], inside[-1]) if len(inside) > 1 else ((0.0, 0), (1.0, 0))  # $SYS: once a second
    latencies.sort()
    return {
        "delivered_per_s": delivered[0] / seconds,
        "broker_sent_per_s": (last[1] - first[1]) / (last[0] - first[0]),
        "p50_ms": 1000 * statistics.median(latencies),
        "p99_ms": 1000 * latencies[int(0.99 * (len(latencies) - 1))],
        "max_ms": 1000 * latencies[-1],
        "sent": sent[0],
        "timed": len(latencies),
        "client_cpu": 100 * (cpu1[1] - cpu0[1]) / (cpu1[0] - cpu0[0]),
        "server_cpu": {process: served1[process] - served0[process] for process in pids},
        "answered": {"commands": sent[0]},
    }


def start_bare(broker: Broker, url: str, devices: int, processes: int, *, states: bool = False,
               wrapper: tuple[str, ...] = ()) -> list[tuple[subprocess.Popen[str], str]]:
    """The bare reference: ``processes`` aiomqtt processes (``benchmarks/fleet_bare.py``), the
    devices dealt to them as the plant deals them to its parts."""
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    started = []
    for part in range(processes):
        names = [f"d{i:03d}" for i in range(devices) if i % processes == part]
        where = ["states", "127.0.0.1", str(broker.port)] if states else ["requests", url, f"bare-p{part}"]
        proc = subprocess.Popen([*wrapper, sys.executable, str(ROOT / "benchmarks" / "fleet_bare.py"), *where, *names],
                                cwd=ROOT, env=env, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                                stderr=subprocess.DEVNULL, text=True)
        started.append(proc)
    joined = []
    for part, proc in enumerate(started):
        assert proc.stdout is not None
        line = proc.stdout.readline()  # bounded by its start-up (it exits on failure)
        if not line.startswith(("fleet: ", "mqtt: ")):
            raise SystemExit(f"a bare responder ended before joining: {proc.args}")
        joined.append((proc, f"bare-p{part}"))
    return joined


def stop_all(members: list[tuple[subprocess.Popen[str], str]], timeout: float = 10.0) -> None:
    for proc, _name in members:
        proc.terminate()
    for proc, _name in members:
        try:
            proc.wait(timeout)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()


def run_side(args: argparse.Namespace, broker: Broker, side: str, tmp: Path) -> dict[str, Any]:
    """One measurement of ``side`` (``devsim``, ``bare``, ``states`` or ``states-bare``) on
    ``broker``; the CPU of every process over the whole run and the measurement's own figures."""
    states = 1.0 / args.rate if side.startswith("states") else None
    url = broker.url if states else f"{broker.url}/{side}"  # each side its own fleet
    members: list[tuple[subprocess.Popen[str], str]] = []
    try:
        if side.endswith("bare"):
            members = start_bare(broker, url, args.devices, args.processes, states=states is not None)
        else:
            members = start_members(url, args.devices, args.processes, tmp, states=states)
        assert broker.process is not None
        pids = {"mosquitto": broker.process.pid, **{name: proc.pid for proc, name in members}}
        before = {key: cpu_seconds(pid) for key, pid in pids.items()}
        started = time.perf_counter()
        names = [f"d{i:03d}" for i in range(args.devices)]
        servers = {name: proc.pid for proc, name in members}
        how = measure_states if states is not None else measure
        result = asyncio.run(how(url, names, args.rate, args.seconds, os.getpid(), servers))
        elapsed = time.perf_counter() - started
        result["cpu"] = {key: 100 * (cpu_seconds(pid) - before[key]) / elapsed for key, pid in pids.items()}
        result["members"] = [name for _proc, name in members]
    finally:
        stop_all(members)
    return result


def per_request_ms(result: dict[str, Any]) -> float:
    """The servers' CPU over the measured window per request they answered in it, in ms."""
    return 1000 * sum(result["server_cpu"].values()) / max(1, sum(result["answered"].values()))


def report(args: argparse.Namespace, side: str, result: dict[str, Any]) -> None:
    if side.startswith("states"):
        who = "the MQTT facade" if side == "states" else "bare aiomqtt processes (benchmarks/fleet_bare.py)"
        print(f"states, {who}: {args.devices} devices in {args.processes} processes publishing over MQTT, a new"
              f" quantity.adc_volts at {args.rate:g} Hz each for {args.seconds:g} s")
        print(f"state messages delivered: {result['delivered_per_s']:.0f}/s ({result['timed']} of"
              f" {result['sent']} commands' states timed)")
        what = "command to published state"
    else:
        who = "devsim up --fleet" if side == "devsim" else "bare aiomqtt responders (benchmarks/fleet_bare.py)"
        print(f"requests, {who}: {args.devices} devices in {args.processes} processes, read at {args.rate:g} Hz"
              f" each for {args.seconds:g} s")
        print(f"round trips answered: {result['answered_per_s']:.0f}/s ({result['requests']} in the window;"
              f" {result['late']} late, {result['failed']} unanswered)")
        what = "round trip"
    print(f"broker messages sent: {result['broker_sent_per_s']:.0f}/s ($SYS/broker/messages/sent)")
    print(f"{what} p50 {result['p50_ms']:.2f} ms, p99 {result['p99_ms']:.2f} ms, max {result['max_ms']:.1f} ms")
    cpu = result["cpu"]
    print(f"CPU (% of one core, whole run incl. warm-up): mosquitto {cpu['mosquitto']:.1f}; {side} "
          + ", ".join(f"{cpu[name]:.1f}" for name in result["members"])
          + f"; the client {result['client_cpu']:.1f} (measured window)")
    what = "command" if side.startswith("states") else "request"
    print(f"CPU per {what} in the {side} processes: {per_request_ms(result):.3f} ms (measured window)")


def run_one(args: argparse.Namespace, measure_what: str) -> None:
    broker = Broker(extra="sys_interval 1\n" + ("set_tcp_nodelay true" if args.nodelay else "")).start()
    devsim, bare = ("states", "states-bare") if measure_what == "states" else ("devsim", "bare")
    cost: dict[str, list[float]] = {devsim: [], bare: []}
    p99: dict[str, list[float]] = {devsim: [], bare: []}
    try:
        with tempfile.TemporaryDirectory(prefix="devsim-fleet-bench-") as tmp:
            for side in [devsim, bare] * args.rounds:
                result = run_side(args, broker, side, Path(tmp))
                report(args, side, result)
                cost[side].append(per_request_ms(result))
                p99[side].append(result["p99_ms"])
    finally:
        broker.stop()
    what = "command" if measure_what == "states" else "request"
    ours, theirs = statistics.median(cost[devsim]), statistics.median(cost[bare])
    print(f"{measure_what}: p99 devsim {', '.join(f'{v:.1f}' for v in p99[devsim])} ms,"
          f" bare {', '.join(f'{v:.1f}' for v in p99[bare])} ms")
    print(f"CPU per {what} (median of {args.rounds}): devsim {ours:.3f} ms, bare aiomqtt {theirs:.3f} ms;"
          f" ratio devsim / bare {ours / theirs:.2f}")


async def ask_in_turn(url: str, devices: list[str], count: int) -> None:
    """Read ``input.I1`` ``count`` times, the devices in turn, each request after the last one's
    answer: every request is a loop turn of its own in the member, as at the benchmark's rate."""
    async with AsyncFleetClient(url, timeout=120.0) as fleet:
        await fleet.wait_for_devices(devices, timeout=600)
        where = {name: fleet.serving(name) for name in devices}
        for index in range(count):
            name = devices[index % len(devices)]
            await fleet.ask(where[name], "read", device=name, name="input.I1")


def process_instructions(broker: Broker, side: str, devices: int, requests: int, tmp: Path,
                         profile: Path | None = None) -> int:
    """Instructions the one server process of ``side`` (``devsim`` or ``bare``, serving
    ``devices``) executes from its start to its stop, asked ``requests`` reads in turn;
    ``profile``: run it under callgrind instead, its output written there."""
    log = tmp / f"valgrind-{side}-{requests}.log"
    if profile is None:
        wrapper: tuple[str, ...] = ("valgrind", "--tool=cachegrind", "--cache-sim=no",
                                    "--cachegrind-out-file=/dev/null", f"--log-file={log}")
    else:
        wrapper = ("valgrind", "--tool=callgrind", f"--callgrind-out-file={profile}", f"--log-file={log}")
    url = f"{broker.url}/{side}-{requests}"  # each run its own fleet: no announcement of an earlier one
    members: list[tuple[subprocess.Popen[str], str]] = []
    try:
        if side == "bare":
            members = start_bare(broker, url, devices, 1, wrapper=wrapper)
        else:
            members = start_members(url, devices, 1, tmp, wrapper=wrapper)
        asyncio.run(ask_in_turn(url, [f"d{i:03d}" for i in range(devices)], requests))
    finally:
        stop_all(members, timeout=120.0)
    for line in log.read_text().splitlines():
        if "I refs:" in line or "I   refs:" in line or "Collected :" in line:
            return int(line.rsplit(":", 1)[1].replace(",", "").strip())
    raise SystemExit(f"no instruction count from valgrind for the {side} process")


#: What every Python call goes through (the interpreter's loop and calls, the program's start):
#: left out of the inclusive table, where it would hide the functions that do the work.
PLUMBING = re.compile(r"^(ceval|call|classobject|methodobject|funcobject|_functoolsmodule|import|pycore_\w+)\.[ch]:"
                      r"|main|^\?\?\?:0x|PROGRAM TOTALS|builtin_exec")


def function_costs(profile: Path, inclusive: bool) -> dict[str, int]:
    """callgrind_annotate's instructions per function of ``profile`` (self, or ``inclusive``)."""
    text = subprocess.run(["callgrind_annotate", f"--inclusive={'yes' if inclusive else 'no'}", "--threshold=100",
                           str(profile)], capture_output=True, text=True, check=True).stdout
    costs: dict[str, int] = {}
    for line in text.splitlines():
        head, _, name = line.strip().partition(" ")
        if not head[:1].isdigit() or not name:
            continue
        name = name.split(")", 1)[1].strip() if name.startswith("(") else name.strip()
        where, _, library = name.partition(" [")
        name = where.rsplit("/", 1)[-1] + (f" [{library.rstrip(']').rsplit('/', 1)[-1]}]" if library else "")
        costs[name] = costs.get(name, 0) + int(head.replace(",", ""))
    return costs


def profile_functions(args: argparse.Namespace) -> None:
    """``--profile N``: the devsim member's N costliest functions per request (callgrind; C
    functions, the interpreter's own included), self and inclusive, differenced as
    ``--instructions`` does."""
    os.environ["PYTHONHASHSEED"] = "0"
    devices = max(1, args.devices // args.processes)
    broker = Broker().start()
    try:
        with tempfile.TemporaryDirectory(prefix="devsim-fleet-bench-") as tmp:
            keep = Path(args.profile_dir) if args.profile_dir else Path(tmp)
            keep.mkdir(parents=True, exist_ok=True)
            outs = [keep / f"callgrind-{n}.out" for n in (args.warmup, args.warmup + args.requests)]
            totals = [process_instructions(broker, "devsim", devices, n, Path(tmp), out)
                      for n, out in zip((args.warmup, args.warmup + args.requests), outs, strict=True)]
            tables = {kind: [function_costs(out, kind == "inclusive") for out in outs] for kind in ("self", "inclusive")}
    finally:
        broker.stop()
    print(f"instructions per request: {(totals[1] - totals[0]) / args.requests / 1e3:.1f} k (callgrind)")
    for kind, (before, after) in tables.items():
        rows = sorted(((after.get(name, 0) - before.get(name, 0)) / args.requests, name) for name in after
                      if kind == "self" or not PLUMBING.search(name))
        print(f"-- {kind} instructions per request, the {args.profile} costliest functions")
        for cost, name in sorted(rows, reverse=True)[:args.profile]:
            print(f"{cost:10.0f}  {name}")


def count_instructions(args: argparse.Namespace) -> None:
    """``--instructions``: instructions per request in one server process (``--devices /
    --processes`` devices), devsim's and the bare responder's: ``--warmup + --requests`` reads
    against ``--warmup`` alone, the same start and stop in both."""
    os.environ["PYTHONHASHSEED"] = "0"
    devices = max(1, args.devices // args.processes)
    broker = Broker().start()
    per_request: dict[str, float] = {}
    try:
        with tempfile.TemporaryDirectory(prefix="devsim-fleet-bench-") as tmp:
            for side in ("devsim", "bare"):
                counts = [process_instructions(broker, side, devices, n, Path(tmp))
                          for n in (args.warmup, args.warmup + args.requests)]
                per_request[side] = (counts[1] - counts[0]) / args.requests
    finally:
        broker.stop()
    print(f"instructions per request in one server process ({devices} devices, {args.requests} reads in turn"
          f" against none, after {args.warmup}): devsim {per_request['devsim'] / 1e3:.1f} k,"
          f" bare aiomqtt {per_request['bare'] / 1e3:.1f} k")
    print(f"instructions per request, devsim / bare: {per_request['devsim'] / per_request['bare']:.2f}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--devices", type=int, default=100)
    parser.add_argument("--processes", type=int, default=4)
    parser.add_argument("--rate", type=float, default=10.0, help="commands or reads per second per device")
    parser.add_argument("--seconds", type=float, default=10.0)
    parser.add_argument("--measure", choices=("states", "requests", "both"), default="both")
    parser.add_argument("--rounds", type=int, default=1,
                        help="requests: devsim and the bare responders measured alternately this many times each")
    parser.add_argument("--nodelay", action="store_true", help="mosquitto's set_tcp_nodelay true")
    parser.add_argument("--instructions", action="store_true",
                        help="count instructions per request in one server process (valgrind) instead of timing")
    parser.add_argument("--profile", type=int, default=0, metavar="N",
                        help="print the devsim member's N costliest functions per request (callgrind) instead")
    parser.add_argument("--profile-dir", help="--profile: keep callgrind's two output files in this directory")
    parser.add_argument("--requests", type=int, default=5000,
                        help="--instructions: reads counted (the start-up of the two runs differs by a few"
                             " million instructions: at 1,000 reads that moved the figure by up to 3 k)")
    parser.add_argument("--warmup", type=int, default=200, help="--instructions: reads before them, in both runs")
    args = parser.parse_args()
    if args.profile:
        profile_functions(args)
        return
    if args.instructions:
        count_instructions(args)
        return
    for what in ("states", "requests") if args.measure == "both" else (args.measure,):
        run_one(args, what)


if __name__ == "__main__":
    main()
