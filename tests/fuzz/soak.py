"""A soak under garbage (issue 32): every kind in its own ``devsim run`` process with a state dir,
every port fed random bytes for a fixed time (ptys, UDP datagrams, TCP and RFC 2217 connections
opened and closed), now and then a valid telegram of the kind's own protocol cut off halfway by a
close (the host reopens at once), every line's telegram tap on (``devsim ctl telegrams``) so that
its decoders see the garbage too; then checked: the process runs, its resident memory grew less
than ``--rss-mb``, its open file descriptors are what they were, a valid request (the control
API's ``state``) is answered, a known-good request in the device's own protocol gets the answer
it got before the garbage (on every port that has one), the stored memory (``*.nvram.json``) is
what it was, and stderr holds no traceback.

    python -m tests.fuzz.soak [--seconds 60] [--kinds sers,gms96,...] [--rss-mb 20] [--transport pty]
                              [--seed N] [--drives 1,2,3] [--pacing] [--speed F]

``--transport`` serves the serial ports on ``pty`` (the default), ``tcp`` or ``rfc2217``;
``--seed`` picks another garbage sequence (default: the kind's own); ``--drives`` puts one SERS per
address on one RS-485 line (each address asked its known-good request); ``--pacing`` paces the
device's output at its baud rate; ``--speed F`` runs the device's time F times as fast (timers,
moves, response delays, timeouts).  A port whose known-good answer changed is reported with the last
bytes fed to it.  Not part of the test suite's default run; exit status 1 when a check failed.
"""

from __future__ import annotations

import argparse
import collections
import contextlib
import glob
import os
import queue
import random
import re
import socket
import sys
import tempfile
import termios
import time

import serial

from devsim.devices.ip247.client import PgClient
from devsim.devices.pcd4h3.sbus import crc16, ether_frame, stuff
from devsim.runtime.client import ControlClient
from tests.support.process import DevsimProcess, stop

KINDS = ("sers", "gms96", "poselesta", "ip247", "pcd4h3")
#: Ports a kind serves on the network by default, moved to ports nobody holds.
NETWORK = {"pcd4h3": ["--port", "ether_udp=udp:0", "--port", "ether_tcp=tcp:0"]}


def _rss_kb(pid: int) -> int:
    with open(f"/proc/{pid}/status") as fh:
        return next(int(line.split()[1]) for line in fh if line.startswith("VmRSS:"))


def _fds(pid: int) -> int:
    return len(os.listdir(f"/proc/{pid}/fd"))


def _address(where: str) -> tuple[str, int]:
    host, _, number = where.split("://", 1)[1].rpartition(":")
    return host, int(number)


def _sbus(command: int) -> bytes:
    """An S-Bus request to station 1 with no parameters (1Dh station, 20h firmware), unstuffed."""
    body = bytes((0xB5, 0, 1, command))
    return body + crc16(body).to_bytes(2, "big")


#: Per kind and port: the host's line settings and a known-good request in the device's protocol,
#: which garbage does not change the answer to (a line end first, for a line-based protocol, so
#: that garbage left in the device's line buffer ends before it).
REQUESTS: dict[str, dict[str, tuple[dict[str, object], list[bytes]]]] = {
    "sers": {"main": ({}, [b"\r", b"#1VER\r"])},
    "gms96": {"main": ({"parity": "E"}, [bytes.fromhex("68 09 09 68 53 03 54 05 00 00 0A 00 00 B9 16")])},  # T5;0;10
    "pcd4h3": {"sbus": ({}, [stuff(_sbus(0x1D))]),
               "ether_udp": ({}, [ether_frame(1, 7, 0, _sbus(0x20)[2:-2])]),
               "ether_tcp": ({}, [ether_frame(1, 7, 0, _sbus(0x20)[2:-2])])},
}


#: The SERS acknowledgement's digit is the drive's state (1 standing, 3 standing with a
#: warning), which garbage may change: compared without it.
_SERS_STATE = re.compile(rb"\nok\d\n")


