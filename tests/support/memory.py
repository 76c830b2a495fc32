"""A device made on a state file as ``devsim run --state-dir`` makes it (``Runtime.add_device``),
and the state file's image as a device wrote it, to edit."""

from __future__ import annotations

import json
import subprocess
import sys
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import pytest

from devsim.core.nvram import NonVolatileMemory, UnfitMemory
from devsim.runtime import Runtime
from tests.support.process import ROOT, devsim_env


def refused_memory(state_dir: Path, kind: str, match: str | None = None,
                   config: dict[str, Any] | None = None) -> UnfitMemory:
    """The refusal of the memory in ``state_dir`` when a ``kind`` device (with ``config``) is made
    on it (the test fails when the device is made); ``match`` as :func:`pytest.raises` takes it."""
    runtime = Runtime(virtual=True, state_dir=state_dir).start()
    try:
        with pytest.raises(UnfitMemory, match=match) as refused:
            runtime.add_device(kind, None, config)
    finally:
        runtime.stop()
    return refused.value


def state_image(state_dir: Path, kind: str) -> dict[str, Any]:
    """The image of the ``kind`` device's state file in ``state_dir`` (its name is the kind's)."""
    image: dict[str, Any] = json.loads((state_dir / f"{kind}.nvram.json").read_text("utf-8"))
    return image


def write_state_image(state_dir: Path, kind: str, image: dict[str, Any]) -> Path:
    """``image`` as the ``kind`` device's state file in ``state_dir`` (a hand edit); its path."""
    path = state_dir / f"{kind}.nvram.json"
    path.write_text(json.dumps(image, ensure_ascii=False), "utf-8")
    return path


def refused_run(kind: str, state_dir: Path) -> tuple[int, str]:
    """A real ``devsim run KIND --pty --virtual --state-dir DIR --no-control`` on a memory it
    refuses: its exit status and stderr once it ended by itself (an AssertionError if it started
    and ran on)."""
    try:
        done = subprocess.run([sys.executable, "-m", "devsim", "run", kind, "--pty", "--virtual", "--state-dir",
                               str(state_dir), "--no-control"], cwd=ROOT, env=devsim_env(), stdin=subprocess.DEVNULL,
                              capture_output=True, text=True, timeout=60)
    except subprocess.TimeoutExpired as exc:
        raise AssertionError(f"the {kind} started on the edited state file: {exc.stderr!r}") from None
    return done.returncode, done.stderr


class Killed(BaseException):
    """The simulator killed (``kill -9``) as it writes a memory file."""


@contextmanager
def killed_at_write(nvram: NonVolatileMemory, at: int) -> Iterator[list[bytes]]:
    """Within the block, the ``at``-th write of ``nvram``'s file raises :class:`Killed` before it
    replaces the file, as a kill at that instant would (the block ends there, nothing else is
    caught); the writes are listed in what the block is given."""
    writes: list[bytes] = []
    write = nvram._save

    def killed(data: bytes) -> None:
        writes.append(data)
        if len(writes) == at:
            raise Killed
        write(data)

    nvram._save = killed  # type: ignore[method-assign]
    try:
        yield writes
    except Killed:
        pass
    finally:
        del nvram._save
