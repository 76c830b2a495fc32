"""Running a scenario: the timeline against a plant, with the host scripted or external.

The runner works inside the runtime's event loop.  In **virtual** time it is the only one that
moves the clock: it jumps from event to event up to each trigger, and after every jump lets the
real ports deliver what the devices wrote (counting bytes, so nothing is left in flight), which
makes a run exact and repeatable.  In **real** time (``--realtime``, or by default when the
scenario does not script the host, so that real host software can drive the plant) it waits on
the real clock, scaled by the speed factor.
"""

from __future__ import annotations

import asyncio
import math
import re
import time
from collections.abc import Awaitable, Callable
from pathlib import Path
from typing import Any

import msgspec

from devsim.core.clock import VirtualClock
from devsim.core.device import Device, SerialSettings
from devsim.core.kit import Command, Table
from devsim.runtime import Runtime
from devsim.scenario.host import HostPort, open_host_port
from devsim.scenario.plant import Plant, build_plant
from devsim.scenario.published import PublishedProgress
from devsim.scenario.schema import Condition, Scenario, Step
from devsim.transports.trace import TapSink

__all__ = ["ScenarioResult", "StepResult", "run_scenario", "run_scenario_async"]

# Real-time guard while waiting for bytes that are known to be on their way through a port.
_IO_GUARD = 5.0
# While an axis moves, `when` conditions are looked at this often (simulated seconds).
_POLL = 0.001
# Virtual time runs from event to event without a turn of the loop while nothing waits for one,
# but gives the loop a turn at least this often (wall seconds): a monitor on --control is served.
_QUIET_SPAN = 0.002


class StepResult(msgspec.Struct):
    index: int  # 1-based
    line: int
    label: str
    time: float  # simulated seconds since the start of the timeline
    status: str  # "pass", "fail", "done" (an action), "skipped"
    message: str = ""

    @property
    def checked(self) -> bool:
        return self.status in ("pass", "fail")


class ScenarioResult(msgspec.Struct):
    name: str
    path: str
    mode: str
    steps: list[StepResult] = msgspec.field(default_factory=list)
    sim_time: float = 0.0
    wall_time: float = 0.0
    error: str = ""
    ports: dict[str, str] = msgspec.field(default_factory=dict)

    @property
    def passed(self) -> bool:
        return not self.error and all(step.status != "fail" for step in self.steps)

    @property
    def failures(self) -> list[StepResult]:
        return [step for step in self.steps if step.status == "fail"]


class _Traffic(TapSink):
    """Taps a line: keeps what the host sent and what the device sent (chained to a tracer)."""

    def __init__(self, inner: Any) -> None:
        super().__init__(inner)
        self.host = bytearray()
        self.device = bytearray()

    def record(self, direction: str, data: bytes, when: float, note: str | None = None) -> None:
        (self.host if direction == "H>D" else self.device).extend(data)
        super().record(direction, data, when, note)


class _StepFailed(Exception):
    pass


class _Abort(Exception):
    pass


def _show(data: bytes, limit: int = 80) -> str:
    text = repr(bytes(data))
    return text if len(text) <= limit else text[: limit - 3] + "..."


def _escape(text: str) -> str:
    """A pattern as one printable line (CR, LF, tab shown as escapes)."""
    return text.replace("\r", "\\r").replace("\n", "\\n").replace("\t", "\\t")


def _label(step: Step) -> str:
    action = step.action
    trigger = ""
    if step.at is not None:
        trigger = f"at {step.at:g}s: "
    elif step.after is not None:
        trigger = f"after {step.after:g}s: "
    elif step.when is not None:
        trigger = f"when {step.when.describe()}: "
    if action is None:
        return trigger.rstrip(": ") or "wait"
    value = getattr(step, action)
    label = LABELS.get(action)
    return trigger + (label(value) if label is not None else f"{action} {value}")


def _for(duration: float | None) -> str:
    return f" for {duration:g}s" if duration is not None else ""


def _expect_label(value: Any) -> str:
    what = _show(value.bytes.encode("latin-1")) if value.bytes is not None else f"/{_escape(value.regex)}/"
    return f"expect {what} within {value.timeout:g}s"


