"""``devsim run``'s plan and server, without click: :func:`plan_run` checks the options of
:func:`devsim.cli.main.run` and :func:`serve` serves the plan until Ctrl-C / SIGTERM / SIGHUP.

Nothing here imports click on the way to a served port (:mod:`devsim.cli.quick` runs a plain
``devsim run`` command line without it): a mistake imports click on the way to its error, and
the facades, the control server, the logs and the motion log are imported only when a plan
has them.
"""

from __future__ import annotations

import asyncio
import gc
import sys
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import msgspec

from devsim.cli.control_address import control_option, default_control, system_failure
from devsim.cli.statuses import INTERRUPTED, StartFailure, file_failure, make_dirs, start_status
from devsim.cli.usage import host_port, usage_error
from devsim.core.console import say as _say  # (replaced by tests and benchmarks/startup.py)
from devsim.core.console import stop_on_signals, warn
from devsim.core.registry import UnknownKind, device_class

if TYPE_CHECKING:  # imported where used: `devsim run` starts faster without them
    from devsim.core.device import Device
    from devsim.runtime.control import ControlAddress

__all__ = ["PORT_SCHEMES", "Plan", "Port", "control_option", "default_control", "plan_run", "serve"]


def _bad_file(message: str) -> Exception:
    from devsim.cli import exits

    return exits.BadFile(message)


class Port(msgspec.Struct):
    scheme: str  # "pty", "tcp", "rfc2217" or "udp"
    host: str = "127.0.0.1"
    port: int = 0
    link: str | None = None


class Plan(msgspec.Struct):
    kind: str
    devices: list[tuple[str, dict[str, Any]]]
    port: Port  # for the ports without a default or an override
    state_dir: str | None
    speed: float
    virtual: bool
    trace: str | None
    pacing: bool
    control: ControlAddress | None
    allow_remote: bool
    printed: list[str] = msgspec.field(default_factory=list)
    overrides: dict[str, Port] = msgspec.field(default_factory=dict)  # --port NAME=SPEC
    modbus: str | None = None  # --modbus tcp:[HOST:]PORT | rtu | rtu:LINK
    modbus_map: str = "points"  # --modbus-map points | mirror
    idle_drop: float | None = None  # --idle-drop SECONDS
    canopen: str | None = None  # --canopen NODE[@[HOST:]PORT]
    mqtt: str | None = None  # --mqtt [URL]: "" for the embedded broker
    mqtt_convention: str = "devsim"  # --mqtt-convention devsim | sparkplug
    mqtt_rate: float = 1.0  # --mqtt-rate SECONDS
    mqtt_plant: str | None = None  # --mqtt-plant NAME (default: the kind)
    mqtt_primary_host: str | None = None  # --mqtt-primary-host HOST_ID (Sparkplug)
    opcua: str | None = None  # --opcua [[HOST:]PORT] ("": the default endpoint)
    opcua_period: float = 0.1  # --opcua-period SECONDS
    fleet: str | None = None  # --fleet mqtt://BROKER[:PORT][/NAME]
    motion_log: str | None = None  # --motion-log FILE.csv
    motion_resolution: float = 0.01  # --motion-resolution SECONDS
    log_level: int = 2  # -v/-q (devsim.observe.live_log)
    web: Any = None  # --web: where to serve the page (devsim.web.server.ListenAddress)


#: What ``--port NAME=SPEC`` accepts after ``NAME=``.
PORT_SCHEMES = ("pty", "udp", "tcp", "rfc2217")


def _parse_port_option(text: str, names: Sequence[str]) -> tuple[str, Port]:
    """``--port NAME=pty|udp:[HOST:]PORT|tcp:[HOST:]PORT|rfc2217:[HOST:]PORT`` → (NAME, port)."""
    name, sep, spec = text.partition("=")
    if not sep or not name:
        raise usage_error(f"--port: expected NAME=SPEC (e.g. ether=udp:5050), got {text!r}")
    if name not in names:
        raise usage_error(f"--port: the kind has no port {name!r} (ports: {', '.join(names)})")
    scheme, _, rest = spec.partition(":")
    if scheme not in PORT_SCHEMES:
        raise usage_error(
            f"--port {name}: expected pty, udp:[HOST:]PORT, tcp:[HOST:]PORT or rfc2217:[HOST:]PORT, got {spec!r}"
        )
    if scheme == "pty":
        if rest:
            raise usage_error(f"--port {name}: pty takes no address, got {spec!r}")
        return name, Port("pty")
    return name, Port(scheme, *host_port(f"--port {name}", rest))


