"""Round-trip latency of a simulated device on a pty, against a bare asyncio echo server.

Starts a :class:`~devsim.runtime.Runtime` (real clock) in a thread with one device of
``--kind`` (default ``sers``) on a :class:`~devsim.transports.pty.PtyTransport`, opens the pty
with pyserial at the device's baud rate and times ``--n`` queries ``#P11?\\r`` (default echo
mode), each until the final acknowledgement line (``\\nok1\\n\\r``, or any ``\\nok...\\r``)
has arrived.  Then it does the same against a minimal asyncio server on a pty in this process
that answers every CR-terminated line with a fixed reply of the same length, and prints p50/p99
of both and their ratio.

Targets: p50 ratio sers/echo ≤ 1.25 in each of ``--runs`` (default 10) interleaved runs, p99 < 2 ms.

The GMS96 part times the Kurzsatz status poll ``#1`` (``10 01 03 04 16`` → ``10 40 03 43 16``)
the same way in ``--runs`` interleaved runs, against the echo server answering every frame that
ends in 16h with a reply of the same length (target: p50 ratio ≤ 1.15 in every run). The last
line is the p50 ratios of the last part measured.

``--instructions`` counts instead the instructions each server process executes per GMS96 status
poll (valgrind's cachegrind; a process polled N times against one polled none, the same warm-up
before both, ``PYTHONHASHSEED=0``): what the machine's load does not move, the servers' own work
without the kernel's.

``--calls`` lists instead the functions each server process calls per GMS96 status poll (Python
functions by file, line and name; C functions by name), counted with ``sys.setprofile`` the same
way (N polls against none): where the instructions go, load-independent too.

    python benchmarks/latency.py [--n 5000] [--runs 10] [--kind sers|stub] [--no-gms96] [--instructions|--calls]

``--kind stub`` uses a tiny stand-in device defined here (for checking the plumbing).
"""

from __future__ import annotations

import argparse
import asyncio
import os
import signal
import statistics
import subprocess
import sys
import tempfile
import threading
import time
import tty
from collections.abc import Callable

import serial

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
try:
    import devsim  # noqa: F401
except ImportError:  # running from a source checkout without installing
    sys.path.insert(0, ROOT)

QUERY = b"#P11?\r"
ACK = b"\nok"
RATIO_TARGET = 1.25
GMS96_RATIO_TARGET = 1.15  # issue 31


# -- the measurement -------------------------------------------------------------------------
def complete(buf: bytes) -> bool:
    """True once an acknowledgement line (``\\nok...\\r``) has arrived in full."""
    at = buf.rfind(ACK)
    return at >= 0 and buf.find(b"\r", at + len(ACK)) >= 0


GMS96_POLL = bytes.fromhex("1001030416")  # Kurzsatz #1 to card 3


def frame_complete(buf: bytes) -> bool:
    """True once a whole FT1.2 fixed frame (10h … 16h, with or without the MB4 octet) is in."""
    return len(buf) >= 5 and buf[0] == 0x10 and buf[-1] == 0x16 and len(buf) in (5, 6)


def round_trips(
    path: str,
    baud: int,
    n: int,
    warmup: int = 200,
    query: bytes = QUERY,
    done: Callable[[bytes], bool] = complete,
) -> tuple[list[float], int]:
    """Time ``n`` queries on ``path``; returns seconds per query and the reply length."""
    times: list[float] = []
    reply_len = 0
    with serial.Serial(path, baud, timeout=2) as port:
        port.reset_input_buffer()
        for i in range(warmup + n):
            elapsed, buf = one_query(port, path, query, done)
            if i >= warmup:
                times.append(elapsed)
            reply_len = len(buf)
    return times, reply_len


def one_query(port: serial.Serial, path: str, query: bytes, done: Callable[[bytes], bool]) -> tuple[float, bytes]:
    """Send ``query`` and read until ``done``; returns the seconds it took and the answer."""
    buf = b""
    start = time.perf_counter()
    port.write(query)
    while not done(buf):
        chunk = port.read(port.in_waiting or 1)
        if not chunk:
            raise SystemExit(f"no complete answer to {query!r} from {path} (got {buf!r})")
        buf += chunk
    return time.perf_counter() - start, buf


