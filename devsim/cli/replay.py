"""The ``devsim record`` and ``devsim replay`` commands (registered lazily in :mod:`devsim.cli`).

* ``devsim record --port PATH_OR_URL --out session.devsim [--kind KIND]`` – a new pty (or
  ``--tcp [HOST:]PORT``) for the host, forwarded to the device's port, both directions written
  to the session file (:mod:`devsim.observe.replay.recorder`, format in :mod:`devsim.observe.replay.session`).
* ``devsim replay session.devsim --pty [--link PATH] [--speed F | --as-fast] [--fallback
  error|live]`` – the device side played back on a new pty, or on ``--tcp [HOST:]PORT``
  (:mod:`devsim.observe.replay.player`).

Both print their ports on stdout, one per line (``record: pty /dev/pts/7``, ``replay: pty
/dev/pts/8``), for scripts to parse; problems are one line on stderr.
"""

from __future__ import annotations

import asyncio
import sys
from typing import Any

import click

from devsim.cli import exits
from devsim.cli.options import FLOAT, INT
from devsim.core.device import SerialSettings

__all__ = ["record", "replay"]


def _kind_defaults(kind: str, port_name: str | None, config: dict[str, Any]) -> tuple[str, SerialSettings]:
    """The port recorded (default: the kind's first) and the line settings the kind uses on it."""
    from devsim.core.clock import VirtualClock
    from devsim.core.nvram import NonVolatileMemory
    from devsim.core.registry import UnknownKind, device_class

    try:
        cls = device_class(kind)
    except UnknownKind as exc:
        raise click.UsageError(str(exc)) from None
    names = [port.name for port in cls.ports]
    port_name = port_name or names[0]
    if port_name not in names:
        raise click.UsageError(f"--device-port: kind {kind!r} has no port {port_name!r} (ports: {', '.join(names)})")
    device = cls(clock=VirtualClock(), config=config or None, nvram=NonVolatileMemory.for_device(None, kind), name=kind)
    try:
        return port_name, device.port(port_name).serial_settings
    finally:
        device.close()


def _load_config(kind: str, path: str | None) -> dict[str, Any]:
    """The kind's configuration file, validated like ``devsim run --config`` (a bad file)."""
    if path is None:
        return {}
    from devsim.core.config import ConfigError, load_yaml, plain, validate
    from devsim.core.registry import device_class

    model = device_class(kind).config_model
    try:
        data = load_yaml(path)
        if model is not None:
            validate(data, model, path)
            return dict(model.parse(plain(data) if isinstance(data, dict) else {}).dump())
    except (ConfigError, ValueError) as exc:
        raise exits.BadFile(str(exc)) from None
    return plain(data) if isinstance(data, dict) else {}


@click.command("record")
@click.option("--port", "device_url", required=True, metavar="PATH_OR_URL",
              help="The device's port: a path (/dev/ttyUSB0, a devsim pty), socket://HOST:PORT or rfc2217://HOST:PORT.")
@click.option("--out", required=True, metavar="FILE", help="The session file to write (JSON lines).")
@click.option("--kind", metavar="KIND", help="The device's kind: its line settings and decoding (sers, gms96, ...).")
@click.option("--device-port", "port_name", metavar="NAME", help="Which of the kind's ports (default: its first).")
@click.option("--link", metavar="PATH", help="A stable symlink to the host's pty.")
@click.option("--tcp", metavar="[HOST:]PORT", help="Give the host a raw TCP port instead of a pty (host 127.0.0.1).")
@click.option("--baud", type=INT, metavar="N", help="The device's baud rate (default: the kind's).")
@click.option("--parity", type=click.Choice(["N", "E", "O", "M", "S"]), help="The device's parity (default: the kind's).")
def record(device_url: str, out: str, kind: str | None, port_name: str | None, link: str | None, tcp: str | None,
           baud: int | None, parity: str | None) -> None:
    """Sit between a host and a device and record both directions with timing.

    Prints the host's port (record: pty PATH, or record: tcp URL), then records until Ctrl-C.
    """
    from msgspec.structs import replace

    from devsim.cli.options import host_port
    from devsim.observe.replay.recorder import HostPortError, RecordPlan, record_session

    if link and tcp:
        raise click.UsageError("choose one host port: --link (a pty) or --tcp")
    if kind is not None:
        port_name, settings = _kind_defaults(kind, port_name, {})
    else:
        if port_name is not None:
            raise click.UsageError("--device-port needs --kind")
        port_name, settings = "main", SerialSettings()
    if baud is not None:
        settings = replace(settings, baudrate=baud)
    if parity is not None:
        settings = replace(settings, parity=parity)
    plan = RecordPlan(device_url=device_url, out=out, kind=kind, port_name=port_name, settings=settings,
                      tcp=host_port("--tcp", tcp) if tcp is not None else None, link=link)
    try:
        status = asyncio.run(record_session(plan))
    except HostPortError as exc:
        raise exits.SystemFailure(str(exc)) from None
    except OSError as exc:
        raise exits.SystemFailure(f"cannot write {out}: {exc}") from None
    sys.exit(exits.UNREACHABLE if status else exits.OK)  # the device's port: not there, or it failed


