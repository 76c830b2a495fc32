"""The live monitor: a textual app attached to a running plant through its control API.

One panel per device: its state line (ready, fault, display, errors ...), the active faults,
each axis's position and velocity with a sparkline of the last positions, the inputs as lamps
that a press flips (settable inputs are buttons), the outputs as lamps, and the last telegrams
of each port in both directions.  Keys: ``f`` fault menu (declared device faults and line faults,
on or off), ``a``/``A`` advance virtual time by 0.1 s / 1 s, ``q`` quit.

Values come from one ``watch`` stream per device (:meth:`ControlClient.watch`, read by a thread
each); telegrams are polled (control op ``telegrams``).  The UI applies what the threads queued
on a timer, so a fast-moving plant never floods the event loop.  The header's clock (device time and
wall time, :func:`~devsim.observe.monitor_text.clock_line`) ticks once a second on the monitor's
own timer, also while nothing changes: the poller asks the simulator for its time, the simulator
keeps no timer for it.
"""

from __future__ import annotations

import json
import queue
import re
import threading
import time
from collections import deque
from collections.abc import Callable
from typing import Any

from rich.markup import escape
from textual import on
from textual.app import App, ComposeResult
from textual.binding import Binding
from textual.containers import Grid, Horizontal, Vertical, VerticalScroll
from textual.message import Message
from textual.screen import ModalScreen
from textual.widgets import Footer, Header, OptionList, Sparkline, Static
from textual.widgets.option_list import Option

from devsim.observe.monitor_text import LINE_FAULTS, clock_line, display_line, is_display, message_line
from devsim.runtime import requests as rq
from devsim.runtime.client import ControlClient, ControlError

__all__ = ["LINE_FAULTS", "MonitorApp"]

_AXIS = re.compile(r"^(axis(?:\.[^.]+)?)\.(position|velocity)$")
_SPARK = 60  # positions kept per axis
_TELEGRAMS = 6  # telegrams shown per port
_TICK = 1.0  # seconds between two ticks of the header's clock


def _ident(text: str) -> str:
    return re.sub(r"[^A-Za-z0-9_-]", "_", text)


def _show(value: Any) -> str:
    if isinstance(value, float):
        return f"{value:.1f}"
    return value if isinstance(value, str) else json.dumps(value)


class Lamp(Static, can_focus=False):
    """An input or output as a lamp; a settable input flips on a click or Enter/space."""

    BINDINGS = [Binding("enter,space", "flip", "flip")]

    class Flip(Message):
        def __init__(self, lamp: Lamp) -> None:
            super().__init__()
            self.lamp = lamp

    def __init__(self, point: str, *, id: str, settable: bool = True) -> None:  # noqa: A002 - textual's name
        super().__init__(id=id)
        self.point = point
        self.label = escape(point.split(".", 1)[1])
        self.can_focus = settable
        self.show(False)

    def show(self, on: bool) -> None:
        self.update(f"[b green]●[/] {self.label}" if on else f"[dim]○[/] {self.label}")

    def on_click(self) -> None:
        self.action_flip()

    def action_flip(self) -> None:
        if self.can_focus:
            self.post_message(self.Flip(self))