def interleaved(
    targets: list[tuple[str, bytes, Callable[[bytes], bool]]], n: int, warmup: int = 200
) -> list[list[float]]:
    """Time ``n`` queries on every target, alternating query by query, so that the machine's
    changing load affects all of them alike.  Returns seconds per query, per target."""
    ports = [serial.Serial(path, 9600, timeout=2) for path, _q, _d in targets]
    times: list[list[float]] = [[] for _ in targets]
    try:
        for port in ports:
            port.reset_input_buffer()
        for i in range(warmup + n):
            for k, (port, (path, query, done)) in enumerate(zip(ports, targets, strict=True)):
                elapsed, _buf = one_query(port, path, query, done)
                if i >= warmup:
                    times[k].append(elapsed)
    finally:
        for port in ports:
            port.close()
    return times


def percentile(values: list[float], q: float) -> float:
    ordered = sorted(values)
    index = min(len(ordered) - 1, max(0, round(q / 100 * (len(ordered) - 1))))
    return ordered[index]


def wait_for_answers(path: str, baud: int, timeout: float = 10.0) -> None:
    """Wait until the device answers (a SERS shows '-' while it boots)."""
    deadline = time.monotonic() + timeout
    with serial.Serial(path, baud, timeout=0.3) as port:
        while time.monotonic() < deadline:
            port.write(QUERY)
            buf = b""
            while chunk := port.read(64):
                buf += chunk
                if complete(buf):
                    return
    raise SystemExit(f"the device on {path} does not answer {QUERY!r}")