def _serial(scheme: str, where: str, settings: dict[str, object], timeout: float = 0.05) -> serial.SerialBase:
    """The port opened as a host opens it, its timeout set in the same request (a pty asked for
    parity twice in a row refuses the second, docs/connect.md); refused anyway, the same request
    a moment later."""
    url = where if scheme == "pty" else f"{scheme if scheme == 'rfc2217' else 'socket'}://{where.split('://', 1)[1]}"
    for attempt in range(5):
        try:
            return serial.serial_for_url(url, baudrate=settings.get("baudrate", 9600), timeout=timeout,
                                         **{k: v for k, v in settings.items() if k != "baudrate"})
        except (termios.error, serial.SerialException):
            if attempt == 4:
                raise
            time.sleep(0.05)
    raise AssertionError("unreachable")


def _quiet_read(port: serial.SerialBase, quiet: float = 0.3, limit: float = 3.0) -> bytes:
    """What the port brings until it has been quiet for ``quiet`` seconds."""
    out, last, end = bytearray(), time.monotonic(), time.monotonic() + limit
    while time.monotonic() - last < quiet and time.monotonic() < end:
        chunk = port.read(4096)
        if chunk:
            out += chunk
            last = time.monotonic()
    return bytes(out)


def _ask(scheme: str, where: str, settings: dict[str, object], steps: list[bytes]) -> bytes:
    """The answer to the last of ``steps`` (each written after the answer to the one before)."""
    if scheme == "udp":
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
            sock.settimeout(2)
            sock.sendto(steps[-1], _address(where))
            try:
                return sock.recv(65536)
            except TimeoutError:
                return b""
    with contextlib.closing(_serial(scheme, where, settings)) as port:
        answer = b""
        for step in steps:
            port.write(step)
            answer = _quiet_read(port)
        return answer


def _ask_ip247(scheme: str, where: str) -> bytes:
    """SYS-ID (READ_REC BA70) over AS511 on the PG port, after the 500 ms that end any transaction:
    the ack and the data (the header's error, mode and attributes of page 4 are garbage's to change)."""
    time.sleep(0.6)
    with contextlib.closing(_serial(scheme, where, {"parity": "E"}, timeout=2)) as port:
        answer = PgClient(port).read_record(4, 70)
        return answer[:1] + answer[8:]


def _ask_poselesta(client: ControlClient, scheme: str, where: str) -> bytes:
    """A tape read in on V7 (T7) into P20, the program the control then holds."""
    for name, value in (("panel.mode", "EXTERNAL_OPERATION"), ("panel.program", 20), ("param.P71", 1),
                        ("v7.transfer", "input")):
        client.set("poselesta", name, value)
    with contextlib.closing(_serial(scheme, where, {"baudrate": 1200, "stopbits": 2})) as port:
        port.write(b"%\r\nN1 X10.5 Y-3\r\nN2 G00 X0 Y0 M02\r\nM30\r\n")
        end = time.monotonic() + 5
        while client.read("poselesta", "v7.state") != "done" and time.monotonic() < end:
            time.sleep(0.05)  # bounded wait for 45 characters at 1200 baud to arrive, not a synchronisation
    return repr(client.read("poselesta", "program.P20")).encode()


def _requests(kind: str, drives: list[int]) -> dict[str, tuple[str, dict[str, object], list[bytes]]]:
    """The known-good requests by name: port, line settings, steps (SERS multidrop: each drive's
    ``#<address>VER``, named ``main#<address>``)."""
    if kind == "sers" and drives:
        return {f"main#{a}": ("main", {}, [b"\r", b"#%dVER\r" % a]) for a in drives}
    return {name: (name, settings, steps) for name, (settings, steps) in REQUESTS.get(kind, {}).items()}


def _known_good(kind: str, ports: dict[str, _Port], client: ControlClient, drives: list[int]) -> dict[str, bytes]:
    """Each port's (each drive's) answer to its known-good request."""
    if kind == "ip247":
        return {"pg": _ask_ip247(ports["pg"].scheme, ports["pg"].where)}
    if kind == "poselesta":
        return {"v7": _ask_poselesta(client, ports["v7"].scheme, ports["v7"].where)}
    return {name: _SERS_STATE.sub(b"\nok\n", _ask(ports[port].scheme, ports[port].where, settings, steps))
            for name, (port, settings, steps) in _requests(kind, drives).items() if port in ports}