@click.command("replay")
@click.argument("session_file", metavar="SESSION")
@click.option("--pty", "use_pty", is_flag=True, help="Serve on a new pseudo-terminal (the default).")
@click.option("--link", metavar="PATH", help="A stable symlink to the pty.")
@click.option("--tcp", metavar="[HOST:]PORT", help="Serve on a raw TCP port instead (host 127.0.0.1).")
@click.option("--speed", type=FLOAT, default=1.0, show_default=True, metavar="F",
              help="Answer F times faster than recorded.")
@click.option("--as-fast", is_flag=True, help="Answer at once, without the recorded delays.")
@click.option("--fallback", type=click.Choice(["error", "live"]), default="error", show_default=True,
              help="On a request not in the recording: report it and stay silent, or hand over to the live model.")
@click.option("--config", "config_file", metavar="FILE.yaml", help="The live model's configuration (with --fallback live).")
def replay(session_file: str, use_pty: bool, link: str | None, tcp: str | None, speed: float, as_fast: bool, fallback: str,
           config_file: str | None) -> None:
    """Play the device side of a recorded SESSION to a host on a new pty (or --tcp port).

    Prints replay: pty PATH once it serves; a request the recording does not know is reported on
    stderr (--fallback error: no answer) or answered by the live model from then on (--fallback live).
    """
    from devsim.cli.options import host_port
    from devsim.observe.replay.player import ReplayPlan, replay_session
    from devsim.observe.replay.session import SessionError, load_session

    if tcp is not None and (use_pty or link):
        raise click.UsageError("choose one port: --pty/--link or --tcp")
    from devsim.core.clock import speed_problem

    if (problem := speed_problem(speed)) is not None:
        raise click.UsageError(f"--speed: {problem}")
    if as_fast and speed != 1.0:
        raise click.UsageError("--speed and --as-fast exclude each other")
    try:
        session = load_session(session_file)
    except SessionError as exc:
        raise exits.BadFile(str(exc)) from None
    if session.cut:
        click.echo(f"replay: {session_file}:{session.cut}: the last line is cut short (the recorder stopped"
                   " writing there); the recording ends before it", err=True)
    config: dict[str, Any] = {}
    if fallback == "live":
        if session.kind is None:
            raise click.UsageError("--fallback live: the session names no kind (record it with --kind)")
        from devsim.core.registry import UnknownKind, device_class

        try:
            device_class(session.kind)
        except UnknownKind as exc:
            raise click.UsageError(f"--fallback live: {exc}") from None
        config = _load_config(session.kind, config_file)
    elif config_file is not None:
        raise click.UsageError("--config is for the live model: add --fallback live")
    plan = ReplayPlan(session=session, link=link, tcp=host_port("--tcp", tcp) if tcp is not None else None, speed=speed, as_fast=as_fast, fallback=fallback, config=config)
    status = asyncio.run(replay_session(plan))
    sys.exit(exits.SYSTEM if status else exits.OK)  # the live model or the port could not start
