"""A device made on a state file as ``devsim run --state-dir`` makes it (``Runtime.add_device``)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from devsim.core.nvram import UnfitMemory
from devsim.runtime import Runtime


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
