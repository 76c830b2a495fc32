"""One device watched live: value changes and events as a stream of JSON-able dicts.

The control op ``watch`` (:mod:`devsim.runtime.control`), ``devsim ctl watch`` and ``devsim
monitor`` are built on :class:`WatchStream`.  It runs in the runtime's loop thread and hands each
item to ``send`` as it happens:

* ``{"type": "change", "name": N, "value": V}`` -- a watched point changed, sampled with
  :class:`~devsim.core.watch.PointWatch` on the device clock every ``period`` seconds (default:
  the device's ``in_state`` points, every ``axis[.N].position``/``velocity`` and every
  ``[...].display``);
* ``{"type": "event", "name": N}`` -- what the model records (``move_start``, ``move_end``,
  ``power_on`` ...; topic ``recorded``), ``"type": "error"`` when the name says ``error``;
* ``{"type": "error" | "refused", "code": C, "text": T}`` -- an error the model reports by its
  code (:meth:`devsim.core.model.Model.report_error`), its text from the kind's error table
  (:attr:`devsim.core.kit.Reference.errors`; ``""`` when the table has no such row):
  ``"refused"`` when it is the device's answer to a host's command (a bare ``error`` event of
  the same moment is left out);
* ``{"type": "fault", "name": KIND, "active": B}`` -- a declared fault switched
  (``fault_switched``; a stream starts with one per fault already on, and a ``line_fault`` per
  line fault already active, so a watcher attaching late knows them); ``{"type": "drive_fault", "axis": A, "code": C}`` -- the model's own
  ``fault`` announcement (what a CANopen facade sends as EMCY);
* ``{"type": "connect" | "disconnect" | "host_settings" | "line_fault", "port": P, "text": T}``
  -- moments of the lines serving the device's ports (``host_settings`` adds ``mismatch``).

Every item carries ``t`` (device time) and ``device``.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Iterable
from typing import Any

from devsim.core.device import Device
from devsim.core.points import UnknownName
from devsim.core.watch import PointWatch
from devsim.runtime.process import FACADE_PORTS, port_key
from devsim.runtime.requests import MIN_WATCH_PERIOD

__all__ = ["DEFAULT_PERIOD", "FACADE_PORTS", "WatchStream", "axis_names", "default_names", "describe", "error_text"]

DEFAULT_PERIOD = 0.1
_AXIS_NAME = re.compile(r"^axis\.(?:[^.]+\.)?(position|velocity)$")

Send = Callable[[dict[str, Any]], None]


def axis_names(device: Device) -> list[str]:
    """``axis.position``, ``axis.1.velocity`` ...: the readable position and velocity names."""
    return [p.name for p in device.points if p.readable and _AXIS_NAME.match(p.name)]


def default_names(device: Device) -> list[str]:
    """What a watch without names watches: the ``in_state`` points, the axes and the displays
    (``display``, ``axis.x.display`` ...)."""
    names = [p.name for p in device.points if p.readable and p.in_state]
    displays = [p.name for p in device.points if p.readable and p.name.rsplit(".", 1)[-1] == "display"]
    return names + [name for name in axis_names(device) + displays if name not in names]


class WatchStream:
    """Watch ``device`` (of ``runtime``); ``send(item)`` gets each change and event (with
    ``values=False`` only the events: nothing is sampled)."""

    def __init__(self, runtime: Any, device: Device, send: Send, *, names: Iterable[str] | None = None,
                 period: float | None = None, values: bool = True, refused: bool = True) -> None:
        period = DEFAULT_PERIOD if period is None else period
        if not period >= MIN_WATCH_PERIOD:
            raise ValueError(f"a watch period is at least {MIN_WATCH_PERIOD:g} s")
        self.runtime = runtime
        self.device = device
        self.send = send
        self.names = (list(names) if names else default_names(device)) if values else []
        for name in self.names:  # an unknown name fails here (UnknownName), not as a stream of None
            try:
                device.read(name)
            except UnknownName:
                raise
            except (ValueError, LookupError, ArithmeticError):
                pass  # a value the device cannot give in its present state: watched as None
        self.period = period
        self._undo: list[Callable[[], Any]] = []
        self._watch: PointWatch | None = None
        self._coded = False  # an error reported by its code, not yet followed by a bare ``error``
        #: Whether the host's commands the device refused are sent (a log below -vv does not show
        #: them: with False no item is made for them, which noise makes by the thousand).
        self.refused = refused

    def _emit(self, kind: str, **fields: Any) -> None:
        self.send({"t": round(self.device.clock.now(), 6), "device": self.device.name, "type": kind, **fields})

    def start(self) -> None:
        """Listen and take the first sample (every watched value, as changes)."""
        model = self.device.model
        self._undo.append(model.listen("recorded", self._event))
        self._undo.append(model.listen("device_error", self._device_error))
        self._undo.append(model.listen("fault_switched",
                                       lambda kind, active: self._emit("fault", name=kind, active=bool(active))))
        self._undo.append(model.listen("fault", lambda axis=None, code=None, *_: self._emit(
            "drive_fault", axis=axis, code=code)))
        for port in self._line_ports():
            line = self.runtime.lines.get(port_key(self.device.name, port))
            if line is None:
                continue
            observer = self._line_observer(port, line)
            line.observers.append(observer)
            self._undo.append(lambda line=line, observer=observer: _remove(line.observers, observer))
        for kind in self.device.active_faults:  # switched before this watch began
            self._emit("fault", name=kind, active=True)
        for port in self._line_ports():
            line = self.runtime.lines.get(port_key(self.device.name, port))
            for fault in line.faults if line is not None else ():
                self._emit("line_fault", port=port, text=f"fault start: {fault.describe()}")
        if self.names:
            self._watch = PointWatch(self.device, self._changes, names=self.names, period=self.period)
            self._watch.start()

    def _line_ports(self) -> tuple[str, ...]:
        """The device's ports and the lines a facade serves for it (:data:`FACADE_PORTS`)."""
        return (*self.device.port_names(), *FACADE_PORTS)

    def _event(self, _time: float, name: str) -> None:
        if self._coded and name.split(" ", 1)[0] == "error":  # "error", "error 5"
            self._coded = False
            return  # said with its code and text by _device_error
        self._emit("error" if "error" in name.lower() else "event", name=name)

    def _device_error(self, code: str, refused: bool = False) -> None:
        self._coded = True
        if refused and not self.refused:
            return
        self._emit("refused" if refused else "error", code=code, text=error_text(type(self.device), code))

    def _changes(self, changes: dict[str, Any]) -> None:
        for name, value in changes.items():
            self._emit("change", name=name, value=value)

    def _line_observer(self, port: str, line: Any) -> Callable[[str, str], None]:
        def observe(event: str, text: str) -> None:
            if event == "host_settings":
                self._emit("host_settings", port=port, text=text, mismatch=bool(line.mismatch))
            else:
                self._emit("line_fault" if event == "fault" else event, port=port, text=text)

        return observe

    def stop(self) -> None:
        if self._watch is not None:
            self._watch.stop()
            self._watch = None
        for undo in self._undo:
            undo()
        self._undo.clear()


