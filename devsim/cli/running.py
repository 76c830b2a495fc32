"""The running simulators on the command line (:mod:`devsim.runtime.discovery`): ``devsim ps``;
:func:`control_target`, the control address ``devsim ctl`` and ``devsim monitor`` mean when given
an address, a name or nothing; :func:`control_option`, the one ``devsim run`` and ``devsim up``
serve on (``--control ADDR``, ``--no-control``, by default a socket in the runtime directory)."""

from __future__ import annotations

import json

import click
import msgspec

from devsim.cli import exits
from devsim.cli.control_address import control_option, default_control
from devsim.runtime.control import ControlAddressError
from devsim.runtime.discovery import DiscoveryError, RuntimeDirError, Simulator, choose, running

__all__ = ["ControlChoiceError", "control_option", "control_target", "default_control", "ps", "uptime_text"]


class ControlChoiceError(click.ClickException):
    """Several simulators run and the command did not say which: exit status 2, as for any
    usage error (the user has to add an option); the message lists them, no usage hint follows."""

    exit_code = 2


def control_target(given: str | None) -> str:
    """The control address meant by ``--control`` (an address, a simulator's name, or None: the
    one running); a one-line error when none runs or none has that name, the list of them when
    several do."""
    try:
        return choose(given)
    except ControlAddressError as exc:
        raise click.UsageError(f"--control: {exc}") from None
    except DiscoveryError as exc:
        if exc.several:
            raise ControlChoiceError(str(exc)) from None
        raise exits.Unreachable(str(exc)) from None
    except RuntimeDirError as exc:
        raise exits.SystemFailure(str(exc)) from None


def uptime_text(seconds: float | None) -> str:
    """``45s``, ``3m05s``, ``2h03m``, ``4d02h``."""
    if seconds is None:
        return "?"
    whole = int(seconds)
    days, rest = divmod(whole, 86400)
    hours, rest = divmod(rest, 3600)
    minutes, secs = divmod(rest, 60)
    if days:
        return f"{days}d{hours:02d}h"
    if hours:
        return f"{hours}h{minutes:02d}m"
    if minutes:
        return f"{minutes}m{secs:02d}s"
    return f"{secs}s"


def _ports_text(sim: Simulator, shown: int = 2) -> str:
    if not sim.answering:
        return "(not answering)"
    items = [f"{key} {where}" for key, where in sim.ports.items()]
    more = f", +{len(items) - shown} more" if len(items) > shown else ""
    return ", ".join(items[:shown]) + more or "-"


@click.command("ps")
@click.option("--json", "as_json", is_flag=True, help="One JSON list (every port) instead of the table.")
def ps(as_json: bool) -> None:
    """List the running simulators: name, kinds, ports, control address, pid and uptime (from
    the control sockets in the runtime directory; sockets of processes that are gone are
    removed)."""
    try:
        found = running()
    except RuntimeDirError as exc:
        raise exits.SystemFailure(str(exc)) from None
    if as_json:
        click.echo(json.dumps([msgspec.to_builtins(sim) for sim in found], indent=2))
        return
    if not found:
        click.echo("no running simulators", err=True)
        return
    header = ("NAME", "KINDS", "PORTS", "CONTROL", "PID", "UPTIME")
    rows = [header, *((sim.name, ", ".join(sim.kinds) or "?", _ports_text(sim), sim.address, str(sim.pid or "?"),
                       uptime_text(sim.uptime)) for sim in found)]
    widths = [max(len(row[col]) for row in rows) for col in range(len(header) - 1)]
    for row in rows:
        click.echo("  ".join([*(cell.ljust(width) for cell, width in zip(row, widths, strict=False)), row[-1]]))
