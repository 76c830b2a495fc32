"""The GMS96 indexer on the shared closed-form axis (manual §1.3, §2.3.1 A/B/f/M/o, §2.7).

Spec §5.1–§5.3 (units: Hz = inc/s, B in Hz/ms → a = 1000·B inc/s²; linear or sin² ramps, N24),
§5.2 (working speed, V-factor quantisation, override), §5.4 (blending: one plan to the chain's
last target, junctions are crossings), §5.7 (following error e = v/Kv, ``blocked`` actual
position, trip at |e| > N20 solved as a crossing time), §5.11 (mechanical end stops block the
axis).  The axis runs in *physical* increments; the card's position counter is
``axis.position() - origin`` (the device's business).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from devsim.core.axis import Axis, RampProfile, Watch
from devsim.core.clock import Timer

if TYPE_CHECKING:
    from devsim.devices.gms96.device import Gms96Device

__all__ = ["Indexer"]

_SINE = RampProfile(shape="sine")


class Indexer:
    """Set-point generation and the position-loop model of one card."""

    def __init__(self, dev: Gms96Device, axis: Axis) -> None:
        self.dev = dev
        self.axis = axis
        self.target: float | None = None  # physical end of the running plan (chain)
        self.kind = "work"  # which speed applies: work | search | spindle | rapid_nv
        self.jog_dir = 0  # endless run (reference search, spindle) instead of a target
        self.spindle_speed = 0.0
        self.on_arrive: Callable[[], None] | None = None
        self.blocked_at: float | None = None  # actual position held by a blockage
        self._fe_timer: Timer | None = None
        self._fe_watches: list[Watch] = []

    # -- speeds ---------------------------------------------------------------------------------
    def v_factor(self) -> int:
        return self.dev.v_factor()

    def override_pct(self) -> float:
        d = self.dev
        if not d.override_on:
            return 100.0
        if d.o2_value is not None:
            return float(d.o2_value)
        if d.ext_override is not None:
            return float(d.ext_override)
        return float(d.signals.get("override_pot"))

    def work_speed(self) -> float:
        """G94: f (≤ M); G95: (f + frac/256) inc/rev × rpm / 60 (spec §5.2)."""
        d = self.dev
        if d.feed_mode == 95:
            v = (d.f + d.f_frac / 256.0) * d.spindle_rpm / 60.0
        else:
            v = float(d.f)
        return min(v, float(d.M))

    def speed(self) -> float:
        """The commanded speed now for the running plan (0: hold)."""
        d = self.dev
        if d.stop_marker() or (self.kind != "spindle" and d.enable_blocked()):
            return 0.0
        if self.kind == "search":
            v = float(d.S)
        elif self.kind == "spindle":
            v = min(self.spindle_speed, float(d.M)) * self.override_pct() / 100.0
        elif self.kind == "rapid_nv":
            v = float(d.nv_M()) * self.override_pct() / 100.0
        else:
            v = min(self.work_speed() * self.override_pct() / 100.0, float(d.M))
        vf = self.v_factor()
        return vf * math.floor(v / vf + 1e-9) if self.kind in ("work", "rapid_nv") else v

    def accel(self) -> tuple[float, RampProfile | None]:
        """(axis acceleration, profile): sin² with peak a = 1000·B needs the axis' raised cosine
        with average 2a/π (spec §5.3: T = π/2·Δv/a)."""
        a = 1000.0 * self.dev.B
        if self.dev.n(24) == 1:
            return a * 2.0 / math.pi, _SINE
        return a, None

    # -- commands -------------------------------------------------------------------------------
    def go(self, target: float, kind: str = "work", on_arrive: Callable[[], None] | None = None) -> None:
        self.target = float(target)
        self.jog_dir = 0
        self.kind = kind
        self.on_arrive = on_arrive
        self.replan()

    def run(self, direction: int, kind: str) -> None:
        """Endless run (reference search, spindle simulation)."""
        self.target = None
        self.jog_dir = direction
        self.kind = kind
        self.on_arrive = None
        self.replan()

    def replan(self) -> None:
        """Re-plan from the exact current state after any change of speed, override or STOP."""
        if self.target is None and self.jog_dir == 0:
            return
        v = self.speed()
        acc, profile = self.accel()
        if v <= 0.0:
            self.axis.stop(acc, profile=profile, speed=max(abs(self.axis.velocity()), 1.0))
        elif self.target is not None:
            self.axis.move_to(self.target, v, acc, on_done=self._arrived, profile=profile)
        else:
            self.axis.jog(self.jog_dir, v, acc, profile=profile)
        self.dev.record_event("replan")
        self.arm_following_error()

    def _arrived(self) -> None:
        self.target = None
        callback, self.on_arrive = self.on_arrive, None
        self.arm_following_error()
        if callback is not None:
            callback()

    def halt(self, on_stopped: Callable[[], None] | None = None) -> None:
        """Decelerate with the programmed ramp (abort, #0); ``on_stopped`` at standstill."""
        self.target = None
        self.jog_dir = 0
        self.on_arrive = None
        acc, profile = self.accel()
        if self.axis.moving:
            self.axis.stop(acc, on_stopped, profile=profile, speed=max(abs(self.axis.velocity()), 1.0))
        elif on_stopped is not None:
            self.dev.clock.call_later(0.0, on_stopped)
        self.arm_following_error()

    def power_off(self, brake: bool) -> None:
        """Current off: the axis stops within ``brake_stop_ms`` where it is (spec §5.13)."""
        self.target = None
        self.jog_dir = 0
        self.on_arrive = None
        v = abs(self.axis.velocity())
        ms = self.dev.cfg.axis.brake_stop_ms
        if self.blocked_at is not None or v == 0.0 or ms <= 0 or not brake:
            actual = self.actual()
            self.axis.quick_stop()
            if not self.axis.moving:
                self.axis.set_position(actual)
        else:
            self.axis.stop(v / (ms / 1000.0))
        self.arm_following_error()

    # -- position loop (spec §5.7) --------------------------------------------------------------
    def kv(self) -> float:
        return max(self.dev.cfg.axis.kv_per_n10 * self.dev.n(10), 1e-6)

    def following_error(self) -> float:
        if not self.dev.controller:
            return 0.0
        if self.blocked_at is not None:
            return self.axis.position() - self.blocked_at
        if self.dev.stepper:
            return 0.0
        return self.axis.velocity() / self.kv()

    def actual(self) -> float:
        if self.blocked_at is not None:
            return self.blocked_at
        return self.axis.position() - (self.following_error() if self.dev.controller else 0.0)

    def block(self, active: bool) -> None:
        if active and self.blocked_at is None:
            self.blocked_at = self.actual()
        elif not active and self.blocked_at is not None:
            self.blocked_at = None
        self.arm_following_error()

    def arm_following_error(self) -> None:
        """Schedule the following-error trip as an event: a crossing of the set-point past the
        blockage (or an end stop) ± N20, or the instant the planned speed exceeds N20·Kv."""
        if self._fe_timer is not None:
            self._fe_timer.cancel()
            self._fe_timer = None
        for w in self._fe_watches:
            w.cancel()
        self._fe_watches = []
        d = self.dev
        if not d.controller or d.stepper:
            return
        limit = float(d.n(20))
        if self.blocked_at is not None:
            hold = self.blocked_at
            if abs(self.axis.position() - hold) > limit:
                d.clock.call_later(0.0, lambda: d.following_error_fault("blocked"))
                return
            self._fe_watches.append(self.axis.watch(hold + limit + 1e-6, lambda s: s > 0 and self._trip()))
            self._fe_watches.append(self.axis.watch(hold - limit, lambda s: s < 0 and self._trip()))
            return
        stops = d.cfg.axis.end_stops
        if stops is not None:
            lo, hi = stops
            self._fe_watches.append(self.axis.watch(hi + limit + 1e-6, lambda s: s > 0 and self._trip()))
            self._fe_watches.append(self.axis.watch(lo - limit, lambda s: s < 0 and self._trip()))
        when = self._speed_exceeds(limit * self.kv())
        if when is not None:
            self._fe_timer = d.clock.call_at(when, self._trip)

    def _trip(self) -> None:
        self.dev.following_error_fault("speed" if self.blocked_at is None else "blocked")

    def _speed_exceeds(self, vmax: float) -> float | None:
        now = self.dev.clock.now()
        for seg in self.axis.segments():
            if seg.t1 <= now:
                continue
            t0 = max(seg.t0, now)
            t1 = seg.t1 if seg.t1 < math.inf else t0 + 1.0
            if abs(seg.velocity(t0)) > vmax:
                return t0
            if abs(seg.velocity(t1)) > vmax:
                lo, hi = t0, t1
                for _ in range(60):
                    mid = 0.5 * (lo + hi)
                    if abs(seg.velocity(mid)) > vmax:
                        hi = mid
                    else:
                        lo = mid
                return hi
        return None

    def state(self) -> dict[str, Any]:
        return {
            "target": self.target,
            "kind": self.kind,
            "run": self.jog_dir,
            "speed": self.speed() if (self.target is not None or self.jog_dir) else 0.0,
            "override": self.override_pct(),
            "blocked_at": self.blocked_at,
        }
