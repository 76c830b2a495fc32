"""``devsim ctl``: the control API of a running simulator (``--control ADDR`` or NAME, or the only
one running: :func:`devsim.cli.running.control_target`) or of a fleet
(``--fleet mqtt://BROKER``, :mod:`devsim.fleet`) on the command line; results are printed as text
(:mod:`devsim.cli.present`; ``--json`` for scripts), errors are one line with the status of
:mod:`devsim.cli.exits`.

One command per op of :data:`devsim.runtime.ops.CONTROL` (``power_cycle`` is ``power-cycle``),
each sending the op's typed request (:mod:`devsim.runtime.requests`); :func:`command_name` names
them and a test holds them to the table."""

from __future__ import annotations

import functools
import json
import sys
from collections.abc import Callable
from typing import Any

import click

from devsim.cli import exits, present
from devsim.cli.options import FLOAT, INT, AsciiFloatRange, AsciiIntRange, check_fleet
from devsim.runtime import requests as rq

__all__ = ["command_name", "ctl"]


def command_name(op: str) -> str:
    """The ``devsim ctl`` command of a control op."""
    return op.replace("_", "-")


def _connect(ctx: click.Context) -> tuple[str, Any]:
    """The address and a client of ``--control`` (or ``--fleet``); a one-line error if it cannot
    be reached."""
    from devsim.runtime.client import ControlClient
    from devsim.runtime.control import ControlAddressError

    addr, fleet = ctx.obj
    if fleet is None:
        from devsim.cli.running import control_target

        addr = control_target(addr)
    try:
        if fleet is not None:
            from devsim.fleet.client import FleetClient

            return fleet, FleetClient(fleet)
        return addr, ControlClient(addr)
    except ControlAddressError as exc:
        raise click.UsageError(f"--control: {exc}") from None
    except OSError as exc:
        raise exits.Unreachable(f"cannot connect to {fleet or addr}: {exc.strerror or exc}") from None


def _call(ctx: click.Context, *requests: rq.ControlRequest, tail: Callable[[Any], str] | None = None) -> None:
    """Send the requests on one connection; print their results (:mod:`devsim.cli.present`) and,
    as text, what ``tail(client)`` adds on the same connection (if anything)."""
    from devsim.runtime.client import ControlError

    addr, client = _connect(ctx)
    try:
        with client:
            answers = [(request, client.call(request)) for request in requests]
            text = present.render(answers, json_output=present.wants_json(ctx), names=client.names)
            more = "" if tail is None or present.wants_json(ctx) else tail(client)
            text = f"{text}\n{more}" if more else text
    except ControlError as exc:
        raise exits.control_error(exc) from None
    except (OSError, ValueError) as exc:
        raise _broken(ctx, addr, exc) from None
    click.echo(text)


def _print_each(stream: Any, line: Callable[[Any], str], broken: Callable[[Exception], click.ClickException]) -> None:
    """Print ``line(item)`` for each item of a ``watch`` or ``capture`` stream until it ends or
    Ctrl-C (status 0); an error of the stream is ``broken(exc)``.  A stdout whose reader went away
    (``| head -3``) is left to click, status 1 and nothing on stderr as for every command
    (docs/cli.md): printed inside the stream's ``try``, its EPIPE was said as the connection's,
    'control connection to … failed: [Errno 32] Broken pipe', status 5."""
    from devsim.runtime.client import ControlError

    items = iter(stream)
    try:
        while True:
            try:
                item = next(items)
            except StopIteration:
                return
            except ControlError as exc:
                raise exits.control_error(exc) from None
            except (OSError, ValueError) as exc:
                raise broken(exc) from None
            click.echo(line(item))
    except KeyboardInterrupt:
        sys.exit(0)


def _broken(ctx: click.Context, addr: str, exc: Exception) -> exits.Unreachable:
    """A connection that broke during a call: over a fleet the client's own words already name
    the broker ("fleet broker mqtt://… lost (…)"), else the control address is named."""
    return exits.Unreachable(str(exc) if ctx.obj[1] is not None else f"control connection to {addr} failed: {exc}")


