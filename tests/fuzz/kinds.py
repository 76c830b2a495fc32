"""Structure-aware fuzzing of a device kind, under virtual time.

The inputs are the test suite's own port inputs (record them first with :mod:`tests.fuzz.corpus`),
mutated (bits and bytes changed, inserted, deleted, runs repeated, pieces of other inputs spliced
in) and fed to the kind's ports in random chunks, mixed with clock advances, point writes at their
limits, declared faults, host disconnects, power cycles and reads of every point.  A step that
raises, or that takes more than ``--watchdog`` seconds (a clock that cannot advance), is a finding:
it is written to ``.fuzz/finding-KIND-SEED-N.json`` with every step since the device was made, and
the fuzzer goes on with a fresh device.  A fresh device is also made every ``--fresh`` steps
(default 200,000), so that the steps kept for a finding (and its replay) stay bounded: a
5-million-step run kept them all, 1.9 GB.

    python -m tests.fuzz.kinds KIND [--seconds 120] [--seed 1] [--fresh 200000]
    python -m tests.fuzz.kinds KIND --replay .fuzz/finding-KIND-1-0.json

A finding file is plain JSON (steps, bytes in hex): replaying one runs nothing but the steps.
"""

from __future__ import annotations

import argparse
import glob
import json
import os
import random
import signal
import tempfile
import time
import traceback
from collections.abc import Callable
from typing import Any

from devsim.core.clock import VirtualClock
from devsim.core.device import Device
from devsim.core.nvram import NonVolatileMemory
from devsim.core.points import BadValue, Point
from devsim.core.registry import device_class
from tests.fuzz.corpus import DIRECTORY

Step = list[Any]  # ["feed", port, hex, [chunk sizes]] | ["advance", s] | ["set", name, value] | …
BOOT = 30.0
SPECIAL = (0x00, 0xFF, 0x7F, 0x80, 0x10, 0x68, 0x16, 0xE5, 0x0D, 0x23)


class Watchdog(Exception):
    """A step ran longer than the watchdog allows."""


def load_corpus(kind: str) -> dict[str, list[bytes]]:
    corpus: dict[str, list[bytes]] = {}
    for path in glob.glob(os.path.join(DIRECTORY, "corpus-*.json")):
        with open(path) as fh:
            for key, chunks in json.load(fh).items():
                owner, _, port = key.partition("/")
                if owner == kind:
                    corpus.setdefault(port, []).extend(bytes.fromhex(c) for c in chunks)
    return corpus


class Rig:
    """One device of the kind on a virtual clock, its ports' output discarded, driven by steps."""

    def __init__(self, kind: str) -> None:
        self.clock = VirtualClock()
        self._state = tempfile.mkdtemp(prefix="devsim-fuzz-")
        self.device: Device = device_class(kind)(clock=self.clock, name="d",
                                                  nvram=NonVolatileMemory.for_device(self._state, "d"))
        self._boot()
        for name in self.device.port_names():
            self.device.port(name).attach(lambda data: None)

    def _boot(self) -> None:
        self.clock.run_until(lambda: not self.device.booting, BOOT)

    def run(self, step: Step) -> None:
        ACTIONS[step[0]](self, *step[1:])

    def feed(self, port: str, data: str, sizes: list[int]) -> None:
        raw, at = bytes.fromhex(data), 0
        for size in sizes:
            self.device.port(port).feed(raw[at : at + size])
            at += size

    def advance(self, seconds: float) -> None:
        self.clock.advance(seconds)

    def set(self, name: str, value: Any) -> None:
        try:
            self.device.set(name, value)
        except BadValue:
            pass  # refused, as it may be

    def fault(self, name: str, active: bool) -> None:
        self.device.fault(name, active)

    def read_all(self) -> None:
        for point in self.device.points:
            if point.readable:
                self.device.read(point.name)
        self.device.state()

    def disconnect(self, port: str) -> None:
        self.device.port(port).host_disconnected()

    def power_cycle(self) -> None:
        self.device.power_cycle()
        self._boot()


ACTIONS: dict[str, Callable[..., None]] = {
    "feed": Rig.feed, "advance": Rig.advance, "set": Rig.set, "fault": Rig.fault, "read_all": Rig.read_all,
    "disconnect": Rig.disconnect, "power_cycle": Rig.power_cycle,
}


