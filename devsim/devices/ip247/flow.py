"""The order in which an IP247 traverse program's blocks run, and the M function the module
shows for each (manual §2.6.5, §2.6.6.4, §2.6.9; spec ip247.md §4.11.5, §4.11.8).

Blocks run in textual order; ``G24 F n`` … ``G20`` repeats n times (F0 endlessly, only in the
main program: error 38), ``L p`` runs program p up to its M02 and returns; loops and calls nest
at most 5 deep (error 39); a missing program is error 19.  The M function shown is M255 until a
traverse (X, G74) or dwell (G04) block brings one, and then that one until the next such block
with an M.  Pure: :func:`steps` yields ``(program, block, m)`` lazily (an endless loop never
ends) and keeps a caller's list of the programs it is inside (main program first).
"""

from __future__ import annotations

from collections.abc import Iterator

from devsim.devices.ip247.program import Block, Program

__all__ = ["FlowError", "MAX_DEPTH", "steps"]

MAX_DEPTH = 5
M_NONE = 255


class FlowError(ValueError):
    def __init__(self, error: int, program: int, block: int) -> None:
        super().__init__(f"module error {error} in program {program}, block {block}")
        self.error, self.program, self.block = error, program, block


def _moves(block: Block) -> bool:
    return block.x is not None or block.g in (74, 4)


def steps(programs: dict[int, Program], number: int, calls: list[int] | None = None) -> Iterator[
    tuple[int, Block, int]
]:
    """The blocks of program ``number`` as they run, each with the M function shown then;
    ``calls`` holds meanwhile the programs being executed, the main program and the subprograms
    it is in (manual §4.3.1: none of them can be changed or deleted)."""
    state = {"m": M_NONE}
    yield from _run(programs, number, 0, True, state, [] if calls is None else calls)


def _run(programs: dict[int, Program], number: int, depth: int, main: bool, state: dict[str, int],
         calls: list[int]) -> Iterator[tuple[int, Block, int]]:
    program = programs.get(number)
    if program is None:
        raise FlowError(19, number, 0)
    calls.append(number)
    try:
        yield from _blocks(programs, program, number, depth, main, state, calls)
    finally:
        calls.pop()


def _blocks(programs: dict[int, Program], program: Program, number: int, depth: int, main: bool,
            state: dict[str, int], calls: list[int]) -> Iterator[tuple[int, Block, int]]:
    blocks = program.blocks
    loops: list[list[int]] = []  # [index of the G24 block, passes left (-1 endless)]
    index = 0
    while index < len(blocks):
        block = blocks[index]
        if block.m is not None and block.m != 2 and _moves(block):
            state["m"] = block.m
        yield number, block, state["m"]
        if block.g == 24:
            if block.f == 0 and not main:
                raise FlowError(38, number, block.ordinal)
            if depth + len(loops) + 1 > MAX_DEPTH:
                raise FlowError(39, number, block.ordinal)
            loops.append([index, -1 if block.f == 0 else (block.f or 1) - 1])
        elif block.g == 20 and loops:
            start, left = loops[-1]
            if left != 0:
                if left > 0:
                    loops[-1][1] -= 1
                index = start + 1
                continue
            loops.pop()
        elif block.call is not None:
            if depth + len(loops) + 1 > MAX_DEPTH:
                raise FlowError(39, number, block.ordinal)
            yield from _run(programs, block.call, depth + len(loops) + 1, False, state, calls)
        if block.m == 2:
            return
        index += 1
