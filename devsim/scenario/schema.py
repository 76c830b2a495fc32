"""Scenario and plant files: the YAML schema (typed data, msgspec) with line-numbered errors.

A **plant** file lists devices (and optional multidrop buses) and how each is reached::

    devices:
      - name: x
        kind: sers
        transport: {pty: {link: /tmp/ttyX}}     # or {tcp: {port: 4001}}, {rfc2217: {port: 4002}},
                                                 # {udp: {port: 5050}}, {bus: line1}
        config: {address: 1, params: {P1017: 1}}
        axis: {limit_right: 128000}              # axis geometry, merged into the device config
        state: {input.I1: true, program: ["ON", "W=360 E"]}
    buses:
      - name: line1
        transport: {pty: {}}

A port given no transport is a pty – unless its kind declares a default network transport
(:attr:`devsim.core.kit.PortDef.default`, e.g. ``udp:5050`` for Ether-S-Bus): then it is served
on that scheme at an *ephemeral* port number on loopback (``{udp: {}}``), so that many plants
can run side by side; the plant reports the number it got (``plant.port(name)``, ``devsim up``).
Give ``{udp: {port: 5050}}`` to have the real one.

A **scenario** file is a plant plus a timeline (``steps``) and expectations.  Each step has at
most one trigger (``at``: time since the start, ``after``: time since the previous step,
``when``: a condition on device state, with ``timeout``) and exactly one action or
expectation; see :data:`ACTIONS`.  Errors read ``scenarios/x.yaml:14: steps.3.after: `after`
must be a duration like 2s or 150ms``.
"""

from __future__ import annotations

import os
import re
from pathlib import Path
from typing import Annotated, Any, Literal

from msgspec import UNSET, Meta, UnsetType, field

from devsim.core.config import ConfigError, LineDict, LineList, load_yaml, plain, validate
from devsim.core.typed import FieldError, Typed, doc
from devsim.runtime import port_key
from devsim.scenario.specs import (
    Between,
    CanopenSpec,
    Duration,
    ModbusSpec,
    MqttSpec,
    OpcuaSpec,
    TransportSpec,
    parse_duration,
)

__all__ = [
    "ACTIONS",
    "Condition",
    "DeviceSpec",
    "ModbusSpec",
    "MqttSpec",
    "OpcuaSpec",
    "PlantSpec",
    "Scenario",
    "Step",
    "load_plant",
    "load_scenario",
    "parse_duration",
]

_NAME = r"^[A-Za-z_][A-Za-z0-9_-]*$"


class DeviceSpec(Typed):
    name: Annotated[str, Meta(pattern=_NAME)]
    kind: str
    transport: TransportSpec | UnsetType = UNSET
    ports: Annotated[dict[str, TransportSpec], doc(
        "per port of the kind: its transport (default: a pty, or the port's declared scheme on an ephemeral port)")] = {}
    config: Annotated[dict[str, Any], doc("device configuration (DIP switches, parameters)")] = {}
    axis: Annotated[dict[str, Any] | None, doc("axis geometry, merged into config['axis']")] = None
    state: Annotated[dict[str, Any], doc("initial state: settable names and 'program'")] = {}
    modbus: Annotated[ModbusSpec | None, doc("also serve the device over Modbus TCP or RTU")] = None
    canopen: Annotated[CanopenSpec | None, doc("also serve the device as a CANopen node")] = None
    part: Annotated[Annotated[str, Meta(pattern=r"^[A-Za-z0-9_.-]+$")] | None, doc(
        "which part of the plant serves it (devsim up --part NAME, for a fleet)")] = None

    def __post_init__(self) -> None:
        if self.transport is not UNSET and self.ports:
            raise ValueError("give 'transport' (one port) or 'ports' (per port), not both")
        for port, spec in self.ports.items():
            if spec.bus is not None and port != "main":
                raise ValueError(f"ports.{port}: only the main port can be on a bus")

    def port_names(self) -> list[str]:
        """The kind's declared serial ports (``main`` if the kind cannot be loaded)."""
        return kind_ports(self.kind)

    def transport_of(self, port: str) -> TransportSpec:
        """The transport serving one port: ``ports[port]``, else ``transport`` (when given) for
        the first port, else the port's declared default scheme on an ephemeral port number,
        else a pty."""
        if port in self.ports:
            return self.ports[port]
        first = port == self.port_names()[0]
        if first and isinstance(self.transport, TransportSpec):
            return self.transport
        default = kind_port_defaults(self.kind).get(port)
        if default is not None:
            return TransportSpec.parse({default[0]: {}})
        return TransportSpec()

    def device_config(self) -> dict[str, Any]:
        config = dict(self.config)
        if self.axis is not None:
            config["axis"] = {**dict(config.get("axis") or {}), **self.axis}
        return config