def _spawn(args: list[str]) -> tuple[subprocess.Popen[str], str]:
    """Start a server process that prints its pty path (``...: pty /dev/pts/N``) on stdout."""
    proc = subprocess.Popen(args, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    assert proc.stdout is not None
    for line in proc.stdout:
        if " pty " in line or line.startswith("echo:"):
            return proc, line.split()[-1]
    proc.kill()
    raise SystemExit(f"{args} did not print a pty path")


def _stop(proc: subprocess.Popen[str]) -> None:
    proc.send_signal(signal.SIGINT)
    try:
        proc.wait(10)
    except subprocess.TimeoutExpired:
        proc.kill()


def start_device(kind: str) -> tuple[subprocess.Popen[str], str]:
    """``devsim run KIND --pty`` in its own process (no boot delay); returns it and its pty."""
    if kind == "stub":
        os.environ["DEVSIM_EXTRA_KINDS"] = "stub=benchmarks.stub:StubDevice"
        os.environ["PYTHONPATH"] = os.pathsep.join(filter(None, [ROOT, os.environ.get("PYTHONPATH")]))
    extra: list[str] = []
    if kind in ("sers", "gms96"):
        fd, config = tempfile.mkstemp(suffix=".yaml")
        with os.fdopen(fd, "w") as fh:
            fh.write("boot_time: 0\n")
        extra = ["--config", config]
    return _spawn([sys.executable, "-m", "devsim", "run", kind, "--pty", *extra])


def measure_device(kind: str, n: int) -> tuple[list[float], int]:
    """The device runs in its own process (``devsim run KIND --pty``), like for a real host."""
    env_kind = kind
    extra = []
    if kind == "stub":
        os.environ["DEVSIM_EXTRA_KINDS"] = "stub=benchmarks.stub:StubDevice"
        os.environ["PYTHONPATH"] = os.pathsep.join(filter(None, [ROOT, os.environ.get("PYTHONPATH")]))
    with tempfile.TemporaryDirectory() as tmp:
        if kind == "sers":
            config = os.path.join(tmp, "bench.yaml")
            with open(config, "w") as fh:
                fh.write("boot_time: 0\n")
            extra = ["--config", config]
        proc, path = _spawn([sys.executable, "-m", "devsim", "run", env_kind, "--pty", *extra])
        try:
            wait_for_answers(path, 9600)
            return round_trips(path, 9600, n)
        finally:
            _stop(proc)


class EchoServer:
    """A bare asyncio server on a pty: every CR-terminated line gets ``reply``."""

    def __init__(self, reply: bytes, terminator: bytes = b"\r") -> None:
        self.reply = reply
        self.terminator = terminator
        self.master, self.slave = os.openpty()
        tty.setraw(self.master)
        tty.setraw(self.slave)
        self.path = os.ttyname(self.slave)
        self._loop = asyncio.new_event_loop()
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._buf = bytearray()

    def _run(self) -> None:
        asyncio.set_event_loop(self._loop)
        self._loop.add_reader(self.master, self._readable)
        self._loop.run_forever()

    def _readable(self) -> None:
        try:
            data = os.read(self.master, 4096)
        except OSError:
            return
        self._buf += data
        while self.terminator in self._buf:
            _, _, rest = bytes(self._buf).partition(self.terminator)
            self._buf = bytearray(rest)
            os.write(self.master, self.reply)

    def __enter__(self) -> EchoServer:
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        def stop() -> None:
            self._loop.remove_reader(self.master)
            self._loop.stop()

        self._loop.call_soon_threadsafe(stop)
        self._thread.join(5)
        os.close(self.master)
        os.close(self.slave)


def measure_echo(reply_len: int, n: int, binary: bool = False) -> list[float]:
    """The echo server runs in its own process too (``latency.py --serve-echo LEN``)."""
    args = [sys.executable, os.path.abspath(__file__), "--serve-echo", str(reply_len)]
    if binary:
        args.append("--binary")
    proc, path = _spawn(args)
    try:
        if binary:
            times, _ = round_trips(path, 9600, n, query=GMS96_POLL, done=frame_complete)
        else:
            times, _ = round_trips(path, 9600, n)
    finally:
        _stop(proc)
    return times


def measure_gms96(n: int) -> tuple[list[float], int]:
    """A GMS96 (card 3, no boot delay) in its own process, polled with Kurzsatz #1."""
    with tempfile.TemporaryDirectory() as tmp:
        config = os.path.join(tmp, "gms96.yaml")
        with open(config, "w") as fh:
            fh.write("boot_time: 0\n")
        proc, path = _spawn([sys.executable, "-m", "devsim", "run", "gms96", "--pty", "--config", config])
        try:
            return round_trips(path, 9600, n, query=GMS96_POLL, done=frame_complete)
        finally:
            _stop(proc)


def serve_echo(reply_len: int, binary: bool = False) -> None:
    if binary:  # a fixed frame of the same length: 10 … 16
        reply = b"\x10" + b"\x00" * max(0, reply_len - 2) + b"\x16"
        server = EchoServer(reply, terminator=b"\x16")
    else:
        tail = b"\nok1\n\r"
        server = EchoServer(b"x" * max(0, reply_len - len(tail)) + tail)
    with server:
        print(f"echo: pty {server.path}", flush=True)
        try:
            signal.sigwait({signal.SIGINT, signal.SIGTERM})
        except KeyboardInterrupt:
            pass


def summary(name: str, times: list[float]) -> tuple[float, float]:
    p50 = percentile(times, 50) * 1e3
    p99 = percentile(times, 99) * 1e3
    print(
        f"  {name:<8} p50 {p50:7.3f} ms   p99 {p99:7.3f} ms   mean {statistics.fmean(times) * 1e3:7.3f} ms"
        f"   max {max(times) * 1e3:7.3f} ms"
    )
    return p50, p99


def process_instructions(server: list[str], polls: int, warmup: int = 100) -> int:
    """Instructions the process ``server`` (which prints its pty) executes in all, polled with
    the GMS96 status poll ``warmup + polls`` times, then stopped."""
    with tempfile.TemporaryDirectory() as tmp:
        log = os.path.join(tmp, "valgrind.log")
        proc, path = _spawn(["valgrind", "--tool=cachegrind", "--cache-sim=no", "--cachegrind-out-file=/dev/null",
                             f"--log-file={log}", *server])
        try:
            round_trips(path, 9600, polls, warmup=warmup, query=GMS96_POLL, done=frame_complete)
        finally:
            _stop(proc)
            proc.wait(60)
        with open(log) as fh:
            for line in fh:
                if "I refs:" in line or "I   refs:" in line:
                    return int(line.rsplit(":", 1)[1].replace(",", "").strip())
    raise SystemExit(f"no instruction count from valgrind for {server}")


def _gms96_servers(tmp: str) -> dict[str, list[str]]:
    """The two servers the instruction and call counts compare: ``devsim run gms96`` (booted at
    once, its config written into ``tmp``) and the echo server answering a 5-byte frame."""
    config = os.path.join(tmp, "gms96.yaml")
    with open(config, "w") as fh:
        fh.write("boot_time: 0\n")
    return {
        "devsim run gms96": [sys.executable, "-m", "devsim", "run", "gms96", "--pty", "--config", config],
        "echo": [sys.executable, os.path.abspath(__file__), "--serve-echo", "5", "--binary"],
    }


def poll_instructions(n: int) -> int:
    """Instructions per GMS96 status poll of ``devsim run gms96`` and of the echo server."""
    os.environ["PYTHONHASHSEED"] = "0"
    with tempfile.TemporaryDirectory() as tmp:
        servers = _gms96_servers(tmp)
        per_poll = {name: (process_instructions(server, n) - process_instructions(server, 0)) / n
                    for name, server in servers.items()}
    print(f"instructions per GMS96 status poll ({n} polls against none): "
          + ", ".join(f"{name} {count / 1e3:.1f} k" for name, count in per_poll.items()))
    print(f"instructions per poll, devsim / echo: {per_poll['devsim run gms96'] / per_poll['echo']:.2f}")
    return 0


#: Run as ``python -c COUNTER FILE [--opcodes] (-m MODULE | SCRIPT) ARGS``: the program with every
#: call counted (``sys.setprofile``, in every thread), or with ``--opcodes`` every bytecode executed,
#: per function (``sys.settrace`` with opcode events: much slower), the counts written to FILE at
#: exit (``count<TAB>name``).  (``-c`` puts the working directory first on ``sys.path``, as ``-m`` does.)
COUNTER = """
import atexit, collections, os, runpy, sys, threading
out, argv, root = sys.argv[1], sys.argv[2:], os.getcwd()
opcodes = argv[0] == "--opcodes"
if opcodes:
    argv = argv[1:]
calls = collections.Counter()

def where(path):
    path = os.path.abspath(path)
    return os.path.relpath(path, root) if path.startswith(root + os.sep) else os.sep.join(path.split(os.sep)[-2:])

def profile(frame, event, arg):
    if event == "call":
        code = frame.f_code
        calls[f"{where(code.co_filename)}:{code.co_firstlineno} {code.co_name}"] += 1
    elif event == "c_call":
        calls[f"(C) {getattr(arg, '__qualname__', arg)}"] += 1

def trace(frame, event, arg):
    frame.f_trace_opcodes = True
    code = frame.f_code
    name = f"{where(code.co_filename)}:{code.co_firstlineno} {code.co_name}"

    def opcode(frame, event, arg):
        if event == "opcode":
            calls[name] += 1
        return opcode
    return opcode

def write():
    sys.setprofile(None)
    sys.settrace(None)
    with open(out, "w") as fh:
        fh.writelines(f"{count}\\t{name}\\n" for name, count in calls.items())

atexit.register(write)
if opcodes:
    sys.settrace(trace)
    threading.settrace(trace)
else:
    sys.setprofile(profile)
    threading.setprofile(profile)
if argv[0] == "-m":
    sys.argv = [argv[1], *argv[2:]]
    runpy.run_module(argv[1], run_name="__main__", alter_sys=True)
else:
    sys.argv = argv
    runpy.run_path(argv[0], run_name="__main__")
"""


def process_calls(server: list[str], polls: int, warmup: int = 100) -> dict[str, int]:
    """The calls the process ``server`` (``python ARGS``) makes in all, polled with the GMS96
    status poll ``warmup + polls`` times, then stopped."""
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "calls.tsv")
        proc, path = _spawn([sys.executable, "-c", COUNTER, out, *server[1:]])
        try:
            round_trips(path, 9600, polls, warmup=warmup, query=GMS96_POLL, done=frame_complete)
        finally:
            _stop(proc)
            proc.wait(60)
        counts: dict[str, int] = {}
        with open(out) as fh:
            for line in fh:
                count, name = line.rstrip("\n").split("\t", 1)
                counts[name] = int(count)
        return counts


