"""A pytest plugin that records what the tests feed into device ports, as a fuzzing corpus.

    python -m pytest -q -p tests.fuzz.corpus tests/sers tests/gms96 tests/poselesta tests/ip247 tests/pcd4h3

writes ``.fuzz/corpus-<pid>.json``: for each kind and port, every distinct chunk (up to 512 bytes)
a test fed in, in hex.  :mod:`tests.fuzz.kinds` mutates them.
"""

from __future__ import annotations

import json
import os
from collections import defaultdict
from typing import Any

from devsim.core import device as _device

DIRECTORY = ".fuzz"
_seen: defaultdict[str, set[bytes]] = defaultdict(set)
_feed = _device.Port.feed


def _recording_feed(self: _device.Port, data: bytes) -> None:
    if 0 < len(data) <= 512:
        _seen[f"{self.device.kind}/{self.name}"].add(bytes(data))
    _feed(self, data)


_device.Port.feed = _recording_feed  # type: ignore[method-assign]


def pytest_sessionfinish(session: Any, exitstatus: int) -> None:
    os.makedirs(DIRECTORY, exist_ok=True)
    path = os.path.join(DIRECTORY, f"corpus-{os.getpid()}.json")
    with open(path, "w") as fh:
        json.dump({key: sorted(chunk.hex() for chunk in chunks) for key, chunks in _seen.items()}, fh)
