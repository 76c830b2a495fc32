"""Virtual time: an hour of looping programs per kind, in simulated seconds per CPU second.

Each run is a fresh process that runs a scenario under virtual time, as ``devsim scenario run
--virtual`` does: a plant whose devices each loop a program of moves, the steps start them and
wait one simulated hour, and the last step checks the loop still ran.  The process's CPU time
over the run gives simulated seconds per CPU second; the clock counts the timer events
scheduled.  The reference, in a fresh process alternating with the kind: the bare virtual clock
(:class:`devsim.core.clock.VirtualClock`, :meth:`advance` over the same span) running as many
timer events, each scheduling the next, with no device work and no event loop: what an event
costs the clock alone.  The ratio devsim CPU / reference CPU is printed last.

The issue's reference case (issue 31): 1 h of 10 SERS each looping a program of two 180° moves
took 4.0 s; target < 0.5 s.

    python benchmarks/virtual.py [--kind sers ...] [--hours 1] [--rounds 1] [--profile N]

``--profile N`` runs each kind once more under cProfile and prints its N costliest functions.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def _sers(seconds: float) -> str:
    """Ten SERS on one RS-485 line, each looping two 180° moves (§4.6: L1 … GT1)."""
    devices = "".join(
        f"  - {{name: d{i}, kind: sers, transport: {{bus: line}}, config: {{address: {i}}},\n"
        f"     state: {{program: [\"ON\", \"L1\", \"WR=180 E\", \"WR=-180 E\", \"GT1\", \"PE\"]}}}}\n"
        for i in range(1, 11)
    )
    start = "".join(f"#{i} RUN\\r" for i in range(1, 11))
    return (f"name: ten SERS looping two 180 degree moves\ntimeout: {seconds + 60}s\ndevices:\n{devices}"
            f"buses:\n  - name: line\nsteps:\n  - send: \"{start}\"\n  - after: {seconds}s\n"
            f"  - expect_state: {{device: d10, name: param.P0, equals: 1}}\n")


def _pcd4h3(seconds: float) -> str:
    """One PCD4.H3 running the manual's example 3 (§9.3, BSP03) with I 8 held: the automatic
    cycle of 150 mm with two break positions and five -30 mm steps, over and over."""
    return (f"name: a PCD4.H3 looping example 3\ntime: virtual\ntimeout: {seconds + 60}s\ndevices:\n"
            "  - name: pcd\n    kind: pcd4h3\n"
            "    config: {h3def: {fmah3: 48, bar: 200, baf: 200, mna: 1}, user_program: example3}\n"
            f"steps:\n  - set: {{device: pcd, values: {{I.8: true}}}}\n  - after: {max(0.0, seconds - 30)}s\n"
            "  - when: {device: pcd, name: axis.1.OnDest, equals: true}\n    timeout: 30s\n")


#: A scenario per kind, given the simulated seconds.  The GMS96, IP247 and POSELESTA have no
#: program a plant can preload yet (each is downloaded through its own telegrams).
SCENARIOS = {"sers": _sers, "pcd4h3": _pcd4h3}

CHILD = r"""
import cProfile, json, pstats, sys, time
from devsim.core.clock import VirtualClock
what, path, seconds, profile = sys.argv[1], sys.argv[2], float(sys.argv[3]), int(sys.argv[4])

class CountingClock(VirtualClock):
    "The virtual clock, counting the timers scheduled on it."
    def __init__(self):
        super().__init__()
        self.scheduled = 0
    def call_at(self, when, callback):
        self.scheduled += 1
        return super().call_at(when, callback)

def run_kind():
    import asyncio
    from devsim.runtime import Runtime
    from devsim.scenario.runner import run_scenario_async
    from devsim.scenario.schema import load_scenario
    scenario = load_scenario(path)
    clock = CountingClock()
    async def go():  # the loop in this thread, so that a profile sees it
        async with Runtime(clock=clock) as runtime:
            return await run_scenario_async(scenario, runtime)
    cpu = time.process_time()
    result = asyncio.run(go())
    cpu = time.process_time() - cpu
    if not result.passed:
        from devsim.scenario.report import format_report
        sys.exit(format_report(result))
    return cpu, clock.scheduled, clock.now()

def run_bare(events):
    clock = VirtualClock()
    step = seconds / events
    left = [events]
    def tick():
        left[0] -= 1
        if left[0]:
            clock.call_later(step, tick)
    cpu = time.process_time()
    clock.call_later(step, tick)
    clock.advance(seconds)
    return time.process_time() - cpu, events - left[0], clock.now()

if what == "bare":
    cpu, events, now = run_bare(int(path))
elif profile:
    profiler = cProfile.Profile()
    profiler.enable()
    cpu, events, now = run_kind()
    profiler.disable()
    stats = pstats.Stats(profiler, stream=sys.stderr)
    stats.sort_stats("tottime").print_stats(profile)
else:
    cpu, events, now = run_kind()
print(json.dumps({"cpu": cpu, "events": events, "simulated": now}), flush=True)
"""


def _run(what: str, arg: str, seconds: float, profile: int = 0) -> dict:
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(p for p in (ROOT, env.get("PYTHONPATH", "")) if p)
    out = subprocess.run([sys.executable, "-c", CHILD, what, arg, str(seconds), str(profile)],
                         cwd=ROOT, env=env, capture_output=True, text=True, timeout=3600)
    if out.returncode != 0:
        raise SystemExit(f"{what} failed:\n{out.stdout}\n{out.stderr}")
    if profile:
        print(out.stderr)
    return json.loads(out.stdout.strip().splitlines()[-1])


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--kind", action="append", choices=sorted(SCENARIOS), help="a kind (default all)")
    parser.add_argument("--hours", type=float, default=1.0, help="simulated time per run (default 1 h)")
    parser.add_argument("--rounds", type=int, default=1, help="runs of each side (median)")
    parser.add_argument("--profile", type=int, default=0, metavar="N", help="print N costliest functions")
    args = parser.parse_args(argv)
    seconds = args.hours * 3600
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for kind in args.kind or sorted(SCENARIOS):
            path = os.path.join(tmp, f"{kind}.yaml")
            with open(path, "w") as f:
                f.write(SCENARIOS[kind](seconds))
            dev, ref, events = [], [], 0
            for _ in range(args.rounds):  # alternate: the kind, then the bare clock with as many events
                run = _run("kind", path, seconds)
                events = run["events"]
                dev.append(run["cpu"])
                ref.append(_run("bare", str(events), seconds)["cpu"])
            cpu, ref_cpu = statistics.median(dev), statistics.median(ref)
            rows.append((kind, cpu, ref_cpu))
            print(f"{kind:10} {seconds:6.0f} s simulated: {cpu:6.2f} s CPU, {seconds / cpu:8.0f} simulated s per CPU s; "
                  f"{events} timer events ({events / cpu:7.0f} per CPU s); bare clock {ref_cpu:5.2f} s", flush=True)
            if args.profile:
                _run("kind", path, seconds, args.profile)
    print("devsim CPU / bare virtual clock CPU for as many events:")
    for kind, cpu, ref_cpu in rows:
        target = "  (target < 0.5 s: " + ("met)" if cpu < 0.5 else "missed)") if kind == "sers" else ""
        print(f"  {kind:10} {cpu:6.2f} s / {ref_cpu:5.2f} s = {cpu / ref_cpu:6.1f}{target}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