class DevicePanel(Vertical):
    """What the monitor shows of one device."""

    DEFAULT_CSS = """
    DevicePanel { height: auto; border: round $accent; padding: 0 1; margin-bottom: 1; }
    DevicePanel .axis { height: 1; }
    DevicePanel .axis Static { width: 44; }
    DevicePanel Sparkline { width: 1fr; height: 1; }
    DevicePanel .lamps { layout: grid; grid-size: 8; grid-rows: 1; grid-gutter: 0 1; height: auto; }
    DevicePanel Lamp { height: 1; width: 1fr; text-wrap: nowrap; text-overflow: ellipsis; }
    DevicePanel Lamp:focus { background: $accent 40%; }
    """

    def __init__(self, info: dict[str, Any], names: list[dict[str, Any]]) -> None:
        self.device = str(info["name"])
        super().__init__(id=f"dev-{_ident(self.device)}")
        self.border_title = f"{self.device} ({info.get('kind')})"
        self.ports = list(info.get("ports") or {"main": None})
        self.values: dict[str, Any] = {}
        self.faults: set[str] = set()
        self.line_faults: dict[str, set[str]] = {}
        self.last_event = ""
        self.inputs = [n["name"] for n in names if n["name"].startswith("input.") and "w" in n["access"]
                       and n["type"] == "bool"]
        self.outputs = [n["name"] for n in names if n["name"].startswith("output.") and "r" in n["access"]
                        and n["type"] == "bool"]
        axes: list[str] = []
        for n in names:
            match = _AXIS.match(n["name"])
            if match and match.group(1) not in axes:
                axes.append(match.group(1))
        self.axes = axes
        self.history: dict[str, deque[float]] = {axis: deque(maxlen=_SPARK) for axis in axes}
        self.telegrams: dict[str, list[dict[str, Any]]] = {}

    def compose(self) -> ComposeResult:
        yield Static(id="state")
        for axis in self.axes:
            with Horizontal(classes="axis"):
                yield Static(id=f"{_ident(axis)}-text")
                yield Sparkline([], id=f"{_ident(axis)}-spark")
        if self.inputs:
            with Grid(classes="lamps"):
                for name in self.inputs:
                    yield Lamp(name, id=f"in-{_ident(name)}")
        if self.outputs:
            with Grid(classes="lamps"):
                for name in self.outputs:
                    yield Lamp(name, id=f"out-{_ident(name)}", settable=False)
        yield Static(id="telegrams")

    def on_mount(self) -> None:
        self.refresh_view()

    def apply(self, item: dict[str, Any]) -> None:
        kind = item.get("type")
        if kind == "change":
            name = str(item["name"])
            self.values[name] = item.get("value")
            match = _AXIS.match(name)
            if match and match.group(2) == "position" and isinstance(item.get("value"), int | float):
                self.history[match.group(1)].append(float(item["value"]))
        elif kind == "fault":
            (self.faults.add if item.get("active") else self.faults.discard)(str(item["name"]))
        elif kind == "line_fault":
            text = str(item.get("text", ""))
            port = str(item.get("port", "main"))
            fault_kind = text.split(": ", 1)[-1].split(" ", 1)[0]
            active = self.line_faults.setdefault(port, set())
            (active.add if text.startswith("fault start") else active.discard)(fault_kind)
        if kind != "change":
            self.last_event = f"{item.get('t', 0):.3f} {kind} {item.get('name') or item.get('text') or ''}".strip()

    def refresh_view(self) -> None:
        if not self.query("#state"):
            return  # not composed yet (items can arrive first): on_mount shows them
        shown = [f"{name}={_show(value)}" for name, value in self.values.items()
                 if not name.startswith(("input.", "output.", "axis.")) and not isinstance(value, dict | list)
                 and not is_display(name)]
        faults = sorted(self.faults) + [f"{port}:{k}" for port, kinds in self.line_faults.items() for k in sorted(kinds)]
        displays, message = display_line(self.values), message_line(self.values)
        lines = ["  ".join(shown[:12]) or "(no state yet)",
                 f"display: {escape(displays)}" if displays else "",
                 f"message: {escape(message)}" if message else "",
                 f"faults: {', '.join(faults) if faults else 'none'}",
                 f"last event: {self.last_event or '-'}"]
        self.query_one("#state", Static).update("\n".join(line for line in lines if line))
        for axis in self.axes:
            position = self.values.get(f"{axis}.position")
            velocity = self.values.get(f"{axis}.velocity")
            self.query_one(f"#{_ident(axis)}-text", Static).update(
                f"{axis}: pos {_show(position)}  vel {_show(velocity)}")
            history = self.history[axis]
            if len(history) > 1 and max(history) - min(history) > 1e-9:  # a flat line: nothing to draw
                self.query_one(f"#{_ident(axis)}-spark", Sparkline).data = list(history)
        for lamp in self.query(Lamp):
            lamp.show(bool(self.values.get(lamp.point)))
        rows = []
        for port in self.ports:
            for telegram in self.telegrams.get(port, [])[-_TELEGRAMS:]:
                fields = [json.dumps(d, separators=(",", ":")) for d in telegram.get("decoded", [])
                          if isinstance(d, dict)]  # a frame's fields, where the kind's protocol is known
                row = f"{port} {telegram['t']:.3f} {telegram['dir']} {escape(telegram['text'][:70])}"
                rows.append(row + (f"  {escape(' '.join(fields))[:100]}" if fields else ""))
        self.query_one("#telegrams", Static).update("\n".join(rows) or "(no telegrams yet)")