class BusSpec(Typed):
    name: Annotated[str, Meta(pattern=_NAME)]
    transport: TransportSpec = field(default_factory=TransportSpec)

    def __post_init__(self) -> None:
        if self.transport.bus is not None:
            raise FieldError("transport", "a bus is reached by pty, tcp, rfc2217 or udp, not by another bus")


def kind_ports(kind: str) -> list[str]:
    """The serial ports a device kind declares (``["main"]`` when the kind cannot be loaded;
    the unknown kind is reported with its line elsewhere)."""
    from devsim.core.registry import device_class

    try:
        return [p.name for p in device_class(kind).ports]
    except Exception:
        return ["main"]


def kind_port_defaults(kind: str) -> dict[str, tuple[str, int]]:
    """The declared default network transports of a kind's ports: name → (scheme, port)."""
    from devsim.core.registry import device_class

    try:
        ports = device_class(kind).ports
    except Exception:
        return {}
    return {p.name: p.default_transport for p in ports if p.default_transport is not None}


class PlantSpec(Typed, kw_only=True):
    name: Annotated[str | None, doc("a name for the plant (shown by devsim up)")] = None
    devices: Annotated[list[DeviceSpec], Meta(min_length=1)]
    buses: list[BusSpec] = []
    mqtt: Annotated[MqttSpec | None, doc("also publish the devices over MQTT")] = None
    opcua: Annotated[OpcuaSpec | None, doc("serve every device on one OPC UA server")] = None

    def __post_init__(self) -> None:
        self._opcua_name()
        self._names()

    def _opcua_name(self) -> None:
        if self.opcua is not None and "opcua" in [d.name for d in self.devices] + [b.name for b in self.buses]:
            raise ValueError("with an opcua section no device or bus may be named 'opcua' (the server's port name)")

    def _names(self) -> None:
        names = [d.name for d in self.devices] + [b.name for b in self.buses]
        for name in names:
            if names.count(name) > 1:
                raise ValueError(f"the name {name!r} is used twice")
        buses = {b.name for b in self.buses}
        for device in self.devices:
            for port in device.port_names():
                bus = device.transport_of(port).bus
                if bus is not None and bus not in buses:
                    raise ValueError(f"device {device.name!r} is on bus {bus!r}, which is not defined")
            bus = device.transport_of("main").bus
            others = {d.part for d in self.devices if d.transport_of("main").bus == bus} if bus else set()
            if len(others) > 1:
                raise ValueError(f"bus {bus!r} has devices of different parts ({', '.join(map(str, others))});"
                                 " a bus is served by one process")
            unknown = sorted(set(device.ports) - set(device.port_names()))
            if unknown:
                raise ValueError(
                    f"device {device.name!r} ({device.kind}) has no port {unknown[0]!r}"
                    f" (ports: {', '.join(device.port_names())})"
                )

    def only_part(self, part: str) -> PlantSpec:
        """The plant with only the devices of ``part`` (and their buses); ValueError if none."""
        devices = [d for d in self.devices if d.part == part]
        if not devices:
            parts = sorted({d.part for d in self.devices if d.part is not None})
            raise ValueError(f"no device has part {part!r}"
                             f" ({'parts: ' + ', '.join(parts) if parts else 'the plant names no parts'})")
        buses = {d.transport_of("main").bus for d in devices}
        return self.replace(devices=devices, buses=[b for b in self.buses if b.name in buses])

    def device_ports(self) -> list[tuple[str, DeviceSpec, str]]:
        """(plant port name, device, device port) of every device port with a transport of its
        own; the plant port name is ``DEVICE`` for a main port, else ``DEVICE.PORT``."""
        rows = []
        for device in self.devices:
            for port in device.port_names():
                if device.transport_of(port).bus is None:
                    rows.append((port_key(device.name, port), device, port))
        return rows

    def ports(self) -> list[str]:
        """Names a host can talk to: device ports with their own transport, buses, and the
        devices' Modbus facades (``NAME.modbus``), and the plant's OPC UA server (``opcua``)."""
        return ([name for name, _device, _port in self.device_ports()] + [b.name for b in self.buses]
                + [f"{d.name}.modbus" for d in self.devices if d.modbus is not None]
                + (["opcua"] if self.opcua is not None else []))


