"""The runtime: one event loop, one clock, the devices and the ports they are served on.

A :class:`Runtime` runs either in a background thread (``start()`` / ``stop()``; what tests and
the CLI use, so that blocking host code such as pyserial can run in the caller's thread) or in
the caller's own loop (``async with runtime``).  All device code runs in the runtime's loop
thread; the control methods (:meth:`read`, :meth:`set`, :meth:`advance`, ...) are thread-safe
and hop into that thread.  This is the in-process form of the control API; the out-of-process
form (``--control``) is a JSON front end to the same methods (:mod:`devsim.runtime.control`).
"""

from __future__ import annotations

import asyncio
import threading
import time
from collections.abc import Awaitable, Callable, Coroutine, Mapping, Sequence
from typing import TYPE_CHECKING, Any, TypeVar

from devsim.core.clock import Clock, RealClock, VirtualClock
from devsim.core.device import Device, UnknownName
from devsim.core.kit import CaptureTag
from devsim.core.nvram import NonVolatileMemory, UnfitMemory
from devsim.core.registry import device_class
from devsim.transports.fdlimit import loop_exception_handler

if TYPE_CHECKING:  # imported where used: a runtime without a state dir needs no pathlib
    from pathlib import Path

__all__ = ["FACADE_PORTS", "Runtime", "UnknownDevice", "port_key"]

T = TypeVar("T")


#: Lines a facade serves for a device beside its own ports, by the port name ``ctl line``,
#: ``line-fault``, ``telegrams`` and ``capture --port`` take: the Modbus RTU line
#: (``NAME.modbus``, :mod:`devsim.facades.modbus`).
FACADE_PORTS = ("modbus",)

#: The longest step of virtual time one ``advance`` may take (about 116 days).
MAX_ADVANCE = 1e7


class UnknownDevice(KeyError):
    def __str__(self) -> str:
        return str(self.args[0]) if self.args else "unknown device"


def port_key(device: str, port: str = "main") -> str:
    """How lines, traces and plant ports name one port of a device: the device's name for its
    ``main`` port, ``DEVICE.PORT`` for the others (``cnc.v7``)."""
    return device if port == "main" else f"{device}.{port}"