def poll_calls(n: int) -> int:
    """The calls per GMS96 status poll of ``devsim run gms96`` and of the echo server."""
    with tempfile.TemporaryDirectory() as tmp:
        servers = _gms96_servers(tmp)
        for name, server in servers.items():
            polled, idle = process_calls(server, n), process_calls(server, 0)
            per_poll = {call: (count - idle.get(call, 0)) / n for call, count in polled.items()}
            shown = sorted(((count, call) for call, count in per_poll.items() if count >= 0.5), reverse=True)
            python = sum(count for count, call in shown if not call.startswith("(C)"))
            print(f"calls per GMS96 status poll in {name} ({n} polls against none): {python:.0f} Python functions")
            for count, call in shown:
                print(f"  {count:5.2f}  {call}")
    return 0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=5000, help="timed queries per target (default 5000)")
    parser.add_argument("--kind", default="sers", help="device kind (default sers; 'stub' = stand-in)")
    parser.add_argument("--runs", type=int, default=10, help="interleaved runs (default 10)")
    parser.add_argument("--no-gms96", action="store_true", help="skip the GMS96 status poll")
    parser.add_argument("--serve-echo", type=int, metavar="LEN", help=argparse.SUPPRESS)
    parser.add_argument("--binary", action="store_true", help=argparse.SUPPRESS)
    parser.add_argument("--instructions", action="store_true",
                        help="count instructions per GMS96 status poll (valgrind) instead of timing")
    parser.add_argument("--calls", action="store_true",
                        help="list the calls per GMS96 status poll in each server instead of timing")
    args = parser.parse_args(argv)
    if args.serve_echo is not None:
        signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT, signal.SIGTERM})
        serve_echo(args.serve_echo, binary=args.binary)
        return 0
    if args.instructions:
        return poll_instructions(args.n)
    if args.calls:
        return poll_calls(args.n)

    device_proc, device_path = start_device(args.kind)
    try:
        wait_for_answers(device_path, 9600)
        _t, reply_len = round_trips(device_path, 9600, 1, warmup=0)
        echo_proc, echo_path = _spawn([sys.executable, os.path.abspath(__file__), "--serve-echo", str(reply_len)])
        runs: list[tuple[list[float], list[float]]] = []
        try:
            for _ in range(args.runs):
                device_times, echo_times = interleaved(
                    [(device_path, QUERY, complete), (echo_path, QUERY, complete)], args.n
                )
                runs.append((device_times, echo_times))
        finally:
            _stop(echo_proc)
    finally:
        _stop(device_proc)

    print(
        f"latency: {args.runs} runs of {args.n} round trips of {QUERY!r} on a pty ({reply_len}-byte answer),"
        " interleaved with the echo"
    )
    ratios = []
    for device_times, echo_times in runs:
        d50, d99 = summary(args.kind, device_times)
        e50, e99 = summary("echo", echo_times)
        ratio50 = d50 / e50 if e50 else float("inf")
        ratio99 = d99 / e99 if e99 else float("inf")
        ratios.append(ratio50)
        print(f"  ratio    p50 {ratio50:7.2f}      p99 {ratio99:7.2f}")
    met = sum(r <= RATIO_TARGET for r in ratios)
    print(f"  p50 ratios: {' '.join(f'{r:.2f}' for r in ratios)}")
    print(f"  target p50 ratio <= {RATIO_TARGET} in every run: {met} of {len(ratios)} -> "
          f"{'met' if met == len(ratios) else 'MISSED'}")
    all_device = [t for device_times, _ in runs for t in device_times]
    d99 = percentile(all_device, 99) * 1e3
    print(f"  {args.kind} p99 {d99:.3f} ms, target < 2 ms: {'met' if d99 < 2.0 else 'MISSED'}")
    if not args.no_gms96:
        gms_proc, gms_path = start_device("gms96")
        gms_runs: list[tuple[list[float], list[float]]] = []
        try:
            _t, gms_len = round_trips(gms_path, 9600, 1, warmup=0, query=GMS96_POLL, done=frame_complete)
            echo_args = [sys.executable, os.path.abspath(__file__), "--serve-echo", str(gms_len), "--binary"]
            echo_proc, echo_path = _spawn(echo_args)
            try:
                for _ in range(args.runs):
                    gms_runs.append(interleaved(
                        [(gms_path, GMS96_POLL, frame_complete), (echo_path, GMS96_POLL, frame_complete)], args.n
                    ))
            finally:
                _stop(echo_proc)
        finally:
            _stop(gms_proc)
        print(f"latency: {args.runs} runs of {args.n} GMS96 status polls #1 {GMS96_POLL.hex(' ')} on a pty "
              f"({gms_len}-byte answer), interleaved with the echo")
        gms_ratios = []
        for gms_times, echo_bin in gms_runs:
            g50, _g99 = summary("gms96", gms_times)
            b50, _b99 = summary("echo", echo_bin)
            gms_ratios.append(g50 / b50 if b50 else float("inf"))
            print(f"  ratio    p50 {gms_ratios[-1]:7.2f}")
        met = sum(r <= GMS96_RATIO_TARGET for r in gms_ratios)
        print(f"  GMS96 target p50 ratio <= {GMS96_RATIO_TARGET} in every run: {met} of {len(gms_ratios)} -> "
              f"{'met' if met == len(gms_ratios) else 'MISSED'}")
        print(f"  GMS96 p50 ratios: {' '.join(f'{r:.2f}' for r in gms_ratios)}")
    else:
        print(f"  p50 ratios: {' '.join(f'{r:.2f}' for r in ratios)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