@click.group(cls=present.JsonGroup)
@click.option(
    "--control", "addr", envvar="DEVSIM_CONTROL", metavar="ADDR",
    help="Control address (unix:/path.sock or [HOST:]PORT) or name of a running simulator; default: the only one"
    " running ('devsim ps'); env DEVSIM_CONTROL.",
)
@click.option(
    "--fleet", metavar="mqtt://BROKER[:PORT][/NAME]",
    help="Instead: every device of every process in this fleet, reached by name.",
)
@click.pass_context
def ctl(ctx: click.Context, addr: str | None, fleet: str | None) -> None:
    """Control a running simulator (or a fleet of them): prints tables and plain words (ok, a
    value with its unit), or JSON with --json."""
    if fleet is not None:
        check_fleet(fleet)
        addr = None
    ctx.obj = (addr, fleet)


@ctl.command(command_name("info"))
@click.option("--device", metavar="NAME", help="With --fleet: only the process serving NAME (default: every one).")
@click.pass_context
def ctl_info(ctx: click.Context, device: str | None) -> None:
    """The process: name, pid, uptime, clock, kinds, devices and ports (what 'devsim ps' lists)."""
    _call(ctx, rq.Info(_fleet_device(ctx, device)))


@ctl.command(command_name("devices"))
@click.pass_context
def ctl_devices(ctx: click.Context) -> None:
    """The devices: name, kind and port."""
    _call(ctx, rq.Devices())


@ctl.command(command_name("read"))
@click.argument("device")
@click.argument("names", nargs=-1, required=True)
@click.pass_context
def ctl_read(ctx: click.Context, device: str, names: tuple[str, ...]) -> None:
    """Read NAMES (e.g. axis.position) of DEVICE: 'axis.position = 1200 inc', a table for
    several (with --json: the value, or an object of name and value)."""
    _call(ctx, *(rq.Read(device, name) for name in names))


@ctl.command(command_name("set"), context_settings={"ignore_unknown_options": True})  # (a VALUE of -5)
@click.argument("device")
@click.argument("name")
@click.argument("value")
@click.pass_context
def ctl_set(ctx: click.Context, device: str, name: str, value: str) -> None:
    """Set NAME of DEVICE to VALUE, read as NAME's declared type (true/false/on/off/yes/no/1/0 for a
    boolean, a finite number, text, or JSON for structured values)."""
    _call(ctx, rq.Set(device, name, value))


@ctl.command(command_name("state"))
@click.argument("device")
@click.pass_context
def ctl_state(ctx: click.Context, device: str) -> None:
    """A snapshot of DEVICE's state."""
    _call(ctx, rq.State(device))


@ctl.command(command_name("power_cycle"))
@click.argument("device")
@click.option("--wipe", is_flag=True, help="Erase non-volatile memory first.")
@click.pass_context
def ctl_power_cycle(ctx: click.Context, device: str, wipe: bool) -> None:
    """Switch DEVICE off and on."""
    _call(ctx, rq.PowerCycle(device, wipe))


@ctl.command(command_name("advance"))
@click.argument("seconds", type=FLOAT)
@click.option("--device", metavar="NAME", help="With --fleet: only the process serving NAME (default: every one).")
@click.pass_context
def ctl_advance(ctx: click.Context, seconds: float, device: str | None) -> None:
    """Advance virtual time by SECONDS (needs 'devsim run --virtual'); prints the new time (with
    --fleet: of each process, or of the one serving --device)."""
    _call(ctx, rq.Advance(seconds, _fleet_device(ctx, device)))


@ctl.command(command_name("now"))
@click.option("--device", metavar="NAME", help="With --fleet: only the process serving NAME (default: every one).")
@click.pass_context
def ctl_now(ctx: click.Context, device: str | None) -> None:
    """The simulator's current time in seconds (with --fleet: of each process)."""
    _call(ctx, rq.Now(_fleet_device(ctx, device)))


def _fleet_device(ctx: click.Context, device: str | None) -> str | None:
    if device is not None and ctx.obj[1] is None:
        raise click.UsageError("--device is for --fleet (one process has one clock)")
    return device


@ctl.command(command_name("line"))
@click.argument("device")
@click.option("--port", default="main", show_default=True, help="Which serial port of DEVICE.")
@click.pass_context
def ctl_line(ctx: click.Context, device: str, port: str) -> None:
    """Status of the line serving a port of DEVICE (settings, mismatch)."""
    _call(ctx, rq.Line(device, port))


