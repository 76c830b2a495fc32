"""Speeds, ramp and override of the indexer (manual §2.3.1 B, M, S, f, o, G0/G94/G95, §2.3.2 #8/#9,
§2.7; spec §3.8, §4.7, §5.2).

The settings the executor sets in queue order (``B``, ``M``, ``S``, ``f``, ``o``), the override
values sent on receipt (``o2``, ``#9``) and the spindle speed of ``#8``.  ``M``, ``B``, ``S`` and
the override activity are saved by ``s85;170``; the M value saved there (:attr:`Feed.eeprom_M`) is
the rapid speed of ``Q-1`` and selects the counter-input mode at the next start (manual §2.6).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from devsim.core.nvram import stored_whole
from devsim.devices.gms96 import tables

__all__ = ["Feed"]


class Feed:
    """The speed settings of one card (manual §2.3.1 B, M, S, f, o; spec §4.7, §5.2)."""

    def __init__(self) -> None:
        self.M = tables.DEFAULTS["M"]  # rapid / maximum speed [Hz]
        self.B = tables.DEFAULTS["B"]  # acceleration [Hz/ms]
        self.S = tables.DEFAULTS["S"]  # reference search speed [Hz]
        self.f = self.M  # working speed [Hz]
        self.f_frac = 0  # f P2: 1/256 inc/rev (G95)
        self.feed_mode = 94  # G94 inc/s, G95 inc/rev
        self.override_on = bool(tables.DEFAULTS["override_active"])
        self.o2_value: int | None = None  # o2;P2: the override-inactive value
        self.ext_override: int | None = None  # #9: the host's override
        self.spindle_rpm = 0  # #8 (G95)
        self.eeprom_M = self.M

    def power_on(self, eeprom: Mapping[str, Any] | None) -> None:
        """The defaults, or what ``s85;170`` saved; G0, G94, no host override."""
        self.defaults()
        if eeprom:
            # as s85;170 stores them: whole numbers, clamped as a write is (spec §3.8.1, §3.8.12,
            # §3.8.16), the activity 0 or 1; else the start refuses the memory (UnfitMemory).
            # int() took "٣", "3", 1.7 and true, and an M of 10**30 loaded unclamped.
            self.M, self.B, self.S = (tables.clamp_setting(name, stored_whole(eeprom[name], name)) for name in "MBS")
            self.override_on = bool(stored_whole(eeprom["o"], "override activity", (0, 1)))
        self.eeprom_M = self.M
        self.f = self.M
        self.o2_value = None
        self.ext_override = None
        self.spindle_rpm = 0

    def defaults(self) -> None:
        """``r0`` (and power-on): the indexer's defaults (manual §2.3.1 r) - M, B, S, the override
        activity, the working speed f = M (the G0 state, spec §3.8.5 [R]) and G94 (manual §2.3.1 G:
        "Grundeinstellung")."""
        self.M, self.B, self.S = tables.DEFAULTS["M"], tables.DEFAULTS["B"], tables.DEFAULTS["S"]
        self.override_on = bool(tables.DEFAULTS["override_active"])
        self.f, self.f_frac = self.M, tables.DEFAULTS["f_fraction"]
        self.feed_mode = tables.DEFAULTS["feed_mode"]

    def eeprom(self) -> dict[str, int]:
        """What ``s85;170`` saves of the speeds (manual §2.3.1 s)."""
        return {"M": self.M, "B": self.B, "S": self.S, "o": int(self.override_on)}

    def saved(self) -> None:
        """The EEPROM holds the current M now (``Q-1``, counter-input mode)."""
        self.eeprom_M = self.M

    def set_feed(self, f: int, frac: int) -> None:
        """``f P1;P2``."""
        self.f, self.f_frac = self.clamp_feed(f, frac)

    def clamp_feed(self, f: int, frac: int) -> tuple[int, int]:
        """``f P1;P2`` as the card takes it: under G94 an f above the M value sets the M value
        (manual §2.3.1 f, P1: [1..M-Wert]); under G95 f is inc/rev, not bounded by M."""
        high = self.M if self.feed_mode == 94 else tables.RANGES["f"][1]
        return max(1, min(f, high)), max(0, min(255, frac))

    def v_factor(self) -> int:
        """The speed resolution the M value gives (manual §2.7)."""
        return tables.v_factor(self.M)

    def set_override_active(self, active: bool) -> None:
        """``o0``/``o1`` (manual §2.3.1 o): the override function off (100 %) or on (potentiometer
        or #9); either ends an override-inactive value that ``o2`` set before."""
        self.override_on = active
        self.o2_value = None

    def set_override_inactive_value(self, percent: int) -> None:
        """``o2;P2`` (manual §2.3.1, immediate commands): the potentiometer override is switched
        off and P2 [0..100] is the override value from now on, whatever ``o0``/``o1`` was in force."""
        self.o2_value = max(0, min(100, percent))
        self.ext_override = None

    def override_pct(self, potentiometer: float) -> float:
        """The override in effect: o2's value since it was received, else 100 % when off (o0),
        else #9, else the potentiometer."""
        if self.o2_value is not None:
            return float(self.o2_value)
        if not self.override_on:
            return 100.0
        if self.ext_override is not None:
            return float(self.ext_override)
        return float(potentiometer)

    def work_speed(self, feed: tuple[int, int] | None = None) -> float:
        """G94: f (≤ M); G95: (f + frac/256) inc/rev × rpm / 60 (spec §5.2).  ``feed``: an
        ``(f, frac)`` to use instead of the current one."""
        f, frac = feed if feed is not None else (self.f, self.f_frac)
        if self.feed_mode == 95:
            v = (f + frac / 256.0) * self.spindle_rpm / 60.0
        else:
            v = float(f)
        return min(v, float(self.M))
