"""Non-volatile memory (EEPROM / flash) of one device, kept in the state dir.

The whole memory image is one JSON document, written atomically: the new image goes to a
temporary file in the same directory, is flushed and fsync'ed, then renamed over the old file
(and the directory is fsync'ed).  A ``kill -9`` at any instant therefore leaves either the old
image or the new one, never a torn file.  Without a state dir the memory lives in RAM only (it
still survives a simulated power cycle, just not a simulator restart).

One simulator owns a device's memory at a time: an OS file lock (``NAME.nvram.lock``, held
while the device lives) refuses a second owner with :class:`MemoryInUse`, so that a second
simulator on the same state dir can neither overwrite an acknowledged save nor delete the
first one's temporary file.  Nothing non-finite is ever written, and an image holding NaN or
infinity is refused at load (:class:`PoisonedMemory`).

A write the file system refuses (a full disk, ``EIO``) does not reach the device: the image it
holds is the simulated EEPROM, so the device answers as having saved, one line on stderr says
the file is behind (``devsim: memory FILE: No space left on device; kept in memory until a
write succeeds``), and the next write, or the close at the end, writes the whole image again.
"""

from __future__ import annotations

import fcntl
import os
import re
from collections.abc import Collection, Container, Mapping
from typing import TYPE_CHECKING, Any

import msgspec

from devsim.core.console import warn

if TYPE_CHECKING:  # imported where used: a device without a state dir needs neither
    from pathlib import Path

__all__ = [
    "KIND_KEY", "UNUSABLE", "MemoryInUse", "NonVolatileMemory", "OtherKindsMemory", "PoisonedMemory", "UnfitMemory",
    "check_name", "numbered", "stored_hex", "stored_key", "stored_object", "stored_whole",
]

_NAME = re.compile(r"^[A-Za-z0-9_][A-Za-z0-9_.-]{0,127}$")
_KEY = re.compile(r"0|-?[1-9][0-9]{0,18}", re.ASCII)  # str(n) of a 64-bit int (ASCII digits only)


class MemoryInUse(RuntimeError):
    """Another simulator holds this device's memory."""


class PoisonedMemory(ValueError):
    """The stored image holds a value no device accepts (NaN, infinity)."""


class OtherKindsMemory(ValueError):
    """The stored image is the memory of a device of another kind (the same name, another kind)."""


class UnfitMemory(ValueError):
    """A device's stored memory image has sections of a shape its kind does not read (raised by
    :meth:`devsim.runtime.Runtime.add_device`, which names the file)."""


#: What makes a state file one a device cannot start on: ``devsim run``, ``up`` and ``scenario
#: run`` say so in one line naming the file.
UNUSABLE = (MemoryInUse, PoisonedMemory, OtherKindsMemory, UnfitMemory)


#: The key under which an image written for a kind names it (not a section: ``get`` never sees it).
KIND_KEY = "devsim-kind"


def check_name(name: str, what: str = "device name") -> str:
    """A name that becomes a file name: letters, digits, ``_ . -``, not starting with a dot,
    so that it stays inside its directory."""
    if not _NAME.match(name) or ".." in name:
        raise ValueError(f"{what} {name!r} cannot name a file (use letters, digits, _ . -; no leading dot)")
    return name


def stored_whole(value: object, what: str, numbers: Container[int] | None = None) -> int:
    """A number a device stored as a JSON integer (not a bool, a fraction, text), one of
    ``numbers`` when given; anything else is a ValueError naming ``what``, so that the start
    refuses the memory (:class:`UnfitMemory`, naming the file)."""
    if type(value) is not int or numbers is not None and value not in numbers:
        raise ValueError(f"stored {what} {value!r:.40} is none the device stores")
    return value


