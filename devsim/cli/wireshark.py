"""``devsim wireshark --install`` and ``devsim extcap`` (Wireshark's live capture of running
simulators): thin commands over :mod:`devsim.wireshark.installer` and :mod:`devsim.wireshark.extcap`."""

from __future__ import annotations

import sys

import click

from devsim.cli import exits

__all__ = ["extcap", "wireshark"]


@click.command(context_settings={"ignore_unknown_options": True, "allow_extra_args": True,
                                 "help_option_names": []})
@click.argument("args", nargs=-1, type=click.UNPROCESSED)
def extcap(args: tuple[str, ...]) -> None:
    """Wireshark's extcap program for the ports of running simulators (Wireshark runs it through
    the launcher 'devsim wireshark --install' puts in its extcap folder): --extcap-interfaces,
    --extcap-interface I --extcap-dlts | --extcap-config | --capture --fifo F."""
    from devsim.wireshark.extcap import main

    sys.exit(main(list(args)))


@click.command()
@click.option("--install", "do_install", is_flag=True, help="Install the dissectors and the extcap launcher.")
@click.option("--dir", "directory", metavar="D", help="Install under D (D/plugins, D/extcap) instead of "
              "Wireshark's personal folders ('tshark -G folders').")
def wireshark(do_install: bool, directory: str | None) -> None:
    """Put devsim's Lua dissectors and its extcap launcher (live capture of running simulators'
    ports) where Wireshark finds them; restart Wireshark afterwards."""
    from devsim.wireshark.installer import install

    if not do_install:
        raise click.UsageError("wireshark: give --install (see 'devsim wireshark --help')")
    try:
        installed = install(directory)
    except OSError as exc:
        raise exits.SystemFailure(f"wireshark --install: {exc}") from None
    folder = installed.dissectors[0].parent if installed.dissectors else None
    click.echo(f"dissectors: {len(installed.dissectors)} files in {folder}")
    click.echo(f"extcap: {installed.launcher}")