class FaultMenu(ModalScreen[rq.ControlRequest | None]):
    """Pick a device fault or a line fault to switch: each choice is its text and its request."""

    DEFAULT_CSS = "FaultMenu { align: center middle; } FaultMenu OptionList { width: 70; height: 20; }"
    BINDINGS = [Binding("escape", "dismiss_menu", "close")]

    def __init__(self, choices: list[tuple[str, rq.ControlRequest]]) -> None:
        super().__init__()
        self.choices = choices

    def compose(self) -> ComposeResult:
        yield OptionList(*[Option(text, id=str(i)) for i, (text, _) in enumerate(self.choices)], id="faults")

    @on(OptionList.OptionSelected)
    def _picked(self, event: OptionList.OptionSelected) -> None:
        self.dismiss(self.choices[int(event.option.id or 0)][1])

    def action_dismiss_menu(self) -> None:
        self.dismiss(None)


class MonitorApp(App[None]):
    """``devsim monitor``: attach to the control API at ``address``."""

    TITLE = "devsim monitor"
    BINDINGS = [
        Binding("f", "faults", "faults"),
        Binding("a", "advance(0.1)", "advance 0.1 s"),
        Binding("A", "advance(1.0)", "advance 1 s"),
        Binding("q", "quit", "quit"),
    ]

    def __init__(self, address: str, *, period: float = 0.1, refresh: float = 0.1,
                 wall_clock: Callable[[], float] = time.time) -> None:
        super().__init__()
        self.wall_clock = wall_clock  # the header's wall time (a test's picture fixes it)
        self.address = address
        self.period = period
        self.refresh_every = refresh
        self.client = ControlClient(address)
        self.infos = self.client.devices()
        self.names = {info["name"]: self.client.names(info["name"]) for info in self.infos}
        for info in self.infos:  # the lines keep their telegrams from now on
            for port in info.get("ports") or {}:
                try:
                    self.client.telegrams(info["name"], port, count=0)
                except ControlError:
                    pass  # a port not on a line
        self.items: queue.Queue[dict[str, Any]] = queue.Queue()
        self.panels: dict[str, DevicePanel] = {}
        self._stop = threading.Event()
        self._streams: list[Any] = []
        self.ended = 0
        #: The device time last heard of (a change, an event, or the clock asked once a second).
        self.device_time: float | None = None

    def compose(self) -> ComposeResult:
        yield Header()
        with VerticalScroll():
            for info in self.infos:
                panel = DevicePanel(info, self.names[info["name"]])
                self.panels[panel.device] = panel
                yield panel
        yield Footer()

    def on_mount(self) -> None:
        self.sub_title = clock_line(None, wall=self.wall_clock())
        for info in self.infos:
            threading.Thread(target=self._watch, args=(info["name"],), daemon=True).start()
        threading.Thread(target=self._poll_telegrams, daemon=True).start()
        self.set_interval(self.refresh_every, self._drain)
        self.set_interval(_TICK, self._show_clock)  # the clock runs while nothing changes

    # -- threads ----------------------------------------------------------------------------
    def _watch(self, device: str) -> None:
        try:
            stream = self.client.watch(device, period=self.period)
            self._streams.append(stream)
            for item in stream:
                self.items.put(item)
                if self._stop.is_set():
                    break
        except (OSError, ControlError, ValueError):
            pass
        self.items.put({"type": "ended", "device": device})

    def _poll_telegrams(self) -> None:
        """The telegrams of every port every 0.3 s, and the device time every second (the
        simulator only answers: it keeps no timer for the monitor)."""
        asked = 0.0
        try:
            with ControlClient(self.address) as client:
                while not self._stop.wait(0.3):
                    if time.monotonic() - asked >= _TICK:
                        asked = time.monotonic()
                        self.items.put({"type": "clock", "t": client.now()})
                    for info in self.infos:
                        for port in info.get("ports") or {"main": None}:
                            try:
                                got = client.telegrams(info["name"], port, count=_TELEGRAMS)
                            except ControlError:
                                continue  # a port not on a line (a facade's)
                            self.items.put({"type": "telegrams", "device": info["name"], "port": port, "list": got})
        except (OSError, ValueError):
            pass

    # -- UI ---------------------------------------------------------------------------------
    def _drain(self) -> None:
        touched: set[str] = set()
        while True:
            try:
                item = self.items.get_nowait()
            except queue.Empty:
                break
            if isinstance(item.get("t"), int | float):
                self.device_time = max(float(item["t"]), self.device_time or 0.0)
            panel = self.panels.get(str(item.get("device")))
            if panel is None:
                continue
            if item["type"] == "telegrams":
                panel.telegrams[item["port"]] = item["list"]
            elif item["type"] == "ended":
                self.ended += 1
                continue
            else:
                panel.apply(item)
            touched.add(panel.device)
        for device in touched:
            self.panels[device].refresh_view()
        self._show_clock()

    def _show_clock(self) -> None:
        self.sub_title = clock_line(self.device_time, stopped=self.ended == len(self.panels) > 0,
                                    wall=self.wall_clock())

    @on(Lamp.Flip)
    def _flip(self, event: Lamp.Flip) -> None:
        panel = next((p for p in event.lamp.ancestors if isinstance(p, DevicePanel)), None)
        if panel is not None:
            self._request(rq.Set(panel.device, event.lamp.point, not bool(panel.values.get(event.lamp.point))))

    def _request(self, request: rq.ControlRequest) -> Any:
        try:
            return self.client.call(request)
        except (ControlError, OSError) as exc:
            self.notify(str(exc), severity="error")
            return None

    def action_advance(self, seconds: float) -> None:
        now = self._request(rq.Advance(seconds))
        if now is not None:
            self.notify(f"time {now:.3f} s", timeout=1)

    def action_faults(self) -> None:
        choices: list[tuple[str, rq.ControlRequest]] = []
        for info in self.infos:
            panel = self.panels[info["name"]]
            for kind in info.get("faults", []):
                active = kind in panel.faults
                choices.append((f"{info['name']}: {kind} {'off' if active else 'on'}",
                                rq.SwitchFault(info["name"], kind, not active)))
            for port in info.get("ports") or {}:
                if not str((info.get("ports") or {}).get(port) or ""):
                    continue
                for kind in LINE_FAULTS:
                    active = kind in panel.line_faults.get(port, set())
                    choices.append((f"{info['name']}.{port}: line {kind} {'off' if active else 'on'}",
                                    rq.LineFault(info["name"], kind, not active, port,
                                                 {} if active else dict(LINE_FAULTS[kind]))))
        self.push_screen(FaultMenu(choices), self._switch_fault)

    def _switch_fault(self, choice: rq.ControlRequest | None) -> None:
        if choice is not None:
            self._request(choice)

    def on_unmount(self) -> None:
        self._stop.set()
        for stream in self._streams:
            try:
                stream.close()
            except (ValueError, RuntimeError):
                pass  # a generator still running in its thread: it ends with the connection
        self.client.close()