# -- conditions ------------------------------------------------------------------------------
class Condition(Typed):
    """A test on one piece of device state: ``{device: x, name: axis.position, ge: 1000}``.

    Operators: ``equals``, ``not_equals``, ``lt``, ``le``, ``gt``, ``ge``, ``approx`` (with
    ``tolerance``), ``regex`` (on the value's text).  ``equals: null`` tests for None.
    """

    device: str
    name: str
    equals: Any = UNSET
    not_equals: Any = UNSET
    lt: float | None = None
    le: float | None = None
    gt: float | None = None
    ge: float | None = None
    approx: float | None = None
    tolerance: Annotated[float, Meta(ge=0)] = 1e-6
    regex: str | None = None

    @property
    def has_equals(self) -> bool:
        return self.equals is not UNSET

    @property
    def has_not_equals(self) -> bool:
        return self.not_equals is not UNSET

    def __post_init__(self) -> None:
        ops = [op for op in ("lt", "le", "gt", "ge", "approx", "regex") if getattr(self, op) is not None]
        if self.has_equals:
            ops.append("equals")
        if self.has_not_equals:
            ops.append("not_equals")
        if not ops:
            raise ValueError("give a test: equals, not_equals, lt, le, gt, ge, approx or regex")
        if self.regex is not None:
            try:
                re.compile(self.regex)
            except re.error as exc:
                raise ValueError(f"bad regex: {exc}") from None

    def test(self, value: Any) -> bool:
        if self.has_equals and value != self.equals:
            return False
        if self.has_not_equals and value == self.not_equals:
            return False
        number = value if isinstance(value, int | float) and not isinstance(value, bool) else None
        for op, limit in (("lt", self.lt), ("le", self.le), ("gt", self.gt), ("ge", self.ge)):
            if limit is None:
                continue
            if number is None:
                return False
            if not {"lt": number < limit, "le": number <= limit, "gt": number > limit, "ge": number >= limit}[op]:
                return False
        if self.approx is not None and (number is None or abs(number - self.approx) > self.tolerance):
            return False
        return not (self.regex is not None and re.search(self.regex, str(value)) is None)

    def describe(self) -> str:
        tests = []
        if self.has_equals:
            tests.append(f"== {self.equals!r}")
        if self.has_not_equals:
            tests.append(f"!= {self.not_equals!r}")
        for op, sym in (("lt", "<"), ("le", "<="), ("gt", ">"), ("ge", ">="), ("regex", "~")):
            if getattr(self, op) is not None:
                tests.append(f"{sym} {getattr(self, op)!r}")
        if self.approx is not None:
            tests.append(f"≈ {self.approx} ± {self.tolerance}")
        return f"{self.device}.{self.name} {' and '.join(tests)}"


# -- actions and expectations -------------------------------------------------------------------
def _text_or_bytes(value: Any) -> bytes:
    """YAML strings are sent as latin-1 bytes (escapes like \\r come from YAML itself)."""
    if isinstance(value, bytes):
        return value
    if isinstance(value, str):
        return value.encode("latin-1")
    raise ValueError("must be a string")


class SendAction(Typed):
    port: str | None = None
    data: str | None = None
    line: Annotated[str | None, doc("like data, with CR appended")] = None

    def __post_init__(self) -> None:
        if (self.data is None) == (self.line is None):
            raise ValueError("give either data or line")
        _text_or_bytes(self.data if self.data is not None else self.line)

    def payload(self) -> bytes:
        if self.line is not None:
            return _text_or_bytes(self.line) + b"\r"
        return _text_or_bytes(self.data)


class ExpectAction(Typed):
    """The device's answer on ``port``: exact ``bytes`` (next bytes) or a ``regex`` match in
    what arrives, within ``timeout`` (simulated time)."""

    port: str | None = None
    bytes: str | None = None
    regex: str | None = None
    timeout: Duration = Duration(1.0)

    def __post_init__(self) -> None:
        if (self.bytes is None) == (self.regex is None):
            raise ValueError("give either bytes or regex")
        if self.regex is not None:
            try:
                re.compile(self.regex.encode("latin-1"))
            except re.error as exc:
                raise ValueError(f"bad regex: {exc}") from None


