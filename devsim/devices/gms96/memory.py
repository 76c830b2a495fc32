"""The card's EEPROM and its static data (manual §2.3.1 s, r, d, m101; spec §4.8).

``s85;170`` saves M, S, B, all N parameters and the override activity; they take effect at the
next start.  DW0..DW79 (data bytes 0..159) and the tool number MB18 survive a power failure.
"""

from __future__ import annotations

from collections.abc import Callable

from devsim.core.nvram import NonVolatileMemory, stored_object, stored_whole
from devsim.devices.gms96.feed import Feed
from devsim.devices.gms96.image import STATIC_BYTES, ProcessImage
from devsim.devices.gms96.params import NParameters

__all__ = ["Memory"]

BYTES = range(0x100)


class Memory:
    """EEPROM (parameters, speeds) and static data of one card in its non-volatile memory (spec §4.8)."""

    def __init__(
        self,
        nvram: NonVolatileMemory,
        params: NParameters,
        feed: Feed,
        image: ProcessImage,
        record_event: Callable[[str], None],
    ) -> None:
        self.nvram = nvram
        self.params = params
        self.feed = feed
        self.image = image
        self.record_event = record_event
        #: The memory could not be read at the start (an unreadable state file): the NV error of
        #: T3;4 I.5/I.6 (manual §2.3.1 T).  It stands at every start until ``s85;170`` has written
        #: the parameters again (spec §4.5.3: "reprogram + s85;170"), or the memory is wiped.
        self.unreadable = bool(nvram.corrupt)

    def load(self) -> bool:
        """Power-on: the parameters and speeds from the EEPROM, the static data; True if the
        memory could not be read (the NV error of T3;4)."""
        eeprom = None  # (none: r1 erased it, or s85;170 never ran)
        if "eeprom" in self.nvram:  # what s85;170 writes, every entry (null, {} or 0 read as none before)
            saved = {**self.feed.eeprom(), **self.params.eeprom()}
            eeprom = stored_object(self.nvram.get("eeprom"), "EEPROM", saved)
        self.params.power_on(eeprom)
        self.feed.power_on(eeprom)
        return self.unreadable

    def load_static(self) -> None:
        """DW0..DW79 and MB18 as :meth:`save_static` stores them: up to 160 bytes, a tool number
        0 … 127; anything else refuses the memory at the start (UnfitMemory): ``int() & 0xFF``
        took "٣", 1.5 and true, and made 300 or -5 another byte.  A stored section has both entries
        and all 160 bytes, as every save wrote them (null, {} or a data of [] read as none before)."""
        if "static" not in self.nvram:  # (no save yet, or a wiped memory)
            self.image.markers[18] = 0
            return
        st = stored_object(self.nvram.get("static"), "static data", ("data", "mb18"))
        data = st["data"]
        if type(data) is not list or len(data) != STATIC_BYTES:
            raise ValueError(f"stored static data {data!r:.40} is no {STATIC_BYTES} bytes")
        self.image.restore_static([stored_whole(value, "data byte", BYTES) for value in data])
        self.image.markers[18] = stored_whole(st["mb18"], "tool number MB18", range(0x80))

    def save_eeprom(self) -> None:
        """``s85;170``: M, S, B, all N and the override activity (manual §2.3.1 s)."""
        self.nvram.put("eeprom", {**self.feed.eeprom(), **self.params.eeprom()})
        self.feed.saved()
        self.unreadable = False
        self.record_event("eeprom_saved")

    def wipe(self) -> None:
        """The whole memory erased (a power cycle with ``wipe``): nothing left that fails to read."""
        self.nvram.wipe()
        self.unreadable = False

    def erase_eeprom(self) -> None:
        """``r1``: the next start uses the defaults."""
        self.nvram.delete("eeprom")

    def save_static(self) -> None:
        self.nvram.put("static", {"data": self.image.static_data(), "mb18": self.image.markers[18] & 0x7F})
