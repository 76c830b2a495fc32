"""A looping program run ahead while nobody looks (issue 31; manual §1.2, §4.8.6.10).

Every statement of a SERS program has its own control cycle (0.5 ms, 2 ms with P1127=1) and a
host sees each at its time, so the drive executes them one by one.  But when nobody can look
before a known moment (the scenario runner waits for a step ``after`` a while, with no facade,
control API or log attached: :meth:`RunAhead.unobserved_until`) and the program loops, every
pass through the loop is the one before moved in time.  At each backward jump of the program
(:meth:`RunAhead.looped`) the drive's whole state is taken down (:class:`_Walk`); when three
passes in a row are the same up to their times, which all moved by the same period, and nothing
was announced to a listener and no signal changed in between, the drive jumps ``n`` passes at
once: each time in its state (the axis's plan and history, timers, the standstill instant …)
moves by ``n`` periods, the event log gets the passes' events, and the program goes on, step by
step, from there.

The jump is exact, not approximate: within one binade of floating point ``[2**(e-1), 2**e)`` a
sum ``t + d`` of two multiples of the binade's unit is the same whatever multiple ``t`` is, but
for the rounding of a tie, which depends on whether ``t`` is an even or an odd multiple; two
passes are compared, one of each parity, so every pass in the binade is the same moved in time.
The jump stays within the binade of the passes compared, and before the moment nobody looks.
``tests/sers/test_runahead.py`` compares drives run ahead with drives run step by step.
"""

from __future__ import annotations

import enum
import math
import types
from collections.abc import Callable
from typing import Any

import msgspec

from devsim.core.clock import Clock, Timer
from devsim.core.device import Port
from devsim.core.parameters import Param, ParameterTable

__all__ = ["RunAhead"]

_ATOMS = (int, str, bool, type(None), bytes, complex)
_PLAIN = frozenset(_ATOMS)
_FLAT = _PLAIN | {float}
_CALLABLES = (types.FunctionType, types.BuiltinFunctionType, types.MethodType, types.BuiltinMethodType,
              types.MethodWrapperType, types.WrapperDescriptorType)
#: Shared, never changed by a drive: taken down by identity only (a Port: the drive's line and
#: the other drives on it, which are not the drive's state).
_SHARED = (ParameterTable, Param, types.MappingProxyType, types.ModuleType, type, Port)
LOG_LIMIT, LOG_CUT = 10000, 5000  # the event log's length and what is cut off beyond it (core.model)


_ATOM, _FROZEN, _TUPLE, _CALL, _SHARED_KIND, _SET, _BYTES, _OPAQUE, _LIST, _DICT, _TIMER, _OBJECT = range(12)
_KINDS: dict[type, int] = {}  # what a walk does with a value of a type, found once per type


def _kind_of(t: type) -> int:
    if issubclass(t, _ATOMS) or issubclass(t, enum.Enum):
        return _ATOM
    if issubclass(t, _CALLABLES):
        return _CALL
    if issubclass(t, (Clock, *_SHARED)):
        return _SHARED_KIND
    if t is tuple:
        return _TUPLE
    if issubclass(t, (set, frozenset)):
        return _SET
    if issubclass(t, bytearray):
        return _BYTES
    if issubclass(t, msgspec.Struct) and t.__struct_config__.frozen:
        return _FROZEN
    if issubclass(t, list):
        return _LIST
    if issubclass(t, dict):
        return _DICT
    if t is Timer:
        return _TIMER
    if hasattr(t, "__dict__") and ("__dict__" in dir(t) or hasattr(t, "__slots__")) or issubclass(t, msgspec.Struct):
        return _OBJECT
    return _OPAQUE


