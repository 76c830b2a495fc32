"""``devsim ctl``: the control API of a running simulator (``--control ADDR``) or of a fleet
(``--fleet mqtt://BROKER``, :mod:`devsim.fleet`) on the command line; results are printed as JSON,
errors are one line."""

from __future__ import annotations

import json
import sys
from typing import Any

import click

from devsim.run_options import check_fleet

__all__ = ["ctl"]


def _emit(result: Any) -> None:
    if isinstance(result, dict | list):
        click.echo(json.dumps(result, indent=2, sort_keys=False))
    else:
        click.echo(json.dumps(result))


def _call(ctx: click.Context, method: str, *args: Any, **kwargs: Any) -> None:
    from devsim.runtime.control import ControlAddressError, ControlClient, ControlError

    addr, fleet = ctx.obj
    client: Any
    try:
        if fleet is not None:
            from devsim.fleet.client import FleetClient

            addr = fleet
            client = FleetClient(fleet)
        else:
            client = ControlClient(addr)
    except ControlAddressError as exc:
        raise click.UsageError(f"--control: {exc}") from None
    except OSError as exc:
        raise click.ClickException(f"cannot connect to {addr}: {exc.strerror or exc}") from None
    try:
        with client:
            result = getattr(client, method)(*args, **kwargs)
    except ControlError as exc:
        raise click.ClickException(str(exc)) from None
    except (OSError, ValueError) as exc:
        raise click.ClickException(f"control connection to {addr} failed: {exc}") from None
    _emit(result)


@click.group()
@click.option(
    "--control", "addr", envvar="DEVSIM_CONTROL", metavar="ADDR",
    help="Control address of a running 'devsim run' (unix:/path.sock or [HOST:]PORT; env DEVSIM_CONTROL).",
)
@click.option(
    "--fleet", metavar="mqtt://BROKER[:PORT][/NAME]",
    help="Instead: every device of every process in this fleet, reached by name (extra [fleet]).",
)
@click.pass_context
def ctl(ctx: click.Context, addr: str | None, fleet: str | None) -> None:
    """Control a running simulator (or a fleet of them); prints JSON results."""
    if fleet is not None:
        check_fleet(fleet)
        addr = None
    elif addr is None:
        raise click.UsageError("Missing option '--control' (or '--fleet')")
    ctx.obj = (addr, fleet)


@ctl.command("devices")
@click.pass_context
def ctl_devices(ctx: click.Context) -> None:
    """The devices: name, kind and port."""
    _call(ctx, "devices")


@ctl.command("read")
@click.argument("device")
@click.argument("name")
@click.pass_context
def ctl_read(ctx: click.Context, device: str, name: str) -> None:
    """Read NAME (e.g. axis.position) of DEVICE."""
    _call(ctx, "read", device, name)


@ctl.command("set")
@click.argument("device")
@click.argument("name")
@click.argument("value")
@click.pass_context
def ctl_set(ctx: click.Context, device: str, name: str, value: str) -> None:
    """Set NAME of DEVICE to VALUE, read as NAME's declared type (true/false/on/off/1/0 for a
    boolean, a finite number, text, or JSON for structured values)."""
    _call(ctx, "set", device, name, value)


@ctl.command("state")
@click.argument("device")
@click.pass_context
def ctl_state(ctx: click.Context, device: str) -> None:
    """A snapshot of DEVICE's state."""
    _call(ctx, "state", device)


@ctl.command("power-cycle")
@click.argument("device")
@click.option("--wipe", is_flag=True, help="Erase non-volatile memory first.")
@click.pass_context
def ctl_power_cycle(ctx: click.Context, device: str, wipe: bool) -> None:
    """Switch DEVICE off and on."""
    _call(ctx, "power_cycle", device, wipe=wipe)


@ctl.command("advance")
@click.argument("seconds", type=float)
@click.option("--device", metavar="NAME", help="With --fleet: only the process serving NAME (default: every one).")
@click.pass_context
def ctl_advance(ctx: click.Context, seconds: float, device: str | None) -> None:
    """Advance virtual time by SECONDS (needs 'devsim run --virtual'); prints the new time (with
    --fleet: of each process, or of the one serving --device)."""
    _call(ctx, "advance", seconds, **_fleet_device(ctx, device))