class _Port:
    """One served port, fed garbage from this side."""

    def __init__(self, port: str, scheme: str, where: str) -> None:
        self.port, self.scheme, self.where = port, scheme, where
        self.fd: int | None = None
        self.sock: socket.socket | None = None
        self.recent: collections.deque[bytes] = collections.deque(maxlen=16)  # the last chunks fed

    def last_fed(self, most: int = 512) -> bytes:
        """The last (up to ``most``) bytes fed to the port, for a report."""
        return b"".join(self.recent)[-most:]

    def feed(self, data: bytes, cut: bool = False) -> int:
        """Bytes the port took (a full pty buffer takes none); ``cut``: the connection is closed
        after them and opened again at once, as a host cut off mid-telegram."""
        taken = 0
        self.recent.append(data)
        with contextlib.suppress(OSError):
            if self.scheme == "pty":
                if self.fd is None:
                    self.fd = os.open(self.where, os.O_RDWR | os.O_NOCTTY | os.O_NONBLOCK)
                with contextlib.suppress(BlockingIOError):
                    os.read(self.fd, 65536)  # what the device answered: drained
                taken = os.write(self.fd, data)
            elif self.scheme == "udp":
                with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
                    return sock.sendto(data, _address(self.where))
            else:
                if self.sock is None or random.random() < 0.02:  # connections come and go
                    self.close()
                    self.sock = socket.create_connection(_address(self.where), timeout=1)
                    self.sock.setblocking(False)
                with contextlib.suppress(BlockingIOError):
                    self.sock.recv(65536)
                taken = self.sock.send(data)
        if cut:
            self.close()
        return taken

    def close(self) -> None:
        if self.fd is not None:
            os.close(self.fd)
            self.fd = None
        if self.sock is not None:
            self.sock.close()
            self.sock = None


def _nvram(directory: str) -> dict[str, bytes]:
    out = {}
    for path in glob.glob(os.path.join(directory, "*.nvram.json")):
        with open(path, "rb") as fh:
            out[os.path.basename(path)] = fh.read()
    return out


def _tracebacks(lines: queue.Queue[str | None]) -> list[str]:
    """The lines of a stopped process's stderr that say an exception escaped (with the line
    before each)."""
    seen: list[str] = []
    with contextlib.suppress(queue.Empty):
        while (line := lines.get(timeout=5)) is not None:
            seen.append(line)
    return [f"{seen[i - 1] if i else ''} / {line}" for i, line in enumerate(seen)
            if line.startswith("Traceback") or "Fatal error" in line]