def _parse_drives(text: str) -> list[int]:
    drives: list[int] = []
    for item in text.split(","):
        item = item.strip()
        if not item:
            continue
        try:
            if "-" in item[1:]:
                low, _, high = item.partition("-")
                numbers = list(range(int(low), int(high) + 1))
                if not numbers:
                    raise ValueError
            else:
                numbers = [int(item)]
        except ValueError:
            raise usage_error(f"--drives: expected addresses like 1,2,3 (or 1-3), got {item!r}") from None
        for number in numbers:
            if number in drives:
                raise usage_error(f"--drives: address {number} given twice")
            drives.append(number)
    if not drives:
        raise usage_error("--drives: expected at least one address, e.g. --drives 1,2,3")
    return drives


def _device_configs(cls: type[Device], kind: str, config_file: str | None, drives: list[int] | None) -> list[
    tuple[str, dict[str, Any]]
]:
    """Validate the configuration file and the drive addresses; name the devices."""
    model = cls.config_model
    base: dict[str, Any] = {}
    if config_file is not None:  # YAML and the line-numbered checks only when there is a file
        from devsim.core.config import ConfigError, load_yaml, plain, validate

        try:
            data = load_yaml(config_file)
            if model is not None:
                validate(data, model, config_file)
            elif data is not None and not isinstance(data, dict):
                raise ConfigError(f"{config_file}:1: expected a mapping at the top level")
        except ConfigError as exc:
            raise _bad_file(str(exc)) from None
        base = plain(data) if isinstance(data, dict) else {}

    def finish(raw: dict[str, Any], source: str) -> dict[str, Any]:
        if model is None:
            return raw
        try:
            return model.parse(raw).dump()
        except ValueError as exc:  # typed.Invalid: "key: message" of the first problem
            if source == "--drives":
                raise usage_error(f"{source}: {exc}") from None
            raise _bad_file(f"{source}: {exc}") from None

    if not drives:
        return [(kind, finish(base, config_file or "config"))]
    line = cls.ports[0]  # where the kind's address comes from: its port's declaration (PortDef.address)
    if line.address is None:
        raise usage_error(f"--drives: {kind} has no address on its port {line.name!r}: one device per line")
    names = [kind] if len(drives) == 1 else [f"{kind}{n}" for n in drives]
    return [(name, finish(line.addressed(base, n), "--drives")) for name, n in zip(names, drives, strict=True)]




