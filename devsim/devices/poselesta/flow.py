"""The order in which a program's blocks run (manual §2.3.13, §2.3.21; spec poselesta.md §4.3.2,
§4.3.6, §4.12.1 and the example §6.6): ascending N, blocks marked ``/`` skipped while the
block-skip input V22/1 is L, subroutines and repeats (G11–G13), and the jump of a block abort to
N = P90."""

from __future__ import annotations

from devsim.core.signals import SignalBank
from devsim.devices.poselesta.functions import BlockFunctions
from devsim.devices.poselesta.screen import Screen
from devsim.devices.poselesta.tape import Block

__all__ = ["CONTOUR_BREAKS", "ProgramFlow"]

#: The G functions of a following block that keep this block's contour from going on into it.
CONTOUR_BREAKS = frozenset((4, 9, 10, 11, 12, 13, 25, 60))


class ProgramFlow:
    """The blocks of the running program and the pointer to the next one (spec §4.3.2);
    ``g13_total``: the a of ``G13 L a.bbb`` counts the passes in all, not the jumps back (spec
    G-LOOP: the manual's example does not decide)."""

    def __init__(self, signals: SignalBank, screen: Screen, *, g13_total: bool = False) -> None:
        self._signals = signals
        self._screen = screen
        self._g13_passes_before = 1 if g13_total else 0  # the pass already run counts towards a
        self.blocks: list[Block] = []
        self.pointer = 0
        self.calls: list[list[int]] = []  # [return index, calls left, subroutine index] (G12)
        self.loops: dict[int, int] = {}  # G13 block index → jumps left

    def restart(self) -> None:
        """Back to the first block."""
        self.pointer = 0
        self.calls.clear()
        self.loops.clear()

    def _skipped(self, block: Block) -> bool:
        return block.skip and not self._signals.get("block_skip_cancel")

    def next_block(self) -> Block | None:
        """The next block in ascending N; a block marked ``/`` is skipped while the block-skip
        input is L (sampled now, §2.3.13); None past the last block (as M02)."""
        while self.pointer < len(self.blocks):
            block = self.blocks[self.pointer]
            if self._skipped(block):
                self._screen.record("block_skipped")
                self.pointer += 1
                continue
            return block
        return None

    def following(self) -> Block | None:
        """The block that runs after the current one if nothing jumps (no event)."""
        index = self.pointer + 1
        while index < len(self.blocks) and self._skipped(self.blocks[index]):
            index += 1
        return self.blocks[index] if index < len(self.blocks) else None

    def contour_goes_on(self, block: Block, functions: BlockFunctions) -> bool:
        """Does the next block continue this block's contour (spec §4.3.3)?  Then this one ends
        at its path speed: no exact positioning, travel commands on, no position reached."""
        if functions.motion not in (1, 2, 3) or functions.contour_ends or block.values("M"):
            return False
        following = self.following()
        if following is None:
            return False
        motion = next((g for g in reversed(following.values("G")) if g in (0, 1, 2, 3)), functions.motion)
        return (motion in (1, 2, 3) and not set(following.values("G")) & CONTOUR_BREAKS
                and not any(following.value(c) is not None for c in "MST")
                and any(following.value(c) is not None for c in "XYZD"))

    def after_block(self, block: Block, flow: set[int]) -> bool:
        """The block is done: on to the next, or where G11, G12 or G13 lead (spec §4.12.1,
        INFERRED from the manual's example §6.6): ``G12 L a.bbb`` calls the subroutine at N bbb
        a times, ``G11`` returns to the block after the call, ``G13 L a.bbb`` jumps back to N bbb
        a more times (a − 1 with ``g13_total``).  False when a jump leads to a missing block (the
        program ends)."""
        self.pointer += 1
        count, target = divmod(block.value("L") or 0, 1000)
        if 12 in flow:
            index = self._index(target)
            if index is None:
                return False
            if count > 0:
                self.calls.append([self.pointer, count - 1, index])
                self.pointer = index
        elif 11 in flow and self.calls:
            call = self.calls[-1]
            if call[1] > 0:
                call[1] -= 1
                self.pointer = call[2]
            else:
                self.calls.pop()
                self.pointer = call[0]
        elif 13 in flow:
            here = self.pointer - 1
            left = self.loops.get(here, count - self._g13_passes_before)
            if left > 0:
                index = self._index(target)
                if index is None:
                    return False
                self.loops[here] = left - 1
                self.pointer = index
            else:
                self.loops.pop(here, None)
        return True

    def _index(self, number: int) -> int | None:
        for index, candidate in enumerate(self.blocks):
            if candidate.number == number:
                return index
        self._screen.record("block_missing")
        self._screen.report("program", "block_missing", number)
        return None

    def jump(self, number: int) -> bool:
        """A block abort goes on at N = ``number`` (P90, spec §4.3.6); False if there is none."""
        index = next((i for i, b in enumerate(self.blocks) if b.number == number), None)
        if index is None:
            return False
        self.pointer = index
        return True