@ctl.command(command_name("names"))
@click.argument("device", metavar="DEVICE|KIND")
@click.pass_context
def ctl_names(ctx: click.Context, device: str) -> None:
    """DEVICE's control names grouped by family (axis, input, param ...), with type, unit, access
    (r, rw, w) and description (--json: with manual sections), then its kind's names made from a
    pattern (marker.M<byte>.<bit>) and its aliases (param.V), as 'devsim doc KIND' shows them (not
    in --json).  With no simulator to ask, or none (of several) that serves a device of that
    name, KIND's names (e.g. 'devsim ctl names sers')."""
    try:
        _call(ctx, rq.Names(device), tail=lambda client: _by_pattern(_kind_of(client, device)))
    except click.ClickException as exc:  # none to ask, several, or no such device: a kind's names
        from devsim.core.registry import UnknownKind, device_class

        if ctx.obj != (None, None):  # an address was given: its answer counts
            raise
        try:
            rows = [point.describe() for point in device_class(device).points]
        except UnknownKind:
            raise exc from None
        text = present.render([(rq.Names(device), rows)], json_output=present.wants_json(ctx))
        more = "" if present.wants_json(ctx) else _by_pattern(device)
        click.echo(f"{text}\n{more}" if more else text)


def _kind_of(client: Any, device: str) -> str | None:
    """The kind of a running DEVICE, from the devices listing (of a process or a fleet)."""
    return next((row.get("kind") for row in client.call(rq.Devices()) if row.get("name") == device), None)


def _by_pattern(kind: str | None) -> str:
    """The end of ``ctl names`` (not of its op's answer, which lists what every reader reads):
    KIND's names made from a pattern and its aliases, as ``devsim doc KIND`` shows them; "" for
    a kind unknown here (a fleet member's plugin)."""
    from devsim.cli.docgen import alias_rows, pattern_rows
    from devsim.core.registry import UnknownKind, device_class

    try:
        cls = device_class(kind or "")
    except UnknownKind:
        return ""
    return present.by_pattern_text(pattern_rows(cls), alias_rows(cls), present.terminal_width())


@ctl.command(command_name("fault"))
@click.argument("device")
@click.argument("kind")
@click.argument("switch", type=click.Choice(["on", "off"]))
@click.pass_context
def ctl_fault(ctx: click.Context, device: str, kind: str, switch: str) -> None:
    """Switch a declared fault KIND of DEVICE on or off (e.g. blocked_axis on)."""
    _call(ctx, rq.SwitchFault(device, kind, switch == "on"))


@ctl.command(command_name("line_fault"))
@click.argument("device")
@click.argument("kind")
@click.argument("switch", type=click.Choice(["on", "off"]))
@click.option("--port", default="main", show_default=True, help="Which serial port of DEVICE.")
@click.option("--direction", type=click.Choice(["to_device", "to_host", "both"]), help="Which way.")
@click.option("--count", type=INT, help="Bytes affected (corrupt, drop, split).")
@click.option("--duration", type=FLOAT, help="Seconds until the fault ends by itself.")
@click.option("--delay", type=FLOAT, help="Seconds (delay, jitter, split).")
@click.option("--rate", type=FLOAT, help="Noise bytes per second (at most 1,000,000).")
@click.option("--baudrate", type=INT, help="The host's rate (baud_mismatch).")
@click.pass_context
def ctl_line_fault(ctx: click.Context, device: str, kind: str, switch: str, port: str, **params: Any) -> None:
    """Start or end a line fault KIND on a port of DEVICE: corrupt, drop, split, delay, jitter,
    noise, baud_mismatch, unplug, hang, silent."""
    given = {name: value for name, value in params.items() if value is not None}
    _call(ctx, rq.LineFault(device, kind, switch == "on", port, given))