class SetAction(Typed):
    """Set inputs, quantities or parameters: ``{device: x, values: {input.I1: true}}``."""

    device: str
    values: Annotated[dict[str, Any], Meta(min_length=1)]


class PulseAction(Typed):
    device: str
    input: str
    width: Duration = Duration(0.05)
    value: Any = True


#: Faults every device has through its power supply; the others are declared by each kind.
POWER_FAULTS = ("power_cycle", "power_cycle_wipe", "power_off", "power_on")


class FaultAction(Typed):
    """A device fault; ``duration`` makes a lasting fault end by itself."""

    device: str
    kind: Annotated[str, doc("a fault the device's kind declares, or power_cycle(_wipe)/power_off/power_on")]
    duration: Duration | None = None


LineFaultKind = Literal["corrupt", "drop", "split", "delay", "jitter", "noise", "baud_mismatch", "unplug", "hang", "silent"]


class LineFaultAction(Typed, kw_only=True):
    """A fault on the real line of ``port``: see :class:`devsim.transports.line.LineFault`."""

    port: str | None = None
    kind: LineFaultKind
    count: Annotated[Annotated[int, Meta(ge=1)] | None, doc("bytes affected (corrupt, drop)")] = None
    duration: Duration | None = None
    delay: Duration | None = None
    rate: Annotated[Annotated[float, Meta(gt=0)] | None, doc("noise bytes per second")] = None
    baudrate: Annotated[int, Meta(gt=0)] | None = None
    direction: Literal["to_device", "to_host", "both"] = "both"


class PowerCycleAction(Typed):
    device: str
    wipe: bool = False


class TrafficExpectation(Typed, kw_only=True):
    """Something on the line since the start matched: ``direction`` host (sent by the host)
    or device (sent by the device)."""

    port: str | None = None
    direction: Literal["host", "device"] = "host"
    regex: str
    count: Annotated[Annotated[int, Meta(ge=0)] | None, doc("exact number of matches")] = None


class TimingExpectation(Typed):
    """A device event (e.g. the SERS ``move_end``) happened between two times since the start."""

    device: str
    event: str
    between: Between
    occurrence: Literal["first", "last", "any"] = "any"


#: Step keys that are actions or expectations (exactly one per step).
ACTIONS = (
    "send", "expect", "set", "pulse", "fault", "line_fault", "power_cycle", "wait", "expect_state",
    "expect_traffic", "expect_timing", "log",
)


class Step(Typed):
    at: Duration | None = None
    after: Duration | None = None
    when: Condition | None = None
    timeout: Duration | None = None

    send: SendAction | str | None = None  # a string: the data to send
    expect: ExpectAction | str | None = None  # a string: the bytes expected
    set: SetAction | None = None
    pulse: PulseAction | None = None
    fault: FaultAction | None = None
    line_fault: LineFaultAction | None = None
    power_cycle: PowerCycleAction | None = None
    wait: Duration | None = None
    expect_state: Condition | None = None
    expect_traffic: TrafficExpectation | None = None
    expect_timing: TimingExpectation | None = None
    log: str | None = None

    #: line of the step in its file (filled in by the loader)
    line: int = 0

    def __post_init__(self) -> None:
        if isinstance(self.send, str):
            try:
                self.send = SendAction(data=self.send)
            except ValueError as exc:
                raise FieldError("send", str(exc)) from None
        if isinstance(self.expect, str):
            self.expect = ExpectAction(bytes=self.expect)
        triggers = [k for k in ("at", "after", "when") if getattr(self, k) is not None]
        if len(triggers) > 1:
            raise ValueError(f"a step has one trigger, not {' and '.join(triggers)}")
        if self.timeout is not None and self.when is None:
            raise ValueError("`timeout` goes with `when`")
        actions = [k for k in ACTIONS if getattr(self, k) is not None]
        if not actions and triggers:
            return  # only a trigger: wait for it (``when`` fails at its timeout)
        if len(actions) != 1:
            what = " and ".join(actions) if actions else "none"
            raise ValueError(f"a step has exactly one action or expectation ({', '.join(ACTIONS)}); got {what}")

    @property
    def action(self) -> str | None:
        return next((k for k in ACTIONS if getattr(self, k) is not None), None)


