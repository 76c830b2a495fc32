"""The stable symlink of a pty port (``--link /tmp/ttySERS``) and who holds it.

A simulator that is killed (``kill -9``, a power cut) leaves its link behind, and the kernel
hands the next pty the lowest free number – very often the one the dead simulator had, so the
stale link points at a pseudo-terminal that exists again (usually the new simulator's own).
Whether the pty exists therefore says nothing about whether the link is still held.

So the holder is recorded: next to the link ``DIR/NAME`` an *owner record* ``DIR/.NAME.owner``
(JSON: the holder's pid, its start time where the system tells it, the pty the link points at
and the command), written before the link and removed with it.  Starting on a link that exists:

* a symlink to something that is not a pseudo-terminal, or not a symlink at all: refused (a
  user's file or link is never replaced);
* an owner record whose process is alive (same pid and start time, not a zombie): refused, with
  a message naming that process;
* an owner record whose process is gone: the link is replaced (the dead simulator's);
* no owner record (a link from before records, or made by hand): replaced when its pty has
  vanished or is the one just opened for us; otherwise refused, the owner unknown.
"""

from __future__ import annotations

import contextlib
import os
import sys
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # json and pathlib imported where used: a pty without --link needs neither
    from pathlib import Path

__all__ = ["LinkInUse", "claim_link", "owner_record_path", "release_link"]


class LinkInUse(FileExistsError):
    """The link is held by a live process (or by something devsim did not make)."""


def owner_record_path(link: str) -> Path:
    """``DIR/.NAME.owner`` for the link ``DIR/NAME``."""
    from pathlib import Path

    path = Path(link)
    return path.with_name(f".{path.name}.owner")


def _started(pid: int) -> int | None:
    """The start time of ``pid`` in clock ticks since boot (Linux ``/proc/PID/stat`` field 22);
    None where it cannot be read."""
    stat = _stat_fields(pid)
    return int(stat[19]) if stat is not None and len(stat) > 19 else None


def _stat_fields(pid: int) -> list[str] | None:
    """The fields of ``/proc/PID/stat`` after the command name (state first), or None."""
    try:
        with open(f"/proc/{pid}/stat", encoding="ascii", errors="replace") as fh:
            text = fh.read()
    except OSError:
        return None
    return text.rpartition(")")[2].split()


def _alive(pid: int, started: int | None) -> bool:
    """Whether process ``pid`` (started at ``started``, when known) still runs: not gone, not a
    zombie, not a later process that was given the same pid."""
    if pid <= 0:
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        pass  # someone else's process: it exists
    stat = _stat_fields(pid)
    if stat is None:
        return True  # no /proc here: the pid exists, trust it
    if stat and stat[0] in ("Z", "X"):
        return False
    return started is None or len(stat) <= 19 or int(stat[19]) == started


def _read_record(link: str) -> dict[str, Any] | None:
    import json

    try:
        data = json.loads(owner_record_path(link).read_text("utf-8"))
    except (OSError, ValueError):
        return None
    return data if isinstance(data, dict) and isinstance(data.get("pid"), int) else None


def _command() -> str:
    """This process's command line as a user typed it (``devsim run sers --pty ...``)."""
    argv = sys.argv or ["?"]
    words = ["devsim", *argv[1:]] if argv[0].endswith(("__main__.py", "devsim")) else argv
    return " ".join(words)[:200]


def _check(link: str, target: str) -> None:
    """Raise :class:`LinkInUse` unless the existing ``link`` may be pointed at ``target``."""
    if not os.path.islink(link):
        raise LinkInUse(f"{link} exists and is not a symlink; not replacing it")
    old = os.readlink(link)
    if not old.startswith("/dev/pts/"):
        raise LinkInUse(f"{link} points at {old}, not at a pseudo-terminal; not replacing it")
    record = _read_record(link)
    if record is not None:
        pid = int(record["pid"])
        started = record.get("started")
        if _alive(pid, started if isinstance(started, int) else None):
            command = str(record.get("command") or "?")
            raise LinkInUse(f"{link} is held by a live process, pid {pid} ({command}); stop it or choose"
                            " another --link")
        return  # its holder is gone: a link a killed simulator left
    if old != target and os.path.exists(old):
        raise LinkInUse(f"{link} points at {old}, a pseudo-terminal in use by an unknown process (no owner"
                        f" record {owner_record_path(link).name}); not replacing it")


def _replace(path: str, write: Any) -> None:
    """Make ``path`` atomically: ``write(tmp)`` then rename over it."""
    tmp = f"{path}.{os.getpid()}.tmp"
    with contextlib.suppress(FileNotFoundError):
        os.unlink(tmp)
    write(tmp)
    try:
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise


def claim_link(target: str, link: str) -> None:
    """Point ``link`` at the pty ``target`` and record this process as its holder (see the
    module docstring for when an existing link is replaced); :class:`LinkInUse` otherwise."""
    if os.path.lexists(link):
        _check(link, target)
    record = {"pid": os.getpid(), "started": _started(os.getpid()), "pty": target, "command": _command()}

    def write_record(tmp: str) -> None:
        import json

        fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_NOFOLLOW | os.O_CLOEXEC, 0o644)
        with os.fdopen(fd, "w", encoding="utf-8") as out:
            json.dump(record, out)

    try:
        _replace(str(owner_record_path(link)), write_record)  # first: a crash after it leaves a record
        _replace(link, lambda tmp: os.symlink(target, tmp))
    except OSError as exc:  # (it named the temporary file it could not make beside the link)
        raise OSError(exc.errno, f"cannot make the link {link}: {exc.strerror}") from None


def release_link(target: str, link: str) -> None:
    """Remove ``link`` and its owner record if they are still this process's (pointing at
    ``target``); someone else's are left alone."""
    with contextlib.suppress(OSError):
        if os.path.islink(link) and os.readlink(link) == target:
            os.unlink(link)
    record = _read_record(link)
    if record is not None and record.get("pid") == os.getpid() and record.get("pty") == target:
        with contextlib.suppress(OSError):
            owner_record_path(link).unlink()
