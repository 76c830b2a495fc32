"""The control address of ``devsim run`` and ``devsim up`` (``--control ADDR`` /
``--no-control``, by default a socket in the runtime directory), without click: what
:mod:`devsim.cli.serve` plans with and :mod:`devsim.cli.running` offers the other commands.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from devsim.cli.usage import usage_error

if TYPE_CHECKING:
    from devsim.runtime.control import ControlAddress

__all__ = ["control_option", "default_control", "system_failure"]


def system_failure(message: str) -> Exception:
    from devsim.cli import exits

    return exits.SystemFailure(message)


def default_control(name: str) -> ControlAddress:
    """The control socket ``devsim run`` and ``devsim up`` open when not told otherwise:
    ``NAME-PID.sock`` in the runtime directory (a one-line error if that is not safe)."""
    from devsim.runtime.control import ControlAddress
    from devsim.runtime.discovery import RuntimeDirError, control_file

    try:
        return ControlAddress(path=control_file(name))
    except RuntimeDirError as exc:
        raise system_failure(f"{exc} (--control ADDR serves the control API elsewhere, --no-control"
                      " not at all)") from None


def control_option(control: str | None, no_control: bool, name: str, *, allow_remote: bool = False) -> ControlAddress | None:
    """``--control ADDR`` / ``--no-control`` of ``devsim run`` and ``devsim up``: the address to
    serve the control API on (by default :func:`default_control`), or None."""
    if no_control:
        if control is not None:
            raise usage_error("--control and --no-control exclude each other")
        return None
    if control is None:
        return default_control(name)
    from devsim.runtime.control import ControlAddressError, parse_address

    try:
        address = parse_address(control)
    except ControlAddressError as exc:
        raise usage_error(f"--control: {exc}") from None
    if not allow_remote and not address.is_loopback():
        raise usage_error(f"--control: refusing non-loopback host {address.host!r} (add --control-allow-remote)")
    return address