class _Walk:
    """One pass over a drive's state in a fixed order: :attr:`leaves`, the flat list of what it
    holds (numbers, names, shapes); with ``times`` (indices into the leaves) and ``delta`` it
    also moves those floats by ``delta`` in place (pending timers are scheduled anew)."""

    def __init__(self, clock: Clock, times: frozenset[int] | None = None, delta: float = 0.0) -> None:
        self.clock = clock
        self.times = times
        self.delta = delta
        self.leaves: list[Any] = []
        self._seen: dict[int, tuple[int, Any]] = {}  # id -> (leaf index, what it became)
        self._alive: list[Any] = []  # (objects walked stay alive: their ids stay theirs)

    def visit(self, x: Any) -> Any:
        t = type(x)
        leaves = self.leaves
        if t is float:
            times = self.times
            if times is not None and len(leaves) in times:
                leaves.append(x)
                return x + self.delta
            leaves.append(x)
            return x
        kind = _KINDS.get(t)
        if kind is None:
            kind = _KINDS[t] = _kind_of(t)
        if kind is _ATOM:
            leaves.append(x)
            return x
        if kind is _FROZEN:
            return self._frozen(x)
        if kind is _TUPLE:
            leaves.append(("tuple", len(x)))
            items = [self.visit(item) for item in x]
            if self.times is not None and any(a is not b for a, b in zip(items, x, strict=True)):
                return tuple(items)
            return x
        if kind is _CALL:  # (a bound method equals one of the same function on the same object)
            leaves.append(x)
            return x
        if kind is _SHARED_KIND:
            leaves.append(("shared", id(x)))
            return x
        if kind is _SET:
            leaves.append(("set", frozenset(x)))
            return x
        if kind is _BYTES:
            leaves.append(bytes(x))
            return x
        if kind is _OPAQUE:
            leaves.append(object())  # something not known: never the same twice, so no jump
            return x
        seen = self._seen.get(id(x))
        if seen is not None:
            leaves.append(("ref", seen[0]))
            return seen[1]
        index = len(leaves)
        self._seen[id(x)] = (index, x)
        self._alive.append(x)
        if kind is _LIST:
            if set(map(type, x)) <= _PLAIN:  # (no float, nothing nested: one leaf)
                leaves.append(("plain", tuple(x)))
                return x
            leaves.append(("list", len(x)))
            if set(map(type, x)) <= _FLAT:  # numbers and names: in one step
                base = len(leaves)
                leaves.extend(x)
                times = self.times
                if times is not None:
                    for i in range(len(x)):
                        if base + i in times:
                            x[i] += self.delta
                return x
            for i, item in enumerate(x):
                new = self.visit(item)
                if new is not item:
                    x[i] = new
            return x
        if kind is _DICT:
            leaves.append(("dict", len(x)))
            for key, item in list(x.items()):
                leaves.append(key)
                new = self.visit(item)
                if new is not item:
                    x[key] = new
            return x
        if kind is _TIMER:
            return self._timer(x, index)
        return self._object(x, t)

    def _frozen(self, x: msgspec.Struct) -> Any:
        leaves = self.leaves
        leaves.append(type(x))
        values = msgspec.structs.astuple(x)
        if set(map(type, values)) <= _FLAT:  # numbers and names (a segment of a plan): in one step
            base = len(leaves)
            leaves.extend(values)
            times = self.times
            if times is None:
                return x
            moved = {field: value + self.delta for i, (field, value) in enumerate(zip(x.__struct_fields__, values, strict=True))
                     if base + i in times}
            return msgspec.structs.replace(x, **moved) if moved else x
        changed = {}
        visit = self.visit
        for field, value in zip(x.__struct_fields__, values, strict=True):
            new = visit(value)
            if new is not value:
                changed[field] = new
        return msgspec.structs.replace(x, **changed) if changed else x

    def _timer(self, timer: Timer, index: int) -> Any:
        self.leaves.append(("timer", timer.cancelled))
        self.leaves.append(timer.callback)
        when = self.visit(timer.when)
        if when is timer.when or timer.cancelled:
            return timer
        moved = self.clock.call_at(when, timer.callback)
        timer.cancel()
        self._seen[id(timer)] = (index, moved)
        return moved

    def _object(self, x: Any, t: type) -> Any:
        slots = _SLOTS.get(t)
        if slots is None:
            slots = _SLOTS[t] = _slots_of(t)
        attrs = getattr(x, "__dict__", None)
        if attrs:
            skip = getattr(t, "not_state", ())  # (what a class says is not its state)
            names = [name for name in attrs if name not in skip] if skip else list(attrs)
            values = [attrs[name] for name in names] if skip else list(attrs.values())
        else:
            names, values = [], []
        for name in slots:
            value = getattr(x, name, _UNSET)
            if value is not _UNSET:
                names.append(name)
                values.append(value)
        leaves = self.leaves
        leaves.append((t, *names))
        visit = self.visit
        times = self.times
        for name, value in zip(names, values, strict=True):
            kind = type(value)
            if kind in _PLAIN or kind is types.MethodType or (kind is float and times is None):  # (the most)
                leaves.append(value)
                continue
            new = visit(value)
            if new is not value:
                setattr(x, name, new)
        return x


