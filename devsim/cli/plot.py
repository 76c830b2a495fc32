"""``devsim plot LOG|TRACE... -o move.png|svg|html`` (imported lazily by :mod:`devsim.cli.main`):
the command around :func:`devsim.observe.plot.render`, with the exit statuses of
:mod:`devsim.cli.exits`."""

from __future__ import annotations

from pathlib import Path

import click

from devsim.cli import exits
from devsim.cli.options import AsciiIntRange

__all__ = ["plot", "require_matplotlib"]


def require_matplotlib() -> None:
    """A one-line error (a missing extra) if matplotlib is not installed."""
    from devsim.observe.plot import MissingMatplotlib
    from devsim.observe.plot import require_matplotlib as check

    try:
        check()
    except MissingMatplotlib as exc:
        raise exits.MissingExtra(str(exc)) from None


@click.command("plot")
@click.argument("files", nargs=-1, required=True, type=click.Path(dir_okay=False))
@click.option("-o", "--output", "output", required=True, metavar="OUT.png|svg|html",
              help="The picture to write; its suffix chooses the format.")
@click.option("--title", metavar="TEXT", help="The picture's title (default: the files' names).")
@click.option("--dpi", type=AsciiIntRange(30, 600), default=100, show_default=True, help="PNG resolution.")
def plot(files: tuple[str, ...], output: str, title: str | None, dpi: int) -> None:
    """Draw motion logs (--motion-log) and wire traces (--trace, text or pcap) in FILES:
    position, velocity and following error against time with the events marked, and the line
    traffic on the same time axis."""
    from devsim.observe.plot import output_format, render
    from devsim.observe.plot_data import PlotInputError

    try:
        output_format(output)
    except ValueError as exc:
        raise click.UsageError(f"-o: {exc}") from None
    for path in files:
        if not Path(path).is_file():
            raise exits.BadFile(f"{path}: no such file")
    require_matplotlib()
    try:
        written = render(files, output, title=title, dpi=dpi)
    except PlotInputError as exc:
        raise exits.BadFile(str(exc)) from None
    except OSError as exc:
        raise exits.SystemFailure(f"cannot write {output}: {exc.strerror or exc}") from None
    click.echo(str(written))