_ERROR_TEXTS: dict[type, dict[str, str]] = {}


def error_text(kind: type[Device], code: str) -> str:
    """The text of error ``code`` in the error table of ``kind`` (a :class:`Device` class), ``""``
    when it has no such row."""
    texts = _ERROR_TEXTS.get(kind)
    if texts is None:
        texts = _ERROR_TEXTS[kind] = {row.code: row.text for row in kind.reference().errors}
    return texts.get(code, "")


def _remove(items: list[Any], item: Any) -> None:
    if item in items:
        items.remove(item)



def _quoted(value: Any) -> str:
    """``value`` as JSON on one line: JSON escapes the C0 controls, not NEL (85h), U+2028 or U+2029,
    which end a line too (str.splitlines, a terminal); text with one of them is written in ASCII."""
    import json  # (a client's: the simulator that serves watches never renders one, nor imports json)

    text = json.dumps(value, ensure_ascii=False)
    return text if text.isprintable() else json.dumps(value)


def describe(item: dict[str, Any]) -> str:
    """One item as a line: ``12.300 sers axis.position 1234.0``, ``12.310 sers event move_end``,
    ``12.400 sers fault blocked_axis on``, ``13.000 sers connect host connected`` (the port is
    added to the device, ``cnc.v7``, where it is not ``main``)."""
    kind = item.get("type")
    head = f"{float(item.get('t', 0.0)):.3f} {item.get('device')}"
    if kind == "change":
        value = item.get("value")
        plain = isinstance(value, str) and value.isprintable()  # (text with a line end is quoted: one item, one line)
        return f"{head} {item.get('name')} {value if plain else _quoted(value)}"
    if kind in ("error", "refused") and "code" in item:  # an error by its code: "sers error P11 8192: drive error: limit switch"
        text = item.get("text")
        return f"{head} {kind} {item['code']}" + (f": {text}" if text else "")
    if kind in ("event", "error"):
        name = str(item.get("name"))
        if not name.isprintable():  # (an event naming a control byte, 'cmd_\x1b': one item, one line)
            name = _quoted(name)
        return f"{head} {name}" if kind == "error" and name.lower().startswith("error") else f"{head} {kind} {name}"
    if kind == "fault":
        return f"{head} fault {item.get('name')} {'on' if item.get('active') else 'off'}"
    if kind == "drive_fault":
        code = item.get("code")
        shown = f"0x{code:04X}" if isinstance(code, int) else str(code)
        return f"{head} drive_fault axis {item.get('axis')} code {shown}"
    port = item.get("port", "main")
    where = head if port == "main" else f"{head}.{port}"
    return f"{where} {kind} {item.get('text', '')}".rstrip()
