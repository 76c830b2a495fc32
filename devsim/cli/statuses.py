"""The exit statuses of every ``devsim`` command as numbers, and the failure of a server that
could not start, without click (:mod:`devsim.cli.exits` has the table and click's exceptions;
``devsim run``'s quick command line, :mod:`devsim.cli.quick`, imports no click)."""

from __future__ import annotations

__all__ = [
    "BAD_FILE",
    "EXIT_CODES",
    "FAILED",
    "INTERRUPTED",
    "OK",
    "REFUSED",
    "SYSTEM",
    "StartFailure",
    "UNREACHABLE",
    "USAGE",
    "file_failure",
    "make_dirs",
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


class StartFailure(Exception):
    """A server (``run``, ``up``) could not start: raised inside its event loop with the one line
    and the status, turned into :func:`devsim.cli.exits.failure` once ``asyncio.run`` has returned."""

    def __init__(self, message: str, status: int) -> None:
        super().__init__(message)
        self.status = status


def start_status(exc: BaseException) -> int:
    """The status of a server that could not start: ``UNREACHABLE`` if what it connects to (a
    broker) does not answer, ``REFUSED`` if a fleet refused its names, else ``SYSTEM``."""
    if isinstance(exc, ConnectionError):
        return UNREACHABLE
    if type(exc).__name__ == "FleetClash":
        return REFUSED
    return SYSTEM


def file_failure(option: str, exc: OSError) -> StartFailure:
    """A file that ``option`` names (``--trace``, ``--motion-log``) cannot be written
    (:class:`~devsim.transports.trace.TraceFileError`): one line naming the option, the file and
    why, ``--trace: adir: Is a directory``, status ``SYSTEM`` as a directory option's
    (:func:`devsim.cli.usage.check_dirs`).  Said as the port being opened, it named no option."""
    return StartFailure(f"{option}: {exc.filename}: {exc.strerror}", SYSTEM)


def make_dirs(dirs: dict[str, str | None]) -> None:
    """Make the directories that options name (option → the path given, or None) as a command
    starts; one that cannot be made (``/proc/td``) is :func:`file_failure` naming its option (said
    as the plant being started or the scenario run, it named none).  Without any, nothing is
    imported (``devsim run``'s start imports no pathlib it does not use)."""
    for option, directory in dirs.items():
        if directory is not None:
            from pathlib import Path

            try:
                Path(directory).mkdir(parents=True, exist_ok=True)
            except OSError as exc:
                raise file_failure(option, exc) from None