class Fuzzer:
    """Draws the steps (see the module docstring)."""

    def __init__(self, rng: random.Random, corpus: dict[str, list[bytes]], device: Device) -> None:
        self.rng, self.corpus = rng, corpus
        self.ports = [p for p in device.port_names() if corpus.get(p)] or device.port_names()
        self.faults = list(device.faults.names())
        self.points = [p for p in device.points if p.settable]

    def step(self) -> Step:
        rng, r = self.rng, self.rng.random()
        if r < 0.80:
            port = rng.choice(self.ports)
            data = self._input(port)
            sizes, left = [], len(data)
            while left > 0:
                sizes.append(min(left, rng.choice((1, 2, 3, 7, left, left))))
                left -= sizes[-1]
            return ["feed", port, data.hex(), sizes]
        if r < 0.90:
            return ["advance", rng.choice((0.0005, 0.003, 0.02, 0.2, 2.0, 10.0))]
        if r < 0.93 and self.faults:
            return ["fault", rng.choice(self.faults), rng.random() < 0.6]
        if r < 0.95 and self.points:
            point = rng.choice(self.points)
            return ["set", point.name, self._value(point)]
        if r < 0.97:
            return ["read_all"]
        if r < 0.985:
            return ["disconnect", rng.choice(self.ports)]
        return ["power_cycle"]

    def _input(self, port: str) -> bytes:
        rng = self.rng
        if not self.corpus.get(port) or rng.random() < 0.1:
            return rng.randbytes(rng.randrange(1, 64))
        b = bytearray(rng.choice(self.corpus[port]))
        for _ in range(rng.choice((0, 1, 1, 2, 3, 8))):
            self._mutate(b)
        return bytes(b) or b"\r"

    def _mutate(self, b: bytearray) -> None:
        rng = self.rng
        at = rng.randrange(len(b)) if b else 0
        how = rng.randrange(7)
        if how == 0 and b:
            b[at] ^= 1 << rng.randrange(8)
        elif how == 1 and b:
            b[at] = rng.randrange(256)
        elif how == 2:
            b.insert(at, rng.randrange(256))
        elif how == 3 and b:
            del b[at : at + rng.randrange(1, 8)]
        elif how == 4:
            other = rng.choice(self.corpus[rng.choice([p for p in self.ports if self.corpus.get(p)])])
            b[at:at] = other[rng.randrange(len(other) + 1) :]
        elif how == 5 and b:
            b[at:at] = b[at : at + rng.randrange(1, 16)] * rng.randrange(1, 4)
        elif how == 6 and b:
            b[at] = rng.choice(SPECIAL)

    def _value(self, point: Point) -> Any:
        rng = self.rng
        if point.choices:
            return rng.choice(list(point.choices))
        if point.type == "bool":
            return rng.random() < 0.5
        if point.type in ("int", "float"):
            lo = point.minimum if point.minimum is not None else -1000.0
            hi = point.maximum if point.maximum is not None else 1000.0
            value = rng.choice((lo, hi, (lo + hi) / 2, lo + (hi - lo) * rng.random()))
            return int(value) if point.type == "int" else value
        return rng.choice(("", "x", "0"))


def _timed(rig: Rig, step: Step, watchdog: float) -> None:
    def expired(*_: object) -> None:
        raise Watchdog(f"step {step[0]} ran longer than {watchdog:g} s")

    previous = signal.signal(signal.SIGALRM, expired)
    signal.setitimer(signal.ITIMER_REAL, watchdog)
    try:
        rig.run(step)
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)


def fuzz(kind: str, seconds: float, seed: int, watchdog: float, fresh: int = 200_000) -> int:
    corpus = load_corpus(kind)
    rng = random.Random(seed)
    rig = Rig(kind)
    fuzzer = Fuzzer(rng, corpus, rig.device)
    seen: set[tuple[str, str, int]] = set()
    history: list[Step] = []
    steps, end = 0, time.monotonic() + seconds
    while time.monotonic() < end:
        if len(history) >= fresh:
            rig, history = Rig(kind), []
            fuzzer = Fuzzer(rng, corpus, rig.device)
        step = fuzzer.step()
        history.append(step)
        steps += 1
        try:
            _timed(rig, step, watchdog)
        except Exception as exc:  # a finding
            frame = traceback.extract_tb(exc.__traceback__)[-1]
            key = (type(exc).__name__, frame.filename, frame.lineno or 0)
            if key not in seen:
                seen.add(key)
                path = os.path.join(DIRECTORY, f"finding-{kind}-{seed}-{len(seen) - 1}.json")
                os.makedirs(DIRECTORY, exist_ok=True)
                with open(path, "w") as fh:
                    json.dump({"kind": kind, "error": "".join(traceback.format_exception(exc)), "steps": history}, fh)
                print(f"{path}: {type(exc).__name__} at {frame.filename}:{frame.lineno}", flush=True)
            rig, history = Rig(kind), []
            fuzzer = Fuzzer(rng, corpus, rig.device)
    print(f"{kind}: {steps} steps, {sum(len(c) for c in corpus.values())} corpus inputs, {len(seen)} findings")
    return 1 if seen else 0


def replay(kind: str, path: str, watchdog: float) -> int:
    with open(path) as fh:
        finding = json.load(fh)
    rig = Rig(kind)
    for number, step in enumerate(finding["steps"]):
        try:
            _timed(rig, step, watchdog)
        except Exception:
            print(f"step {number} of {len(finding['steps'])}: {step[:2]}")
            traceback.print_exc()
            return 1
    print(f"{len(finding['steps'])} steps replayed without an error")
    return 0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("kind")
    parser.add_argument("--seconds", type=float, default=120.0)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--watchdog", type=float, default=20.0, help="seconds one step may take")
    parser.add_argument("--replay", help="a finding file to run again")
    parser.add_argument("--fresh", type=int, default=200_000, help="steps before a fresh device (default 200000)")
    args = parser.parse_args(argv)
    if args.replay:
        return replay(args.kind, args.replay, args.watchdog)
    return fuzz(args.kind, args.seconds, args.seed, args.watchdog, max(1, args.fresh))


if __name__ == "__main__":
    raise SystemExit(main())
