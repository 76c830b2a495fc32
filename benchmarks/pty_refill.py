"""Does a pty refill while its reader works?  (With this script's writer: no.)

A writer process pours random bytes into a pty's slave as fast as the pty takes them; a bare
asyncio reader empties the master 4 KiB per loop turn (as devsim reads a pty) and then works
``W`` µs per chunk (a busy loop standing in for the face's work). If the pty refilled while the
reader works, a chunk's cycle would stay that of the bare reader until ``W`` exceeds it; if the
refill waits for the next read, the cycle grows by ``W``: the reader's work adds to the pty's
time instead of overlapping it. The script prints the cycle per chunk for each ``W`` (measured
in one run, alternating) and the share of the work that overlapped the refill, last.

The writer here is a forked child writing from the pty's own slave descriptor, and the bare reader
is CPU-bound (about 28 µs and 146 MB/s per 4 KiB on 2026-11-30).  ``benchmarks/noise.py``'s writer
is a separate process that opens the slave's path; there the bare reader waits for the refill
about half the time, and a reader's work of up to about 20 µs per read hides in that wait
(docs/performance-history.md, "Raw noise, the seventeenth session"): this script does not bound
the raw-noise ratio.

    python benchmarks/pty_refill.py [--megabytes 20] [--work 0,20,40,80] [--rounds 3]
"""

from __future__ import annotations

import argparse
import asyncio
import os
import random
import statistics
import time
import tty

CHUNK = 4096


def cycle(megabytes: float, work_us: float) -> float:
    """Seconds per chunk of one reader that works ``work_us`` µs per 4 KiB read."""
    master, slave = os.openpty()
    tty.setraw(master)
    tty.setraw(slave)
    total = int(megabytes * 1e6)
    pid = os.fork()
    if pid == 0:  # the writer
        os.close(master)
        block = random.Random(1).randbytes(1 << 16)
        sent = 0
        while sent < total:
            sent += os.write(slave, block[: min(len(block), total - sent)])
        os._exit(0)
    os.close(slave)
    os.set_blocking(master, False)
    loop = asyncio.new_event_loop()
    done = loop.create_future()
    got, reads, work = 0, 0, work_us / 1e6

    def readable() -> None:
        nonlocal got, reads
        try:
            chunk = os.read(master, CHUNK)
        except (BlockingIOError, OSError):  # (EIO once the writer closed its side)
            return
        got += len(chunk)
        reads += 1
        end = time.perf_counter() + work * len(chunk) / CHUNK
        while time.perf_counter() < end:
            pass
        if got >= total and not done.done():
            done.set_result(None)

    loop.add_reader(master, readable)
    start = time.perf_counter()
    loop.run_until_complete(done)
    elapsed = time.perf_counter() - start
    loop.close()
    os.close(master)
    os.waitpid(pid, 0)
    return elapsed / reads


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--megabytes", type=float, default=20.0)
    parser.add_argument("--work", default="0,20,40,80", help="µs of work per 4 KiB chunk, comma-separated")
    parser.add_argument("--rounds", type=int, default=3)
    args = parser.parse_args(argv)
    works = [float(w) for w in args.work.split(",")]
    if works[0] != 0:
        works.insert(0, 0.0)
    cycles: dict[float, list[float]] = {w: [] for w in works}
    for _ in range(args.rounds):
        for w in works:  # (alternating: each round sees every W on the same machine)
            cycles[w].append(cycle(args.megabytes, w))
    bare = statistics.median(cycles[0.0])
    overlaps = []
    for w in works:
        c = statistics.median(cycles[w])
        print(f"work {w:5.0f} µs per chunk: cycle {c * 1e6:6.1f} µs per 4 KiB ({CHUNK / c / 1e6:5.1f} MB/s), "
              f"grown by {(c - bare) * 1e6:6.1f} µs")
        if w:
            overlaps.append(1 - (c - bare) / (w / 1e6))
    print(f"share of the reader's work that overlapped the pty's refill: {statistics.median(overlaps):.2f} "
          "(0: the work adds to every cycle; 1: hidden behind the refill)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
