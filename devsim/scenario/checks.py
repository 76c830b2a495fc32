"""The names in a plant or scenario file, checked against what each device's kind declares.

Each check returns every problem it finds as ``(location, message)``, the location in the file's
data (``("devices", 0, "state", "input.limit_rigth")``: list items counted from 0 here, printed
from 1 with the line by :func:`devsim.core.config.located`), so that ``devsim check`` reports
them all at once, with the schema's own problems:

* :func:`device_problems` – the kind exists; the device's ``config`` (with ``axis`` merged in)
  fits the kind's configuration; the initial ``state`` names points the kind has, with values
  of their type; the Modbus map's entries fit the kind's points;
* :func:`step_problems` – the names in ``set``, ``pulse``, ``when`` and ``expect_state`` are
  points of the device's kind; a ``fault`` is one the kind declares;
* :func:`bus_address_problems` – no two devices of a kind on one bus have the same address;
* :func:`bus_port_problems` – the devices of a bus are on it by ports of one name;
* :func:`canopen_node_problems` – no two devices of one process are one CANopen node id on
  one network;
* :func:`shared_endpoints` – two ports of the plant (its devices', buses', facades' and the
  servers it connects to) on one pty link or TCP/UDP port (:func:`endpoints_clash`).

They work on the parts of a file that parsed (a device or step that did not is left to the
schema's message), and take the device and step objects by their attributes, so that this module
needs nothing of :mod:`devsim.scenario.schema`.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from typing import Any

from devsim.core.points import BadValue, ReadOnlyName, UnknownName
from devsim.core.registry import UnknownKind, device_class
from devsim.core.typed import Invalid
from devsim.scenario.specs import TcpSpec, TransportSpec

__all__ = ["POWER_FAULTS", "Problem", "bus_address_problems", "bus_port_problems", "canopen_node_problems",
           "device_problems", "endpoints_clash", "fault_problem", "shared_endpoints", "step_problems"]

Problem = tuple[tuple[int | str, ...], str]

#: Faults every device has through its power supply; the others are declared by each kind.
POWER_FAULTS = ("power_cycle", "power_cycle_wipe", "power_off", "power_on")


def device_problems(index: int, device: Any, raw: Any) -> list[Problem]:
    """Problems of device ``index`` (a parsed ``DeviceSpec``; ``raw`` its mapping in the file)."""
    at = ("devices", index)
    try:
        cls = device_class(device.kind)
    except UnknownKind as exc:
        return [((*at, "kind"), str(exc))]
    return _config_problems(at, cls, device, raw) + _state_problems(at, cls, device) + _modbus_problems(at, cls, device)


def _config_problems(at: tuple[int | str, ...], cls: Any, device: Any, raw: Any) -> list[Problem]:
    model = getattr(cls, "config_model", None)
    if model is None:
        return []
    try:
        model.parse(device.device_config())
    except Invalid as exc:
        axis = raw.get("axis") if isinstance(raw, Mapping) else None
        problems: list[Problem] = []
        for loc, text in exc.problems:
            from_axis = len(loc) > 1 and loc[0] == "axis" and isinstance(axis, Mapping) and loc[1] in axis
            problems.append(((*at, "axis", *loc[1:]) if from_axis else (*at, "config", *loc), text))
        return problems
    return []


def _state_problems(at: tuple[int | str, ...], cls: Any, device: Any) -> list[Problem]:
    problems: list[Problem] = []
    for name, value in device.state.items():
        text = _point_problem(cls.points, device.name, name, value)
        if text is not None:
            problems.append(((*at, "state", name), text))
    return problems


def _modbus_problems(at: tuple[int | str, ...], cls: Any, device: Any) -> list[Problem]:
    """The Modbus map's entries (``modbus: {map: …}``), made as the facade makes them."""
    modbus = getattr(device, "modbus", None)
    if modbus is None or not modbus.map:
        return []
    from devsim.facades.modbus_map import ModbusMap

    try:
        ModbusMap.layout(cls.points, modbus.layout, modbus.map)
    except ValueError as exc:
        return [((*at, "modbus", "map"), str(exc))]
    return []


def _point_problem(points: Any, owner: str, name: str, value: Any) -> str | None:
    try:
        points.parse(name, value, owner)
    except (UnknownName, ReadOnlyName, BadValue) as exc:
        return str(exc)
    return None


