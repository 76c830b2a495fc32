"""``devsim monitor [--control ADDR|NAME]``: the live monitor (:mod:`devsim.observe.monitor`) on the
control API of a running ``devsim run``, ``devsim up`` or real-time scenario."""

from __future__ import annotations

import sys

import click

from devsim.cli import exits
from devsim.cli.options import AsciiFloatRange
from devsim.runtime.requests import MIN_WATCH_PERIOD

__all__ = ["monitor"]


@click.command("monitor")
@click.option(
    "--control", "addr", envvar="DEVSIM_CONTROL", metavar="ADDR",
    help="Control address (unix:/path.sock or [HOST:]PORT) or name of the running plant; default: the only one"
    " running ('devsim ps'); env DEVSIM_CONTROL.",
)
@click.option("--period", type=AsciiFloatRange(min=MIN_WATCH_PERIOD, finite=True), default=0.1, show_default=True,
              metavar="SECONDS", help=f"How often values are sampled, in device time (at least {MIN_WATCH_PERIOD:g}).")
def monitor(addr: str | None, period: float) -> None:
    """A live view of every device: state, display, faults, axes with sparklines, inputs (press
    to flip) and outputs, the last telegrams per port; f: fault menu, a/A: advance virtual time,
    q: quit.  Needs the extra [monitor] (textual)."""
    from devsim.runtime.control import ControlAddressError

    try:
        from devsim.observe.monitor import MonitorApp
    except ImportError as exc:
        from devsim.core.extras import install_command

        raise exits.MissingExtra(f"devsim monitor needs textual: {install_command('monitor')} ({exc})") from None
    from devsim.cli.running import control_target

    addr = control_target(addr)
    try:
        app = MonitorApp(addr, period=period)
    except ControlAddressError as exc:
        raise click.UsageError(f"--control: {exc}") from None
    except OSError as exc:
        raise exits.Unreachable(f"cannot connect to {addr}: {exc.strerror or exc}") from None
    if not sys.stdout.isatty():  # (a pipe or a file would get the screen's escape codes)
        raise click.UsageError("devsim monitor draws on a terminal, and its output is not one; "
                               "'devsim ctl watch' prints the same changes and events as lines")
    app.run()
