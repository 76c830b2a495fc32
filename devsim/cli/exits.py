"""The exit statuses of every ``devsim`` command: one kind of mistake, one status, whichever
command meets it (docs/cli.md has the same table for users; a test runs each row through the CLI).

=====  ===============  =================================================================================
 code   name             when
=====  ===============  =================================================================================
 0      ``OK``           it worked (a server stopped by Ctrl-C, SIGTERM or SIGHUP ends with 0 too)
 1      ``FAILED``       it ran and the result is "no": a scenario's expectation failed (and a command
                         whose output's reader went away: click's convention for EPIPE)
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
and exits with its status.  The numbers themselves, :class:`StartFailure` and :func:`start_status`
live in :mod:`devsim.cli.statuses` (without click, for ``devsim run``'s quick command line) and
are the same names here.
"""

from __future__ import annotations

import click

from devsim.cli.statuses import (
    BAD_FILE,
    EXIT_CODES,
    FAILED,
    INTERRUPTED,
    OK,
    REFUSED,
    SYSTEM,
    UNREACHABLE,
    USAGE,
    StartFailure,
    start_status,
)

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


def failure(status: int, message: str) -> click.ClickException:
    """The one-line error that exits with ``status``."""
    error = click.ClickException(message)
    error.exit_code = status
    return error


#: Errors of the control API (``ControlError.type``) that say the device was not reached.
NOT_REACHED = frozenset({"Offline", "Timeout", "Busy"})


def control_error(exc: Exception) -> click.ClickException:
    """The one-line error of a control API error (a :class:`devsim.runtime.client.ControlError`):
    ``Unreachable`` if the device was not reached (a fleet's offline or silent process), else
    ``Refused`` (``UnknownName: sers has no 'axis.positon' ...``)."""
    if getattr(exc, "type", None) in NOT_REACHED:
        return Unreachable(str(exc))
    return Refused(str(exc))