#: Where a step's actions are described (the section of each row below).
_STEPS = "README: Scenarios and plants"

#: A step's action → its line in the report (``log`` steps print their text as it is).
LABELS: Table[Callable[[Any], str]] = Table((
    Command("send", lambda v: f"send {_show(v.payload())}", _STEPS),
    Command("expect", _expect_label, _STEPS),
    Command("expect_state", lambda v: f"expect {v.describe()}", _STEPS),
    Command("expect_traffic", lambda v: f"expect {v.direction} sent /{_escape(v.regex)}/"
            + (f" {v.count} times" if v.count is not None else ""), _STEPS),
    Command("expect_timing", lambda v: f"expect {v.device} {v.event} between {v.between[0]:g}s and {v.between[1]:g}s",
            _STEPS),
    Command("set", lambda v: f"set {v.device} " + ", ".join(f"{k}={x!r}" for k, x in v.values.items()), _STEPS),
    Command("pulse", lambda v: f"pulse {v.device}.{v.input} for {v.width:g}s", _STEPS),
    Command("fault", lambda v: f"fault {v.device} {v.kind}{_for(v.duration)}", _STEPS),
    Command("line_fault", lambda v: f"line fault {v.kind}{_for(v.duration)}", _STEPS),
    Command("power_cycle", lambda v: f"power cycle {v.device}" + (" (memory wiped)" if v.wipe else ""), _STEPS),
    Command("wait", lambda v: f"wait {v:g}s", _STEPS),
))