class Runtime:
    """Owns the loop, the clock, devices, lines and transports of one simulator process."""

    def __init__(
        self,
        *,
        virtual: bool = False,
        speed: float = 1.0,
        state_dir: str | Path | None = None,
        clock: Clock | None = None,
        name: str = "devsim",
    ) -> None:
        #: The simulator's name (``devsim ps``, the ``info`` op): the kind of ``devsim run``, the plant's name.
        self.name = name
        #: When the runtime was made (seconds since the epoch), and the same on the monotonic clock.
        self.started = time.time()
        self.started_monotonic = time.monotonic()
        self.clock: Clock = clock or (VirtualClock() if virtual else RealClock(speed))
        self.state_dir: Path | None = None
        if state_dir is not None:
            from pathlib import Path

            self.state_dir = Path(state_dir)
        self.devices: dict[str, Device] = {}
        self.lines: dict[str, Any] = {}  # port_key(device, port) -> Line serving it
        self.ports: dict[str, str] = {}  # port_key(device, port) -> URL/path a host opens
        #: port_key -> how a serial line's pcap records are tagged (None: captured as IPv4)
        self.capture_tags: dict[str, CaptureTag | None] = {}
        #: port_key -> the transport's (host, device) addresses of the moment, where it knows them
        #: (TCP, UDP: what a pcap of its packets carries, a trace's and a live capture's alike)
        self.trace_peers: dict[str, Callable[[], Any]] = {}
        self.transports: list[Any] = []
        self.closers: list[Callable[[], Awaitable[Any]]] = []
        #: Seconds a TCP host may stay idle before a waiting client takes its place (``--idle-drop``;
        #: None: :data:`devsim.transports.hosts.DEFAULT_IDLE_DROP`).
        self.idle_drop: float | None = None
        #: A running scenario's steps and progress as the scenario runner publishes them (op
        #: ``scenario``; :class:`devsim.scenario.published.PublishedProgress`), None without one.
        self.scenario: dict[str, Any] | None = None
        self._line_faults: dict[tuple[str, str], list[Any]] = {}
        self._loop: asyncio.AbstractEventLoop | None = None
        self._loop_thread: int | None = None  # the thread the loop runs in (threading.get_ident())
        self._thread: threading.Thread | None = None
        self._stopped = threading.Event()

    # -- loop ownership ------------------------------------------------------------------
    @property
    def loop(self) -> asyncio.AbstractEventLoop:
        if self._loop is None:
            raise RuntimeError("runtime not started")
        return self._loop

    def start(self) -> Runtime:
        """Run the loop in a daemon thread; returns once it is running."""
        if self._loop is not None:
            return self
        ready = threading.Event()

        def main() -> None:
            loop = asyncio.new_event_loop()
            asyncio.set_event_loop(loop)
            loop.set_exception_handler(loop_exception_handler)
            self._loop, self._loop_thread = loop, threading.get_ident()
            loop.call_soon(ready.set)
            try:
                loop.run_forever()
            finally:
                loop.run_until_complete(loop.shutdown_asyncgens())
                loop.close()
                self._stopped.set()

        self._thread = threading.Thread(target=main, name="devsim-runtime", daemon=True)
        self._thread.start()
        ready.wait()
        return self

    def stop(self) -> None:
        """Close every port and device, then end the loop thread."""
        if self._loop is None:
            return
        if self._thread is not None and threading.current_thread() is not self._thread:
            try:
                self.run(self.aclose())
            finally:
                self._loop.call_soon_threadsafe(self._loop.stop)
                self._thread.join(timeout=10)
                self._loop = None
                self._thread = None

    async def __aenter__(self) -> Runtime:
        self._loop, self._loop_thread = asyncio.get_running_loop(), threading.get_ident()
        self._loop.set_exception_handler(loop_exception_handler)
        return self

    async def __aexit__(self, *exc: object) -> None:
        await self.aclose()
        self._loop = None

    async def aclose(self) -> None:
        for close in reversed(self.closers):
            await close()
        self.closers.clear()
        for transport in reversed(self.transports):
            await transport.close()
        self.transports.clear()
        for line in {id(line): line for line in self.lines.values()}.values():
            line.close()
        self.lines.clear()
        self.ports.clear()
        self.capture_tags.clear()
        self.trace_peers.clear()
        for device in self.devices.values():
            device.close()
        if isinstance(self.clock, VirtualClock):
            self.clock.stop_auto()

    def _in_loop_thread(self) -> bool:
        # (the loop's thread, and the loop running in it: what asyncio.get_running_loop() says,
        # without the system call for the process id it makes each time, once per request)
        loop = self._loop
        return loop is not None and threading.get_ident() == self._loop_thread and loop.is_running()

    def call(self, fn: Callable[..., T], *args: Any, **kwargs: Any) -> T:
        """Run ``fn`` in the loop thread and return its result (directly if already there).

        From another thread the caller waits on a bare lock the loop thread releases: the
        cheapest hand-over there is (a facade's request from python-can's notifier thread pays
        it on every access)."""
        if self._in_loop_thread():
            return fn(*args, **kwargs)
        done = threading.Lock()
        done.acquire()
        outcome: list[Any] = []

        def invoke() -> None:
            try:
                outcome.append((True, fn(*args, **kwargs)))
            except BaseException as exc:  # handed to the caller
                outcome.append((False, exc))
            finally:
                done.release()

        self.loop.call_soon_threadsafe(invoke)
        done.acquire()
        ok, value = outcome[0]
        if not ok:
            raise value
        return value

    def run(self, coro: Coroutine[Any, Any, T], timeout: float | None = None) -> T:
        """Run a coroutine in the loop thread from another thread and wait for it (cancelled if
        the wait ends otherwise: a timeout, Ctrl-C)."""
        future = asyncio.run_coroutine_threadsafe(coro, self.loop)
        try:
            return future.result(timeout)
        except BaseException:
            future.cancel()
            raise

    # -- building a plant ----------------------------------------------------------------
    def add_device(self, kind: str, name: str | None = None, config: Mapping[str, Any] | None = None) -> Device:
        """Create a device of ``kind`` (in the loop thread); its NVRAM lives in the state dir."""

        def create() -> Device:
            cls = device_class(kind)
            dev_name = name or kind
            if dev_name in self.devices:
                raise ValueError(f"a device named {dev_name!r} exists already")
            nvram = NonVolatileMemory.for_device(self.state_dir, dev_name, kind)
            try:
                device = cls(clock=self.clock, config=config, nvram=nvram, name=dev_name)
            except BaseException as exc:
                nvram.close()  # (the lock: a device that never lived owns no memory)
                from devsim.core.config import ConfigError  # (only now: a start imports no yaml)

                if nvram.path is None or not nvram.sections() or isinstance(exc, ConfigError):
                    raise
                if isinstance(exc, TypeError | AttributeError | KeyError | ValueError | IndexError | ArithmeticError):
                    # a section of the wrong shape (hand-edited, another kind's file): the reader
                    # trusted the JSON; say which file, and leave it as it is
                    raise UnfitMemory(f"{nvram.path}: this memory image does not fit the kind {kind!r}"
                                      f" ({type(exc).__name__}: {exc}); fix or delete the file") from exc
                raise
            self.devices[dev_name] = device
            return device

        return self.call(create)

    async def serve(
        self,
        devices: Device | Sequence[Device],
        transport: Any,
        *,
        port: str = "main",
        pacing: bool = False,
        trace: str | Path | None = None,
    ) -> Any:
        """Serve one port of a device, or the same port of several devices on a multidrop bus,
        on ``transport``; returns the Line.  ``trace`` names a trace file: ``*.pcap`` is written
        as pcap (:mod:`devsim.transports.pcap`), anything else as the text trace."""

        group = [devices] if isinstance(devices, Device) else list(devices)
        if len(group) == 1:
            target: Any = group[0].port(port)
        else:  # (a multidrop bus only when devices share a line: a plain run starts without it)
            from devsim.core.bus import Bus

            target = Bus(group, port)
        limit = getattr(transport, "limit_hosts", None)
        if limit is not None:  # how many hosts the port serves: the kind's declaration (PortDef.hosts)
            spec = group[0].port(port).spec
            framing = spec.framing
            limit(spec.hosts, self.idle_drop, framing.split if framing is not None else None)
        line = await self.serve_target([port_key(device.name, port) for device in group], target, transport,
                                       pacing=pacing, trace=trace, capture=group[0].port(port).spec.capture)
        if line.tracer is not None:  # the trace says what it traces: a reader decodes it by the port's framing
            from devsim.transports.trace import source_note

            line.tracer.note(source_note([d.name for d in group], port, group[0].kind), self.clock.now())
        return line

    async def serve_target(self, keys: Sequence[str], target: Any, transport: Any, *, pacing: bool = False,
                           trace: str | Path | None = None, capture: CaptureTag | None = None) -> Any:
        """Serve any line target (a device's port, a bus, a facade's endpoint) on ``transport``
        under the port keys ``keys``; returns the Line.  ``capture`` tags a serial line's pcap
        records (:class:`~devsim.core.kit.CaptureTag`; ``None``: captured as IPv4/UDP)."""
        from devsim.transports.line import Line, wire_settings

        line = Line(target, self.clock, pacing=pacing)
        if trace is not None:  # FILE.pcap: a serial line's records, or packets with the transport's addresses
            from devsim.transports.tracing import open_trace

            peers = getattr(transport, "trace_peers", None)
            line.tracer = open_trace(trace, peers=peers, name=keys[0], capture=capture,
                                     settings=lambda: wire_settings(line))
        await transport.start(line)
        self.transports.append(transport)
        peers = getattr(transport, "trace_peers", None)
        for key in keys:
            self.lines[key] = line
            self.capture_tags[key] = capture
            if peers is not None:
                self.trace_peers[key] = peers
            self.ports[key] = str(getattr(transport, "url", "") or getattr(transport, "address", ""))
        return line

    def add_closer(self, close: Callable[[], Awaitable[Any]]) -> None:
        """Something else the runtime serves (a facade's own server): closed first at the end."""
        self.closers.append(close)

    def serve_sync(self, devices: Device | Sequence[Device], transport: Any, **kwargs: Any) -> Any:
        return self.run(self.serve(devices, transport, **kwargs))

    # -- control API (thread-safe) -------------------------------------------------------
    def device(self, name: str) -> Device:
        try:
            return self.devices[name]
        except KeyError:
            shown = name if len(name) <= 60 else name[:57] + "..."
            raise UnknownDevice(f"no device named {shown!r} (have: {', '.join(self.devices)})") from None

    def read(self, device: str, name: str) -> Any:
        if name.startswith("line."):
            return self.call(lambda: self._line_status(device)[name[5:]])
        return self.call(lambda: self.device(device).read(name))

    def set(self, device: str, name: str, value: Any) -> None:
        self.call(lambda: self.device(device).set(name, value))

    def names(self, device: str) -> list[dict[str, Any]]:
        """The declared points of a device: name, type, unit, access, doc, section."""

        return self.call(lambda: [point.describe() for point in self.device(device).points])

    def fault(self, device: str, kind: str, active: bool) -> None:
        """Switch a declared device fault on or off."""
        self.call(lambda: self.device(device).fault(kind, active))

    def line_fault(
        self, device: str, kind: str, active: bool = True, *, port: str = "main", **params: Any
    ) -> None:
        """Start (``active``) or end a fault on the line serving a port of ``device``: any kind
        of :class:`~devsim.transports.line.LineFault` (``corrupt``, ``drop``, ``noise`` with
        ``rate``, ``unplug`` ...), with its parameters; ending it ends every fault of that kind
        started here.

        [SIM-CHOICE] A fault started where one of the same kind and direction started here is
        still kept replaces it (a switch turned on again, with the new parameters): ``noise on
        --rate 200`` then ``--rate 500`` is 500 bytes/s, not 700.  They piled up: each request
        added one, every byte and noise tick walked them all, and 800 ``noise on`` requests took
        the simulator's whole CPU.  So a line holds at most three per kind from here (to_device,
        to_host, both); a scenario's ``line_fault`` steps still add up (:meth:`Line.inject`)."""
        from devsim.transports.line import LineFault

        def apply() -> None:
            key = port_key(device, port)
            line = self.lines.get(key)
            if line is None:
                raise self._no_line(device, port)
            handles = self._line_faults.setdefault((key, kind), [])
            if active:
                fault = LineFault(kind=kind, **params)  # type: ignore[arg-type]
                for handle in [h for h in handles if h.fault.direction == fault.direction]:
                    handle.cancel()
                    handles.remove(handle)
                handles.append(line.inject(fault))
            else:
                for handle in handles:
                    handle.cancel()
                handles.clear()

        self.call(apply)

    def state(self, device: str) -> dict[str, Any]:
        def snapshot() -> dict[str, Any]:
            data = self.device(device).state()
            if device in self.lines:
                data["line"] = self._line_status(device)
            return data

        return self.call(snapshot)

    def power_cycle(self, device: str, *, wipe: bool = False) -> None:
        self.call(lambda: self.device(device).power_cycle(wipe=wipe))

    def line_status(self, device: str, port: str = "main") -> dict[str, Any]:
        """The status of the line serving a port of ``device`` (settings, mismatch, counters)."""
        return self.call(lambda: self._line_status(device, port))

    def now(self) -> float:
        return self.call(self.clock.now)

    def advance(self, seconds: float) -> float:
        """Advance virtual time (refused on a real clock) by at most :data:`MAX_ADVANCE`
        seconds at a time; returns the new time."""
        clock = self.clock
        if not isinstance(clock, VirtualClock):
            raise RuntimeError("advance needs virtual time (the runtime runs on a real clock)")
        if not 0 <= seconds <= MAX_ADVANCE:
            raise ValueError(f"advance takes 0 … {MAX_ADVANCE:g} seconds at a time, not {seconds!r}")

        def go() -> float:
            clock.advance(seconds)
            return clock.now()

        return self.call(go)

    def run_until(self, predicate: Callable[[], bool], timeout: float) -> bool:
        """Virtual time: jump from event to event until ``predicate`` (run in the loop thread)
        holds or ``timeout`` simulated seconds pass."""
        clock = self.clock
        if not isinstance(clock, VirtualClock):
            raise RuntimeError("run_until needs virtual time")
        return self.call(lambda: clock.run_until(predicate, timeout))

    def _line_status(self, device: str, port: str = "main") -> dict[str, Any]:
        line = self.lines.get(port_key(device, port))
        if line is None:
            raise self._no_line(device, port)
        status: dict[str, Any] = line.status()
        return status

    def _no_line(self, device: str, port: str) -> UnknownName:
        """Why no line serves ``port`` of ``device``: no such device (raised), no such port, the
        ports it has being the device's own and the facade lines served for it (the Modbus RTU
        line ``modbus``: it listed only the device's own), or a port on no line (UDP)."""
        ports = [*self.device(device).port_names(), *(p for p in FACADE_PORTS if port_key(device, p) in self.lines)]
        if port not in ports:
            return UnknownName(f"{device} has no port {port!r} (ports: {', '.join(ports)})")
        return UnknownName(f"port {port!r} of device {device!r} is not on a line")