def stored_object(value: object, what: str, keys: Collection[str], optional: Collection[str] = ()) -> dict[str, Any]:
    """``value`` if it is a JSON object of the entries a device's save writes: all of ``keys``, and
    any of ``optional`` (one an older devsim did not write yet), nothing else.  Anything else is a
    ValueError naming ``what``: null, ``[]``, ``0``, ``""`` or ``{}`` read as nothing stored, so a
    damaged section loaded as the factory's data without a word."""
    if type(value) is not dict or not set(keys) <= value.keys() or not value.keys() <= {*keys, *optional}:
        raise ValueError(f"stored {what} {value!r:.40} is not what the device writes (an object of {', '.join(keys)})")
    return value


def stored_hex(value: object) -> bytes | None:
    """The bytes of ``value`` if it is text as ``bytes.hex()`` writes them (lowercase hex pairs,
    nothing between them), else None: ``bytes.fromhex`` also reads capitals, blanks and newlines,
    which no device's save writes."""
    if type(value) is not str:
        return None
    try:
        data = bytes.fromhex(value)
    except ValueError:
        return None
    return data if data.hex() == value else None


def stored_key(key: object, what: str, numbers: Container[int] | None = None) -> int:
    """The number of a section's key as a device writes it (``str(n)``: ASCII digits, a ``-``
    for a negative, no leading zero), one of ``numbers`` when given; anything else is a
    ValueError naming ``what``.  ``int`` also reads other scripts' digits (``'٣'``), ``'1_0'``,
    ``' 3'``, ``'+3'`` and ``'03'``: a hand-edited key the device never wrote, which could even
    be a second entry for a number already stored."""
    if type(key) is not str or _KEY.fullmatch(key) is None:
        raise ValueError(f"stored {what} {key!r:.40} is no number the device writes")
    return stored_whole(int(key), what, numbers)


def numbered(section: object, what: str, numbers: Container[int] | None = None) -> dict[int, Any]:
    """A stored section ``{str(n): value}`` by its numbers (:func:`stored_key`); a section that is
    no JSON object is a ValueError too."""
    if type(section) is not dict:
        raise ValueError(f"stored {what}s {section!r:.40} are no numbered entries")
    return {stored_key(key, what, numbers): value for key, value in section.items()}


def _reject_constant(token: str) -> Any:
    raise PoisonedMemory(f"holds a non-finite number ({token})")


def _finite_float(token: str) -> float:
    """A JSON number as a float; one beyond the floats (``1e999``, which ``float`` makes
    infinite) is refused as NaN and Infinity are."""
    value = float(token)
    if value - value != 0.0:
        _reject_constant(token)
    return value