def step_problems(index: int, step: Any, kinds: Mapping[str, str]) -> list[Problem]:
    """Problems of the names in step ``index`` (a parsed ``Step``), each part against the kind of
    the device it names (a step may wait on one device and act on another); ``kinds``: device →
    kind of the devices that parsed (a part on another device is left to the reference check)."""
    at = ("steps", index)
    problems: list[Problem] = []
    if step.set is not None and (points := _points(step.set.device, kinds)) is not None:
        for name, value in step.set.values.items():
            text = _point_problem(points, step.set.device, name, value)
            if text is not None:
                problems.append(((*at, "set", "values", name), text))
    if step.pulse is not None and (points := _points(step.pulse.device, kinds)) is not None:
        name = step.pulse.input if "." in step.pulse.input else f"input.{step.pulse.input}"
        text = _point_problem(points, step.pulse.device, name, step.pulse.value)
        if text is not None:
            problems.append(((*at, "pulse", "input"), text))
    for key in ("when", "expect_state"):
        cond = getattr(step, key)
        if cond is None or cond.name.startswith("line.") or (points := _points(cond.device, kinds)) is None:
            continue
        try:
            points.lookup(cond.name, cond.device)
        except UnknownName as exc:
            problems.append(((*at, key, "name"), str(exc)))
    return problems


def _points(device: str, kinds: Mapping[str, str]) -> Any:
    """The points of ``device``'s kind, or None (a device that did not parse, an unknown kind:
    reported elsewhere)."""
    if device not in kinds:
        return None
    try:
        return device_class(kinds[device]).points
    except UnknownKind:
        return None


def fault_problem(fault: str, kind: str) -> str | None:
    """Why ``kind`` has no fault ``fault`` (None if it has, or if the kind is unknown: that is
    reported at the device)."""
    if fault in POWER_FAULTS:
        return None
    try:
        declared = device_class(kind).faults.names()
    except UnknownKind:
        return None
    if fault in declared:
        return None
    return f"{kind} has no fault {fault!r} (declared: {', '.join([*declared, *POWER_FAULTS])})"


def bus_address_problems(devices: Iterable[tuple[int, Any]]) -> list[Problem]:
    """Devices of one kind at one address on one bus (an RS-485 multidrop line), each after the
    first: both would take what is sent to that address and answer together (SERS manual §4.1:
    "Nach dem Senden der Adresse sind alle folgenden Kommandos und Parameter-Zuweisungen dem
    entsprechenden Antrieb zugeordnet. Alle anderen angeschlossenen Antriebe ignorieren die
    Kommandos"; GMS96 manual §2.2, §2.3: the DIL switch's address, "<Adresszeichen><Befehlszeichen>").
    The address is the one the kind's port declares (:attr:`devsim.core.kit.PortDef.address`), as
    the device's configuration sets it or by its default.  ``devices``: (index in the file, parsed
    ``DeviceSpec``); a device whose kind or configuration is wrong is reported elsewhere."""
    first: dict[tuple[str, str, Any], str] = {}
    problems: list[Problem] = []
    for index, device in devices:
        try:
            cls = device_class(device.kind)
        except UnknownKind:
            continue
        line, bus = cls.ports[0], device.bus()  # (a device is on a bus by its first port)
        if bus is None or line.address is None:
            continue
        address = line.address_in(_settings(cls, device.device_config()))
        if address is None:
            continue
        seen = first.setdefault((bus, device.kind, address), device.name)
        if seen != device.name:
            problems.append((("devices", index, "config", *line.address.split(".")),
                             f"devices {seen!r} and {device.name!r} are both at {line.address} {address} on bus {bus!r}"))
    return problems


def bus_port_problems(devices: Iterable[tuple[int, Any]]) -> list[Problem]:
    """Devices on one bus by ports of different names (a device is on a bus by its first port:
    ``main``, a PCD4.H3's ``sbus``): a bus serves the one port of its devices, of one name.
    ``devices``: (index in the file, parsed ``DeviceSpec``)."""
    first: dict[str, tuple[str, str]] = {}
    problems: list[Problem] = []
    for index, device in devices:
        bus, port = device.bus(), device.port_names()[0]
        if bus is None:
            continue
        name, its = first.setdefault(bus, (device.name, port))
        if its != port:
            problems.append((("devices", index, "kind"), f"device {device.name!r} is on bus {bus!r} by its port {port!r},"
                             f" device {name!r} by {its!r}: the devices of a bus share one port of one name"))
    return problems


def canopen_node_problems(devices: Iterable[tuple[int, Any]]) -> list[Problem]:
    """Two devices as one CANopen node id on one ``canopen.network`` (the network as written: the
    plant serves one CAN bus per network it names), in one process (``part``; processes of a fleet
    may run on different machines); ``devsim up`` failed with a ValueError traceback."""
    seen: dict[tuple[Any, str, int], int] = {}
    problems: list[Problem] = []
    for i, device in devices:
        canopen = device.canopen
        if canopen is None:
            continue
        key = (device.part, canopen.network, canopen.node)
        if key in seen:
            problems.append((("devices", i, "canopen", "node"), f"CANopen node {canopen.node} on {canopen.network}"
                             f" is taken by devices.{seen[key] + 1}.canopen already"))
        else:
            seen[key] = i
    return problems


