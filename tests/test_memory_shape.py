"""What a device holds stays in the small form CPython gives instances of one class: an instance
dictionary that shares its keys with the other devices' (issue 31: a device's share of a plant's
memory is what its state needs).  CPython 3.11 shares the keys of up to 29 attributes; one more
makes every device's dictionary a table of its own, 1.3 KB a device (``benchmarks/memory.py``:
a SERS drive's 30th attribute took it from 19.0 to 20.3 KB, over its 20 KB target)."""

from __future__ import annotations

import sys
from collections.abc import Iterator
from typing import Any

import pytest

from devsim.core.registry import kinds
from devsim.runtime import Runtime

SHARED_KEYS = 29


def _parts(x: Any, path: str = "model", depth: int = 3, seen: set[int] | None = None) -> Iterator[tuple[str, Any]]:
    """The model and the parts it holds, and theirs, to ``depth`` (devsim objects with an instance
    dictionary, also in lists: a PCD4.H3's drives and their LM628 chips)."""
    seen = set() if seen is None else seen
    if id(x) in seen:
        return
    seen.add(id(x))
    yield path, x
    if depth == 0:
        return
    for name, value in vars(x).items():
        for index, item in enumerate(value if type(value) in (list, tuple) else [value]):
            if type(item).__module__.startswith("devsim.") and hasattr(item, "__dict__"):
                where = f"{path}.{name}" + (f"[{index}]" if item is not value else "")
                yield from _parts(item, where, depth - 1, seen)


@pytest.mark.parametrize("kind", sorted(set(kinds()) - {"stub"}))
def test_a_device_and_its_parts_keep_dictionaries_that_share_their_keys(kind: str) -> None:
    runtime = Runtime(virtual=True).start()
    try:
        models = [runtime.add_device(kind, name=f"{kind}{n}").model for n in (1, 2)]
        for path, part in _parts(models[1]):
            assert len(vars(part)) <= SHARED_KEYS, (path, type(part).__name__, sorted(vars(part)))
        assert sys.getsizeof(vars(models[1])) < sys.getsizeof(dict(vars(models[1])))
    finally:
        runtime.stop()