class Runner:
    """Executes one scenario against a plant that runs in the current loop."""

    def __init__(self, scenario: Scenario, plant: Plant, mode: str,
                 on_step: Callable[[StepResult | None, float], None] | None = None) -> None:
        self.scenario = scenario
        #: ``on_step(step, now)`` after each step (``None`` at the start of the timeline), in the
        #: loop thread: what a progress display hears (:mod:`devsim.scenario.progress`).
        self.on_step = on_step
        self.plant = plant
        self.runtime: Runtime = plant.runtime
        self.clock = self.runtime.clock
        self.mode = mode
        self.hosts: dict[str, HostPort] = {}
        self._settled: dict[str, tuple[int, int]] = {}  # line-less port → (sent, received) when it settled
        self.traffic: dict[str, _Traffic] = {}
        self.t0 = 0.0
        self._turned = -_QUIET_SPAN  # wall time of the last drain
        #: (device, input) → its value before the pulses on it began, and when the last of them ends
        self._pulses: dict[tuple[str, str], tuple[Any, float]] = {}

    # -- time ----------------------------------------------------------------------------------
    @property
    def virtual(self) -> bool:
        return isinstance(self.clock, VirtualClock)

    def now(self) -> float:
        return self.clock.now() - self.t0

    async def _drain(self) -> None:
        """Virtual time: let every port deliver the bytes that are already on their way."""
        for _ in range(3):
            await asyncio.sleep(0)
        deadline = time.monotonic() + _IO_GUARD
        for name, host in self.hosts.items():
            line = self.plant.lines.get(name)
            if line is None:  # a server of its own (the Modbus TCP facade): answers come on their own
                await self._settle(host, deadline)
                continue
            transport = self.plant.transports[name]
            while True:
                expected = line.bytes_delivered - getattr(transport, "dropped", 0) - getattr(transport, "pending", 0)
                if len(host.received) >= expected:
                    break
                if time.monotonic() > deadline:
                    raise _Abort(f"port {name}: {expected - len(host.received)} bytes never arrived at the host")
                await host.wait_data(0.01)
        self._turned = time.monotonic()

    def _quiet(self) -> bool:
        """Virtual time: a drain would change nothing: no callback is ready in the loop, no byte
        is on its way to a host, and the loop had a turn within ``_QUIET_SPAN``."""
        if time.monotonic() - self._turned > _QUIET_SPAN or getattr(asyncio.get_running_loop(), "_ready", True):
            return False
        for name, host in self.hosts.items():
            line = self.plant.lines.get(name)
            if line is None:
                return False
            transport = self.plant.transports[name]
            expected = line.bytes_delivered - getattr(transport, "dropped", 0) - getattr(transport, "pending", 0)
            if len(host.received) < expected:
                return False
        return True

    async def _settle(self, host: HostPort, deadline: float) -> None:
        """A port without a line (the Modbus TCP facade, a server in this process): after a send,
        wait in real time, bounded by the drain's guard, for the answer and until it is complete."""
        sent, received = self._settled.get(host.name, (0, 0))
        if host.sent == sent:
            return
        while len(host.received) == received and time.monotonic() < deadline:
            await host.wait_data(0.01)
        while time.monotonic() < deadline:
            before = len(host.received)
            await host.wait_data(0.01)
            if len(host.received) == before:
                break
        self._settled[host.name] = (host.sent, len(host.received))

    async def _wait_until(self, predicate: Callable[[], bool], timeout: float) -> bool:
        """Until ``predicate()`` holds or ``timeout`` simulated seconds pass."""
        deadline = self.clock.now() + timeout
        if self.virtual:
            clock = self.clock
            assert isinstance(clock, VirtualClock)
            while True:
                if not self._quiet():
                    await self._drain()
                if predicate():
                    return True
                upcoming = clock.next_event()
                if self._moving():
                    # positions change between events: look again every millisecond
                    step = clock.now() + _POLL
                    upcoming = step if upcoming is None else min(upcoming, step)
                if upcoming is None or upcoming > deadline:
                    clock.advance_to(deadline)
                    await self._drain()
                    return predicate()
                clock.advance_to(upcoming)
        while not predicate():
            remaining = deadline - self.clock.now()
            if remaining <= 0:
                return predicate()
            await self.clock.sleep(min(remaining, 0.002 * getattr(self.clock, "speed", 1.0)))
        return True

    async def _sleep_until(self, when: float) -> None:
        """Move to ``when``; virtual time jumps from event to event (no polling needed).  With
        nothing else attached (no facade, control API, log or player) nobody looks at a device
        before ``when``, and the devices hear so (a looping program may run ahead, issue 31)."""
        if self.virtual:
            clock = self.clock
            assert isinstance(clock, VirtualClock)
            devices = self._unobserved_devices()
            for device in devices:
                device.unobserved_until(when)
            try:
                while True:
                    if not self._quiet():
                        await self._drain()
                    upcoming = clock.next_event()
                    if upcoming is None or upcoming > when:
                        clock.advance_to(max(when, clock.now()))
                        await self._drain()
                        return
                    clock.advance_to(upcoming)
            finally:
                for device in devices:
                    device.unobserved_until(-math.inf)
        remaining = when - self.clock.now()
        if remaining > 0:
            await self.clock.sleep(remaining)

    def _unobserved_devices(self) -> list[Device]:
        """The devices only the scripted host and the steps look at: none if a facade or the
        control API serves the plant or anything (a motion log, a player, a fleet member) was
        attached to the runtime; not one that hears another on its bus that may talk to it."""
        if self.plant.facades or self.runtime.closers:
            return []
        plant = self.plant
        lines: dict[str, list[Device]] = {}
        for name, device in plant.devices.items():
            lines.setdefault(plant.port_of(name), []).append(device)
        return [device for mates in lines.values() for device in mates
                if not device.hears_others or not any(m.talks_to_others for m in mates if m is not device)]

    def _moving(self) -> bool:
        """Whether any device moves (the shared ``motion`` name): conditions are then looked at
        every ``_POLL`` seconds, since positions change between events."""
        return any("motion" in d.points and d.read("motion") for d in self.plant.devices.values())

    # -- ports -----------------------------------------------------------------------------------
    def _port(self, name: str | None) -> str:
        return name or self.scenario.default_port()

    def _host(self, name: str | None) -> HostPort:
        port = self._port(name)
        if port not in self.hosts:
            raise _StepFailed(f"port {port} is not held by the scripted host")
        return self.hosts[port]

    async def _open_hosts(self) -> None:
        wanted: set[str] = set()
        for step in self.scenario.steps:
            for item in (step.send, step.expect):
                if item is not None:
                    wanted.add(self._port(item.port))
        for name in sorted(wanted):
            line = self.plant.lines.get(name)  # (a Modbus TCP facade is a server of its own: no line)
            settings = line.device_settings if line is not None else SerialSettings()
            host = open_host_port(name, self.plant.kinds[name], self.plant.transports[name], settings)
            await host.open()
            self.hosts[name] = host

    def _tap_lines(self) -> None:
        for name, line in self.plant.lines.items():
            tap = _Traffic(line.tracer)
            line.tracer = tap
            self.traffic[name] = tap

    # -- the run -----------------------------------------------------------------------------------
    async def run(self) -> ScenarioResult:
        scenario = self.scenario
        result = ScenarioResult(scenario.name or "scenario", scenario.path, self.mode)
        result.ports = {name: self.plant.port(name) for name in self.plant.transports}
        wall = time.monotonic()
        self._tap_lines()
        try:
            await self._open_hosts()
            if scenario.start == "after_boot":
                devices = list(self.plant.devices.values())
                if not await self._wait_until(lambda: not any(d.booting for d in devices), 60.0):
                    raise _Abort("the devices did not finish booting")
            self.t0 = self.clock.now()
            if self.on_step is not None:
                self.on_step(None, 0.0)
            previous = self.t0
            for index, step in enumerate(scenario.steps, start=1):
                outcome = await self._step(index, step, previous)
                result.steps.append(outcome)
                if self.on_step is not None:
                    self.on_step(outcome, self.now())
                previous = self.clock.now()
                if previous - self.t0 > scenario.timeout:  # (after each step: the last one too)
                    raise _Abort(f"the scenario ran longer than its timeout of {scenario.timeout:g}s")
                if outcome.status == "fail" and step.when is not None and outcome.message.startswith("condition"):
                    for rest_index, rest in enumerate(scenario.steps[index:], start=index + 1):
                        result.steps.append(StepResult(rest_index, rest.line, _label(rest), self.now(), "skipped"))
                    break
            if self.virtual:
                await self._drain()
        except _Abort as exc:
            result.error = str(exc)
        finally:
            for host in self.hosts.values():
                await host.close()
        result.sim_time = self.now()
        result.wall_time = time.monotonic() - wall
        return result

    async def _step(self, index: int, step: Step, previous: float) -> StepResult:
        label = _label(step)
        # trigger
        if step.at is not None:
            await self._sleep_until(self.t0 + step.at)
        elif step.after is not None:
            await self._sleep_until(previous + step.after)
        elif step.when is not None:
            cond = step.when
            timeout = step.timeout if step.timeout is not None else 30.0
            if not await self._wait_until(lambda: self._test(cond), timeout):
                return StepResult(
                    index, step.line, label, self.now(), "fail",
                    f"condition not met within {timeout:g}s: {cond.describe()} (is {self._value(cond)!r})",
                )
        action = step.action
        if action is None:
            return StepResult(index, step.line, label, self.now(), "pass" if step.when is not None else "done")
        try:
            checked = await ACTIONS[action](self, getattr(step, action), index)
        except _StepFailed as exc:
            return StepResult(index, step.line, label, self.now(), "fail", str(exc))
        except (KeyError, ValueError, TypeError) as exc:
            return StepResult(index, step.line, label, self.now(), "fail", f"{type(exc).__name__}: {exc}")
        return StepResult(index, step.line, label, self.now(), "pass" if checked else "done")

    # -- state -------------------------------------------------------------------------------------
    def _value(self, cond: Condition) -> Any:
        try:
            return self.plant.devices[cond.device].read(cond.name)
        except KeyError as exc:
            return f"<cannot read: {exc}>"

    def _test(self, cond: Condition) -> bool:
        return cond.test(self._value(cond))

    # -- actions (each returns True if it checked something) ---------------------------------------
    async def _do_send(self, action: Any, index: int) -> bool:
        host = self._host(action.port)
        data = action.payload()
        line = self.plant.lines.get(self._port(action.port))
        if line is None:  # a server of its own: what it received is seen by its answer (``_settle``)
            await host.send(data)
            return False
        before = line.bytes_in
        await host.send(data)
        if self.virtual:
            deadline = time.monotonic() + _IO_GUARD
            while line.bytes_in < before + len(data):
                if time.monotonic() > deadline:
                    raise _Abort(f"port {host.name}: the device never received the bytes sent")
                await asyncio.sleep(0.0005)
        return False

    async def _do_expect(self, action: Any, index: int) -> bool:
        host = self._host(action.port)
        if action.bytes is not None:
            wanted = action.bytes.encode("latin-1")
            await self._wait_until(lambda: len(host.unread) >= len(wanted), action.timeout)
            got = host.unread[: len(wanted)]
            host.consume(host.position + len(got))
            if got != wanted:
                raise _StepFailed(f"expected {_show(wanted)}, got {_show(got)}")
            return True
        pattern = re.compile(action.regex.encode("latin-1"))
        found: list[re.Match[bytes]] = []

        def matched() -> bool:
            match = pattern.search(host.unread)
            if match:
                found.append(match)
            return match is not None

        if not await self._wait_until(matched, action.timeout):
            raise _StepFailed(
                f"no match for /{_escape(action.regex)}/ within {action.timeout:g}s; got {_show(host.unread)}"
            )
        host.consume(host.position + found[-1].end())
        return True

    async def _do_set(self, action: Any, index: int) -> bool:
        device = self.plant.devices[action.device]
        for name, value in action.values.items():
            device.set(name, value)
        return False

    async def _do_pulse(self, action: Any, index: int) -> bool:
        """Set the input, and put it back after ``width``; pulses on one input that overlap are
        one pulse to their last end, which puts back the value from before the first."""
        device = self.plant.devices[action.device]
        name = action.input if "." in action.input else f"input.{action.input}"
        key = (action.device, name)
        end = self.clock.now() + action.width
        before, ends = self._pulses.get(key, (device.read(name), end))
        self._pulses[key] = (before, max(ends, end))
        device.set(name, action.value)

        def put_back() -> None:
            base, last = self._pulses.get(key, (before, end))
            if last <= self.clock.now():
                del self._pulses[key]
                device.set(name, base)

        self.clock.call_later(action.width, put_back)
        return False

    async def _do_fault(self, action: Any, index: int) -> bool:
        device = self.plant.devices[action.device]
        kind = action.kind
        if kind in ("power_cycle", "power_cycle_wipe"):
            device.power_cycle(wipe=kind == "power_cycle_wipe")
            return False
        name = {"power_off": "power", "power_on": "power"}.get(kind, kind)
        active = kind != "power_on"
        device.fault(name, active)
        if action.duration is not None and kind != "power_on":
            self.clock.call_later(action.duration, lambda: device.fault(name, False))
        return False

    async def _do_line_fault(self, action: Any, index: int) -> bool:
        from devsim.transports.line import LineFault

        line = self.plant.lines[self._port(action.port)]
        line.inject(
            LineFault(
                kind=action.kind, direction=action.direction, count=action.count, duration=action.duration,
                delay=action.delay, rate=action.rate, baudrate=action.baudrate, seed=index,
            )
        )
        return False

    async def _do_power_cycle(self, action: Any, index: int) -> bool:
        self.plant.devices[action.device].power_cycle(wipe=action.wipe)
        return False

    async def _do_wait(self, seconds: float, index: int) -> bool:
        await self._sleep_until(self.clock.now() + seconds)
        return False

    async def _do_log(self, text: str, index: int) -> bool:
        return False

    async def _do_expect_state(self, cond: Condition, index: int) -> bool:
        value = self._value(cond)
        if not cond.test(value):
            raise _StepFailed(f"{cond.describe()}: is {value!r}")
        return True

    async def _do_expect_traffic(self, action: Any, index: int) -> bool:
        tap = self.traffic[self._port(action.port)]
        data = bytes(tap.host if action.direction == "host" else tap.device)
        matches = list(re.finditer(action.regex.encode("latin-1"), data))
        if action.count is not None:
            if len(matches) != action.count:
                raise _StepFailed(f"/{_escape(action.regex)}/ matched {len(matches)} times, expected {action.count}")
        elif not matches:
            raise _StepFailed(f"the {action.direction} never sent anything matching /{_escape(action.regex)}/")
        return True

    async def _do_expect_timing(self, action: Any, index: int) -> bool:
        device = self.plant.devices[action.device]
        times = [when - self.t0 for when, name in device.events if name == action.event and when >= self.t0]
        low, high = action.between
        if not times:
            raise _StepFailed(f"{action.device} had no {action.event} event")
        chosen = {"first": times[:1], "last": times[-1:], "any": times}[action.occurrence]
        if not any(low - 1e-9 <= t <= high + 1e-9 for t in chosen):
            shown = ", ".join(f"{t:.4f}s" for t in chosen[:5])
            raise _StepFailed(f"{action.event} at {shown}, not between {low:g}s and {high:g}s")
        return True


