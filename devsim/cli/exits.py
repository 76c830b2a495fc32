"""The exit statuses of every ``devsim`` command: one kind of mistake, one status, whichever
command meets it (docs/cli.md has the same table for users; a test runs each row through the CLI).

=====  ===============  =================================================================================
 code   name             when
=====  ===============  =================================================================================
 0      ``OK``           it worked (a server stopped by Ctrl-C or SIGTERM ends with 0 too)
 1      ``FAILED``       it ran and the result is "no": a scenario's expectation failed
 2      ``USAGE``        the command line is wrong: an unknown option or kind, a bad option value
 3      ``BAD_FILE``     a file named on the command line is missing, unreadable or wrong (YAML, schema,
                         misspelt names): a config, plant, scenario, session or motion log
 4      ``REFUSED``      the simulator refused a request: no such device, name or fault, a value of the
                         wrong type or out of range, ``advance`` without virtual time
 5      ``UNREACHABLE``  no simulator (or fleet broker, or device port) answers at the address, or the
                         connection broke
 6      ``SYSTEM``       this machine stopped it: a port in use, a file that cannot be written, a
                         missing extra (the line names the ``pip install``)
 130    ``INTERRUPTED``  Ctrl-C before the command was ready to stop cleanly
=====  ===============  =================================================================================

Each status but ``OK``, ``FAILED`` and ``INTERRUPTED`` has a :class:`click.ClickException` here; the
``devsim`` group (:class:`devsim.cli.main._Cli`) prints its message as one ``Error:`` line on stderr
and exits with its status.
"""

from __future__ import annotations

import click

__all__ = [
    "BAD_FILE",
    "EXIT_CODES",
    "FAILED",
    "INTERRUPTED",
    "OK",
    "REFUSED",
    "SYSTEM",
    "UNREACHABLE",
    "USAGE",
    "BadFile",
    "MissingExtra",
    "Refused",
    "SystemFailure",
    "Unreachable",
    "StartFailure",
    "control_error",
    "failure",
    "start_status",
]

OK = 0
FAILED = 1
USAGE = 2  # click's own status for a usage error
BAD_FILE = 3
REFUSED = 4
UNREACHABLE = 5
SYSTEM = 6
INTERRUPTED = 130  # 128 + SIGINT, as a shell reports it

#: Every status by name (docs and tests read it; the order is the table's).
EXIT_CODES: dict[str, int] = {
    "OK": OK,
    "FAILED": FAILED,
    "USAGE": USAGE,
    "BAD_FILE": BAD_FILE,
    "REFUSED": REFUSED,
    "UNREACHABLE": UNREACHABLE,
    "SYSTEM": SYSTEM,
    "INTERRUPTED": INTERRUPTED,
}


class BadFile(click.ClickException):
    """A file named on the command line is missing, unreadable or wrong."""

    exit_code = BAD_FILE


class Refused(click.ClickException):
    """The simulator answered a request with an error."""

    exit_code = REFUSED


class Unreachable(click.ClickException):
    """Nothing answers at the address, or the connection broke."""

    exit_code = UNREACHABLE


class SystemFailure(click.ClickException):
    """The machine stopped the command: a port in use, a file that cannot be written."""

    exit_code = SYSTEM


class MissingExtra(SystemFailure):
    """A feature's libraries are not installed; the message names the ``pip install``."""


class StartFailure(Exception):
    """A server (``run``, ``up``) could not start: raised inside its event loop with the one line
    and the status, turned into :func:`failure` once ``asyncio.run`` has returned."""

    def __init__(self, message: str, status: int) -> None:
        super().__init__(message)
        self.status = status


def failure(status: int, message: str) -> click.ClickException:
    """The one-line error that exits with ``status``."""
    error = click.ClickException(message)
    error.exit_code = status
    return error


def start_status(exc: BaseException) -> int:
    """The status of a server that could not start: ``UNREACHABLE`` if what it connects to (a
    broker) does not answer, ``REFUSED`` if a fleet refused its names, else ``SYSTEM``."""
    if isinstance(exc, ConnectionError):
        return UNREACHABLE
    if type(exc).__name__ == "FleetClash":
        return REFUSED
    return SYSTEM


#: Errors of the control API (``ControlError.type``) that say the device was not reached.
NOT_REACHED = frozenset({"Offline", "Timeout"})


def control_error(exc: Exception) -> click.ClickException:
    """The one-line error of a control API error (a :class:`devsim.runtime.client.ControlError`):
    ``Unreachable`` if the device was not reached (a fleet's offline or silent process), else
    ``Refused`` (``UnknownName: sers has no 'axis.positon' ...``)."""
    if getattr(exc, "type", None) in NOT_REACHED:
        return Unreachable(str(exc))
    return Refused(str(exc))
