"""The card's FLASH: CNC programs and the PLC program image, and a running download (manual
§2.3.1 p, a, §2.5; spec §3.8.13, §3.8.24, §4.8, §4.9).
"""

from __future__ import annotations

from collections.abc import Container
from typing import Any

from devsim.core.nvram import NonVolatileMemory, numbered, stored_hex, stored_object, stored_whole
from devsim.devices.gms96.codec import S24_MAX, S24_MIN

__all__ = ["Flash"]

Program = list[list[Any]]  # rows [letter, P1, P2, P3, count]
#: the program numbers a card keeps (spec §3.8.13; config ``max_programs`` at most 100)
PROGRAMS = range(100)


class Flash:
    """Programs and the PLC image of one card, kept in its non-volatile memory (spec §4.8)."""

    def __init__(self, nvram: NonVolatileMemory, queued: Container[str], *, max_programs: int = 100,
                 max_commands: int = 8192, plc_bytes: int = 32768) -> None:
        self.nvram = nvram
        #: the letters of the queued commands: what a stored program's rows may be (power_on)
        self.queued = queued
        #: what the configured FLASH holds (``max_programs``, ``max_total_commands``,
        #: ``plc.flash_bytes``): no download stores more, and power_on refuses a memory holding more
        self.max_programs, self.max_commands, self.plc_bytes = max_programs, max_commands, plc_bytes
        self.programs: dict[int, Program] = {}
        self.plc_image: str | None = None  # hex of the downloaded ``a`` frames
        self.plc_frames: list[int] = []  # their lengths
        #: A running download: ("cnc" | "plc", program number, the recorded rows).
        self.download: tuple[str, int, list[list[Any]]] | None = None
        #: T3;4 I.4: the last CNC download did not fit (until a download fits or the next power-on).
        self.cnc_storage_error = False
        #: The ``flash_error`` fault: while set, no erase or write of the FLASH succeeds.
        self.defective = False
        #: T3;4 I.2 "Programmier-/Löschfehler des Flash-Speichers (z.B. nach Download)" (manual
        #: §2.3.1 T): the last erase or write of the FLASH failed, until one succeeds or the next
        #: power-on [SIM-CHOICE, as the storage error I.4].
        self.write_error = False

    def power_on(self) -> None:
        """The programs as downloads stored them; a program number a download never gives (0 … 99,
        written as ``str(n)``: not ``'٣'``, ``'03'``, ``'+3'``, ``'-3'``) is a ValueError, and the
        start refuses the memory naming its file (spec §3.8.13: programs 0 … 99)."""
        flash: dict[str, Any] = {"programs": {}, "plc": None}  # (nothing downloaded yet, or a wiped memory)
        if "flash" in self.nvram:  # what save() writes (null, {} or programs of null read as none before)
            flash = stored_object(self.nvram.get("flash"), "FLASH", flash, optional=("plc_frames",))
        self.programs = {number: [_queued(row, self.queued) for row in v]
                         for number, v in numbered(flash["programs"], "CNC program", PROGRAMS).items()}
        image = flash["plc"]  # (an older devsim wrote no frames: the image was one)
        self.plc_image, self.plc_frames = _plc(image, flash.get("plc_frames", [len(image) // 2] if type(image) is str else []))
        self._fits()
        self.download = None
        self.cnc_storage_error = False  # the programs in the FLASH are the ones that fitted
        self.write_error = False

    def _fits(self) -> None:
        """[SIM-CHOICE] Programs or a PLC image beyond what the configured FLASH holds (a state file
        of a card configured larger, or hand-edited): what a card does at power-on with memory it
        cannot hold is in no manual, so the start refuses the memory (UnfitMemory, naming the file)
        rather than keep programs no download could have stored (spec §3.8.13, §3.8.24)."""
        beyond = [number for number in self.programs if number >= self.max_programs]
        commands = sum(len(rows) for rows in self.programs.values())
        plc = sum(self.plc_frames)
        if beyond or commands > self.max_commands or plc > self.plc_bytes:
            raise ValueError(
                f"the stored FLASH holds more than the configured card keeps: programs {sorted(self.programs)} of"
                f" max_programs {self.max_programs}, {commands} commands of max_total_commands {self.max_commands},"
                f" a PLC image of {plc} bytes of plc.flash_bytes {self.plc_bytes}")

    def _writable(self) -> bool:
        """Whether an erase or write of the FLASH succeeds now (not while the ``flash_error`` fault
        is on); T3;4 I.2 tells how the last one went.  A failed one leaves the FLASH as it was."""
        self.write_error = self.defective
        return not self.defective

    def save(self) -> None:
        self.nvram.put(
            "flash",
            {"programs": {str(k): v for k, v in self.programs.items()}, "plc": self.plc_image,
             "plc_frames": list(self.plc_frames)},
        )

    def recording(self, kind: str) -> list[list[Any]] | None:
        """The rows a running ``kind`` download records, or None."""
        download = self.download
        return download[2] if download is not None and download[0] == kind else None

    def store_program(self, number: int, rows: Program, max_total: int) -> bool:
        """The end of a CNC download: program ``number`` (0: all programs anew); False (and the
        storage error) if the programs would exceed ``max_total`` commands (the programs a new
        program 0 deletes take no room: manual §2.3.1 p "alle zuvor vorhandenen Programme gelöscht")."""
        kept = [] if number == 0 else [p for k, p in self.programs.items() if k != number]
        total = sum(len(p) for p in kept) + len(rows)
        if total > max_total:
            self.cnc_storage_error = True
            return False
        self.cnc_storage_error = False
        if not self._writable():
            return False
        if number == 0:
            self.programs = {}
        self.programs[number] = rows
        self.save()
        return True

    def erase_plc(self) -> None:
        """``p1;100``: the PLC sector is erased (not while the FLASH is defective: T3;4 I.2)."""
        if not self._writable():
            return
        self.plc_image = None
        self.plc_frames = []
        self.save()

    def store_plc(self, frames: list[bytes]) -> bool:
        """``p1;101``: the ``a`` frames' data in order (an empty download leaves no program);
        False if the FLASH is defective (T3;4 I.2)."""
        if not self._writable():
            return False
        if frames:
            self.plc_image = b"".join(frames).hex()
            self.plc_frames = [len(f) for f in frames]
        self.save()
        return True


def _queued(row: Any, letters: Container[str]) -> list[Any]:
    """A stored program row as a download records it: ``[letter, P1, P2, P3, count]`` of a queued
    command (``letters``).  Another (a hand-edited state file) is a ValueError, so that the start
    refuses the memory naming its file; before, it loaded and the program's run failed in the
    executor (``Cmd(*row)``, a move's target, an M function) with a TypeError."""
    if (type(row) is not list or len(row) != 5 or not isinstance(row[0], str) or row[0] not in letters
            or any(type(value) is not int for value in row[1:])):
        raise ValueError(f"stored program row {row!r} is no command the card queues")
    # what a telegram carries (spec Appendix B): up to 3 parameters of 24 bits, signed, the ones not
    # sent 0 (before, P1 = 10**30 or a count of -1 loaded, and program.n served 'A1000…000')
    count, params = row[4], row[1:4]
    if not 0 <= count <= 3 or any(not S24_MIN <= p <= S24_MAX for p in params) or any(params[count:]):
        raise ValueError(f"stored program row {row!r:.60} is no command a 24-bit telegram carries")
    return row


def _plc(image: Any, frames: Any) -> tuple[str | None, list[int]]:
    """The stored PLC image and its frames as :meth:`Flash.store_plc` writes them: the ``a``
    frames' bytes as hex text, and their lengths, which add up to it (none without an image).
    Another (a hand-edited state file) is a ValueError, so that the start refuses the memory
    naming its file; before, an image of true, 5 or a list failed every read of ``plc``
    and ``state`` with TypeError, and "x" or frames that are not its bytes were served."""
    if image is None:
        if frames != []:
            raise ValueError(f"stored PLC frames {frames!r:.40} without a PLC image")
        return None, []
    if not stored_hex(image):  # (nor "": an empty download leaves no program)
        raise ValueError(f"stored PLC image {image!r:.40} is no bytes a download stores")
    if type(frames) is not list or sum(stored_whole(f, "PLC frame length", _FRAME) for f in frames) != len(image) // 2:
        raise ValueError(f"stored PLC frames {frames!r:.40} are not the {len(image) // 2} bytes of its image")
    return image, frames


_FRAME = range(256)  # a frame's bytes: the user data of one Langsatz (L < 256, spec §3.4)
