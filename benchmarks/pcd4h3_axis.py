"""CPU of one moving PCD4.H3 axis, against a bare asyncio loop running a timer of the PLC cycle's
period, measured in the same run (issue 31: "sampled loops only while they matter").

Each phase is a fresh child process that measures its own CPU time (user + system) over
``--seconds`` of wall time on a real clock, after ``--settle`` seconds:

* ``axis``: a PCD4 (the model: PLC cycle, AxHndlg, the LM628 with its motor) whose axis 1 runs
  FForw (a move towards 3FFFFFFFh that outlasts the phase) at ``--velocity`` user units/s, after
  a ramp at ``--accel`` user units/s² that ends within the settling time (the example's machine
  factor, 100 counts per unit: 500 units/s are 50,000 counts/s, 17 counts per sample);
* ``timer``: a bare asyncio loop whose one timer fires every PLC cycle (10 ms), doing nothing:
  the cost of being woken as often as the moving PLC is;
* ``idle``: the same PCD4 with the axis standing (settled: no timer at all).

The phases alternate (axis, timer, idle, axis, …) ``--rounds`` times; the medians are printed,
then the axis's own share (axis − timer) as % of a core, the moving axis's whole cost (axis −
idle: since the PLC no longer wakes every cycle while the axis only moves, the share can be
negative, and this is the figure to hold against the target), and last the ratio axis / timer.

    python benchmarks/pcd4h3_axis.py [--rounds 5] [--seconds 4] [--velocity 500] [--accel 2000]
"""

from __future__ import annotations

import argparse
import asyncio
import json
import os
import statistics
import subprocess
import sys
import time

# the checkout, for devsim itself when it is not installed
ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

EXAMPLE = {"h3def": {"fmah3": 48, "bar": 200, "baf": 200, "mna": 1}, "response_delay_ms": 0}
PERIOD = 0.010  # the PLC cycle of the example installation (plc_cycle_ms)


def cpu_seconds() -> float:
    return time.process_time()  # user + system of the process, nanosecond clock (os.times ticks 10 ms)


async def _measure(seconds: float, settle: float) -> tuple[float, float]:
    await asyncio.sleep(settle)
    cpu0, wall0 = cpu_seconds(), time.monotonic()
    await asyncio.sleep(seconds)
    return cpu_seconds() - cpu0, time.monotonic() - wall0


async def _axis(seconds: float, settle: float, velocity: float, accel: float, moving: bool) -> dict[str, float]:
    from devsim.core.clock import RealClock
    from devsim.devices.pcd4h3.model import Pcd4

    pcd = Pcd4(clock=RealClock(), config=EXAMPLE)
    try:
        await asyncio.sleep(0.2)  # AxInit's cycles
        if moving:
            axis = pcd.axes[0]
            axis.registers.load("Veloc", velocity)
            axis.registers.load("Accel", accel)
            axis.set_flag("FLdAA", 1)
            axis.set_flag("FLdVA", 1)
            axis.set_flag("FForw", 1)
            pcd.wake()
        cpu, wall = await _measure(seconds, settle)
        pcd.catch_up()
        chip = pcd.drives[0].chip
        return {"cpu": cpu, "wall": wall, "position": chip.actual, "settled": pcd.drives[0].settled}
    finally:
        pcd.close()


async def _timer(seconds: float, settle: float) -> dict[str, float]:
    loop = asyncio.get_running_loop()
    handle: list[asyncio.TimerHandle] = []
    due = [loop.time()]

    def tick() -> None:
        due[0] += PERIOD
        handle[:] = [loop.call_at(due[0], tick)]

    tick()
    try:
        cpu, wall = await _measure(seconds, settle)
    finally:
        handle[0].cancel()
    return {"cpu": cpu, "wall": wall}


def child(phase: str, seconds: float, settle: float, velocity: float, accel: float) -> None:
    if phase == "timer":
        result = asyncio.run(_timer(seconds, settle))
    else:
        result = asyncio.run(_axis(seconds, settle, velocity, accel, moving=phase == "axis"))
    print(json.dumps(result))


def run_phase(phase: str, args: argparse.Namespace) -> dict[str, float]:
    command = [sys.executable, os.path.abspath(__file__), "--child", phase, "--seconds", str(args.seconds),
               "--settle", str(args.settle), "--velocity", str(args.velocity), "--accel", str(args.accel)]
    out = subprocess.run(command, check=True, capture_output=True, text=True, cwd=ROOT, timeout=120)
    return json.loads(out.stdout.strip().splitlines()[-1])


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=5, help="alternations of the three phases (default 5)")
    parser.add_argument("--seconds", type=float, default=4.0, help="measuring time per phase (default 4 s)")
    parser.add_argument("--settle", type=float, default=0.5, help="wait before measuring (default 0.5 s)")
    parser.add_argument("--velocity", type=float, default=500.0, help="Veloc, user units/s (default 500)")
    parser.add_argument("--accel", type=float, default=2000.0, help="Accel, user units/s² (default 2000)")
    parser.add_argument("--child", choices=("axis", "timer", "idle"), help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.child:
        child(args.child, args.seconds, args.settle, args.velocity, args.accel)
        return 0

    share: dict[str, list[float]] = {"axis": [], "timer": [], "idle": []}
    print(f"one PCD4.H3 axis moving (FForw at Veloc {args.velocity:g}, Accel {args.accel:g}) vs a bare asyncio timer every"
          f" {PERIOD * 1e3:g} ms vs the PCD idle; {args.rounds} rounds of {args.seconds:g} s, real clock")
    for n in range(args.rounds):
        line = []
        for phase in ("axis", "timer", "idle"):
            result = run_phase(phase, args)
            percent = 100.0 * result["cpu"] / result["wall"]
            share[phase].append(percent)
            extra = f" (position {result['position']}, settled {result['settled']})" if phase != "timer" else ""
            line.append(f"{phase} {percent:.3f} %{extra}")
        print(f"  round {n + 1}: " + "; ".join(line))
    axis, timer, idle = (statistics.median(share[p]) for p in ("axis", "timer", "idle"))
    print(f"median: axis {axis:.3f} %, timer {timer:.3f} %, idle {idle:.3f} % of a core")
    print(f"the moving axis's own share (axis - timer): {axis - timer:.3f} % of a core")
    print(f"the moving axis's whole cost (axis - idle): {axis - idle:.3f} % of a core (target <= 0.3 %)")
    print(f"ratio axis / timer: {axis / timer:.2f}" if timer > 0 else "ratio axis / timer: n/a (timer used no CPU)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