def plan_run(
    kind: str,
    use_pty: bool = False,
    link: str | None = None,
    tcp: str | None = None,
    rfc2217: str | None = None,
    config_file: str | None = None,
    state_dir: str | None = None,
    speed: float = 1.0,
    virtual: bool = False,
    trace: str | None = None,
    control: str | None = None,
    no_control: bool = False,
    control_allow_remote: bool = False,
    drives: str | None = None,
    pacing: bool = False,
    idle_drop: float | None = None,
    port_options: Sequence[str] = (),
    modbus: str | None = None,
    canopen: str | None = None,
    opcua: str | None = None,
    opcua_period: float = 0.1,
    modbus_map: str = "points",
    mqtt: str | None = None,
    mqtt_convention: str = "devsim",
    mqtt_rate: float = 1.0,
    mqtt_plant: str | None = None,
    mqtt_primary_host: str | None = None,
    fleet: str | None = None,
    web: str | None = None,
    motion_log: str | None = None,
    motion_resolution: float = 0.01,
    verbose: int = 0,
    quiet: int = 0,
) -> Plan:
    """The plan of ``devsim run`` from its options (the parameters of the click command, by the
    same names and with the same defaults); a mistake raises the click error that says it."""
    try:
        cls = device_class(kind)
    except UnknownKind as exc:
        raise usage_error(str(exc)) from None
    except Exception as exc:
        raise system_failure(f"cannot load device kind {kind!r}: {type(exc).__name__}: {exc}") from None

    chosen = [name for name, given in (("--pty/--link", use_pty or link), ("--tcp", tcp), ("--rfc2217", rfc2217)) if given]
    if len(chosen) > 1:
        raise usage_error(f"choose one port: {' or '.join(chosen)}")
    if tcp is not None:
        port = Port("tcp", *host_port("--tcp", tcp))
    elif rfc2217 is not None:
        port = Port("rfc2217", *host_port("--rfc2217", rfc2217))
    else:
        port = Port("pty", link=link)
    overrides: dict[str, Port] = {}
    for text in port_options:
        name, spec = _parse_port_option(text, [p.name for p in cls.ports])
        if name in overrides:
            raise usage_error(f"--port: port {name!r} given twice")
        overrides[name] = spec
    if any(option is not None for option in (modbus, canopen, mqtt, opcua, fleet)):
        from devsim.cli.options import check_canopen, check_fleet, check_modbus, check_mqtt, check_opcua

        if modbus is not None:
            check_modbus(modbus)
        if canopen is not None:
            check_canopen(canopen)
        if mqtt is not None:
            check_mqtt(mqtt, mqtt_convention, mqtt_rate, mqtt_plant, mqtt_primary_host)
        if opcua is not None:
            check_opcua(opcua, opcua_period)
        if fleet is not None:
            check_fleet(fleet)
    if motion_log is not None:
        from devsim.observe.motion_log import motion_log_problem

        if (problem := motion_log_problem(motion_resolution)) is not None:
            raise usage_error(problem)
    from devsim.core.clock import speed_problem

    if (problem := speed_problem(speed)) is not None:
        raise usage_error(f"--speed: {problem}")
    if virtual and speed != 1.0:
        raise usage_error("--speed and --virtual exclude each other")
    if state_dir is not None:
        from devsim.cli.usage import check_dirs

        check_dirs({"--state-dir": state_dir})
    if idle_drop is not None:
        from devsim.transports.hosts import idle_drop_problem

        if (problem := idle_drop_problem(idle_drop)) is not None:
            raise usage_error(f"--idle-drop: {problem}")

    from devsim.observe.live_log import level_of

    web_listen = None
    if web is not None:
        from devsim.cli.web import web_option

        if no_control:
            raise usage_error("--web shows the plant through its control API: not with --no-control")
        web_listen = web_option(web)
    configs = _device_configs(cls, kind, config_file, _parse_drives(drives) if drives is not None else None)
    control_addr = control_option(control, no_control, kind, allow_remote=control_allow_remote)
    return Plan(
        kind=kind,
        devices=configs,
        port=port,
        state_dir=state_dir,
        speed=speed,
        virtual=virtual,
        trace=trace,
        pacing=pacing,
        control=control_addr,
        allow_remote=control_allow_remote,
        overrides=overrides,
        modbus=modbus,
        modbus_map=modbus_map,
        idle_drop=idle_drop,
        canopen=canopen,
        mqtt=mqtt,
        mqtt_convention=mqtt_convention,
        mqtt_rate=mqtt_rate,
        mqtt_plant=mqtt_plant,
        mqtt_primary_host=mqtt_primary_host,
        opcua=opcua,
        opcua_period=opcua_period,
        fleet=fleet,
        motion_log=motion_log,
        motion_resolution=motion_resolution,
        log_level=level_of(verbose, quiet),
        web=web_listen,
    )


def serve(plan: Plan) -> None:
    """Serve ``plan`` until Ctrl-C, SIGTERM or SIGHUP; a server that could not start raises
    :class:`~devsim.cli.statuses.StartFailure` (its one line and status)."""
    try:
        asyncio.run(_serve(plan))
    except KeyboardInterrupt:  # Ctrl-C before the handlers were in place
        sys.exit(INTERRUPTED)


def _make_transport(port: Port) -> Any:
    if port.scheme == "udp":
        from devsim.transports.udp import UdpTransport

        return UdpTransport(host=port.host, port=port.port)
    if port.scheme == "tcp":
        from devsim.transports.tcp import TcpTransport

        return TcpTransport(host=port.host, port=port.port)
    if port.scheme == "rfc2217":
        from devsim.transports.rfc2217 import Rfc2217Transport

        return Rfc2217Transport(host=port.host, port=port.port)
    from devsim.transports.pty import PtyTransport

    return PtyTransport(link=port.link)


