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

A device is on a bus by its first port (``main``; a PCD4.H3's ``sbus``), through ``transport``
or ``ports``; the devices of a bus are on it by ports of one name, each at its own address.

A port given no transport is a pty – unless its kind declares a default network transport
(:attr:`devsim.core.kit.PortDef.default`, e.g. ``udp:5050`` for Ether-S-Bus): then it is served
on that scheme at an *ephemeral* port number on loopback (``{udp: {}}``), so that many plants
can run side by side; the plant reports the number it got (``plant.port(name)``, ``devsim up``).
Give ``{udp: {port: 5050}}`` to have the real one.

A **scenario** file is a plant plus a timeline (``steps``) and expectations.  Each step has at
most one trigger (``at``: time since the start, ``after``: time since the previous step,
``when``: a condition on device state, with ``timeout``) and exactly one action or
expectation; see :data:`ACTIONS`.  Errors read ``scenarios/x.yaml:14: steps.3.after: `after`
must be a duration like 2s or 150ms`` (list items counted from 1: the third step).

:func:`inspect_file` finds every mistake of a file in one pass (``devsim check``): the schema's,
references across its parts (:func:`plant_problems`), and the names each device's kind declares
(:mod:`devsim.scenario.checks`); a part that fails the schema is still parsed on its own, so
that its neighbours are checked against it.
"""

from __future__ import annotations

import os
import re
from pathlib import Path
from typing import Annotated, Any, ClassVar, Literal, NamedTuple

from msgspec import UNSET, Meta, UnsetType, field

from devsim.core.config import ConfigError, LineDict, LineList, load_yaml, plain, report
from devsim.core.typed import FieldError, Invalid, Typed, doc
from devsim.runtime import port_key
from devsim.scenario.checks import (
    Problem,
    bus_address_problems,
    bus_port_problems,
    canopen_node_problems,
    device_problems,
    fault_problem,
    shared_endpoints,
    step_problems,
)
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
    "dotted",
    "inspect_file",
    "load_plant",
    "load_scenario",
    "parse_duration",
    "plant_problems",
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
            if spec.bus is not None and port != (first := self.port_names()[0]):
                raise ValueError(f"ports.{port}: only the first port ({first}) can be on a bus")

    def port_names(self) -> list[str]:
        """The kind's declared serial ports (``main`` if the kind cannot be loaded)."""
        return kind_ports(self.kind)

    def bus(self) -> str | None:
        """The bus the device is on, by its first port (its serial line: ``main``, a PCD4.H3's
        ``sbus``), or None."""
        return self.transport_of(self.port_names()[0]).bus

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
    description: Annotated[str, doc("what the plant or scenario is, for its reader")] = ""
    devices: Annotated[list[DeviceSpec], Meta(min_length=1)]
    buses: list[BusSpec] = []
    mqtt: Annotated[MqttSpec | None, doc("also publish the devices over MQTT")] = None
    opcua: Annotated[OpcuaSpec | None, doc("serve every device on one OPC UA server")] = None

    def __post_init__(self) -> None:
        problem = next(iter(self.problems()), None)
        if problem is not None:
            raise ValueError(dotted(*problem))

    def problems(self) -> list[Problem]:
        """Every reference across the plant's parts that does not hold (names used twice, a
        bus not defined, two devices at one address on a bus …), located; a file reports them all (:func:`inspect_file`), a plant
        given as data raises the first."""
        return plant_problems(_Parts.of(self))

    def only_part(self, part: str) -> PlantSpec:
        """The plant with only the devices of ``part`` (and their buses); ValueError if none."""
        devices = [d for d in self.devices if d.part == part]
        if not devices:
            parts = sorted({d.part for d in self.devices if d.part is not None})
            raise ValueError(f"no device has part {part!r}"
                             f" ({'parts: ' + ', '.join(parts) if parts else 'the plant names no parts'})")
        buses = {d.bus() for d in devices}
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
        return _ports(self.devices, self.buses, self.opcua is not None)


def _ports(devices: list[DeviceSpec], buses: list[BusSpec], opcua: bool) -> list[str]:
    own = [port_key(d.name, port) for d in devices for port in d.port_names() if d.transport_of(port).bus is None]
    return (own + [b.name for b in buses] + [f"{d.name}.modbus" for d in devices if d.modbus is not None]
            + (["opcua"] if opcua else []))


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
        if self.has_equals and not _same(value, self.equals):
            return False
        if self.has_not_equals and _same(value, self.not_equals):
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


def _same(value: Any, wanted: Any) -> bool:
    """``value == wanted``, but a boolean equals only a boolean (Python's ``False == 0``: a
    ``equals: 0`` held for a switch that is off)."""
    if isinstance(value, bool) != isinstance(wanted, bool):
        return False
    if isinstance(value, list | tuple) and isinstance(wanted, list | tuple):
        return len(value) == len(wanted) and all(_same(a, b) for a, b in zip(value, wanted, strict=True))
    if isinstance(value, dict) and isinstance(wanted, dict):
        return value.keys() == wanted.keys() and all(_same(value[k], wanted[k]) for k in value)
    return bool(value == wanted)


# -- actions and expectations -------------------------------------------------------------------
def _text_or_bytes(value: Any) -> bytes:
    """YAML strings are sent as latin-1 bytes (escapes like \\r come from YAML itself)."""
    if isinstance(value, bytes):
        return value
    if isinstance(value, str):
        return _latin1(value)
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
        if self.bytes is not None and not _latin1(self.bytes):
            raise ValueError(f"an empty answer is there at once, whatever the device says {_SILENCE}")
        if self.regex is not None and _byte_regex(self.regex).match(b""):
            raise ValueError(f"the regex matches nothing at all, so it holds at once, whatever the device says {_SILENCE}")


#: How a scenario says that a device does not answer (an empty ``expect`` cannot fail).
_SILENCE = "(that it says nothing: expect_traffic with direction: device and count: 0)"


def _latin1(text: str) -> bytes:
    """Text that stands for bytes on the line: latin-1, one byte per character."""
    try:
        return text.encode("latin-1")
    except UnicodeEncodeError as exc:
        raise ValueError(f"{text[exc.start:exc.end]!r} is no byte: the line's text is latin-1 "
                         "(one character a byte, \\xNN for any byte)") from None


def _byte_regex(regex: str) -> re.Pattern[bytes]:
    try:
        return re.compile(_latin1(regex))
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

    def __post_init__(self) -> None:
        if _byte_regex(self.regex).match(b""):
            raise ValueError("the regex matches nothing at all: it would count the gaps between bytes")


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


class Step(Typed, dict=True):
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

    #: line of the step in its file (filled in by the loader; not a key of the file)
    line: ClassVar[int] = 0

    def __post_init__(self) -> None:
        if isinstance(self.send, str):
            try:
                self.send = SendAction(data=self.send)
            except ValueError as exc:
                raise FieldError("send", str(exc)) from None
        if isinstance(self.expect, str):
            try:
                self.expect = ExpectAction(bytes=self.expect)
            except ValueError as exc:
                raise FieldError("expect", str(exc)) from None
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


class Scenario(PlantSpec, kw_only=True, dict=True):
    name: str | None = None
    time: Annotated[Literal["virtual", "realtime"] | None, doc(
        "default: virtual when the scenario scripts the host, else realtime")] = None
    speed: Annotated[float, Meta(gt=0)] = 1.0
    start: Literal["after_boot", "power_on"] = "after_boot"
    timeout: Annotated[Duration, doc("limit on the whole run (simulated seconds)")] = Duration(300.0)
    host: Annotated[dict[str, Any], doc("{port: name} the default port of host actions")] = {}
    steps: list[Step] = []

    #: the file it came from (filled in by the loader; not a key of the file)
    path: ClassVar[str] = ""

    def problems(self) -> list[Problem]:
        """The plant's problems, and every step's reference to a device, port or fault that
        does not exist."""
        return plant_problems(_Parts.of(self))

    @property
    def scripts_host(self) -> bool:
        return any(step.send is not None or step.expect is not None for step in self.steps)

    def mode(self) -> str:
        return self.time or ("virtual" if self.scripts_host else "realtime")

    def default_port(self) -> str:
        return str(self.host.get("port") or self.ports()[0])


class _Parts(NamedTuple):
    """The parts of a plant or scenario that parsed (None for a device, bus or step that did not)."""

    devices: list[DeviceSpec | None]
    buses: list[BusSpec | None]
    steps: list[Step | None]
    host: dict[str, Any]
    opcua: bool
    #: the names of the devices that did not parse (None if one has no name to read)
    unparsed: tuple[str, ...] | None = ()
    #: the plant's OPC UA server and MQTT broker (None: none, or not parsed)
    opcua_server: OpcuaSpec | None = None
    mqtt: MqttSpec | None = None

    @classmethod
    def of(cls, spec: PlantSpec) -> _Parts:
        """The parts of a plant or scenario that parsed whole."""
        return cls(list(spec.devices), list(spec.buses), list(getattr(spec, "steps", [])), getattr(spec, "host", {}),
                   spec.opcua is not None, opcua_server=spec.opcua, mqtt=spec.mqtt)

    @classmethod
    def salvage(cls, data: Any) -> _Parts:
        """Each part of a file that failed the schema, parsed on its own."""
        raw = data if isinstance(data, dict) else {}

        def each(kind: type[Typed], key: str) -> list[Any]:
            items = raw.get(key)
            return [_parsed(kind, item) for item in items] if isinstance(items, list) else []

        host = raw.get("host")
        devices = each(DeviceSpec, "devices")
        items = raw.get("devices")
        listed = items if isinstance(items, list) else []  # (``devices: 5``: zip() raised TypeError, a traceback)
        names = [item.get("name") if isinstance(item, dict) else None
                 for item, device in zip(listed, devices, strict=False) if device is None]
        unparsed = tuple(names) if isinstance(items, list | None) and all(isinstance(n, str) for n in names) else None
        return cls(devices, each(BusSpec, "buses"), each(Step, "steps"), dict(host) if isinstance(host, dict) else {},
                   raw.get("opcua") is not None, unparsed,  # type: ignore[arg-type]
                   _parsed(OpcuaSpec, raw.get("opcua")), _parsed(MqttSpec, raw.get("mqtt")))


def _parsed(kind: type[Typed], item: Any) -> Any:
    try:
        return kind.parse(item)
    except Invalid:
        return None


def dotted(loc: tuple[int | str, ...], text: str) -> str:
    """A problem without its file: ``steps.3.fault.kind: …``, list items counted from 1."""
    where = ".".join(str(p + 1) if isinstance(p, int) else str(p) for p in loc)
    return f"{where}: {text}" if where else text


def plant_problems(parts: _Parts) -> list[Problem]:
    """References across a plant's (or scenario's) parts that do not hold, and devices at one
    address on one bus (:func:`~devsim.scenario.checks.bus_address_problems`), located."""
    devices = [(i, d) for i, d in enumerate(parts.devices) if d is not None]
    named = [(("devices", i, "name"), d.name) for i, d in devices]
    named += [(("buses", i, "name"), b.name) for i, b in enumerate(parts.buses) if b is not None]
    problems: list[Problem] = []
    if parts.opcua and "opcua" in [name for _loc, name in named]:
        problems.append((("opcua",), "with an opcua section no device or bus may be named 'opcua'"
                         " (the server's port name)"))
    seen: set[str] = set()
    for loc, name in named:
        if name in seen:
            problems.append((loc, f"the name {name!r} is used twice"))
        seen.add(name)
    complete = None not in parts.buses
    buses = {b.name for b in parts.buses if b is not None}
    mixed: set[str] = set()
    for i, device in devices:
        for port in device.port_names():
            bus = device.transport_of(port).bus
            if bus is not None and complete and bus not in buses:
                where = ("ports", port) if port in device.ports else ("transport",)
                problems.append((("devices", i, *where, "bus"),
                                 f"device {device.name!r} is on bus {bus!r}, which is not defined"))
        bus = device.bus()
        others = {d.part for _j, d in devices if d.bus() == bus} if bus else set()
        if bus is not None and len(others) > 1 and bus not in mixed:
            mixed.add(bus)
            problems.append((("devices", i, "part"), f"bus {bus!r} has devices of different parts"
                             f" ({', '.join(sorted(map(str, others)))}); a bus is served by one process"))
        for port in sorted(set(device.ports) - set(device.port_names())):
            problems.append((("devices", i, "ports", port), f"device {device.name!r} ({device.kind}) has no port"
                             f" {port!r} (ports: {', '.join(device.port_names())})"))
    return (problems + bus_port_problems(devices) + bus_address_problems(devices) + canopen_node_problems(devices)
            + shared_endpoints(parts) + _step_references(parts))


def _step_references(parts: _Parts) -> list[Problem]:
    """Steps naming a device, port or fault that does not exist (checked only against parts that
    parsed: a device that did not is reported by the schema)."""
    if not parts.steps and "port" not in parts.host:
        return []
    known = parts.unparsed is not None
    devices = [d for d in parts.devices if d is not None]
    kinds = {d.name: d.kind for d in devices}
    names = {*kinds, *(parts.unparsed or ())}
    ports = set(_ports(devices, [b for b in parts.buses if b is not None], parts.opcua))
    ports_known = None not in parts.devices and None not in parts.buses
    problems: list[Problem] = []
    default_port = parts.host.get("port")
    if default_port is not None and ports_known and (not isinstance(default_port, str) or default_port not in ports):
        problems.append((("host", "port"), f"{default_port!r} is not a device or bus with its own port"))
    for i, step in enumerate(parts.steps):
        if step is None:
            continue
        for key in ("when", "expect_state", "set", "pulse", "fault", "power_cycle", "expect_timing"):
            item = getattr(step, key)
            if item is not None and known and item.device not in names:
                problems.append((("steps", i, key, "device"), f"no device named {item.device!r}"))
        if step.fault is not None and step.fault.device in kinds:
            text = fault_problem(step.fault.kind, kinds[step.fault.device])
            if text is not None:
                problems.append((("steps", i, "fault", "kind"), text))
        for key in ("send", "expect", "line_fault", "expect_traffic"):
            port = getattr(getattr(step, key), "port", None)
            if port is not None and ports_known and port not in ports:
                problems.append((("steps", i, key, "port"),
                                 f"no port named {port!r} (ports: {', '.join(sorted(ports))})"))
    return problems


class _PlantFile(PlantSpec, kw_only=True):
    """A plant file's schema alone: its references are checked with their lines (:func:`inspect_file`)."""

    def __post_init__(self) -> None:
        pass


class _ScenarioFile(Scenario, kw_only=True):
    """A scenario file's schema alone (see :class:`_PlantFile`)."""

    def __post_init__(self) -> None:
        pass


def inspect_file(
    path: str | os.PathLike[str], scenario: bool | None = None
) -> tuple[PlantSpec | None, list[str]]:
    """A plant or scenario file (``scenario``: read as one; by default a file with ``steps``
    is) and every mistake in it, in one pass:
    the schema's, the references across its parts, and the names each device's kind declares,
    one ``file:line: field: message`` each, in the file's order (the spec is None if any)."""
    name = os.fspath(path)
    try:
        data = load_yaml(path)
    except ConfigError as exc:
        return None, exc.messages
    if data is None:
        data = LineDict()
        data.key_lines = {}
    is_scenario = scenario if scenario is not None else isinstance(data, LineDict) and "steps" in data
    model: type[PlantSpec] = _ScenarioFile if is_scenario else _PlantFile
    problems: list[Problem] = []
    try:
        shape: PlantSpec | None = model.parse(data)
    except Invalid as exc:
        shape = None
        problems += exc.problems
    parts = _Parts.salvage(data) if shape is None else _Parts.of(shape)
    problems += plant_problems(parts)
    raw_devices = data.get("devices") if isinstance(data, dict) else None
    for i, device in enumerate(parts.devices):
        if device is not None:
            problems += device_problems(i, device, raw_devices[i])  # type: ignore[index]
    kinds = {d.name: d.kind for d in parts.devices if d is not None}
    for i, step in enumerate(parts.steps):
        if step is not None:
            problems += step_problems(i, step, kinds)
    if problems:
        return None, report(name, data, problems)
    assert shape is not None
    spec = (Scenario if is_scenario else PlantSpec)(**{f: getattr(shape, f) for f in shape.__struct_fields__})
    if isinstance(spec, Scenario):
        _step_lines(data, spec)
        spec.path = name
        spec.name = spec.name or Path(path).stem
    return spec, []


def _step_lines(data: Any, scenario: Scenario) -> None:
    steps = data.get("steps") if isinstance(data, LineDict) else None
    if isinstance(steps, LineList):
        for step, line in zip(scenario.steps, steps.item_lines, strict=False):
            step.line = line


def load_plant(path: str | os.PathLike[str]) -> PlantSpec:
    """Load and validate a plant file (a scenario file also works: its steps are ignored);
    raises ConfigError naming every mistake (:func:`inspect_file`)."""
    spec, messages = inspect_file(path)
    if spec is None:
        raise ConfigError.of(messages)
    return spec


def load_scenario(path: str | os.PathLike[str]) -> Scenario:
    """Load and validate a scenario file; raises ConfigError with ``file:line: …`` per mistake."""
    spec, messages = inspect_file(path, scenario=True)
    if not isinstance(spec, Scenario):
        raise ConfigError.of(messages)
    return spec


def scenario_from_dict(data: dict[str, Any], name: str = "scenario") -> Scenario:
    """Build a scenario from Python data (tests, the pytest plugin)."""
    scenario = Scenario.parse(plain(data))
    scenario.name = scenario.name or name
    return scenario
