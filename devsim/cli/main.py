"""The ``devsim`` command line.

* ``devsim list`` – the device kinds, one per line.
* ``devsim run KIND [--pty | --link PATH | --tcp [HOST:]PORT | --rfc2217 [HOST:]PORT] ...`` – serve
  one device (or several on one RS-485 line with ``--drives``, alias ``--addresses``) until Ctrl-C / SIGTERM.  Every
  port and the control address are printed on stdout, one per line, for scripts to parse::

      sers: pty /dev/pts/5
      control: unix:/run/user/1000/devsim/sers-4242.sock

  The control API is served on ``NAME-PID.sock`` in the user's runtime directory
  (:mod:`devsim.runtime.discovery`) unless ``--control ADDR`` names another address or
  ``--no-control`` none.

  A port whose kind declares a default network transport (``PortDef.default``, e.g.
  ``"udp:5050"``) is served there on loopback; ``--port NAME=SPEC`` (repeatable) puts one port on
  ``pty``, ``udp:[HOST:]PORT``, ``tcp:[HOST:]PORT`` or ``rfc2217:[HOST:]PORT`` instead, and
  ``--pty``/``--link``/``--tcp``/``--rfc2217`` choose for the other ports.

* ``devsim ps`` – the running simulators (:mod:`devsim.cli.running`).
* ``devsim ctl [--control ADDR|NAME] devices|read|set|state|power-cycle|advance|now|line|...`` – talk to a
  running simulator's control API and print the result (``--json``: as JSON); ``devsim ctl
  --fleet mqtt://BROKER ...`` the same with every device of a fleet (``devsim run/up --fleet``,
  :mod:`devsim.fleet`).
* ``devsim web [--control ADDR|NAME] [--listen [HOST:]PORT]`` – the plant in a browser
  (:mod:`devsim.cli.web`, :mod:`devsim.web`); ``devsim run ... --web [HOST:]PORT`` serves the page
  from the simulator's own process and prints ``web: http://HOST:PORT/``.

Every error is one line on stderr (``Error: config.yaml:3: baud: ...``); the exit status says
which kind of mistake it was, the same in every command (:mod:`devsim.cli.exits`: 2 a usage
error, 3 a bad file, 6 a port in use ...).
"""

from __future__ import annotations

import asyncio
import gc
import signal
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any, NoReturn

import click
import msgspec

from devsim import __version__
from devsim.cli import exits
from devsim.cli.options import (
    check_canopen,
    check_fleet,
    check_modbus,
    check_mqtt,
    check_opcua,
    host_port,
    modbus_for,
)
from devsim.core.registry import UnknownKind, device_class, kinds
from devsim.observe.live_log import DEFAULT_LEVEL, attach_log, banner, level_of, log_options

if TYPE_CHECKING:  # imported where used: `devsim run` starts faster without them
    from devsim.core.device import Device
    from devsim.runtime.control import ControlAddress

__all__ = ["cli", "main"]


# -- one-line errors -------------------------------------------------------------------------
class _Cli(click.Group):
    """A group that reports every usage error as a single line (no usage block, no traceback),
    and imports the modules of the ``LAZY_COMMANDS`` only when one of them runs."""

    def list_commands(self, ctx: click.Context) -> list[str]:
        return sorted([*super().list_commands(ctx), *LAZY_COMMANDS])

    def get_command(self, ctx: click.Context, cmd_name: str) -> click.Command | None:
        if cmd_name in LAZY_COMMANDS:
            return _lazy_command(cmd_name)
        return super().get_command(ctx, cmd_name)

    def main(  # type: ignore[override]
        self,
        args: Sequence[str] | None = None,
        prog_name: str | None = None,
        complete_var: str | None = None,
        standalone_mode: bool = True,
        **extra: Any,
    ) -> Any:
        if not standalone_mode:
            return super().main(args, prog_name, complete_var, standalone_mode=False, **extra)
        try:
            rv = super().main(args, prog_name, complete_var, standalone_mode=False, **extra)
        except click.UsageError as exc:
            hint = ""
            if exc.ctx is not None:
                hint = f" (see '{exc.ctx.command_path} --help')"
            _fail(f"{exc.format_message()}{hint}", exc.exit_code)
        except click.ClickException as exc:
            _fail(exc.format_message(), exc.exit_code)
        except click.Abort:
            _fail("aborted", exits.INTERRUPTED)
        except BrokenPipeError:
            sys.exit(exits.SYSTEM)
        sys.exit(rv if isinstance(rv, int) else 0)