async def _serve(plan: Plan) -> None:
    from devsim.runtime import Runtime, port_key

    if plan.control is not None:
        from devsim.runtime.control import ControlServer

    loop = asyncio.get_running_loop()
    stop = asyncio.Event()
    unsignal = stop_on_signals(loop, stop.set)

    runtime = Runtime(virtual=plan.virtual, speed=plan.speed, state_dir=plan.state_dir, name=plan.kind)
    runtime.idle_drop = plan.idle_drop
    async with runtime:
        stage = "create the devices"
        server: Any = None
        page: Any = None
        web_lines: list[str] = []
        make_dirs({"--state-dir": plan.state_dir})  # (/proc/sd: 'cannot create the devices: [Errno 2] ...')
        try:
            devices = [runtime.add_device(plan.kind, name, config) for name, config in plan.devices]
            if plan.motion_log is not None:
                stage = f"write the motion log {plan.motion_log}"
                from devsim.observe.motion_log import start_motion_log

                start_motion_log(runtime, devices, plan.motion_log, plan.motion_resolution)
            served: list[tuple[str, Any, Port]] = []  # port name, transport, spec
            plan_ports = _plan_ports(plan, devices[0].ports)
            for index, (port_name, spec) in enumerate(plan_ports):
                trace = _trace_for(plan.trace, port_name, index)
                stage = f"open the {spec.scheme} port" + (f" with its trace {trace}" if trace else "")
                transport = _make_transport(spec)
                await runtime.serve(devices, transport, port=port_name, pacing=plan.pacing, trace=trace)
                served.append((port_name, transport, spec))
            modbus_served: list[tuple[str, str]] = []
            if plan.modbus is not None:
                stage = f"serve Modbus ({plan.modbus})"
                from devsim.cli.options import modbus_for
                from devsim.facades.modbus import start_modbus

                for index, device in enumerate(devices):
                    spec = modbus_for(plan.modbus, index)
                    modbus_name = "modbus" if len(devices) == 1 else f"{device.name}.modbus"  # its trace: FILE-modbus
                    where, _transport = await start_modbus(runtime, device, spec, layout=plan.modbus_map,
                                                           trace=_trace_for(plan.trace, modbus_name,
                                                                            len(plan_ports) + index))
                    modbus_served.append((device.name, where))
            canopen_lines: list[str] = []
            if plan.canopen is not None:
                stage = f"serve CANopen ({plan.canopen})"
                from devsim.facades.canopen_node import start_canopen

                canopen_lines = await start_canopen(runtime, devices, plan.canopen)
            mqtt_lines: list[str] = []
            if plan.mqtt is not None:
                stage = f"serve MQTT ({plan.mqtt or 'embedded broker'})"
                from devsim.facades.mqtt import start_mqtt

                mqtt_lines = await start_mqtt(runtime, devices, plan.mqtt or None, plant=plan.mqtt_plant or plan.kind,
                                              convention=plan.mqtt_convention,  # type: ignore[arg-type]
                                              rate=plan.mqtt_rate, primary_host=plan.mqtt_primary_host)
            opcua_url: str | None = None
            if plan.opcua is not None:
                stage = "serve OPC UA"
                from devsim.facades.opcua import start_opcua

                opcua_url = (await start_opcua(runtime, devices, plan.opcua, period=plan.opcua_period)).url
            if plan.control is not None:
                stage = f"serve the control API on {plan.control}"
                server = ControlServer(runtime, plan.control, allow_remote=plan.allow_remote)
                address = await server.start()
            fleet_line = None
            if plan.fleet is not None:
                stage = f"join the fleet {plan.fleet}"
                from devsim.fleet.member import join_fleet

                member = await join_fleet(runtime, plan.fleet, about={"command": f"devsim run {plan.kind}"})
                fleet_line = f"fleet: {member.url} as {member.process}"
            if plan.web is not None:
                stage = f"serve the web page on {plan.web}"
                from devsim.cli.web import start_web

                page, web_lines = await asyncio.to_thread(start_web, str(address), plan.web)
        except Exception as exc:  # one line, no traceback: a port in use, a bad path, ...
            if server is not None:
                await server.close()
            from devsim.transports.trace import TraceFileError

            if isinstance(exc, TraceFileError):  # (the file of --motion-log, or of a --trace)
                motion_log = plan.motion_log is not None and exc.filename == str(plan.motion_log)
                raise file_failure("--motion-log" if motion_log else "--trace", exc) from None
            from devsim.core.nvram import UNUSABLE  # (a state file the device cannot start on: its own words)

            expected = isinstance(exc, (OSError, ValueError, *UNUSABLE))
            detail = str(exc) if expected else f"{type(exc).__name__}: {exc}"
            raise StartFailure(f"cannot {stage}: {detail}", start_status(exc)) from None

        logs: list[Any] = []
        try:
            for device in devices:
                for port_name, transport, spec in served:
                    key = port_key(device.name, port_name)
                    _say(f"{key}: {spec.scheme} {_port_text(transport, spec.scheme)}")
                    if spec.link:
                        _say(f"{key}: link {spec.link}")
            for text in canopen_lines:
                _say(text)
            for text in mqtt_lines:
                _say(text)
            for name, where in modbus_served:
                _say(f"{name}.modbus: {'tcp' if plan.modbus and plan.modbus.startswith('tcp') else 'rtu'} {where}")
            if opcua_url is not None:
                _say(f"opcua: {opcua_url}")
            if server is not None:
                _say(f"control: {address}")
            if fleet_line is not None:
                _say(fleet_line)
            for text in web_lines:
                _say(text)
            for device in devices:  # NAME: ready, each time it has booted and listens
                device.on_ready(lambda name=device.name: _say(f"{name}: ready"))
            from devsim.observe.live_log import DEFAULT_LEVEL, attach_log, banner

            logs = attach_log(runtime, plan.log_level)
            if plan.log_level >= DEFAULT_LEVEL:  # (-q: warnings and errors only)
                warn(banner(runtime, devices))
            # What exists now (modules, tables, devices) lives as long as the process: keep it
            # out of the garbage collector's scans, so that a request's few objects are cheap.
            gc.freeze()
            gc.enable()  # (the quick command line keeps it off while it starts: see devsim.cli.quick)
            await stop.wait()
        finally:
            for log in logs:  # the repeat counts not yet written are written now
                log.stop()
            if page is not None:
                await asyncio.to_thread(page.stop)
            if server is not None:
                await server.close()
    unsignal()