class NonVolatileMemory:
    """Sections of JSON-serialisable data, persisted together.

    ``get(section)`` returns a deep copy, so a device cannot change stored data by accident;
    ``put(section, data)`` replaces a section and writes the image through at once.
    """

    def __init__(self, path: str | os.PathLike[str] | None = None, kind: str | None = None) -> None:
        self.path: Path | None = None
        #: the kind of the device that owns this memory: written with the image, and an image that
        #: names another is refused (:class:`OtherKindsMemory`); an image without it (older
        #: devsim, a hand-made file) is taken as it is
        self.kind = kind
        if path is not None:
            from pathlib import Path

            self.path = Path(path)
        self._image: dict[str, Any] = {}
        self._lock: int | None = None
        self.behind = False  # the file lacks a change the file system refused
        if self.path is not None:
            self._take_lock()
            # temp files of a write that was killed half-way: the old image is intact
            for stale in self.path.parent.glob(self.path.name + ".*.tmp"):
                stale.unlink(missing_ok=True)
        #: an unreadable file the first write moves aside instead of replacing (the user's data)
        self._unreadable: Path | None = None
        if self.path is not None and self.path.exists():
            import json

            try:
                image = json.loads(self.path.read_text("utf-8"), parse_constant=_reject_constant,
                                   parse_float=_finite_float)
                if type(image) is not dict:  # (a list, a number, null: no memory image either)
                    raise ValueError(f"holds a JSON {type(image).__name__}, not an object of sections")
            except PoisonedMemory as exc:
                self.close()
                raise PoisonedMemory(f"{self.path}: {exc}; refusing to load it (fix or delete the file)") from None
            except (OSError, ValueError, RecursionError) as exc:  # (nested deeper than the decoder goes)
                # A file we cannot read is treated like an erased EEPROM; the device decides
                # what that means (e.g. the SERS shows display '7').  [SIM-CHOICE] The file is
                # the user's, not the simulated chip: it stays as it is until the device first
                # saves, which moves it aside to NAME.nvram.json.unreadable instead of losing it.
                reason = exc.strerror if isinstance(exc, OSError) and exc.strerror else str(exc) or type(exc).__name__
                if isinstance(exc, RecursionError):
                    reason = "nested deeper than the decoder goes"
                warn(f"devsim: memory {self.path}: unreadable ({reason}); the device starts with an erased memory,"
                     " and its first save moves the file aside instead of replacing it")
                self._image = {}
                self.corrupt = True
                self._unreadable = self.path
                return
            stored_kind = image.pop(KIND_KEY, None)
            if kind is not None and stored_kind is not None and stored_kind != kind:
                self.close()
                raise OtherKindsMemory(
                    f"{self.path}: holds the memory of a {stored_kind!r} device, not of a {kind!r};"
                    " give this device another name or another --state-dir (the file is left as it is)")
            self._image = image
        self.corrupt = False

    def _take_lock(self) -> None:
        assert self.path is not None
        lock_path = self.path.with_name(self.path.name + ".lock")
        fd = os.open(lock_path, os.O_RDWR | os.O_CREAT | os.O_NOFOLLOW | os.O_CLOEXEC, 0o644)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            owner = os.pread(fd, 32, 0).decode("ascii", "replace").strip() or "?"
            os.close(fd)
            raise MemoryInUse(
                f"{self.path.parent}: the memory of {self.path.name.removesuffix('.nvram.json')!r} is in use by"
                f" another simulator (pid {owner}); give each simulator its own --state-dir"
            ) from None
        os.ftruncate(fd, 0)
        os.pwrite(fd, f"{os.getpid()}\n".encode(), 0)
        self._lock = fd

    def close(self) -> None:
        """Release the memory's lock (the device is gone); the image stays on disk (one the file
        system refused before is written once more now)."""
        if self.behind:
            self._write()
            if self.behind:
                warn(f"devsim: memory {self.path}: its last changes are lost")
                self.behind = False
        if self._lock is not None:
            os.close(self._lock)
            self._lock = None

    @classmethod
    def for_device(cls, state_dir: str | os.PathLike[str] | None, name: str,
                   kind: str | None = None) -> NonVolatileMemory:
        check_name(name)
        if state_dir is None:
            return cls(None, kind)
        from pathlib import Path

        directory = Path(state_dir)
        directory.mkdir(parents=True, exist_ok=True)
        return cls(directory / f"{name}.nvram.json", kind)

    def __contains__(self, section: object) -> bool:
        """Whether the image holds ``section`` (one stored as ``null`` too: ``get`` cannot tell it
        from an absent one)."""
        return section in self._image

    def get(self, section: str, default: Any = None) -> Any:
        if section not in self._image:
            return _copied(default)
        return _copied(self._image[section])

    def put(self, section: str, data: Any) -> None:
        """Store ``data`` as ``section`` and save the image; data the file cannot hold (NaN,
        infinity, text with a lone surrogate) raises :class:`PoisonedMemory` and the section keeps
        what it held."""
        self.put_sections({section: data})

    def put_sections(self, sections: Mapping[str, Any]) -> None:
        """Store several sections with one write of the image, so that a kill leaves all of them
        or none (a save of one record over several sections, written one ``put`` each, left the
        first without the rest); data the file cannot hold leaves each section as it was."""
        try:
            copied = {section: _copied(data) for section, data in sections.items()}
        except ValueError as exc:
            raise PoisonedMemory(f"{self.path or 'memory'}: refusing to save a non-finite number ({exc})") from None
        before = {section: self._image[section] for section in copied if section in self._image}
        self._image.update(copied)
        try:
            self._write()
        except PoisonedMemory:
            for section in copied:
                if section in before:
                    self._image[section] = before[section]
                else:
                    del self._image[section]
            raise

    def delete(self, *sections: str) -> None:
        """Remove ``sections`` with one write of the image (a kill leaves all of them or none)."""
        removed = [self._image.pop(section) for section in sections if section in self._image]
        if removed:
            self._write()

    def wipe(self) -> None:
        self._image = {}
        self._write()

    def sections(self) -> list[str]:
        return sorted(self._image)

    def _write(self) -> None:
        if self.path is None:
            return
        # (the image holds finite numbers only, put() sees to it; msgspec formats as json.dumps
        # with indent=1 and sorted keys does, in C: a whole-memory save of a full POSELESTA
        # program memory took 13 ms in json's pure-Python indenting encoder)
        image = self._image if self.kind is None else {KIND_KEY: self.kind, **self._image}
        try:
            data = msgspec.json.format(msgspec.json.encode(image, order="sorted"), indent=1)
        except UnicodeEncodeError as exc:  # (a lone surrogate: once in the image, no write succeeded again)
            raise PoisonedMemory(f"{self.path}: refusing to save text that is no text ({exc.object!r:.40})") from None
        try:
            self._save(data)
        except OSError as exc:
            if not self.behind:
                warn(f"devsim: memory {self.path}: {exc.strerror or exc}; kept in memory until a write succeeds")
                self.behind = True
            return
        if self.behind:
            warn(f"devsim: memory {self.path}: saved again")
            self.behind = False

    def _save(self, data: bytes) -> None:
        assert self.path is not None
        directory = self.path.parent
        if self._unreadable is not None:
            self._keep_unreadable()
        import tempfile  # only when memory is written: start-up does without it

        fd, tmp = tempfile.mkstemp(prefix=self.path.name + ".", suffix=".tmp", dir=directory)
        try:
            with os.fdopen(fd, "wb") as fh:
                fh.write(data)
                fh.flush()
                os.fsync(fh.fileno())
            os.replace(tmp, self.path)
        except BaseException:
            try:
                os.unlink(tmp)
            except OSError:
                pass
            raise
        dfd = os.open(directory, os.O_RDONLY)
        try:
            os.fsync(dfd)
        finally:
            os.close(dfd)

    def _keep_unreadable(self) -> None:
        """Move the file load could not read to ``NAME.nvram.json.unreadable`` (``.unreadable.1``
        ... when that exists), so that the save replacing it loses nothing of the user's."""
        assert self.path is not None
        if not self.path.is_file() or self.path.is_symlink():  # (a directory in its place: the save fails)
            self._unreadable = None
            return
        aside = self.path.with_name(self.path.name + ".unreadable")
        number = 0
        while aside.exists() or aside.is_symlink():
            number += 1
            aside = self.path.with_name(f"{self.path.name}.unreadable.{number}")
        os.rename(self.path, aside)  # (an OSError: the save is refused, the file stays where it is)
        self._unreadable = None
        warn(f"devsim: memory {self.path}: the unreadable file is kept as {aside}")


_IMMUTABLE = frozenset({int, float, str, bool, type(None), bytes})


def _copied(data: Any) -> Any:
    """A deep copy of a section (what a JSON document holds: dicts, lists, numbers, text), so that
    the image never shares a mutable value with a device; anything else through
    :func:`copy.deepcopy` (the copy module is not imported by a start, issue 31)."""
    kind = type(data)
    if kind is float and data - data != 0.0:  # (NaN, infinity: no JSON number; ValueError)
        raise ValueError(f"{data!r} is no finite number")
    if kind in _IMMUTABLE:
        return data
    if kind is dict:
        return {key: _copied(value) for key, value in data.items()}
    if kind is list:
        return [_copied(value) for value in data]
    if kind is tuple:
        return tuple(_copied(value) for value in data)
    import copy

    return copy.deepcopy(data)