_SLOTS: dict[type, tuple[str, ...]] = {}  # a class's slots (and a struct's fields), found once per class
_UNSET = object()


def _slots_of(t: type) -> tuple[str, ...]:
    if issubclass(t, msgspec.Struct):
        names = list(t.__struct_fields__)
    else:
        names = []
        for cls in t.__mro__:
            slots = cls.__dict__.get("__slots__", ())
            names += [slots] if isinstance(slots, str) else list(slots)
    skip = getattr(t, "not_state", ())
    return tuple(name for name in names if name not in skip and name not in ("__weakref__", "__dict__"))


def _binade(x: float) -> int:
    return math.frexp(x)[1]


class _Head:
    """The drive at a backward jump of its program."""

    __slots__ = ("now", "leaves", "logged", "last", "noticed")

    def __init__(self, now: float, leaves: list[Any], log: list[tuple[float, str]], noticed: int) -> None:
        self.now = now
        self.leaves = leaves
        self.logged = len(log)  # entries of the event log so far
        self.last = log[-1] if log else None  # (the entry itself: a log cut since shows)
        self.noticed = noticed

    def still(self, log: list[tuple[float, str]], noticed: int) -> bool:
        """Nobody heard anything since, and the log was not cut."""
        logged = self.logged
        return (noticed == self.noticed and logged <= len(log)
                and (logged == 0 or log[logged - 1] is self.last))


class RunAhead:
    """Jumps a looping program's passes while nobody looks (see the module's text): the part of
    a SERS that takes the drive's state down at each backward jump (``root``: the drive as a
    whole; a class's ``not_state`` names the attributes that are not) and moves it in time."""

    __slots__ = ("clock", "_root", "_log", "_oldest", "_until", "_heads", "_wait", "_failed", "_not_before", "noticed",
                 "jumped")

    def __init__(self, clock: Clock, root: Any, log: list[tuple[float, str]], oldest: Callable[[], float]) -> None:
        self.clock = clock
        self._root = root
        self._log = log  # the model's event log (same list)
        self._oldest = oldest  # the earliest instant the drive remembers (the axis's history)
        self._until = -math.inf  # nobody looks before then
        self._heads: list[_Head] = []
        self._wait = 0  # passes not to take down (a pass that cannot lead to a jump yet)
        self._failed = 0  # passes that were not the same, one after the other
        self._not_before = -math.inf  # no jump in the binade that ends there
        #: Announcements to a listener and signal changes so far: anything a listener heard.
        self.noticed = 0
        #: Passes jumped so far (for tests and benchmarks).
        self.jumped = 0

    def notice(self, *_args: Any) -> None:
        """Something was announced to a listener, or a signal changed (someone may have seen it)."""
        self.noticed += 1

    def unobserved_until(self, when: float) -> None:
        """Nobody looks at the drive before ``when`` (``-inf``: someone may look at any time)."""
        self._until = when
        self._heads.clear()
        self._wait = 0
        self._not_before = -math.inf

    def looped(self) -> None:
        """The program jumped back (the next statement's cycle is scheduled): a pass may end."""
        now = self.clock.now()
        if now >= self._until or now < self._not_before:
            self._heads.clear()
            return
        if self._wait:
            self._wait -= 1
            return
        heads = self._heads
        binade = _binade(now)
        if self._oldest() < math.ldexp(0.5, binade):  # times from the binade before: not yet
            heads.clear()
            return
        if heads and (high := math.ldexp(1.0, binade)) - now < 48 * (now - heads[-1].now):
            self._not_before = high  # too few passes left in this binade for a jump to pay
            heads.clear()
            return
        log = self._log
        if heads and not heads[0].still(log, self.noticed):
            heads.clear()  # someone heard something, or the log was cut: start again
        walk = _Walk(self.clock)
        walk.visit(self._root)
        heads.append(_Head(now, walk.leaves, log, self.noticed))
        if len(heads) > 3:
            del heads[0]
        if len(heads) == 3 or (len(heads) == 2 and _even(heads[1].now - heads[0].now, now)):
            self._jump(heads)

    def _jump(self, heads: list[_Head]) -> None:
        """Compare the passes between ``heads`` (two passes; one if its period is an even
        number of the binade's units: every pass of the binade then starts on the same last
        bit) and jump if they are alike."""
        first, third = heads[0], heads[-1]
        period = heads[1].now - first.now
        if period <= 0 or third.now - heads[-2].now != period:
            return
        times = _moved([head.leaves for head in heads], period)
        if times is None:
            if len(heads) == 3:  # not the same: look again later, less often the more it failed
                self._failed += 1
                self._hold(min(64, 2 ** self._failed))
            return
        log = self._log
        before = log[first.logged:heads[1].logged]
        during = log[heads[-2].logged:third.logged]
        if len(before) != len(during) or any(a[1] != b[1] or (b is not a and b[0] - a[0] != period)
                                             for a, b in zip(before, during, strict=True)):
            return
        binade = _binade(third.now)
        low, high = math.ldexp(0.5, binade), math.ldexp(1.0, binade)
        oldest = [first.leaves[i] for i in times] + [entry[0] for entry in before]
        latest = [third.leaves[i] for i in times] + [entry[0] for entry in during]
        if not oldest:
            return
        if min(oldest) < low:  # times from the binade before: when they are gone
            self._hold(math.ceil((low - min(oldest)) / period))
            return
        span = third.now - min(latest)  # how far back the drive's times reach
        by_look = math.floor((self._until - third.now) / period) - 1
        by_binade = math.floor((high - max(latest)) / period) - 1
        passes = min(by_look, by_binade)
        if passes < 2:
            # no further jump before the look; in the next binade, once its times are all in it
            self._not_before = math.inf if by_look < 2 else high + span + 2 * period
            return
        delta = passes * period
        # the next jump: none before the look, or in the next binade once its times are all in it
        self._not_before = math.inf if by_look <= by_binade else high + span + 2 * period
        _Walk(self.clock, frozenset(times), delta).visit(self._root)
        _extend_log(log, during, period, passes)
        self.jumped += passes
        self._heads.clear()
        self._failed = 0

    def _hold(self, passes: int) -> None:
        """Take the next ``passes`` passes not down, and start afresh after them."""
        self._wait = max(0, passes)
        self._heads.clear()


