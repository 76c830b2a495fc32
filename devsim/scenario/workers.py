"""``devsim up --workers N``: one plant spread over N processes, behind one control address.

A Python process serves its devices on one core.  With ``--workers N`` the plant's ports are
dealt out to N worker processes (each a plain ``devsim up`` of its share of the plant, a bus
staying whole with its devices), and this process

* prints what the workers print (every port, ``NAME: ready``), unchanged;
* serves the control API on the address given with ``--control`` (or its default socket) and
  hands each request to the worker that holds the device (``devices`` gathers them from all,
  with a ``worker`` number; ``info`` says this process's name, pid and uptime, and all ports);
* stops the workers on Ctrl-C / SIGTERM / SIGHUP, and stops the others if one dies;
* holds each worker's stdin, a pipe: when this process dies, even by ``kill -9``, the worker
  reads its end and stops as on Ctrl-C (:func:`end_with_parent`), so no orphan keeps the
  plant's links, ports and state-dir locks, and the same ``devsim up`` can start again.

Traces (``--trace-dir``), state (``--state-dir``) and faults work as in one process: the names
are distinct, each device's memory is locked by its own worker.  Under virtual time a plant
stays in one process (one clock must order every event), and ``devsim up`` says so.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import os
import shutil
import signal
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from devsim.core.console import say, stop_on_signals, warn
from devsim.core.points import ascii_digits
from devsim.observe.live_log import DEFAULT_LEVEL, level_of
from devsim.scenario.schema import PlantSpec

__all__ = ["WORKER_ENV", "end_with_parent", "run_workers", "split_plant"]

#: The start of the name of the directory (in the system's temporary directory) that holds the
#: workers' plant files and control sockets; the pid of the ``devsim up --workers`` follows.
_DIRECTORY = "devsim-workers-"

#: Set in a worker's environment (to the pid of its ``devsim up --workers``): its stdin is the
#: pipe whose end says that process is gone.
WORKER_ENV = "DEVSIM_WORKER_OF"


def end_with_parent(loop: asyncio.AbstractEventLoop, stop: Callable[[], None]) -> None:
    """In a worker (``WORKER_ENV`` set): call ``stop`` when the stdin pipe from the ``devsim up
    --workers`` process ends, i.e. when that process has ended, however it died."""
    if not os.environ.get(WORKER_ENV):
        return

    def readable() -> None:
        try:
            data = os.read(0, 4096)
        except BlockingIOError:
            return
        except OSError:
            data = b""
        if not data:
            loop.remove_reader(0)
            stop()

    os.set_blocking(0, False)
    loop.add_reader(0, readable)


def sweep_stale(root: str | None = None) -> None:
    """Remove the directories that ``devsim up --workers`` processes killed by ``kill -9`` left in
    ``root`` (the system's temporary directory): their workers ended with them, and nothing else
    removes them.  A directory whose process still runs, or is someone else's, stays."""
    from devsim.runtime.discovery import process_alive

    for path in Path(root or tempfile.gettempdir()).glob(f"{_DIRECTORY}*"):
        pid, dash, _ = path.name.removeprefix(_DIRECTORY).partition("-")
        if dash and ascii_digits(pid) and not process_alive(int(pid)):
            shutil.rmtree(path, ignore_errors=True)


def split_plant(spec: PlantSpec, workers: int) -> list[dict[str, Any]]:
    """The plant dealt into at most ``workers`` sub-plants (plain data, loadable as YAML): each
    bus with its devices is one unit, the other devices of one CANopen network one unit (a
    network is served by one process), each other device one unit, dealt round-robin."""
    units: list[tuple[list[Any], list[Any]]] = []
    by_bus: dict[str, tuple[list[Any], list[Any]]] = {}
    for bus in spec.buses:
        by_bus[bus.name] = ([], [bus])
        units.append(by_bus[bus.name])
    for device in spec.devices:
        bus = device.bus()
        if bus is not None and bus in by_bus:
            by_bus[bus][0].append(device)
        elif device.canopen is not None:
            key = f"canopen {device.canopen.network}"
            if key not in by_bus:
                by_bus[key] = ([], [])
                units.append(by_bus[key])
            by_bus[key][0].append(device)
        else:
            units.append(([device], []))
    shares: list[dict[str, Any]] = [{"devices": [], "buses": []} for _ in range(max(1, min(workers, len(units))))]
    for index, (devices, buses) in enumerate(units):
        share = shares[index % len(shares)]
        share["devices"] += [d.dump() for d in devices]
        share["buses"] += [b.dump() for b in buses]
    for number, share in enumerate(shares):
        share["name"] = f"{spec.name or 'plant'} (worker {number})"
    return [s for s in shares if s["devices"]]


class _Worker:
    def __init__(self, number: int, proc: asyncio.subprocess.Process, control: str) -> None:
        self.number = number
        self.proc = proc
        self.control = control
        self.devices: set[str] = set()
        self._reader: asyncio.StreamReader | None = None
        self._writer: asyncio.StreamWriter | None = None
        self._lock = asyncio.Lock()

    async def ask(self, request: dict[str, Any]) -> dict[str, Any]:
        async with self._lock:
            if self._writer is None:
                self._reader, self._writer = await asyncio.open_unix_connection(self.control)
            assert self._reader is not None
            self._writer.write((json.dumps(request) + "\n").encode())
            await self._writer.drain()
            line = await self._reader.readline()
            if not line:
                raise ConnectionError(f"worker {self.number} closed its control connection")
            answer: dict[str, Any] = json.loads(line)
            return answer

    async def close(self) -> None:
        if self._writer is not None:
            self._writer.close()
            with contextlib.suppress(Exception):
                await self._writer.wait_closed()


async def _forward(stream: asyncio.StreamReader | None, control_seen: asyncio.Event, out: Any) -> None:
    if stream is None:
        return
    while True:
        line = await stream.readline()
        if not line:
            return
        text = line.decode(errors="replace")
        if text.startswith("control: "):
            control_seen.set()  # the worker's own control address is ours to hide
            continue
        say(text.rstrip("\n"), out)  # (a reader gone: the worker's lines are still taken)


async def _proxy(workers: list[_Worker], about: dict[str, Any], reader: asyncio.StreamReader,
                 writer: asyncio.StreamWriter) -> None:
    streams: list[asyncio.Task[None]] = []
    try:
        while line := await reader.readline():
            if not line.strip():
                continue
            try:
                request = json.loads(line)
                if not isinstance(request, dict):
                    raise ValueError("a request is a JSON object")
            except (ValueError, RecursionError) as exc:
                answer: dict[str, Any] = {"id": None, "ok": False, "error": f"not JSON: {exc}"[:300], "type": "BadRequest"}
            else:
                worker = _worker_of(workers, request.get("device"))
                if request.get("op") == "watch" and worker is not None:
                    streams.append(asyncio.ensure_future(_watch(worker, line, writer)))
                    continue
                answer = await _route(workers, request, about)
            writer.write((json.dumps(answer) + "\n").encode())
            await writer.drain()
    except (ConnectionError, asyncio.CancelledError):
        pass
    finally:
        for stream in streams:
            stream.cancel()
        with contextlib.suppress(Exception):
            writer.close()


def _worker_of(workers: list[_Worker], device: Any) -> _Worker | None:
    return next((worker for worker in workers if device in worker.devices), None)


async def _watch(worker: _Worker, request: bytes, writer: asyncio.StreamWriter) -> None:
    """A ``watch`` on a connection of its own to the worker: its answer and stream, line by line."""
    reader, upstream = await asyncio.open_unix_connection(worker.control)
    try:
        upstream.write(request if request.endswith(b"\n") else request + b"\n")
        await upstream.drain()
        while line := await reader.readline():
            writer.write(line)
            await writer.drain()
    except (ConnectionError, asyncio.CancelledError):
        pass
    finally:
        upstream.close()


async def _info(workers: list[_Worker], request: dict[str, Any], about: dict[str, Any]) -> dict[str, Any]:
    """``info`` of the plant: this process's name, pid and uptime, every worker's kinds, devices and ports."""
    result: dict[str, Any] = {"name": about["name"], "pid": os.getpid(), "started": about["started"],
                              "uptime": time.monotonic() - about["monotonic"], "clock": "real",
                              "kinds": [], "devices": [], "ports": {}}
    for worker in workers:
        answer = await worker.ask(request)
        if not answer.get("ok"):
            return answer
        part = answer["result"]
        result["kinds"] = sorted({*result["kinds"], *part["kinds"]})
        result["devices"] += part["devices"]
        result["ports"].update(part["ports"])
    return {"id": request.get("id"), "ok": True, "result": result}


async def _route(workers: list[_Worker], request: dict[str, Any], about: dict[str, Any]) -> dict[str, Any]:
    op = request.get("op")
    if op == "info":
        return await _info(workers, request, about)
    if op == "devices":
        rows: list[Any] = []
        for worker in workers:
            answer = await worker.ask(request)
            if not answer.get("ok"):
                return answer
            rows += [{**row, "worker": worker.number} for row in answer["result"]]
        return {"id": request.get("id"), "ok": True, "result": rows}
    device = request.get("device")
    if device is None:
        return await workers[0].ask(request)  # now, advance: every worker has the same time
    for worker in workers:
        if device in worker.devices:
            return await worker.ask(request)
    known = sorted(name for worker in workers for name in worker.devices)
    return {
        "id": request.get("id"),
        "ok": False,
        "error": f"no device named {str(device)[:60]!r} (have: {', '.join(known)})",
        "type": "UnknownDevice",
    }


async def run_workers(
    spec: PlantSpec,
    workers: int,
    *,
    control: Any = None,
    name: str = "devsim",
    state_dir: str | None = None,
    speed: float = 1.0,
    trace_dir: str | None = None,
    fleet: str | None = None,
    verbose: int = 0,
    quiet: int = 0,
    idle_drop: float | None = None,
) -> int:
    """Serve ``spec`` from ``workers`` processes until Ctrl-C / SIGTERM / SIGHUP; returns an exit status."""
    loop = asyncio.get_running_loop()
    stop = asyncio.Event()
    unsignal = stop_on_signals(loop, stop.set)
    shares = split_plant(spec, workers)
    about = {"name": name, "started": time.time(), "monotonic": time.monotonic()}
    sweep_stale()
    with tempfile.TemporaryDirectory(prefix=f"{_DIRECTORY}{os.getpid()}-") as tmp:
        running: list[_Worker] = []
        try:
            for number, share in enumerate(shares):
                plant_file = Path(tmp) / f"worker{number}.yaml"
                plant_file.write_text(json.dumps(share))
                sock = str(Path(tmp) / f"w{number}.sock")
                args = [sys.executable, "-m", "devsim", "up", str(plant_file), "--control", f"unix:{sock}",
                        "--speed", repr(speed)]
                if state_dir is not None:
                    args += ["--state-dir", state_dir]
                if trace_dir is not None:
                    args += ["--trace-dir", trace_dir]
                if fleet is not None:  # each worker is a fleet member of its own
                    args += ["--fleet", fleet]
                if idle_drop is not None:
                    args += ["--idle-drop", repr(idle_drop)]
                args += ["-v"] * verbose + ["-q"] * quiet  # the workers log to our stderr
                proc = await asyncio.create_subprocess_exec(
                    *args, stdin=asyncio.subprocess.PIPE, stdout=asyncio.subprocess.PIPE,
                    env={**os.environ, WORKER_ENV: str(os.getpid())},
                )
                worker = _Worker(number, proc, sock)
                worker.devices = {d["name"] for d in share["devices"]}
                running.append(worker)
            seen = [asyncio.Event() for _ in running]
            pumps = [asyncio.ensure_future(_forward(w.proc.stdout, seen[i], sys.stdout)) for i, w in enumerate(running)]
            ended = [asyncio.ensure_future(w.proc.wait()) for w in running]
            waiting = [asyncio.ensure_future(e.wait()) for e in seen]
            all_seen = asyncio.ensure_future(asyncio.gather(*waiting))
            done, _ = await asyncio.wait([*ended, all_seen], return_when=asyncio.FIRST_COMPLETED)
            if any(task in done for task in ended):
                all_seen.cancel()  # (left pending, it was logged as never retrieved at the loop's end)
                await asyncio.gather(all_seen, return_exceptions=True)
                warn("devsim: a worker ended while starting")
                return 1
            server = None
            if control is not None:
                if control.path is not None:
                    server = await asyncio.start_unix_server(lambda r, w: _proxy(running, about, r, w), path=control.path)
                    os.chmod(control.path, 0o600)
                    shown = f"unix:{control.path}"
                else:
                    server = await asyncio.start_server(lambda r, w: _proxy(running, about, r, w), control.host, control.port)
                    shown = f"{control.host}:{server.sockets[0].getsockname()[1]}"
                say(f"control: {shown}")
            if level_of(verbose, quiet) >= DEFAULT_LEVEL:  # (-q: warnings and errors only)
                processes, devices = len(running), len(spec.devices)
                warn(f"devsim: plant up in {processes} worker process{'' if processes == 1 else 'es'}"
                     f" ({devices} device{'' if devices == 1 else 's'}); Ctrl-C to stop")
            stopping = asyncio.ensure_future(stop.wait())
            done, _ = await asyncio.wait([stopping, *ended], return_when=asyncio.FIRST_COMPLETED)
            status = 0 if stopping in done else 1
            if status:
                warn("devsim: a worker ended; stopping the others")
            if server is not None:
                server.close()
                if control.path is not None:
                    with contextlib.suppress(OSError):
                        os.unlink(control.path)
            for pump in pumps:
                pump.cancel()
            return status
        finally:
            for worker in running:
                await worker.close()
                if worker.proc.returncode is None:
                    worker.proc.send_signal(signal.SIGTERM)
            for worker in running:
                with contextlib.suppress(Exception):
                    await asyncio.wait_for(worker.proc.wait(), 10)
                if worker.proc.returncode is None:
                    worker.proc.kill()
                    await worker.proc.wait()
            unsignal()
