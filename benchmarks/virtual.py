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

    python benchmarks/virtual.py [--kind sers ...] [--hours 1] [--rounds 1] [--profile N] [--limit-switches]

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


def _still_looping(device: str, event: str, seconds: float) -> str:
    """The last steps: at the end, the loop's ``event`` last happened within its last 30 s (a
    check of the event log, not a condition looked at every millisecond while the axis moves)."""
    return (f"  - at: {seconds}s\n"
            f"    expect_timing: {{device: {device}, event: {event}, between: [{max(0.0, seconds - 30)}s, {seconds}s], "
            "occurrence: last}\n")


def _gms96(seconds: float, limit_switches: bool = False) -> str:
    """One GMS96 looping CNC program 0 (§2.5), stored as its download would store it: a move out,
    M50 with the PLC's acknowledge (M6.0 reset after 100 ms, §2.4.1), a dwell (WAIT), output A0.2
    on (SETO), the move back, A0.2 off (RESO), a dwell.  The PLC starts the program again when
    it ended (M1.0 → M0.2, §2.4.1 MB0/MB1); the host switches the position controller on (Q3)
    and starts it (p3;1;0).  ``limit_switches``: the PLC has two limit rules (spec §4.10.3: a
    stop towards −, an abort with a message towards +) on switches on the axis (§5.11) beyond
    the moves' ends, as a machine has them."""
    limits = ("limit_switches: [{input: E0.3, action: stop, direction: '-'}, "
              "{input: E0.4, action: abort, direction: '+', message: 31}], ") if limit_switches else ""
    axis = (", axis: {limit_switches: [{input: E0.3, high: -5000}, {input: E0.4, low: 15000}]}"
            if limit_switches else "")
    program = '["A10000", "m50", "p10;14;5", "p10;16;2", "A0", "p10;17;2", "p10;14;5"]'
    return (f"name: a GMS96 looping CNC program 0\ntimeout: {seconds + 60}s\ndevices:\n"
            "  - name: card\n    kind: gms96\n"
            f"    config: {{dil: {{address: 3}}, plc: {{{limits}auto_ack_m_functions_ms: 100, "
            f"copy_bits: [{{from: M1.0, to: M0.2}}]}}{axis}}}\n"
            f"    state: {{program.0: {program}}}\n"
            "steps:\n"
            '  - send: "\\x68\\x06\\x06\\x68\\x53\\x03\\x51\\x03\\x00\\x00\\xAA\\x16"\n'  # Q3
            '  - expect: "\\xE5"\n'
            '  - send: "\\x68\\x0C\\x0C\\x68\\x53\\x03\\x70\\x03\\x00\\x00\\x01\\x00\\x00\\x00\\x00\\x00\\xCA\\x16"\n'
            '  - expect: "\\xE5"\n'  # p3;1;0
            + _still_looping("card", "move_start", seconds))


def _ip247(seconds: float) -> str:
    """One IP247 axis with the manual's machine data (§6.1) and its reference set (BA5), running
    traverse program 1 (stored as BA22 would) from the PLC side (FB164 BA8 Start): an endless
    loop (G24 F0 … G20, §2.6.6.4) of a 100 mm move out with M20, a 0.5 s dwell with M21 and the
    move back with M22."""
    md = ("0046 0044 4201 0001 0100 0000 1388 0000 00C8 0000 C350 001E 0040 0004 00C8 0000 07D0 0000 0BB8 0000 "
          "0BB8 0000 0BB8 0000 0BB8 0000 0020 0000 0000 FFF9 E580 0007 A120 0001 0000 08FC 0000 0000 0000 2710 "
          "0000 61A8 0000 0CB2 FFFE DB08" + " 0000" * 24)
    program = r"%  1 LOOP\nN10 G24 F0\nN20 X100.000 F3000 M20\nN30 G04 F5 M21\nN40 X0.000 F3000 M22\nN50 G20\nN99 M02\n"
    return (f"name: an IP247 looping a traverse program\ntime: virtual\ntimeout: {seconds + 60}s\ndevices:\n"
            "  - name: ip\n    kind: ip247\nsteps:\n"
            "  - set: {device: ip, values: {input.ANF1: true, input.END1: true}}\n"
            f'  - set: {{device: ip, values: {{axis.1.machine_data: "{md}"}}}}\n'
            "  - set: {device: ip, values: {ag.operate: {page: 0, ba: 5, cmd: Start, b: 1}}}\n"
            f'  - set: {{device: ip, values: {{program.1: "{program}"}}}}\n'
            "  - set: {device: ip, values: {ag.operate: {page: 0, ba: 8, cmd: Start, b: 1}}}\n"
            + _still_looping("ip", "move_start", seconds))