def soak(kind: str, seconds: float, rss_mb: float, directory: str, transport: str = "pty", *,
         seed: int | None = None, drives: list[int] | None = None, pacing: bool = False,
         speed: float | None = None) -> list[str]:
    """Run ``kind`` under garbage; the failed checks (none: it held).  ``drives``: one device
    per address on one line (``--drives``); ``pacing``: output paced (``--pacing``); ``speed``:
    the device's time factor (``--speed``)."""
    drives = drives or []
    control = f"unix:{directory}/{kind}.sock"
    state = os.path.join(directory, f"state-{kind}")
    sim = DevsimProcess("run", kind, f"--{transport}", *(["0"] if transport != "pty" else []), "-q",
                        "--control", control, "--state-dir", state, *NETWORK.get(kind, []),
                        *(["--drives", ",".join(map(str, drives))] if drives else []), *(["--pacing"] if pacing else []),
                        *(["--speed", str(speed)] if speed is not None else []))
    devices = [f"{kind}{a}" for a in drives] or [kind]
    ports: dict[str, _Port] = {}
    problems: list[str] = []
    try:
        waiting = set(devices)
        while waiting:
            line = sim.next_match(sim.out, lambda text: True, 60, f"{kind}'s ports")
            name, _, rest = line.partition(": ")
            scheme, _, where = rest.partition(" ")
            if scheme in ("pty", "udp", "tcp", "rfc2217") and name.startswith(kind):
                port = name.partition(".")[2] or "main"
                ports[port] = _Port(port, scheme, where)  # (a multidrop line: every drive names it)
            if rest == "ready":
                waiting.discard(name)
        client = ControlClient(control)
        good = _known_good(kind, ports, client, drives)
        memory = _nvram(state)
        for port in ports.values():
            client.telegrams(devices[0], port.port, count=0)  # the tap and its decoders from now on
        rss, fds = _rss_kb(sim.proc.pid), _fds(sim.proc.pid)
        rng = random.Random(kind if seed is None else f"{kind}:{seed}")
        telegrams: list[bytes] = [step for _, _, steps in _requests(kind, drives).values() for step in steps if len(step) > 1]
        fed, end = 0, time.monotonic() + seconds
        while time.monotonic() < end:
            port = rng.choice(list(ports.values()))
            if telegrams and port.scheme != "udp" and rng.random() < 0.05:
                telegram = rng.choice(telegrams)
                fed += port.feed(telegram[: rng.randrange(1, len(telegram))], cut=True)
            else:
                fed += port.feed(rng.randbytes(rng.randrange(1, 256)))
        for port in ports.values():
            port.close()
        time.sleep(0.5)  # line idle, as the protocols ask after garbage (GMS96 FT1.2 R4: 33 bit times)
        drained = time.monotonic() + 120  # paced: the echo of the garbage still on the wire (at most 64 KiB)
        while pacing and time.monotonic() < drained and any(
                client.line(devices[0], port.port)["pending_out"] for port in ports.values() if port.scheme != "udp"):
            time.sleep(0.1)  # bounded wait for the paced output to leave, not a synchronisation
        answers = [client.state(device) for device in devices]  # answered after the garbage
        settle = time.monotonic() + 5  # connections the soak just closed may still be closing
        while _fds(sim.proc.pid) > fds + 2 and time.monotonic() < settle:
            client.state(devices[0])
            time.sleep(0.05)  # bounded wait for the server to see the closes, not a synchronisation
        after_rss, after_fds = _rss_kb(sim.proc.pid), _fds(sim.proc.pid)
        after = _known_good(kind, ports, client, drives)
        client.close()
        print(f"{kind}: {fed} bytes on {len(ports)} ports in {seconds:g} s; resident {rss} -> {after_rss} kB, "
              f"fds {fds} -> {after_fds}, state of {sum(map(len, answers))} names, known-good answers on "
              f"{', '.join(good) or 'no port'}", flush=True)
        if sim.proc.poll() is not None:
            problems.append(f"{kind}: the process ended ({sim.proc.returncode})")
        if after_rss - rss > rss_mb * 1024:
            problems.append(f"{kind}: resident memory grew {after_rss - rss} kB")
        if after_fds > fds + 2:
            problems.append(f"{kind}: open file descriptors {fds} -> {after_fds}")
        problems += [f"{kind}.{name}: answered {after.get(name)!r}, before the garbage {answer!r}; the last bytes "
                     f"fed to it: {ports[name.partition('#')[0]].last_fed()!r}"
                     for name, answer in good.items() if after.get(name) != answer]
        if _nvram(state) != memory:
            problems.append(f"{kind}: the stored memory changed under garbage ({state})")
    except Exception as exc:  # a check that could not be made is a failure too
        problems.append(f"{kind}: {type(exc).__name__}: {exc}")
    finally:
        for port in ports.values():
            port.close()
        stop(sim.proc)
        problems += [f"{kind}: stderr: {line}" for line in _tracebacks(sim.err)]
    return problems


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=60.0, help="garbage time per kind (default 60)")
    parser.add_argument("--kinds", default=",".join(KINDS), help="comma-separated kinds (default all)")
    parser.add_argument("--rss-mb", type=float, default=20.0, help="resident growth allowed (default 20 MB)")
    parser.add_argument("--transport", choices=("pty", "tcp", "rfc2217"), default="pty",
                        help="how the serial ports are served (default pty)")
    parser.add_argument("--seed", type=int, default=None, help="another garbage sequence (default: the kind's own)")
    parser.add_argument("--drives", default="", help="comma-separated SERS addresses on one RS-485 line")
    parser.add_argument("--pacing", action="store_true", help="pace the device's output at its baud rate")
    parser.add_argument("--speed", type=float, default=None, help="the device's time factor (devsim run --speed)")
    args = parser.parse_args(argv)
    drives = [int(a) for a in args.drives.split(",") if a]
    problems: list[str] = []
    with tempfile.TemporaryDirectory(prefix="devsim-soak-") as directory:
        for kind in args.kinds.split(","):
            problems += soak(kind, args.seconds, args.rss_mb, directory, args.transport, seed=args.seed,
                             drives=drives, pacing=args.pacing, speed=args.speed)
    for problem in problems:
        print(problem, file=sys.stderr)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