@ctl.command("now")
@click.option("--device", metavar="NAME", help="With --fleet: only the process serving NAME (default: every one).")
@click.pass_context
def ctl_now(ctx: click.Context, device: str | None) -> None:
    """The simulator's current time in seconds (with --fleet: of each process)."""
    _call(ctx, "now", **_fleet_device(ctx, device))


def _fleet_device(ctx: click.Context, device: str | None) -> dict[str, str]:
    if device is None:
        return {}
    if ctx.obj[1] is None:
        raise click.UsageError("--device is for --fleet (one process has one clock)")
    return {"device": device}


@ctl.command("line")
@click.argument("device")
@click.option("--port", default="main", show_default=True, help="Which serial port of DEVICE.")
@click.pass_context
def ctl_line(ctx: click.Context, device: str, port: str) -> None:
    """Status of the line serving a port of DEVICE (settings, mismatch)."""
    _call(ctx, "line", device, port)


@ctl.command("names")
@click.argument("device")
@click.pass_context
def ctl_names(ctx: click.Context, device: str) -> None:
    """DEVICE's control names with type, unit, access (r, rw, w), description and manual section."""
    _call(ctx, "names", device)


@ctl.command("fault")
@click.argument("device")
@click.argument("kind")
@click.argument("switch", type=click.Choice(["on", "off"]))
@click.pass_context
def ctl_fault(ctx: click.Context, device: str, kind: str, switch: str) -> None:
    """Switch a declared fault KIND of DEVICE on or off (e.g. blocked_axis on)."""
    _call(ctx, "fault", device, kind, switch == "on")


@ctl.command("line-fault")
@click.argument("device")
@click.argument("kind")
@click.argument("switch", type=click.Choice(["on", "off"]))
@click.option("--port", default="main", show_default=True, help="Which serial port of DEVICE.")
@click.option("--direction", type=click.Choice(["to_device", "to_host", "both"]), help="Which way.")
@click.option("--count", type=int, help="Bytes affected (corrupt, drop, split).")
@click.option("--duration", type=float, help="Seconds until the fault ends by itself.")
@click.option("--delay", type=float, help="Seconds (delay, jitter, split).")
@click.option("--rate", type=float, help="Noise bytes per second.")
@click.option("--baudrate", type=int, help="The host's rate (baud_mismatch).")
@click.pass_context
def ctl_line_fault(ctx: click.Context, device: str, kind: str, switch: str, port: str, **params: Any) -> None:
    """Start or end a line fault KIND on a port of DEVICE: corrupt, drop, split, delay, jitter,
    noise, baud_mismatch, unplug, hang, silent."""
    given = {name: value for name, value in params.items() if value is not None}
    _call(ctx, "line_fault", device, kind, switch == "on", port=port, **given)


@ctl.command("watch")
@click.argument("device")
@click.argument("names", nargs=-1)
@click.option("--json", "as_json", is_flag=True, help="One JSON object per line instead of text.")
@click.option("--period", type=float, metavar="SECONDS", help="Sampling period in device time (default 0.1).")
def ctl_watch(device: str, names: tuple[str, ...], as_json: bool, period: float | None) -> None:
    """Print changes of DEVICE's NAMEs (default: its state and axes) and its events (move start
    and end, faults, errors, host connects) as they happen, one line each, until Ctrl-C or the
    simulator stops: '12.300 sers axis.position 1234.0'."""
    from devsim.runtime.control import ControlAddressError, ControlClient, ControlError
    from devsim.runtime.watch_stream import describe

    addr, fleet = click.get_current_context().obj
    if fleet is not None:
        raise click.UsageError("watch needs --control (a fleet has no stream)")
    try:
        client = ControlClient(addr)
    except ControlAddressError as exc:
        raise click.UsageError(f"--control: {exc}") from None
    except OSError as exc:
        raise click.ClickException(f"cannot connect to {addr}: {exc.strerror or exc}") from None
    stream = client.watch(device, list(names) or None, period=period)
    try:
        for item in stream:
            click.echo(json.dumps(item) if as_json else describe(item))
    except KeyboardInterrupt:
        sys.exit(0)
    except ControlError as exc:
        raise click.ClickException(str(exc)) from None
    except (OSError, ValueError) as exc:
        raise click.ClickException(f"control connection to {addr} failed: {exc}") from None
    finally:
        stream.close()
        client.close()