def _poselesta(seconds: float) -> str:
    """One POSELESTA in AUTO_CONTINUOUS running P20 (preloaded as entered, §2.6.3): a subroutine
    called 99 times (G12 L99.100) that repeats itself 99 more times (G13 L99.100, §2.4.2, spec
    §6.6): rapid out with S1200 M03 M08 on the M/S/T bus (the PLC acknowledging after 35 ms),
    back at F3000, a 0.5 s dwell with M09 – about ten hours of work."""
    program = (r"N1 G12 L99.100\nN2 M02\nN100 G00 X100 S1200 M03 M08\nN101 G01 X0 F3000\n"
               r"N102 G04 L0.500 M09\nN103 G13 L99.100\nN104 G11")
    return (f"name: a POSELESTA looping an NC program\ntime: virtual\ntimeout: {seconds + 60}s\ndevices:\n"
            "  - name: cnc\n    kind: poselesta\n    config: {plc: {mst_ack: delayed}}\n"
            f'    state: {{program.P20: "{program}", panel.program: 20}}\n'
            "steps:\n  - set: {device: cnc, values: {panel.mode: AUTO_CONTINUOUS}}\n"
            "  - after: 100ms\n    set: {device: cnc, values: {panel.nc_start: true}}\n"
            + _still_looping("cnc", "position_reached", seconds))


#: A scenario per kind, given the simulated seconds: each loops what a user would load into
#: that device – a program in a plant's ``state`` (SERS ``program``, GMS96 ``program.<n>``,
#: POSELESTA ``program.P<nn>``), or set by a step (IP247 ``program.<n>``), or the configured
#: user program (PCD4.H3).
SCENARIOS = {"gms96": _gms96, "ip247": _ip247, "pcd4h3": _pcd4h3, "poselesta": _poselesta, "sers": _sers}

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
    parser.add_argument("--limit-switches", action="store_true",
                        help="the GMS96 card with two limit rules on switches on its axis")
    args = parser.parse_args(argv)
    seconds = args.hours * 3600
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for kind in args.kind or sorted(SCENARIOS):
            path = os.path.join(tmp, f"{kind}.yaml")
            with open(path, "w") as f:
                f.write(_gms96(seconds, True) if kind == "gms96" and args.limit_switches else SCENARIOS[kind](seconds))
            dev, ref, events = [], [], 0
            for _ in range(args.rounds):  # alternate: the kind, then the bare clock with as many events
                run = _run("kind", path, seconds)
                events = run["events"]
                dev.append(run["cpu"])
                ref.append(_run("bare", str(events), seconds)["cpu"])
            cpu, ref_cpu = statistics.median(dev), statistics.median(ref)
            rows.append((kind, cpu, ref_cpu))
            print(f"{kind:10} {seconds:6.0f} s simulated: {cpu:6.2f} s CPU, {seconds / cpu:8.0f} simulated s per CPU s; "
                  f"{events} timer events ({events / cpu:7.0f} per CPU s); bare clock {ref_cpu:6.3f} s", flush=True)
            if args.profile:
                _run("kind", path, seconds, args.profile)
    print("devsim CPU / bare virtual clock CPU for as many events:")
    for kind, cpu, ref_cpu in rows:
        target = "  (target < 0.5 s: " + ("met)" if cpu < 0.5 else "missed)") if kind == "sers" else ""
        print(f"  {kind:10} {cpu:6.2f} s / {ref_cpu:6.3f} s = {cpu / ref_cpu:6.1f}{target}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
