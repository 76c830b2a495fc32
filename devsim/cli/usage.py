"""Usage errors without click on the way to them (``devsim run``'s quick command line,
:mod:`devsim.cli.quick`, imports no click unless it has a mistake to say), and ``[HOST:]PORT``."""

from __future__ import annotations

from devsim.core.points import ascii_digits

__all__ = ["check_dirs", "host_port", "usage_error"]


def usage_error(message: str) -> Exception:
    """click's usage error (exit status 2, one line), click imported on the way to it."""
    import click

    return click.UsageError(message)


def host_port(option: str, text: str) -> tuple[str, int]:
    """``[HOST:]PORT`` of ``option`` (host 127.0.0.1 when not given)."""
    host, sep, port_text = text.rpartition(":")
    if not sep:
        host = "127.0.0.1"
    host = host.strip("[]") or "127.0.0.1"
    if not ascii_digits(port_text) or len(port_text) > 5:  # (int() read '٣' and '-0', and raised past 4300 digits)
        raise usage_error(f"{option}: expected [HOST:]PORT, got {text!r}")
    port = int(port_text)
    if not 0 <= port <= 65535:
        raise usage_error(f"{option}: port {port} is not in 0..65535")
    return host, port


def check_dirs(dirs: dict[str, str | None]) -> None:
    """Directory options (option → the path given, or None), checked before anything starts:
    an empty one is a usage error (it was the current directory); one that is a file, or lies
    below one, is a file that cannot be written (status SYSTEM, as before) in one line naming the
    option.  They were made at start with ``mkdir(parents=True)``: run said 'cannot create the
    devices: [Errno 17] File exists: …', scenario run named the scenario file."""
    import os

    from devsim.cli.exits import SystemFailure

    for option, path in dirs.items():
        if path is None:
            continue
        if not path:
            raise usage_error(f"{option}: needs a directory")
        if os.path.exists(path) and not os.path.isdir(path):
            raise SystemFailure(f"{option}: {path}: not a directory")
        parent = os.path.dirname(os.path.abspath(path))
        while not os.path.exists(parent):
            parent = os.path.dirname(parent)
        if not os.path.isdir(parent):
            raise SystemFailure(f"{option}: {path}: {parent} is not a directory")