def _plan_ports(plan: Plan, ports: Sequence[Any]) -> list[tuple[str, Port]]:
    """The transport of every port of the kind (``ports``: its :class:`PortDef` rows): the
    ``--port`` override, else the port's declared default on loopback, else the shared choice
    (``--pty``/``--link``/``--tcp``/``--rfc2217``) spread over those ports by :func:`_port_for`."""
    shared = [p.name for p in ports if p.name not in plan.overrides and p.default is None]
    chosen: list[tuple[str, Port]] = []
    for spec in ports:
        if spec.name in plan.overrides:
            chosen.append((spec.name, plan.overrides[spec.name]))
        elif spec.default is not None:
            scheme, number = spec.default_transport
            chosen.append((spec.name, Port(scheme, "127.0.0.1", number)))
        else:
            chosen.append((spec.name, _port_for(plan.port, spec.name, shared.index(spec.name), len(shared))))
    return chosen


def _port_for(port: Port, name: str, index: int, count: int) -> Port:
    """The transport of one port of a kind with ``count`` ports: a pty each (``--link PATH``
    becomes ``PATH-NAME`` beyond the first port), consecutive TCP port numbers from the given one."""
    if count == 1 or index == 0:
        return port
    link = f"{port.link}-{name}" if port.link else None
    number = port.port + index if port.port else 0
    return Port(port.scheme, port.host, number, link)


def _trace_for(trace: str | None, name: str, index: int) -> str | None:
    """``--trace FILE`` for the first port, ``FILE-NAME`` beside it for the others
    (``STEM-NAME.pcap`` for ``STEM.pcap``, so that the others are pcap files too)."""
    if trace is None or index == 0:
        return trace
    stem, dot, suffix = trace.rpartition(".")
    if dot and suffix.lower() == "pcap" and "/" not in suffix:
        return f"{stem}-{name}.{suffix}"
    return f"{trace}-{name}"


def _port_text(transport: Any, scheme: str) -> str:
    """The pty's device path (its link gets a line of its own), or the pyserial URL of a port."""
    address = str(getattr(transport, "address", "") or "")
    url = str(getattr(transport, "url", "") or "")
    if scheme == "pty":
        return address or url
    return url or address


#: Commands whose module is imported only when one of them runs (``devsim run`` starts faster):