def _fail(message: str, code: int) -> NoReturn:
    click.echo(f"Error: {message}", err=True)
    sys.exit(code)


@click.group(cls=_Cli, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(__version__, prog_name="devsim")
def cli() -> None:
    """Software twins of legacy motion controllers on virtual serial ports."""


def main() -> None:
    """Entry point of the ``devsim`` command."""
    cli.main(prog_name="devsim")


# -- devsim list -----------------------------------------------------------------------------
@cli.command("list")
def list_kinds() -> None:
    """List the device kinds, one per line: kind and description."""
    for kind, target in kinds().items():
        try:
            description = device_class(kind).description or "-"
        except Exception as exc:  # a broken plug-in must not hide the others
            description = f"(cannot load {target}: {type(exc).__name__}: {exc})"
        click.echo(f"{kind:<12} {description}")


# -- devsim doc ------------------------------------------------------------------------------
@cli.command("doc")
@click.argument("kind")
@click.option("--modbus", "modbus_map", is_flag=True, help="Print the Modbus register map instead.")
@click.option("--eds", "eds_file", is_flag=True, help="Print the CANopen EDS (object dictionary) instead.")
def doc(kind: str, modbus_map: bool, eds_file: bool) -> None:
    """Print KIND's reference in Markdown: ports, control names, faults, commands, parameters,
    error codes and configuration keys, from the tables that drive the simulator (with --modbus:
    the register map its points give)."""
    from devsim.cli.docgen import modbus_markdown, reference_markdown

    try:
        cls = device_class(kind)
    except UnknownKind as exc:
        raise click.UsageError(str(exc)) from None
    if eds_file:
        from devsim.facades.canopen_od import eds

        click.echo(eds(cls.kind, cls.description, cls.points, drive=cls.drive is not None))
        return
    click.echo(modbus_markdown(cls) if modbus_map else reference_markdown(cls))


# -- devsim run ------------------------------------------------------------------------------
class _Port(msgspec.Struct):
    scheme: str  # "pty", "tcp", "rfc2217" or "udp"
    host: str = "127.0.0.1"
    port: int = 0
    link: str | None = None


class _Plan(msgspec.Struct):
    kind: str
    devices: list[tuple[str, dict[str, Any]]]
    port: _Port  # for the ports without a default or an override
    state_dir: str | None
    speed: float
    virtual: bool
    trace: str | None
    pacing: bool
    control: ControlAddress | None
    allow_remote: bool
    printed: list[str] = msgspec.field(default_factory=list)
    overrides: dict[str, _Port] = msgspec.field(default_factory=dict)  # --port NAME=SPEC
    modbus: str | None = None  # --modbus tcp:[HOST:]PORT | rtu | rtu:LINK
    modbus_map: str = "points"  # --modbus-map points | mirror
    idle_drop: float | None = None  # --idle-drop SECONDS
    canopen: str | None = None  # --canopen NODE[@[HOST:]PORT]
    mqtt: str | None = None  # --mqtt [URL]: "" for the embedded broker
    mqtt_convention: str = "devsim"  # --mqtt-convention devsim | sparkplug
    mqtt_rate: float = 1.0  # --mqtt-rate SECONDS
    mqtt_plant: str | None = None  # --mqtt-plant NAME (default: the kind)
    opcua: str | None = None  # --opcua [[HOST:]PORT] ("": the default endpoint)
    opcua_period: float = 0.1  # --opcua-period SECONDS
    fleet: str | None = None  # --fleet mqtt://BROKER[:PORT][/NAME]
    motion_log: str | None = None  # --motion-log FILE.csv
    motion_resolution: float = 0.01  # --motion-resolution SECONDS
    log_level: int = 2  # -v/-q (devsim.observe.live_log)
    web: Any = None  # --web: where to serve the page (devsim.web.server.ListenAddress)


#: What ``--port NAME=SPEC`` accepts after ``NAME=``.
PORT_SCHEMES = ("pty", "udp", "tcp", "rfc2217")


def _parse_port_option(text: str, names: Sequence[str]) -> tuple[str, _Port]:
    """``--port NAME=pty|udp:[HOST:]PORT|tcp:[HOST:]PORT|rfc2217:[HOST:]PORT`` → (NAME, port)."""
    name, sep, spec = text.partition("=")
    if not sep or not name:
        raise click.UsageError(f"--port: expected NAME=SPEC (e.g. ether=udp:5050), got {text!r}")
    if name not in names:
        raise click.UsageError(f"--port: the kind has no port {name!r} (ports: {', '.join(names)})")
    scheme, _, rest = spec.partition(":")
    if scheme not in PORT_SCHEMES:
        raise click.UsageError(
            f"--port {name}: expected pty, udp:[HOST:]PORT, tcp:[HOST:]PORT or rfc2217:[HOST:]PORT, got {spec!r}"
        )
    if scheme == "pty":
        if rest:
            raise click.UsageError(f"--port {name}: pty takes no address, got {spec!r}")
        return name, _Port("pty")
    return name, _Port(scheme, *host_port(f"--port {name}", rest))


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
            raise click.UsageError(f"--drives: expected addresses like 1,2,3 (or 1-3), got {item!r}") from None
        for number in numbers:
            if number in drives:
                raise click.UsageError(f"--drives: address {number} given twice")
            drives.append(number)
    if not drives:
        raise click.UsageError("--drives: expected at least one address, e.g. --drives 1,2,3")
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
            raise exits.BadFile(str(exc)) from None
        base = plain(data) if isinstance(data, dict) else {}

    def finish(raw: dict[str, Any], source: str) -> dict[str, Any]:
        if model is None:
            return raw
        try:
            return model.parse(raw).dump()
        except ValueError as exc:  # typed.Invalid: "key: message" of the first problem
            if source == "--drives":
                raise click.UsageError(f"{source}: {exc}") from None
            raise exits.BadFile(f"{source}: {exc}") from None

    if not drives:
        return [(kind, finish(base, config_file or "config"))]
    names = [kind] if len(drives) == 1 else [f"{kind}{n}" for n in drives]
    def addressed(n: int) -> dict[str, Any]:
        # the address is a DIL-switch setting on cards that have one (GMS96: dil.address)
        keys = model.__struct_encode_fields__ if model is not None else ()
        if "address" not in keys and "dil" in keys:
            return {**base, "dil": {**(base.get("dil") or {}), "address": n}}
        return {**base, "address": n}

    return [(name, finish(addressed(n), "--drives")) for name, n in zip(names, drives, strict=True)]


@cli.command()
@click.argument("kind")
@click.option("--pty", "use_pty", is_flag=True, help="Serve on a new pseudo-terminal (the default).")
@click.option("--link", metavar="PATH", help="Stable symlink to the pty, e.g. /tmp/ttySERS (implies --pty).")
@click.option("--tcp", metavar="[HOST:]PORT", help="Raw TCP port, like a serial device server (host 127.0.0.1).")
@click.option("--rfc2217", metavar="[HOST:]PORT", help="RFC 2217 port: line settings travel with the data.")
@click.option("--config", "config_file", metavar="FILE.yaml", help="DIP switches, parameters, axis geometry.")
@click.option("--state-dir", metavar="DIR", help="Where non-volatile memory (EEPROM) is kept.")
@click.option("--speed", type=float, default=1.0, show_default=True, metavar="F", help="Time speed factor.")
@click.option("--virtual", is_flag=True, help="Virtual time: it moves only through 'devsim ctl advance'.")
@click.option(
    "--trace", metavar="FILE", help="Write a timestamped trace of the line traffic (FILE.pcap: a pcap file for Wireshark; "
    "other ports and a Modbus RTU line beside it as FILE-PORT, FILE-modbus)."
)
@click.option("--control", metavar="ADDR", help="Serve the control API on unix:/path.sock or [HOST:]PORT (default:"
              " NAME-PID.sock in the runtime directory, see 'devsim ps').")
@click.option("--no-control", is_flag=True, help="Serve no control API.")
@click.option("--control-allow-remote", is_flag=True, help="Allow a non-loopback --control host.")
@click.option(
    "--drives",
    "--addresses",
    "drives",
    metavar="1,2,3",
    help="RS-485 multidrop: one device per address on one line (--addresses is the same option).",
)
@click.option("--pacing", is_flag=True, help="Pace output at the configured baud rate.")
@click.option("--idle-drop", type=click.FloatRange(min=0), default=None, metavar="SECONDS",
              help="Drop a TCP host idle this long when another client finds its port full (default 30).")
@click.option(
    "--port",
    "port_options",
    multiple=True,
    metavar="NAME=SPEC",
    help="Serve port NAME on SPEC: pty, udp:[HOST:]PORT, tcp:[HOST:]PORT or rfc2217:[HOST:]PORT (repeatable).",
)
@click.option(
    "--modbus",
    metavar="SPEC",
    help="Also serve the device over Modbus (extra [modbus]): tcp:[HOST:]PORT, rtu (a pty) or rtu:LINK.",
)
@click.option(
    "--canopen",
    metavar="NODE[@[HOST:]PORT]",
    help="Also serve the device as CANopen node NODE (extra [can]) on a socketcand server (default port 29536).",
)
@click.option(
    "--opcua",
    metavar="[[HOST:]PORT]",
    is_flag=False,
    flag_value="",
    default=None,
    help="Also serve the devices on an OPC UA server (extra [opcua]), default opc.tcp://127.0.0.1:4840/devsim/.",
)
@click.option("--opcua-period", type=float, default=0.1, show_default=True, metavar="SECONDS",
              help="How often the OPC UA server samples the points for subscriptions (device time).")
@click.option(
    "--modbus-map",
    type=click.Choice(["points", "mirror"]),
    default="points",
    show_default=True,
    help="The Modbus map: generated from the points, or the kind's own mirror (pcd4h3: its media).",
)
@click.option(
    "--mqtt",
    metavar="[URL]",
    is_flag=False,
    flag_value="",
    default=None,
    help="Also publish the devices over MQTT (extra [mqtt]) on the broker mqtt://HOST[:PORT]; with no URL on an"
    " embedded broker on loopback (port 1883 if free).",
)
@click.option(
    "--mqtt-convention",
    type=click.Choice(["devsim", "sparkplug"]),
    default="devsim",
    show_default=True,
    help="MQTT topics: devsim/PLANT/DEVICE/... (JSON), or Sparkplug B.",
)
@click.option("--mqtt-rate", type=float, default=1.0, show_default=True, metavar="SECONDS",
              help="How often (device time) the MQTT facade samples the points for changes.")
@click.option("--mqtt-plant", metavar="NAME", help="The plant's name in MQTT topics (default: the kind).")
@click.option(
    "--fleet",
    metavar="mqtt://BROKER[:PORT][/NAME]",
    help="Join a fleet (extra [fleet]): announce the devices on the broker, take control requests from it.",
)
@click.option("--web", metavar="[HOST:]PORT", help="Also serve the plant's web page there (extra [web]; host"
              " 127.0.0.1 unless named, another host gets a token).")
@click.option("--motion-log", metavar="FILE.csv", help="Write every axis's motion (set-point, position, velocity,"
              " following error, events) as CSV, for 'devsim plot'.")
@click.option("--motion-resolution", type=float, default=0.01, show_default=True, metavar="SECONDS",
              help="How often (device time) the motion log samples the axes, besides every event.")
@log_options
def run(
    kind: str,
    use_pty: bool,
    link: str | None,
    tcp: str | None,
    rfc2217: str | None,
    config_file: str | None,
    state_dir: str | None,
    speed: float,
    virtual: bool,
    trace: str | None,
    control: str | None,
    no_control: bool,
    control_allow_remote: bool,
    drives: str | None,
    pacing: bool,
    idle_drop: float | None,
    port_options: tuple[str, ...],
    modbus: str | None,
    canopen: str | None,
    opcua: str | None,
    opcua_period: float,
    modbus_map: str,
    mqtt: str | None,
    mqtt_convention: str,
    mqtt_rate: float,
    mqtt_plant: str | None,
    fleet: str | None,
    web: str | None,
    motion_log: str | None,
    motion_resolution: float,
    verbose: int,
    quiet: int,
) -> None:
    """Serve a simulated KIND device until Ctrl-C.

    Prints one line per device port (NAME: pty|tcp|rfc2217|udp ADDRESS) and the control address.
    A port the kind declares on the network (e.g. Ether-S-Bus on udp:5050) is served there on
    loopback unless --port NAME=SPEC says otherwise; the other ports follow --pty/--tcp/--rfc2217.
    A trace named FILE.pcap is written as pcap (Wireshark, tshark).  Host connects, disconnects,
    line mismatches and device errors are logged to stderr (-v: more, -q: less).
    """
    try:
        cls = device_class(kind)
    except UnknownKind as exc:
        raise click.UsageError(str(exc)) from None
    except Exception as exc:
        raise exits.SystemFailure(f"cannot load device kind {kind!r}: {type(exc).__name__}: {exc}") from None

    chosen = [name for name, given in (("--pty/--link", use_pty or link), ("--tcp", tcp), ("--rfc2217", rfc2217)) if given]
    if len(chosen) > 1:
        raise click.UsageError(f"choose one port: {' or '.join(chosen)}")
    if tcp is not None:
        port = _Port("tcp", *host_port("--tcp", tcp))
    elif rfc2217 is not None:
        port = _Port("rfc2217", *host_port("--rfc2217", rfc2217))
    else:
        port = _Port("pty", link=link)
    overrides: dict[str, _Port] = {}
    for text in port_options:
        name, spec = _parse_port_option(text, [p.name for p in cls.ports])
        if name in overrides:
            raise click.UsageError(f"--port: port {name!r} given twice")
        overrides[name] = spec
    if modbus is not None:
        check_modbus(modbus)
    if canopen is not None:
        check_canopen(canopen)
    if mqtt is not None:
        check_mqtt(mqtt, mqtt_convention, mqtt_rate, mqtt_plant)
    if opcua is not None:
        check_opcua(opcua, opcua_period)
    if fleet is not None:
        check_fleet(fleet)
    if motion_log is not None:
        from devsim.observe.motion_log import motion_log_problem

        if (problem := motion_log_problem(motion_resolution)) is not None:
            raise click.UsageError(problem)
    if speed <= 0:
        raise click.UsageError("--speed: must be positive")
    if virtual and speed != 1.0:
        raise click.UsageError("--speed and --virtual exclude each other")

    from devsim.cli.running import control_option

    web_listen = None
    if web is not None:
        from devsim.cli.web import web_option

        if no_control:
            raise click.UsageError("--web shows the plant through its control API: not with --no-control")
        web_listen = web_option(web)
    configs = _device_configs(cls, kind, config_file, _parse_drives(drives) if drives is not None else None)
    control_addr = control_option(control, no_control, kind, allow_remote=control_allow_remote)
    plan = _Plan(
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
        opcua=opcua,
        opcua_period=opcua_period,
        fleet=fleet,
        motion_log=motion_log,
        motion_resolution=motion_resolution,
        log_level=level_of(verbose, quiet),
        web=web_listen,
    )
    try:
        asyncio.run(_serve(plan))
    except KeyboardInterrupt:  # Ctrl-C before the handlers were in place
        sys.exit(exits.INTERRUPTED)
    except exits.StartFailure as exc:
        raise exits.failure(exc.status, str(exc)) from None


def _make_transport(port: _Port) -> Any:
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


def _say(line: str) -> None:
    print(line, flush=True)


async def _serve(plan: _Plan) -> None:
    from devsim.runtime import Runtime, port_key

    if plan.control is not None:
        from devsim.runtime.control import ControlServer

    loop = asyncio.get_running_loop()
    stop = asyncio.Event()
    for signum in (signal.SIGINT, signal.SIGTERM):
        loop.add_signal_handler(signum, stop.set)

    runtime = Runtime(virtual=plan.virtual, speed=plan.speed, state_dir=plan.state_dir, name=plan.kind)
    runtime.idle_drop = plan.idle_drop
    async with runtime:
        stage = "create the devices"
        server: Any = None
        page: Any = None
        web_lines: list[str] = []
        try:
            if plan.state_dir is not None:
                Path(plan.state_dir).mkdir(parents=True, exist_ok=True)
            devices = [runtime.add_device(plan.kind, name, config) for name, config in plan.devices]
            if plan.motion_log is not None:
                stage = f"write the motion log {plan.motion_log}"
                from devsim.observe.motion_log import start_motion_log

                start_motion_log(runtime, devices, plan.motion_log, plan.motion_resolution)
            served: list[tuple[str, Any, _Port]] = []  # port name, transport, spec
            plan_ports = _plan_ports(plan, devices[0].ports)
            for index, (port_name, spec) in enumerate(plan_ports):
                stage = f"open the {spec.scheme} port"
                transport = _make_transport(spec)
                trace = _trace_for(plan.trace, port_name, index)
                await runtime.serve(devices, transport, port=port_name, pacing=plan.pacing, trace=trace)
                served.append((port_name, transport, spec))
            modbus_served: list[tuple[str, str]] = []
            if plan.modbus is not None:
                stage = f"serve Modbus ({plan.modbus})"
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
                                              rate=plan.mqtt_rate)
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
            detail = str(exc) if isinstance(exc, OSError | ValueError) else f"{type(exc).__name__}: {exc}"
            raise exits.StartFailure(f"cannot {stage}: {detail}", exits.start_status(exc)) from None

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
            logs = attach_log(runtime, plan.log_level)
            if plan.log_level >= DEFAULT_LEVEL:  # (-q: warnings and errors only)
                print(banner(runtime, devices), file=sys.stderr, flush=True)
            # What exists now (modules, tables, devices) lives as long as the process: keep it
            # out of the garbage collector's scans, so that a request's few objects are cheap.
            gc.freeze()
            await stop.wait()
        finally:
            for log in logs:  # the repeat counts not yet written are written now
                log.stop()
            if page is not None:
                await asyncio.to_thread(page.stop)
            if server is not None:
                await server.close()
    for signum in (signal.SIGINT, signal.SIGTERM):
        loop.remove_signal_handler(signum)