class Scenario(PlantSpec, kw_only=True):
    name: str | None = None
    description: str = ""
    time: Annotated[Literal["virtual", "realtime"] | None, doc(
        "default: virtual when the scenario scripts the host, else realtime")] = None
    speed: Annotated[float, Meta(gt=0)] = 1.0
    start: Literal["after_boot", "power_on"] = "after_boot"
    timeout: Annotated[Duration, doc("limit on the whole run (simulated seconds)")] = Duration(300.0)
    host: Annotated[dict[str, Any], doc("{port: name} the default port of host actions")] = {}
    steps: list[Step] = []

    #: the file it came from (filled in by the loader)
    path: str = ""

    def __post_init__(self) -> None:
        super().__post_init__()
        self._references()

    def _references(self) -> None:
        devices = {d.name for d in self.devices}
        kinds = {d.name: d.kind for d in self.devices}
        ports = set(self.ports())
        default_port = self.host.get("port")
        if default_port is not None and default_port not in ports:
            raise ValueError(f"host.port {default_port!r} is not a device or bus with its own port")
        for number, step in enumerate(self.steps):
            where = f"step {number + 1}"
            for item in (step.when, step.expect_state, step.set, step.pulse, step.fault, step.power_cycle,
                         step.expect_timing):
                if item is not None and getattr(item, "device", None) not in devices:
                    raise ValueError(f"{where}: no device named {item.device!r}")  # type: ignore[union-attr]
            if step.fault is not None:
                _check_fault(where, step.fault, kinds[step.fault.device])
            for item in (step.send, step.expect, step.line_fault, step.expect_traffic):
                port = getattr(item, "port", None) if item is not None else None
                if port is not None and port not in ports:
                    raise ValueError(f"{where}: no port named {port!r} (ports: {', '.join(sorted(ports))})")

    @property
    def scripts_host(self) -> bool:
        return any(step.send is not None or step.expect is not None for step in self.steps)

    def mode(self) -> str:
        return self.time or ("virtual" if self.scripts_host else "realtime")

    def default_port(self) -> str:
        return str(self.host.get("port") or self.ports()[0])


def _check_fault(where: str, action: FaultAction, kind: str) -> None:
    from devsim.core.registry import device_class

    if action.kind in POWER_FAULTS:
        return
    try:
        declared = device_class(kind).faults.names()
    except Exception:
        return  # the unknown kind is reported with its own line
    if action.kind not in declared:
        known = ", ".join([*declared, *POWER_FAULTS])
        raise ValueError(f"{where}: {kind} has no fault {action.kind!r} (declared: {known})")


def _step_lines(data: Any, scenario: Scenario) -> None:
    steps = data.get("steps") if isinstance(data, LineDict) else None
    if isinstance(steps, LineList):
        for step, line in zip(scenario.steps, steps.item_lines, strict=False):
            step.line = line


def _check_device_configs(data: Any, spec: PlantSpec, path: str) -> None:
    """Validate each device's config against its kind's model, with the YAML lines."""
    from devsim.core.registry import UnknownKind, device_class

    raw_devices = data.get("devices") if isinstance(data, LineDict) else None
    for index, device in enumerate(spec.devices):
        raw = raw_devices[index] if isinstance(raw_devices, LineList) and index < len(raw_devices) else None
        line = raw_devices.item_lines[index] if isinstance(raw_devices, LineList) and index < len(raw_devices) else 1
        try:
            cls = device_class(device.kind)
        except UnknownKind as exc:
            key_line = raw.key_lines.get("kind", line) if isinstance(raw, LineDict) else line
            raise ConfigError(f"{path}:{key_line}: devices.{index}.kind: {exc}") from None
        model = getattr(cls, "config_model", None)
        if model is None:
            continue
        config = raw.get("config") if isinstance(raw, LineDict) else None
        merged = LineDict(config if isinstance(config, LineDict) else {})
        merged.line = getattr(config, "line", line)
        merged.key_lines = dict(getattr(config, "key_lines", {}))
        axis = raw.get("axis") if isinstance(raw, LineDict) else None
        if isinstance(axis, LineDict):
            inner = merged.get("axis")
            combined = LineDict({**(inner if isinstance(inner, dict) else {}), **axis})
            combined.line = axis.line
            combined.key_lines = {**getattr(inner, "key_lines", {}), **axis.key_lines}
            merged["axis"] = combined
            merged.key_lines["axis"] = raw.key_lines.get("axis", line)
        try:
            validate(merged, model, path)
        except ConfigError as exc:
            prefix = f"devices.{index}.config."
            raise ConfigError(_prefix(str(exc), prefix), [_prefix(m, prefix) for m in exc.messages]) from None