@ctl.command(command_name("telegrams"))
@click.argument("device")
@click.option("--port", default="main", show_default=True, help="Which port of DEVICE (or 'modbus': its RTU line).")
@click.option("--count", type=AsciiIntRange(0, 200), default=20, show_default=True, help="How many.")
@click.pass_context
def ctl_telegrams(ctx: click.Context, device: str, port: str, count: int) -> None:
    """The last telegrams on the line of a port of DEVICE (time, direction, bytes and, where the
    port declares its framing, the decoded messages); kept from the first request on."""
    _call(ctx, rq.Telegrams(device, port, count))


@ctl.command(command_name("scenario"))
@click.pass_context
def ctl_scenario(ctx: click.Context) -> None:
    """The running scenario (devsim scenario run --control/--web): its steps so far, pass or fail,
    and its progress."""
    _call(ctx, rq.Scenario())


@ctl.command(command_name("watch"))
@click.argument("device", required=False)
@click.argument("names", nargs=-1)
@click.option("--json", "as_json", is_flag=True, help="One JSON object per line instead of text.")
@click.option("--period", type=AsciiFloatRange(min=rq.MIN_WATCH_PERIOD, finite=True), metavar="SECONDS",
              help=f"Sampling period in device time (default 0.1, at least {rq.MIN_WATCH_PERIOD:g}).")
def ctl_watch(device: str | None, names: tuple[str, ...], as_json: bool, period: float | None) -> None:
    """Print changes of DEVICE's NAMEs (default: its state and axes) and its events (move start
    and end, faults, errors, host connects) as they happen, one line each, until Ctrl-C or the
    simulator stops: '12.300 sers axis.position 1234.0'.  With --fleet, over the broker (JSON
    lines add the serving 'process'); without DEVICE, every device of the fleet."""
    from devsim.runtime.watch_stream import describe

    ctx = click.get_current_context()
    if device is None and ctx.obj[1] is None:
        raise click.UsageError("watch needs DEVICE (every device at once: with --fleet)")
    addr, client = _connect(ctx)
    fleet = ctx.obj[1] is not None
    say = functools.partial(click.echo, err=True)
    told = {"on_offline": say, "on_back": say} if fleet else {}  # a member went offline, or is back
    stream = client.watch(device, list(names) or None, period=period, **told)
    as_json = as_json or present.wants_json(ctx)
    try:
        _print_each(stream, lambda item: json.dumps(item, ensure_ascii=False) if as_json else describe(item),
                    lambda exc: _broken(ctx, addr, exc))
    finally:
        stream.close()
        client.close()


@ctl.command(command_name("capture"))
@click.argument("device")
@click.option("--port", default="main", show_default=True, help="Which port of DEVICE (or 'modbus': its RTU line).")
@click.option("--json", "as_json", is_flag=True, help="One JSON object per line instead of text.")
def ctl_capture(device: str, port: str, as_json: bool) -> None:
    """Print the chunks crossing the line of a port of DEVICE as they cross, one line each, until
    Ctrl-C or the simulator stops: '12.345678 H>D 23 52 46 0d "#RF\\r"' as in a text trace (a
    reader too slow for the line is told how many chunks it missed).  Wireshark captures the
    same live through 'devsim extcap' (docs: Wireshark)."""
    from devsim.cli.running import control_target
    from devsim.runtime.client import CaptureSubscription, ControlError
    from devsim.transports.trace import render

    ctx = click.get_current_context()
    addr, fleet = ctx.obj
    if fleet is not None:
        raise click.UsageError("capture talks to one simulator: give --control, not --fleet")
    addr = control_target(addr)
    try:
        stream = CaptureSubscription(addr, device, port)
    except ControlError as exc:
        raise exits.control_error(exc) from None
    except OSError as exc:
        raise exits.Unreachable(f"cannot connect to {addr}: {exc.strerror or exc}") from None
    as_json = as_json or present.wants_json(ctx)

    def line(item: dict[str, Any]) -> str:
        if as_json:
            return json.dumps(item)
        if item["type"] == "dropped":
            return f"{item['t']:.6f} -- {item['count']} chunks dropped (this reader was too slow)"
        data = bytes.fromhex(item["data"])
        return f"{item['t']:.6f} {item['dir']} {data.hex(' ')} {render(data)}"

    try:
        _print_each(stream, line, lambda exc: exits.Unreachable(f"control connection to {addr} failed: {exc}"))
    finally:
        stream.close()