def _plan_ports(plan: _Plan, ports: Sequence[Any]) -> list[tuple[str, _Port]]:
    """The transport of every port of the kind (``ports``: its :class:`PortDef` rows): the
    ``--port`` override, else the port's declared default on loopback, else the shared choice
    (``--pty``/``--link``/``--tcp``/``--rfc2217``) spread over those ports by :func:`_port_for`."""
    shared = [p.name for p in ports if p.name not in plan.overrides and p.default is None]
    chosen: list[tuple[str, _Port]] = []
    for spec in ports:
        if spec.name in plan.overrides:
            chosen.append((spec.name, plan.overrides[spec.name]))
        elif spec.default is not None:
            scheme, number = spec.default_transport
            chosen.append((spec.name, _Port(scheme, "127.0.0.1", number)))
        else:
            chosen.append((spec.name, _port_for(plan.port, spec.name, shared.index(spec.name), len(shared))))
    return chosen


def _port_for(port: _Port, name: str, index: int, count: int) -> _Port:
    """The transport of one port of a kind with ``count`` ports: a pty each (``--link PATH``
    becomes ``PATH-NAME`` beyond the first port), consecutive TCP port numbers from the given one."""
    if count == 1 or index == 0:
        return port
    link = f"{port.link}-{name}" if port.link else None
    number = port.port + index if port.port else 0
    return _Port(port.scheme, port.host, number, link)


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
#: command name → the module that defines it as a click command of the same name.
LAZY_COMMANDS: dict[str, str] = {
    "check": "devsim.cli.scenario",
    "ctl": "devsim.cli.ctl",
    "extcap": "devsim.cli.wireshark",
    "monitor": "devsim.cli.monitor",
    "plot": "devsim.cli.plot",
    "ps": "devsim.cli.running",
    "record": "devsim.cli.replay",
    "replay": "devsim.cli.replay",
    "scenario": "devsim.cli.scenario",
    "up": "devsim.cli.scenario",
    "wireshark": "devsim.cli.wireshark",
    "web": "devsim.cli.web",
}


def _lazy_command(name: str) -> click.Command:
    import importlib

    command: click.Command = getattr(importlib.import_module(LAZY_COMMANDS[name]), name)
    return command