def _check_state(data: Any, spec: PlantSpec, path: str) -> None:
    """Initial ``state`` names and values, checked against each kind's declared points."""
    from devsim.core.registry import device_class

    raw_devices = data.get("devices") if isinstance(data, LineDict) else None
    for index, device in enumerate(spec.devices):
        raw = raw_devices[index] if isinstance(raw_devices, LineList) and index < len(raw_devices) else None
        state = raw.get("state") if isinstance(raw, LineDict) else None
        lines = getattr(state, "key_lines", {})
        try:
            points = device_class(device.kind).points
        except Exception:
            continue
        for name, value in device.state.items():
            _check_point(points, device.name, name, value, f"{path}:{lines.get(name, 1)}: devices.{index}.state.{name}")


def _check_point(points: Any, owner: str, name: str, value: Any, where: str) -> None:
    from devsim.core.points import BadValue, ReadOnlyName, UnknownName

    try:
        points.parse(name, value, owner)
    except (UnknownName, ReadOnlyName, BadValue) as exc:
        raise ConfigError(f"{where}: {exc}") from None


def _check_steps(scenario: Scenario, path: str) -> None:
    """Names in ``set``, ``pulse``, ``when`` and ``expect_state`` steps, checked against the
    declared points of each device's kind."""
    from devsim.core.points import UnknownName
    from devsim.core.registry import device_class

    kinds = {d.name: d.kind for d in scenario.devices}
    for number, step in enumerate(scenario.steps, 1):
        where = f"{path}:{step.line or 1}: steps.{number}"
        target = step.set or step.pulse or step.when or step.expect_state
        if target is None:
            continue
        try:
            points = device_class(kinds[target.device]).points
        except Exception:
            continue
        if step.set is not None:
            for name, value in step.set.values.items():
                _check_point(points, step.set.device, name, value, f"{where}.set.{name}")
        if step.pulse is not None:
            name = step.pulse.input if "." in step.pulse.input else f"input.{step.pulse.input}"
            _check_point(points, step.pulse.device, name, step.pulse.value, f"{where}.pulse")
        for cond in (step.when, step.expect_state):
            if cond is not None and not cond.name.startswith("line."):
                try:
                    points.lookup(cond.name, cond.device)
                except UnknownName as exc:
                    raise ConfigError(f"{where}: {exc}") from None


def _prefix(message: str, prefix: str) -> str:
    """Insert ``prefix`` before the field of a ``file:line: field: message`` line."""
    parts = message.split(": ", 2)
    if len(parts) == 3:
        return f"{parts[0]}: {prefix}{parts[1]}: {parts[2]}"
    return message


def load_plant(path: str | os.PathLike[str]) -> PlantSpec:
    """Load and validate a plant file (a scenario file also works: its steps are ignored)."""
    data = load_yaml(path)
    if isinstance(data, LineDict) and "steps" in data:
        return load_scenario(path)
    spec = validate(data, PlantSpec, path)
    _check_device_configs(data, spec, os.fspath(path))
    _check_state(data, spec, os.fspath(path))
    return spec


def load_scenario(path: str | os.PathLike[str]) -> Scenario:
    """Load and validate a scenario file; raises ConfigError with ``file:line: …``."""
    data = load_yaml(path)
    scenario = validate(data, Scenario, path)
    _step_lines(data, scenario)
    _check_device_configs(data, scenario, os.fspath(path))
    _check_state(data, scenario, os.fspath(path))
    _check_steps(scenario, os.fspath(path))
    scenario.path = os.fspath(path)
    if scenario.name is None:
        scenario.name = Path(path).stem
    return scenario


def scenario_from_dict(data: dict[str, Any], name: str = "scenario") -> Scenario:
    """Build a scenario from Python data (tests, the pytest plugin)."""
    scenario = Scenario.parse(plain(data))
    scenario.name = scenario.name or name
    return scenario