#: A step's action → what the runner does (one row per action of the scenario schema's steps).
ACTIONS: Table[Callable[..., Awaitable[bool]]] = Table((
    Command("send", Runner._do_send, _STEPS, "bytes from a host port to a device"),
    Command("expect", Runner._do_expect, _STEPS, "an answer the host must receive"),
    Command("set", Runner._do_set, _STEPS, "a control name set to a value"),
    Command("pulse", Runner._do_pulse, _STEPS, "an input set, then reset after a time"),
    Command("fault", Runner._do_fault, _STEPS, "a declared device fault switched on or off"),
    Command("line_fault", Runner._do_line_fault, _STEPS, "a fault on a port's line"),
    Command("power_cycle", Runner._do_power_cycle, _STEPS, "a device switched off and on"),
    Command("wait", Runner._do_wait, _STEPS, "simulated time passes"),
    Command("log", Runner._do_log, _STEPS, "a line in the report"),
    Command("expect_state", Runner._do_expect_state, _STEPS, "a control name must read a value"),
    Command("expect_traffic", Runner._do_expect_traffic, _STEPS, "bytes a port must have carried"),
    Command("expect_timing", Runner._do_expect_timing, _STEPS, "the time between two recorded events"),
))


async def run_scenario_async(
    scenario: Scenario,
    runtime: Runtime,
    *,
    trace_dir: str | Path | None = None,
    announce: Callable[[Plant], None] | None = None,
    on_step: Callable[[StepResult | None, float], None] | None = None,
    control: str | None = None,
) -> ScenarioResult:
    """Build the scenario's plant in ``runtime`` (running in this loop) and run the timeline;
    ``control``: also serve the control API there while it runs (``devsim monitor``), its
    address announced as ``control: ADDR`` among the plant's lines."""
    mode = "virtual" if isinstance(runtime.clock, VirtualClock) else "realtime"
    plant = await build_plant(runtime, scenario, trace_dir=trace_dir)
    server = None
    if control is not None:
        from devsim.runtime.control import ControlServer

        server = ControlServer(runtime, control)
        plant.facades.append(f"control: {await server.start()}")
    try:
        if announce is not None:
            announce(plant)
        if server is None:
            return await Runner(scenario, plant, mode, on_step).run()
        published = PublishedProgress(runtime, scenario, mode, [_label(step) for step in scenario.steps])

        def hook(step: StepResult | None, now: float) -> None:
            published.step(step, now)
            if on_step is not None:
                on_step(step, now)

        result = await Runner(scenario, plant, mode, hook).run()
        published.finish(result)
        return result
    finally:
        if server is not None:
            await server.close()


def run_scenario(
    scenario: Scenario,
    *,
    mode: str | None = None,
    speed: float | None = None,
    state_dir: str | Path | None = None,
    trace_dir: str | Path | None = None,
    announce: Callable[[Plant], None] | None = None,
    on_step: Callable[[StepResult | None, float], None] | None = None,
    control: str | None = None,
) -> ScenarioResult:
    """Run a scenario in a fresh runtime (background thread); ``mode`` virtual or realtime
    (default: the scenario's own choice; anything else is a ``ValueError``)."""
    chosen = mode or scenario.mode()
    if chosen not in ("virtual", "realtime"):
        raise ValueError(f"a scenario's time mode is 'virtual' or 'realtime', not {chosen!r}")
    runtime = Runtime(
        virtual=chosen == "virtual", speed=speed if speed is not None else scenario.speed, state_dir=state_dir
    ).start()
    try:
        return runtime.run(run_scenario_async(scenario, runtime, trace_dir=trace_dir, announce=announce,
                                              on_step=on_step, control=control))
    finally:
        runtime.stop()
