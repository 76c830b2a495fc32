"""What a SERS drive holds stays in the small form CPython gives instances of one class: a
dictionary sharing its keys with the other drives' (issue 31: under 20 KB a drive in a plant of
1,000).  CPython 3.11 shares the keys of up to 29 attributes; a 30th attribute made every drive's
dictionary a table of its own, 1.3 KB more a drive (``benchmarks/memory.py``: 19.0 → 20.3 KB)."""

from __future__ import annotations

import sys

from devsim.runtime import Runtime


def test_a_drive_keeps_its_attributes_in_a_dictionary_that_shares_its_keys() -> None:
    runtime = Runtime(virtual=True).start()
    try:
        drives = [runtime.add_device("sers", name=f"d{n}").model for n in (1, 2)]
        for drive in drives:
            assert sys.getsizeof(vars(drive)) < sys.getsizeof(dict(vars(drive))), len(vars(drive))
    finally:
        runtime.stop()
