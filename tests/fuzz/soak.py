"""A soak under garbage (issue 32): every kind in its own ``devsim run`` process, every port fed
random bytes for a fixed time (ptys, UDP datagrams, TCP connections opened and closed), every
line's telegram tap on (``devsim ctl telegrams``) so that its decoders see the garbage too; then
checked: the process runs, its resident memory grew less than ``--rss-mb``, its open file
descriptors are what they were, and a valid request (the control API's ``state``) is answered.

    python -m tests.fuzz.soak [--seconds 60] [--kinds sers,gms96,...] [--rss-mb 20]

Not part of the test suite's default run; exit status 1 when a check failed.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import random
import socket
import sys
import tempfile
import time

from devsim.runtime.client import ControlClient
from tests.support.process import DevsimProcess, stop

KINDS = ("sers", "gms96", "poselesta", "ip247", "pcd4h3")


def _rss_kb(pid: int) -> int:
    with open(f"/proc/{pid}/status") as fh:
        return next(int(line.split()[1]) for line in fh if line.startswith("VmRSS:"))


def _fds(pid: int) -> int:
    return len(os.listdir(f"/proc/{pid}/fd"))


class _Port:
    """One served port, fed garbage from this side."""

    def __init__(self, port: str, scheme: str, where: str) -> None:
        self.port, self.scheme, self.where = port, scheme, where
        self.fd: int | None = None
        self.sock: socket.socket | None = None

    def _address(self) -> tuple[str, int]:
        host, _, number = self.where.split("://", 1)[1].rpartition(":")
        return host, int(number)

    def feed(self, data: bytes) -> int:
        """Bytes the port took (a full pty buffer takes none)."""
        with contextlib.suppress(OSError):
            if self.scheme == "pty":
                if self.fd is None:
                    self.fd = os.open(self.where, os.O_RDWR | os.O_NOCTTY | os.O_NONBLOCK)
                with contextlib.suppress(BlockingIOError):
                    os.read(self.fd, 65536)  # what the device answered: drained
                return os.write(self.fd, data)
            elif self.scheme == "udp":
                with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
                    return sock.sendto(data, self._address())
            else:
                if self.sock is None or random.random() < 0.02:  # connections come and go
                    self.close()
                    self.sock = socket.create_connection(self._address(), timeout=1)
                    self.sock.setblocking(False)
                with contextlib.suppress(BlockingIOError):
                    self.sock.recv(65536)
                return self.sock.send(data)
        return 0

    def close(self) -> None:
        if self.fd is not None:
            os.close(self.fd)
            self.fd = None
        if self.sock is not None:
            self.sock.close()
            self.sock = None


def soak(kind: str, seconds: float, rss_mb: float, directory: str) -> list[str]:
    """Run ``kind`` under garbage; the failed checks (none: it held)."""
    control = f"unix:{directory}/{kind}.sock"
    sim = DevsimProcess("run", kind, "--pty", "-q", "--control", control)
    ports: list[_Port] = []
    problems: list[str] = []
    try:
        while True:
            line = sim.next_match(sim.out, lambda text: True, 60, f"{kind}'s ports")
            name, _, rest = line.partition(": ")
            scheme, _, where = rest.partition(" ")
            if scheme in ("pty", "udp", "tcp") and name.startswith(kind):
                ports.append(_Port(name.partition(".")[2] or "main", scheme, where))
            if line == f"{kind}: ready":
                break
        client = ControlClient(control)
        for port in ports:
            client.telegrams(kind, port.port, count=0)  # the tap and its decoders from now on
        rss, fds = _rss_kb(sim.proc.pid), _fds(sim.proc.pid)
        rng = random.Random(kind)
        fed, end = 0, time.monotonic() + seconds
        while time.monotonic() < end:
            port = rng.choice(ports)
            data = rng.randbytes(rng.randrange(1, 256))
            fed += port.feed(data)
        for port in ports:
            port.close()
        state = client.state(kind)  # answered after the garbage
        settle = time.monotonic() + 5  # connections the soak just closed may still be closing
        while _fds(sim.proc.pid) > fds + 2 and time.monotonic() < settle:
            client.state(kind)
            time.sleep(0.05)  # bounded wait for the server to see the closes, not a synchronisation
        after_rss, after_fds = _rss_kb(sim.proc.pid), _fds(sim.proc.pid)
        client.close()
        print(f"{kind}: {fed} bytes on {len(ports)} ports in {seconds:g} s; resident {rss} -> {after_rss} kB, "
              f"fds {fds} -> {after_fds}, state of {len(state)} names", flush=True)
        if sim.proc.poll() is not None:
            problems.append(f"{kind}: the process ended ({sim.proc.returncode})")
        if after_rss - rss > rss_mb * 1024:
            problems.append(f"{kind}: resident memory grew {after_rss - rss} kB")
        if after_fds > fds + 2:
            problems.append(f"{kind}: open file descriptors {fds} -> {after_fds}")
    except Exception as exc:  # a check that could not be made is a failure too
        problems.append(f"{kind}: {type(exc).__name__}: {exc}")
    finally:
        for port in ports:
            port.close()
        stop(sim.proc)
    return problems


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=60.0, help="garbage time per kind (default 60)")
    parser.add_argument("--kinds", default=",".join(KINDS), help="comma-separated kinds (default all)")
    parser.add_argument("--rss-mb", type=float, default=20.0, help="resident growth allowed (default 20 MB)")
    args = parser.parse_args(argv)
    problems: list[str] = []
    with tempfile.TemporaryDirectory(prefix="devsim-soak-") as directory:
        for kind in args.kinds.split(","):
            problems += soak(kind, args.seconds, args.rss_mb, directory)
    for problem in problems:
        print(problem, file=sys.stderr)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
