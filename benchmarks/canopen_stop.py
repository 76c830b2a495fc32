"""How long ``devsim run sers --pty --canopen 5@127.0.0.1:0`` takes to exit after SIGTERM: idle, and
while raw-mode socketcand clients flood it with ``< send … >`` frames (and read what it sends).

A probe, not a test (wall time on a shared machine): it prints, for each case and run, the
seconds from SIGTERM to the process's exit, its status, and whether stderr had a traceback.
Measured 2026-12-01 on the shared 2-core machine (3 runs each): before the bus readers of
``devsim.transports.can_reader`` and the sessions' turn per read, 0.92 to 0.96 s idle (up to the
1 s cycle of python-can's notifier, by its phase), 2.0 to 2.6 s with one flooding client, 10.3 to
11.7 s with three; after, 0.03 to 0.07 s idle, 0.07 to 0.13 s with one, 0.42 to 0.54 s with three.

    python benchmarks/canopen_stop.py [--runs 3] [--clients 0 1 3] [--flood 2]
"""

from __future__ import annotations

import argparse
import contextlib
import os
import re
import signal
import socket
import subprocess
import sys
import threading
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
FRAME = b"< send 123 8 01 02 03 04 05 06 07 08 >"


def raw_client(port: int) -> socket.socket:
    client = socket.create_connection(("127.0.0.1", port), timeout=10)
    for command, reply in ((b"", b"< hi >"), (b"< open can0 >", b"< ok >"), (b"< rawmode >", b"< ok >")):
        client.sendall(command)
        received = b""
        while reply not in received:
            received += client.recv(100)
    client.settimeout(None)
    return client


def one_run(clients: int, flood: float) -> tuple[float, int, bool]:
    """Start the simulator, connect ``clients`` flooding clients, flood ``flood`` s, SIGTERM: the
    seconds to its exit, its status, whether stderr had a traceback."""
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(p for p in (ROOT, os.environ.get("PYTHONPATH", "")) if p))
    proc = subprocess.Popen([sys.executable, "-m", "devsim", "run", "sers", "--pty", "--canopen", "5@127.0.0.1:0"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, stdin=subprocess.DEVNULL, env=env, text=True)
    assert proc.stdout is not None and proc.stderr is not None
    port = None
    while port is None:
        line = proc.stdout.readline()
        if not line:
            raise SystemExit(f"devsim run ended: {proc.stderr.read()}")
        found = re.search(r"socketcand 127\.0\.0\.1:(\d+)", line)
        port = int(found.group(1)) if found else None
    stop = threading.Event()
    sockets = [raw_client(port) for _ in range(clients)]

    def send(client: socket.socket) -> None:
        with contextlib.suppress(OSError):
            while not stop.is_set():
                client.sendall(FRAME * 100)

    def read(client: socket.socket) -> None:
        with contextlib.suppress(OSError):
            while client.recv(65536):
                pass

    for client in sockets:
        threading.Thread(target=send, args=(client,), daemon=True).start()
        threading.Thread(target=read, args=(client,), daemon=True).start()
    time.sleep(flood)
    start = time.monotonic()
    proc.send_signal(signal.SIGTERM)
    status = proc.wait()
    seconds = time.monotonic() - start
    stop.set()
    err = proc.stderr.read()
    for client in sockets:
        client.close()
    return seconds, status, "Traceback" in err


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=3, help="runs per case (default 3)")
    parser.add_argument("--clients", type=int, nargs="+", default=[0, 1, 3], help="flooding clients per case")
    parser.add_argument("--flood", type=float, default=2.0, help="seconds of flood before SIGTERM (default 2)")
    args = parser.parse_args(argv)
    for clients in args.clients:
        for run in range(args.runs):
            seconds, status, traceback = one_run(clients, args.flood if clients else 1.0)
            print(f"{clients} flooding client(s), run {run + 1}: exit status {status} {seconds:.3f} s after SIGTERM"
                  + (" (traceback on stderr)" if traceback else ""))
    return 0


if __name__ == "__main__":
    sys.exit(main())
