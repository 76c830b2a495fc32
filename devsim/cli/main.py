"""The ``devsim`` command line.

* ``devsim list`` – the device kinds, one per line.
* ``devsim run KIND [--pty | --link PATH | --tcp [HOST:]PORT | --rfc2217 [HOST:]PORT] ...`` – serve
  one device (or several on one RS-485 line with ``--drives``, alias ``--addresses``) until Ctrl-C / SIGTERM / SIGHUP.  Every
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

import sys
from collections.abc import Sequence
from typing import Any, NoReturn

import click

from devsim import __version__
from devsim.cli import exits
from devsim.cli.options import FLOAT, AsciiFloatRange
from devsim.cli.serve import plan_run, serve
from devsim.cli.statuses import StartFailure
from devsim.core.registry import UnknownKind, device_class, kinds
from devsim.observe.live_log import log_options

__all__ = ["cli"]


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
        sys.exit(rv if isinstance(rv, int) else 0)


def _fail(message: str, code: int) -> NoReturn:
    click.echo(f"Error: {message}", err=True)
    sys.exit(code)


@click.group(cls=_Cli, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(__version__, prog_name="devsim")
def cli() -> None:
    """Software twins of legacy motion controllers on virtual serial ports."""


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

        click.echo(eds(cls.kind, cls.description, cls.points, drive=cls.drive is not None,
                       homing=cls.drive is not None and cls.drive.homing is not None))
        return
    click.echo(modbus_markdown(cls) if modbus_map else reference_markdown(cls))


# -- devsim run ------------------------------------------------------------------------------

@cli.command()
@click.argument("kind")
@click.option("--pty", "use_pty", is_flag=True, help="Serve on a new pseudo-terminal (the default).")
@click.option("--link", metavar="PATH", help="Stable symlink to the pty, e.g. /tmp/ttySERS (implies --pty).")
@click.option("--tcp", metavar="[HOST:]PORT", help="Raw TCP port, like a serial device server (host 127.0.0.1).")
@click.option("--rfc2217", metavar="[HOST:]PORT", help="RFC 2217 port: line settings travel with the data.")
@click.option("--config", "config_file", metavar="FILE.yaml", help="DIP switches, parameters, axis geometry.")
@click.option("--state-dir", metavar="DIR", help="Where non-volatile memory (EEPROM) is kept.")
@click.option("--speed", type=FLOAT, default=1.0, show_default=True, metavar="F", help="Time speed factor.")
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
@click.option("--idle-drop", type=AsciiFloatRange(min=0), default=None, metavar="SECONDS",
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
@click.option("--opcua-period", type=FLOAT, default=0.1, show_default=True, metavar="SECONDS",
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
@click.option("--mqtt-rate", type=FLOAT, default=1.0, show_default=True, metavar="SECONDS",
              help="How often (device time) the MQTT facade samples the points for changes.")
@click.option("--mqtt-plant", metavar="NAME", help="The plant's name in MQTT topics (default: the kind).")
@click.option("--mqtt-primary-host", metavar="HOST_ID",
              help="Sparkplug: the Primary Host Application's id; the edge node sends its births only while"
              " spBv1.0/STATE/HOST_ID says online, and reconnects when it says offline (default: no primary host).")
@click.option(
    "--fleet",
    metavar="mqtt://BROKER[:PORT][/NAME]",
    help="Join a fleet: announce the devices on the broker, take control requests from it.",
)
@click.option("--web", metavar="[HOST:]PORT", help="Also serve the plant's web page there (extra [web]; host"
              " 127.0.0.1 unless named, another host gets a token).")
@click.option("--motion-log", metavar="FILE.csv", help="Write every axis's motion (set-point, position, velocity,"
              " following error, events) as CSV, for 'devsim plot'.")
@click.option("--motion-resolution", type=FLOAT, default=0.01, show_default=True, metavar="SECONDS",
              help="How often (device time) the motion log samples the axes, besides every event.")
@log_options
def run(**params: Any) -> None:
    """Serve a simulated KIND device until Ctrl-C.

    Prints one line per device port (NAME: pty|tcp|rfc2217|udp ADDRESS) and the control address.
    A port the kind declares on the network (e.g. Ether-S-Bus on udp:5050) is served there on
    loopback unless --port NAME=SPEC says otherwise; the other ports follow --pty/--tcp/--rfc2217.
    A trace named FILE.pcap is written as pcap (Wireshark, tshark).  Host connects, disconnects,
    line mismatches and device errors are logged to stderr (-v: more, -q: less).
    """
    plan = plan_run(**params)
    try:
        serve(plan)
    except StartFailure as exc:
        raise exits.failure(exc.status, str(exc)) from None


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
