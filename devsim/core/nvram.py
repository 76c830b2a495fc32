"""Non-volatile memory (EEPROM / flash) of one device, kept in the state dir.

The whole memory image is one JSON document, written atomically: the new image goes to a
temporary file in the same directory, is flushed and fsync'ed, then renamed over the old file
(and the directory is fsync'ed).  A ``kill -9`` at any instant therefore leaves either the old
image or the new one, never a torn file.  Without a state dir the memory lives in RAM only (it
still survives a simulated power cycle, just not a simulator restart).
"""

from __future__ import annotations

import copy
import json
import os
import tempfile
from pathlib import Path
from typing import Any

__all__ = ["NonVolatileMemory"]


class NonVolatileMemory:
    """Sections of JSON-serialisable data, persisted together.

    ``get(section)`` returns a deep copy, so a device cannot change stored data by accident;
    ``put(section, data)`` replaces a section and writes the image through at once.
    """

    def __init__(self, path: str | os.PathLike[str] | None = None) -> None:
        self.path = Path(path) if path is not None else None
        self._image: dict[str, Any] = {}
        if self.path is not None:
            # temp files of a write that was killed half-way: the old image is intact
            for stale in self.path.parent.glob(self.path.name + ".*.tmp"):
                stale.unlink(missing_ok=True)
        if self.path is not None and self.path.exists():
            try:
                self._image = json.loads(self.path.read_text("utf-8"))
            except (OSError, ValueError):
                # A file we cannot read is treated like an erased EEPROM; the device decides
                # what that means (e.g. the SERS shows display '7').
                self._image = {}
                self.corrupt = True
                return
        self.corrupt = False

    @classmethod
    def for_device(cls, state_dir: str | os.PathLike[str] | None, name: str) -> NonVolatileMemory:
        if state_dir is None:
            return cls(None)
        directory = Path(state_dir)
        directory.mkdir(parents=True, exist_ok=True)
        return cls(directory / f"{name}.nvram.json")

    def get(self, section: str, default: Any = None) -> Any:
        if section not in self._image:
            return copy.deepcopy(default)
        return copy.deepcopy(self._image[section])

    def put(self, section: str, data: Any) -> None:
        self._image[section] = copy.deepcopy(data)
        self._write()

    def delete(self, section: str) -> None:
        if self._image.pop(section, None) is not None:
            self._write()

    def wipe(self) -> None:
        self._image = {}
        self._write()

    def sections(self) -> list[str]:
        return sorted(self._image)

    def _write(self) -> None:
        if self.path is None:
            return
        data = json.dumps(self._image, sort_keys=True, indent=1).encode("utf-8")
        directory = self.path.parent
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
