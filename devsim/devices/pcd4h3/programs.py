"""The manual's three example user programs as the simulated PLC runs them (manual §9.1–§9.3,
BSP01/02/03.SRC; spec pcd4h3.md §6.2–§6.5): the cyclic part after AxHndlg (cyclic reads, DP14,
the mode and stop keys of Example 3) and the motion program, a GRAFTEC sequential block of steps
and transitions.

A step's actions run once in the cycle it becomes active; its outgoing transitions are looked at
from the next cycle on, after AxHndlg has run what the step set (so ``STH F OnDest`` sees the new
move, as on the PCD).  A transition without a condition fires at once; of several transitions
leaving a step (an alternative branch) the first that holds fires.  Timers count down in tenths of
a second (``LD T 0 30`` = 3 s; ``STL T 0`` holds once it reached 0); the keys are PLC inputs
(I 8 start, and in Example 3 I 0 manual/automatic, I 9/I 10 jog, I 11 zero, I 15 stop), so the
examples want the manual's installation with FMAH3 48.  Declared as tables; one small runner.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, MutableMapping
from typing import Any

import msgspec

from devsim.core.kit import Command, Table
from devsim.devices.pcd4h3.library import H3Axis
from devsim.devices.pcd4h3.timers import Timers

__all__ = ["ACTIONS", "PROGRAMS", "Look", "Sequence", "Step", "Transition"]

Action = tuple[Any, ...]  # ("load", register, value) / ("set", flag) / ("timer", n, tenths) / ("counter", n, v) / ("dec", n)
Condition = Callable[["Look"], bool]  # of the PLC as a cycle of the user program sees it


class Step(msgspec.Struct, frozen=True):
    name: str
    actions: tuple[Action, ...] = ()


class Transition(msgspec.Struct, frozen=True):
    name: str
    source: str
    targets: tuple[str, ...]
    condition: Condition | None = None


class Program(msgspec.Struct, frozen=True):
    """A user program: its steps and transitions, the initial step, and the cyclic part."""

    steps: tuple[Step, ...]
    transitions: tuple[Transition, ...]
    initial: str = "IST0"
    cyclic_reads: tuple[str, ...] = ()
    display: bool = False  # DP14 2×6 of RActP over RSetV every cycle
    mode_keys: bool = False  # Example 3: I 0 edges restart the SB, I 15 stops the axis


def _flag(symbol: str) -> Condition:
    return lambda view: bool(view.flag(symbol))


def _input(n: int, level: bool = True) -> Condition:
    return lambda view: view.input(n) == level


def _timer_done(view: Look) -> bool:
    return view.timer(0) == 0


def _move(destination: int) -> tuple[Action, ...]:
    return (("load", "DestP", destination), ("set", "FLdDA"), ("set", "FStart"))


EXAMPLE_1 = Program(
    steps=(Step("IST0"), Step("ST1", _move(1000)), Step("ST2", (("timer", 0, 30),)), Step("ST3", _move(0))),
    transitions=(
        Transition("TR0", "IST0", ("ST1",), _input(8)),
        Transition("TR1", "ST1", ("ST2",), _flag("OnDest")),
        Transition("TR2", "ST2", ("ST3",), _timer_done),
        Transition("TR3", "ST3", ("IST0",), _flag("OnDest")),
    ),
)
"""BSP01 (manual §9.1): on the key I 8 to 100 mm, 3 s, back to 0."""

EXAMPLE_2 = Program(
    steps=(
        Step("IST0"),
        Step("ST1", (*_move(1000)[:2], ("load", "BrkP", 700), ("set", "FLdBPA"), ("load", "StaFRR", 0),
                     ("set", "FResSF"), ("set", "FStart"))),
        Step("ST2", (("load", "Veloc", 200), ("set", "FLdVA"), ("set", "FStart"))),
        Step("ST3", (("timer", 0, 30),)),
        Step("ST4", (("load", "DestP", 0), ("set", "FLdDA"), ("set", "FResSF"), ("set", "FStart"))),
        Step("ST5", (("load", "Veloc", 500), ("set", "FLdVA"), ("set", "FStart"))),
    ),
    transitions=(
        Transition("TR0", "IST0", ("ST1",), _input(8)),
        Transition("TR1", "ST1", ("ST2",), _flag("BrkPos")),
        Transition("TR2", "ST2", ("ST3",), _flag("OnDest")),
        Transition("TR3", "ST3", ("ST4",), _timer_done),
        Transition("TR4", "ST4", ("ST5",), _flag("BrkPos")),
        Transition("TR5", "ST5", ("IST0",), _flag("OnDest")),
    ),
    cyclic_reads=("FRdAP", "FRdSV"),
    display=True,
)
"""BSP02 (manual §9.2): fast to 70 mm, slow to 100 mm; back slow to 70 mm, fast to 0; DP14."""

EXAMPLE_3 = Program(
    steps=(
        Step("IST0"), Step("ST1"), Step("ST2"),
        Step("ST10", (("load", "Veloc", 100), ("set", "FLdVA"), *_move(1500)[:2], ("load", "BrkP", 300),
                      ("set", "FLdBPA"), ("load", "StaFRR", 0), ("set", "FResSF"), ("set", "FStart"))),
        Step("ST11", (("load", "Veloc", 500), ("set", "FLdVA"), ("load", "BrkP", 1100), ("set", "FLdBPA"),
                      ("set", "FResSF"), ("set", "FStart"))),
        Step("ST12", (("load", "Veloc", 100), ("set", "FLdVA"), ("set", "FStart"))),
        Step("ST13", (("timer", 0, 20),)),
        Step("ST15", (("load", "Veloc", 300), ("set", "FLdVA"), ("counter", 100, 5))),
        Step("ST16", (("load", "DestP", -300), ("set", "FLdDR"), ("set", "FStart"))),
        Step("ST17", (("dec", 100), ("timer", 0, 10))),
        Step("ST18"), Step("ST14"),
        Step("ST3"),
        Step("ST7", (("load", "Veloc", 200), ("set", "FLdVA"), ("set", "FForw"))),
        Step("ST8", (("set", "FStop"),)),
        Step("ST5", (("load", "Veloc", 200), ("set", "FLdVA"), ("set", "FBackw"))),
        Step("ST6", (("set", "FStop"),)),
        Step("ST4", (("set", "FSetZP"),)),
        Step("ST9"),
    ),
    transitions=(
        Transition("TR0", "IST0", ("ST1",), _input(0, False)),  # "input 0 = '0'": automatic (G-37)
        Transition("TR1", "IST0", ("ST3",), _input(0, True)),  # manual
        Transition("TR4", "ST1", ("ST2",), _input(8)),
        Transition("TR5", "ST2", ("ST10",)),
        Transition("TR16", "ST10", ("ST11",), _flag("BrkPos")),
        Transition("TR17", "ST11", ("ST12",), _flag("BrkPos")),
        Transition("TR18", "ST12", ("ST13",), _flag("OnDest")),
        Transition("TR19", "ST13", ("ST15",), _timer_done),
        Transition("TR22", "ST15", ("ST16",)),
        Transition("TR23", "ST16", ("ST17",), _flag("OnDest")),
        Transition("TR24", "ST17", ("ST18",), lambda v: v.counter(100) == 0 and _timer_done(v)),
        Transition("TR25", "ST17", ("ST16",), lambda v: v.counter(100) > 0 and _timer_done(v)),
        Transition("TR21", "ST18", ("ST14",)),
        Transition("TR7", "ST14", ("ST2",)),
        Transition("TR8", "ST3", ("ST7",), _input(9)),
        Transition("TR9", "ST3", ("ST5",), _input(10)),
        Transition("TR10", "ST3", ("ST4",), _input(11)),
        Transition("TR14", "ST7", ("ST8",), _input(9, False)),
        Transition("TR12", "ST5", ("ST6",), _input(10, False)),
        Transition("TR15", "ST8", ("ST9",)),
        Transition("TR13", "ST6", ("ST9",)),
        Transition("TR11", "ST4", ("ST9",)),
        Transition("TR3", "ST9", ("IST0",)),
    ),
    cyclic_reads=("FRdAP", "FRdSV"),
    display=True,
    mode_keys=True,
)
"""BSP03 (manual §9.3): automatic 0 → 150 mm with break positions at 30 and 110 mm, then five
relative −30 mm moves, endlessly; manual jog ±20 mm/s on I 9 / I 10, zero on I 11; I 0 switches
(restarting the SB at step 0, a running move is completed), I 15 stops."""

PROGRAMS: dict[str, Program] = {"example1": EXAMPLE_1, "example2": EXAMPLE_2, "example3": EXAMPLE_3}


class Look:
    """The PLC as a transition's condition sees it in a cycle that starts ``at`` (None: now): the
    flags of axis 1, the inputs, the counters, and the timers as they count at that start (spec
    pcd4h3.md §6.3 `STL T`, §6.5; manual §9.1, §9.3)."""

    __slots__ = ("at", "sequence")

    def __init__(self, sequence: Sequence, at: float | None) -> None:
        self.sequence, self.at = sequence, at

    def flag(self, symbol: str) -> int:
        return self.sequence.axis.flag(symbol)

    def input(self, n: int) -> bool:
        return self.sequence.input(n)

    def timer(self, n: int) -> int:
        return self.sequence.timers.value(n, self.at)

    def counter(self, n: int) -> int:
        return self.sequence.counters.get(n, 0)


class Sequence:
    """A running sequential block on axis 1 of a PLC: the axis (its registers and flags), the
    PLC's inputs and counters, and its timers."""

    def __init__(self, program: Program, axis: H3Axis, inputs: Mapping[int, int], counters: MutableMapping[int, int],
                 timers: Timers) -> None:
        self.program, self.axis = program, axis
        self.inputs, self.counters, self.timers = inputs, counters, timers
        self.steps = {step.name: step for step in program.steps}
        self.leaving: dict[str, list[Transition]] = {}
        for transition in program.transitions:
            self.leaving.setdefault(transition.source, []).append(transition)
        self.active: dict[str, bool] = {}  # name → actions done
        self.restart()
        self._keys = {n: self.input(n) for n in (0, 15)}

    def restart(self) -> None:
        """RSB: the initial step becomes the only active one."""
        self.active = {self.program.initial: False}

    def input(self, n: int) -> bool:
        return bool(self.inputs.get(n, 0))

    # -- the statements of a step's actions ------------------------------------------------------
    def load_register(self, action: Action) -> None:
        """``LD R symbol+RA1 value``."""
        self.axis.registers.load(action[1], action[2])

    def set_flag(self, action: Action) -> None:
        """``SET F symbol+FA1``."""
        self.axis.set_flag(action[1], 1)

    def load_timer(self, action: Action) -> None:
        """``LD T n tenths``."""
        self.timers.load(action[1], action[2])

    def load_counter(self, action: Action) -> None:
        """``LD C n value``."""
        self.counters[action[1]] = action[2]

    def decrement_counter(self, action: Action) -> None:
        """``DEC C n`` (not below 0)."""
        self.counters[action[1]] = max(0, self.counters.get(action[1], 0) - 1)

    # -- one call of the cyclic part after AxHndlg ---------------------------------------------
    def before_handling(self) -> None:
        for symbol in self.program.cyclic_reads:
            self.axis.set_flag(symbol, 1)
        if self.program.display:
            self.axis.set_flag("DplM", 1)

    def cycle(self, at: float | None = None) -> None:
        """CSB 0 in the PLC cycle that starts ``at`` (None: now; earlier for a cycle the PLC runs
        late, whose timers count to its start), then (Example 3) the mode and stop keys."""
        view = Look(self, at)
        for name, done in list(self.active.items()):
            if not done:
                self._run(self.steps[name])
                self.active[name] = True
                continue
            for transition in self.leaving.get(name, ()):
                if transition.condition is None or transition.condition(view):
                    del self.active[name]
                    for target in transition.targets:
                        self.active[target] = False
                    break
        if self.program.mode_keys:
            self._mode_keys()

    def _mode_keys(self) -> None:
        manual, stop = self.input(0), self.input(15)
        if manual != self._keys[0]:
            self.restart()  # either edge of I 0: RSB 0 at step 0 (a running move is completed)
        if stop and not self._keys[15]:
            self.axis.set_flag("FStop", 1)
            self.restart()
        self._keys = {0: manual, 15: stop}

    def _run(self, step: Step) -> None:
        for action in step.actions:
            ACTIONS[action[0]](self, action)

    @property
    def busy(self) -> bool:
        """Something will happen at the next cycle without an outside event: a step's actions
        to run, or a transition that holds."""
        view = Look(self, None)
        for name, done in self.active.items():
            if not done:
                return True
            for transition in self.leaving.get(name, ()):
                if transition.condition is None or transition.condition(view):
                    return True
        return False


ACTIONS: Table[Callable[[Sequence, Action], None]] = Table([
    Command("load", Sequence.load_register, "§6.3", "LD R symbol+RA1 value: load a register of axis 1"),
    Command("set", Sequence.set_flag, "§6.3", "SET F symbol+FA1: set a flag of axis 1"),
    Command("timer", Sequence.load_timer, "§6.3", "LD T n tenths: start timer n"),
    Command("counter", Sequence.load_counter, "§6.5", "LD C n value: load counter n"),
    Command("dec", Sequence.decrement_counter, "§6.5", "DEC C n: count counter n down"),
])
"""What a step's actions do, by the statement (the first item of an action); sections of the spec
(manual §9.1, §9.3)."""
