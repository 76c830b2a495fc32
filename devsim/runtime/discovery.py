"""Where running simulators are found: one control socket per process in a runtime directory of
the user's own (``devsim run`` and ``devsim up`` open one unless told otherwise), and what
``devsim ps``, ``devsim ctl`` and ``devsim monitor`` make of them.

* The directory is ``$XDG_RUNTIME_DIR/devsim``, else ``devsim-UID`` in ``$TMPDIR`` (``/tmp``);
  also when ``$XDG_RUNTIME_DIR`` is no directory of the user's (one left from the session ``su``
  came from).
  It is made with mode 0700 and used only while it is a real directory (not a symlink), owned
  by the user, that nobody else may enter: a control socket can move machinery.
* A process's socket is ``NAME-PID.sock``, NAME the simulator's (the kind of ``devsim run``, the
  plant's name of ``devsim up``) reduced to letters, digits, ``_``, ``-`` and single dots
  (:func:`safe_name`), so that a name never leads out of the directory.
* :func:`running` asks every socket there for its ``info`` (the control op); a socket nobody
  listens on any more, left by a process that was killed, is removed.
* :func:`choose` picks the one a command means: the only one running, or the one named.
"""

from __future__ import annotations

import contextlib
import os
import re
import stat
import time
from typing import TYPE_CHECKING, Any

import msgspec

from devsim.core.points import ascii_digits
from devsim.runtime.control import ControlAddressError, parse_address

if TYPE_CHECKING:
    from pathlib import Path

__all__ = [
    "DiscoveryError",
    "RuntimeDirError",
    "Simulator",
    "choose",
    "control_file",
    "control_path",
    "is_address",
    "listing",
    "runtime_dir",
    "running",
    "safe_name",
]

#: The longest path a Unix socket address holds (``sun_path``, Linux), less its NUL byte.
MAX_SOCKET_PATH = 107
#: Seconds a socket nobody listens on is left alone while the process named in it lives.
STARTING = 5.0
_WORDS = re.compile(r"[A-Za-z0-9-]+(?:\.[A-Za-z0-9-]+)*")


class RuntimeDirError(OSError):
    """The runtime directory cannot be made or is not safe to use."""


class DiscoveryError(LookupError):
    """No simulator, several where one was meant, or none of the name asked for; ``several``
    when the user has to choose among the running ones."""

    def __init__(self, message: str, *, several: bool = False) -> None:
        super().__init__(message)
        self.several = several

    def __str__(self) -> str:
        return str(self.args[0])


class Simulator(msgspec.Struct, frozen=True):
    """One running simulator, as its control socket describes it (``info``)."""

    address: str
    name: str
    pid: int | None = None
    kinds: list[str] = []
    devices: list[str] = []
    ports: dict[str, str] = {}
    uptime: float | None = None
    clock: str | None = None
    answering: bool = True
    #: port key -> how it is captured (``link``, ``protocol``, ``port_byte``: ``devsim extcap``)
    captures: dict[str, dict[str, Any]] = {}


# -- the directory ------------------------------------------------------------------------------
def runtime_dir(*, create: bool = False) -> Path:
    """The user's runtime directory for control sockets (made when ``create``); a
    :class:`RuntimeDirError` when it is a symlink, not a directory, someone else's or open to
    others."""
    from pathlib import Path

    return Path(_runtime_dir(create))