def _moved(heads: list[list[Any]], period: float) -> list[int] | None:
    """The indices of the leaves that moved by ``period`` from each head to the next (times),
    or None if anything else differs."""
    first = heads[0]
    if any(len(leaves) != len(first) for leaves in heads):
        return None
    times = []
    for index, values in enumerate(zip(*heads, strict=True)):
        a = values[0]
        if all(type(v) is float for v in values):
            if all(v == a for v in values):
                continue
            if all(b - v == period for v, b in zip(values, values[1:], strict=False)):
                times.append(index)
                continue
            return None
        if not all(v == a for v in values):
            return None
    return times


def _even(period: float, now: float) -> bool:
    """``period`` is an even number of units of the binade of ``now`` (an exact multiple)."""
    units = period / math.ulp(now)
    return units == int(units) and int(units) % 2 == 0


def _extend_log(log: list[tuple[float, str]], during: list[tuple[float, str]], period: float, passes: int) -> None:
    """Append ``passes`` passes of ``during`` (each a period later than the one before) to the
    event log, cut as :meth:`devsim.core.model.Model.record_event` cuts it, making only the
    entries that stay."""
    per = len(during)
    added = per * passes
    if not added:
        return
    length = len(log)
    to_first_cut = LOG_LIMIT + 1 - length
    if added < to_first_cut:
        final = length + added
    else:
        final = LOG_LIMIT + 1 - LOG_CUT + (added - to_first_cut) % LOG_CUT
    keep_old = max(0, final - added)
    first_new = added - (final - keep_old)
    if keep_old < length:
        del log[: length - keep_old]
    first_pass, first_entry = divmod(first_new, per)
    log.extend((when + (j + 1) * period, name) for j in range(first_pass, passes) for when, name in during)
    if first_entry:  # (the first pass kept only in part)
        del log[len(log) - (added - first_new) - first_entry : len(log) - (added - first_new)]