#: The loopback name a server binds on each of its addresses, and those addresses.
_LOOPBACK = frozenset({"localhost", "127.0.0.1", "::1"})


def endpoints_clash(one: tuple[str, ...], other: tuple[str, ...]) -> bool:
    """Two endpoints (``("link", PATH)``, ``("tcp" | "udp", HOST, PORT)``) that cannot both be
    held: the same link, or one protocol's port on the same host, on every address (``::``, or
    ``""``) beside any, on every IPv4 address (``0.0.0.0``) beside one that is no IPv6 address, or
    on ``localhost`` beside a loopback address (a bind on ``0.0.0.0:5020`` and one on
    ``127.0.0.1:5020`` passed devsim check, and the second failed in devsim up)."""
    if one == other:
        return True
    if one[0] != other[0] or one[0] == "link" or one[2] != other[2]:
        return False
    hosts = {one[1], other[1]}
    if hosts & {"", "::"}:  # (Linux: a bind on :: takes the IPv4 addresses too)
        return True
    if "0.0.0.0" in hosts:
        return not any(":" in host for host in hosts)
    return "localhost" in hosts and hosts <= _LOOPBACK


def _settings(cls: Any, config: dict[str, Any]) -> Mapping[str, Any]:
    """A device's configuration with the kind's defaults filled in (empty if it does not parse)."""
    model = getattr(cls, "config_model", None)
    if model is None:
        return config
    try:
        return model.parse(config).dump()  # type: ignore[no-any-return]
    except Invalid:
        return {}


def _endpoint(transport: TransportSpec) -> tuple[str, ...] | None:
    """What two ports cannot both hold: a pty link's path, or a TCP or UDP port number (0: a
    free one, never shared)."""
    kind = transport.kind
    if kind == "pty":
        return ("link", transport.pty.link) if transport.pty is not None and transport.pty.link else None
    if kind in ("tcp", "rfc2217", "udp"):
        where = getattr(transport, kind)
        if where is None or where.port == 0:
            return None
        return ("udp" if kind == "udp" else "tcp", where.host, str(where.port))
    return None


def shared_endpoints(parts: Any) -> list[Problem]:
    """Two ports of the plant (``parts``: the parts of a plant file that parsed, :class:`devsim.scenario.schema._Parts`) (a device's Modbus facade's, a CANopen network's socketcand server,
    the OPC UA server and the MQTT broker it connects to too) on one pty link or one TCP/UDP port:
    the second could not open (or the plant would talk MQTT to its own port)."""
    owners: list[tuple[tuple[int | str, ...], TransportSpec]] = []
    networks: set[tuple[str | None, str]] = set()  # (part, network): one socketcand server each
    for i, device in enumerate(parts.devices):
        if device is None:
            continue
        for port in device.port_names():
            where = ("devices", i, "ports", port) if port in device.ports else ("devices", i, "transport")
            owners.append((where, device.transport_of(port)))
        if device.modbus is not None:  # the facade's own pty link or TCP port
            owners.append((("devices", i, "modbus"), TransportSpec(pty=device.modbus.rtu, tcp=device.modbus.tcp)))
        server = device.canopen.server if device.canopen is not None else None
        if server is not None and (device.part, device.canopen.network) not in networks:
            networks.add((device.part, device.canopen.network))
            owners.append((("devices", i, "canopen", "network"), TransportSpec(tcp=TcpSpec(port=server[1],
                                                                                           host=server[0]))))
    owners += [(("buses", i, "transport"), bus.transport) for i, bus in enumerate(parts.buses) if bus is not None]
    if parts.opcua_server is not None:
        owners.append((("opcua", "port"), TransportSpec(tcp=TcpSpec(port=parts.opcua_server.port,
                                                                     host=parts.opcua_server.host))))
    if parts.mqtt is not None and parts.mqtt.url is not None:
        host, number = parts.mqtt.url.address
        owners.append((("mqtt", "url"), TransportSpec(tcp=TcpSpec(port=number, host=host))))
    seen: dict[tuple[str, ...], tuple[int | str, ...]] = {}
    problems: list[Problem] = []
    for where, transport in owners:
        endpoint = _endpoint(transport)
        if endpoint is None:
            continue
        held = next((other for other in seen if endpoints_clash(other, endpoint)), None)
        if held is not None:
            what = f"link {endpoint[1]}" if endpoint[0] == "link" else f"{endpoint[0]} port {endpoint[1]}:{endpoint[2]}"
            first = ".".join(str(p + 1) if isinstance(p, int) else str(p) for p in seen[held])
            on = f" (on {held[1]}:{held[2]})" if held != endpoint else ""
            problems.append((where, f"{what} is taken by {first}{on} already"))
        else:
            seen[endpoint] = where
    return problems