def _runtime_dir(create: bool) -> str:
    """:func:`runtime_dir` as text, the way :class:`pathlib.Path` spells it (``devsim run``
    finds its socket's place without importing pathlib)."""
    xdg = os.environ.get("XDG_RUNTIME_DIR", "")
    if os.path.isabs(xdg) and _yours(xdg):
        path = _posix_path(f"{xdg}/devsim")
    else:
        path = _posix_path(f"{os.environ.get('TMPDIR') or '/tmp'}/devsim-{os.getuid()}")
    if create:
        try:
            os.mkdir(path, 0o700)
            os.chmod(path, 0o700)  # whatever the umask
        except FileExistsError:
            pass
        except OSError as exc:
            raise RuntimeDirError(f"cannot make the runtime directory {path}: {exc.strerror or exc}") from None
    try:
        info = os.lstat(path)
    except FileNotFoundError:
        return path  # not made yet: nothing runs
    if stat.S_ISLNK(info.st_mode):
        raise RuntimeDirError(f"the runtime directory {path} is a symlink; remove it")
    if not stat.S_ISDIR(info.st_mode):
        raise RuntimeDirError(f"the runtime directory {path} is not a directory; remove it")
    if info.st_uid != os.getuid():
        raise RuntimeDirError(f"the runtime directory {path} belongs to uid {info.st_uid}, not to you")
    if info.st_mode & 0o077:
        raise RuntimeDirError(f"the runtime directory {path} is open to others (mode "
                              f"{stat.S_IMODE(info.st_mode):o}); chmod 700 it")
    return path


def _yours(directory: str) -> bool:
    """Whether ``directory`` is a directory of this user's: a ``$XDG_RUNTIME_DIR`` that is gone
    or another user's (left from the session ``su`` or ``sudo -u`` came from) is not used, as
    if it were not set."""
    try:
        info = os.stat(directory)
    except OSError:
        return False
    return stat.S_ISDIR(info.st_mode) and info.st_uid == os.getuid()


def _posix_path(text: str) -> str:
    """``str(pathlib.PurePosixPath(text))``: empty and ``.`` parts dropped, ``..`` kept, a
    leading ``//`` kept (POSIX leaves its meaning open), ``.`` for nothing."""
    root = "//" if text.startswith("//") and not text.startswith("///") else "/" if text.startswith("/") else ""
    parts = [part for part in text.split("/") if part and part != "."]
    return root + "/".join(parts) if root or parts else "."


def safe_name(name: str) -> str:
    """``name`` as a file name that stays in its directory: its words of letters, digits and
    ``-`` (single dots kept between them, ``line.cell-a``) joined by ``_``, at most 40
    characters; ``devsim`` when nothing is left (``../../line 7`` is ``line_7``)."""
    return "_".join(_WORDS.findall(name))[:40] or "devsim"


def control_path(name: str, pid: int | None = None) -> Path:
    """The control socket of the simulator ``name`` in this process (or ``pid``): the runtime
    directory (made if need be) / ``NAME-PID.sock``."""
    from pathlib import Path

    return Path(control_file(name, pid))


def control_file(name: str, pid: int | None = None) -> str:
    """:func:`control_path` as text (what ``devsim run`` serves on, without pathlib)."""
    directory = _runtime_dir(True)
    file = f"{safe_name(name)}-{os.getpid() if pid is None else pid}.sock"
    path = _posix_path(f"{directory}/{file}")
    if "/" in file or os.path.dirname(path) != directory:  # safe_name keeps it there; say so loudly if that ever changes
        raise RuntimeDirError(f"{name!r} leads out of {directory}")
    if len(os.fsencode(path)) > MAX_SOCKET_PATH:
        raise RuntimeDirError(f"the socket path {path} is longer than a Unix socket address holds"
                              f" ({MAX_SOCKET_PATH} bytes); set XDG_RUNTIME_DIR to a shorter directory")
    return path


# -- the running simulators ---------------------------------------------------------------------
def _pid_of(path: Path) -> int | None:
    _, _, tail = path.stem.rpartition("-")
    return int(tail) if ascii_digits(tail) else None  # ('x-².sock': isdigit, not int)


def process_alive(pid: int | None) -> bool:
    """Whether a process ``pid`` exists (someone else's counts; None does not)."""
    if pid is None:
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (PermissionError, OverflowError):
        return True
    return True


