"""Start-up time: from launching ``devsim run KIND --pty`` to a port a host can use.

Each run starts ``python -m devsim run KIND --pty`` and stops the clock at the line that prints
the port (the pty exists and is served from then on).  Two references are measured alternately
in the same run, so all see the same machine: the interpreter's own floor, ``python -c pass``,
and a bare asyncio pty server (imports asyncio, opens a pty, prints its name and serves it), the
least any asyncio simulator must do before its port is usable.
Modules are compiled once before the timed runs (bytecode cached in a temporary directory), as
they are when the package is installed.

Targets: < 120 ms for ``sers``; devsim / the bare server ≤ 1.4 (issue 31), printed last.

    python benchmarks/startup.py [--kind sers] [--runs 20]
"""

from __future__ import annotations

import argparse
import os
import signal
import statistics
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def _env(pycache: str) -> dict[str, str]:
    """Compiled modules are cached (in ``pycache``), as they are for an installed package: a
    ``PYTHONDONTWRITEBYTECODE`` in the caller's environment would measure the compiler."""
    env = dict(os.environ)
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    env["PYTHONPYCACHEPREFIX"] = pycache
    env["PYTHONPATH"] = os.pathsep.join(p for p in (ROOT, env.get("PYTHONPATH", "")) if p)
    env["DEVSIM_EXTRA_KINDS"] = "stub=benchmarks.stub:StubDevice"
    return env


def time_to_port(kind: str, env: dict[str, str]) -> float:
    start = time.perf_counter()
    proc = subprocess.Popen(
        [sys.executable, "-m", "devsim", "run", kind, "--pty"],
        cwd=ROOT, env=env, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True,
    )
    assert proc.stdout is not None
    line = proc.stdout.readline()
    elapsed = time.perf_counter() - start
    proc.send_signal(signal.SIGTERM)
    proc.wait(timeout=20)
    if ": pty /dev/" not in line:
        raise SystemExit(f"unexpected first line {line!r}")
    return elapsed


def time_floor(env: dict[str, str]) -> float:
    start = time.perf_counter()
    subprocess.run([sys.executable, "-c", "pass"], env=env, check=True)
    return time.perf_counter() - start


BARE_PTY_SERVER = """
import asyncio, os, sys
async def main():
    master, slave = os.openpty()
    loop = asyncio.get_running_loop()
    loop.add_reader(master, lambda: os.write(master, os.read(master, 4096)))
    print(f"bare: pty {os.ttyname(slave)}", flush=True)
    await asyncio.Event().wait()
asyncio.run(main())
"""


def time_bare(env: dict[str, str]) -> float:
    start = time.perf_counter()
    proc = subprocess.Popen([sys.executable, "-c", BARE_PTY_SERVER], env=env, stdin=subprocess.DEVNULL,
                            stdout=subprocess.PIPE, text=True)
    assert proc.stdout is not None
    line = proc.stdout.readline()
    elapsed = time.perf_counter() - start
    proc.kill()
    proc.wait(timeout=20)
    if ": pty /dev/" not in line:
        raise SystemExit(f"unexpected first line {line!r}")
    return elapsed


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--kind", default="sers")
    parser.add_argument("--runs", type=int, default=20)
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory() as pycache:
        env = _env(pycache)
        time_to_port(args.kind, env)  # warm the file cache and compile once
        time_bare(env)
        devsim, floor, bare = [], [], []
        for _ in range(args.runs):
            devsim.append(time_to_port(args.kind, env))
            floor.append(time_floor(env))
            bare.append(time_bare(env))
    med, flo, ref = statistics.median(devsim), statistics.median(floor), statistics.median(bare)
    print(f"devsim run {args.kind} --pty to a usable port: median {med * 1e3:.0f} ms "
          f"(min {min(devsim) * 1e3:.0f}, max {max(devsim) * 1e3:.0f}) over {args.runs} runs")
    print(f"interpreter floor (python -c pass): median {flo * 1e3:.0f} ms")
    print(f"bare asyncio pty server: median {ref * 1e3:.0f} ms")
    print(f"above the floor: {(med - flo) * 1e3:.0f} ms; target < 120 ms in all: {'met' if med < 0.120 else 'missed'}")
    print(f"start-up to a usable port, devsim / bare asyncio pty server: {med / ref:.2f} (target <= 1.4)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