def _ask(path: Path, timeout: float) -> Simulator | None:
    """The simulator behind the socket ``path``; None (and the socket removed) when nobody
    listens there any more."""
    from devsim.runtime import requests as rq
    from devsim.runtime.client import ControlClient, ControlError

    address = f"unix:{path}"
    try:
        client = ControlClient(address, timeout=timeout)
    except (ConnectionRefusedError, FileNotFoundError):
        # Nobody listens: a process killed before it could remove its socket (unless one has
        # bound it this very moment and listens a moment later: its pid lives, the socket is new).
        with contextlib.suppress(OSError):
            if not process_alive(_pid_of(path)) or time.time() - path.lstat().st_mtime > STARTING:
                path.unlink()
        return None
    except OSError:
        return Simulator(address, path.stem, _pid_of(path), answering=False)
    try:
        with client:
            info: dict[str, Any] = client.call(rq.Info())
        return msgspec.convert({**info, "address": address}, Simulator, strict=False)
    except (OSError, ValueError, ControlError, msgspec.ValidationError):  # busy, stopped or not a devsim
        return Simulator(address, path.stem, _pid_of(path), answering=False)


def running(timeout: float = 2.0) -> list[Simulator]:
    """The simulators whose sockets are in the runtime directory, by name then pid; sockets
    of processes that are gone are removed.  :class:`RuntimeDirError` if the directory is not
    safe (see :func:`runtime_dir`)."""
    directory = runtime_dir()
    if not directory.is_dir():
        return []
    found: list[Simulator] = []
    for path in sorted(directory.glob("*.sock")):
        try:
            info = os.lstat(path)
        except FileNotFoundError:
            continue
        if not stat.S_ISSOCK(info.st_mode) or info.st_uid != os.getuid():
            continue
        simulator = _ask(path, timeout)
        if simulator is not None:
            found.append(simulator)
    return sorted(found, key=lambda s: (s.name, s.pid or 0))


def listing(simulators: list[Simulator]) -> str:
    """One indented line per simulator: name, kinds, pid, address."""
    width = max((len(s.name) for s in simulators), default=0)
    kinds_width = max((len(", ".join(s.kinds)) for s in simulators), default=0)
    return "\n".join(f"  {s.name:<{width}}  {', '.join(s.kinds) or '?':<{kinds_width}}  pid {s.pid or '?'}  {s.address}"
                     for s in simulators)


def is_address(text: str) -> bool:
    """Whether ``text`` is a control address rather than a simulator's name."""
    if text.startswith(("unix:", "tcp:", "/", "[")) or ascii_digits(text):  # a bare number is a port
        return True
    try:
        parse_address(text)
    except ControlAddressError:
        return False
    return True


def choose(target: str | None, simulators: list[Simulator] | None = None) -> str:
    """The control address a command means: ``target`` itself when it is an address, the
    simulator named ``target``, or, without one, the only one running.  A
    :class:`DiscoveryError` otherwise: none runs, none has that name, or several could be
    meant (``several``: the message lists them)."""
    if target is not None and is_address(target):
        return str(parse_address(target)) if not target.startswith("/") else f"unix:{target}"
    found = running() if simulators is None else simulators
    live = [s for s in found if s.answering]
    if target is None:
        candidates = live
        if not candidates:
            raise DiscoveryError(f"no running simulator found in {runtime_dir()} (start one with"
                                 " 'devsim run KIND', or give --control ADDR)")
    else:
        candidates = [s for s in live if s.name == target or target in s.devices]
        named = [s for s in candidates if s.name == target]
        candidates = named or candidates
        if not candidates:
            have = ", ".join(sorted({s.name for s in live})) or "none"
            raise DiscoveryError(f"no running simulator named {target[:60]!r} (running: {have}; see 'devsim ps')")
    if len(candidates) > 1:
        names = [s.name for s in candidates]
        how = "--control NAME or --control ADDR" if len(set(names)) == len(names) else "--control ADDR"
        raise DiscoveryError(f"{len(candidates)} simulators are running; choose one with {how}:\n"
                             f"{listing(candidates)}", several=True)
    return candidates[0].address

