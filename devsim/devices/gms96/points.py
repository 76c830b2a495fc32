"""The GMS96's control names, signals and faults, declared once (spec gms96.md §7, manual per row).

``param.N<k>`` rows are generated from the N-parameter table, ``marker.MB<n>`` and the marker
bits from the process image's layout; spellings the card's documentation uses (``param.n15``,
``param.15``, ``marker.M7.0``) resolve through the alias hook.  Values are checked by type and
range before they take effect; an N parameter also gets the card's own range rule.
``program.<n>`` is a CNC program as the manual writes its commands (``A1000``, ``p10;16;2``);
setting it stores the program as its download ``p3;100;n`` … ``p3;101`` would (§2.5).
"""

from __future__ import annotations

import re
from typing import Any

import msgspec

from devsim.core.kit import Fault, FaultTable, SignalDef, signal_points
from devsim.core.parameters import Param, alias_hook, parameter_points
from devsim.core.points import BadValue, Family, Point, PointTable, ascii_digits, strip_blanks
from devsim.core.settings import Invalid
from devsim.devices.gms96 import tables
from devsim.devices.gms96.codec import S24_MIN, wrap24
from devsim.devices.gms96.commands import QUEUED_COMMANDS
from devsim.devices.gms96.config import DilSwitch
from devsim.devices.gms96.image import parse_bit
from devsim.devices.gms96.io import INPUT_BYTES
from devsim.devices.gms96.nparams import N_TABLE

__all__ = ["FAULTS", "LEDS", "POINTS", "SIGNALS", "command_rows", "command_text"]

LEDS = {"dc_overvoltage": "red", "dc_undervoltage": "yellow", "overtemperature": "green"}

SIGNALS: tuple[SignalDef, ...] = (
    *(SignalDef(f"E{byte}.{bit}", "input", False, f"24 V input E{byte}.{bit}", "§4.4")
      for byte in range(INPUT_BYTES) for bit in range(8)),
    *(SignalDef(f"A{n // 8}.{n % 8}", "output", False, f"24 V output A{n // 8}.{n % 8}", "§4.4") for n in range(16)),
    SignalDef("emergency_stop", "input", False, "Notaus input at 0 V (low-active): emergency stop", "§2.2"),
    SignalDef("override_pot", "quantity", 100.0, "override potentiometer", "§2.3.1 o", "%", minimum=0, maximum=125),
    SignalDef("load_pct", "quantity", 0.0, "load current in % of the maximum current (I²t)", "§4.5.3", "%",
              minimum=0, maximum=1000),
    SignalDef("blocked", "quantity", False, "the mechanics hold the axis (following error grows)", "§4.5.3",
              type="bool"),
    SignalDef("monitoring", "quantity", "", "power-stage monitoring cause ('' = none)", "§4.5.3", type="str"),
    SignalDef("output_overload", "quantity", False, "24 V outputs overloaded / short-circuited", "§4.5.3",
              type="bool"),
    SignalDef("ref_pulse_hz", "quantity", 0.0, "pulse rate on the counter input reference track (Q8)", "§5.10",
              "Hz", minimum=0, maximum=1e7),
)


def _read_n(card: Any, row: Param) -> int:
    return int(card.params.read(int(row.key)))


def _write_n(card: Any, row: Param, value: Any) -> None:
    card.set_n(int(row.key), value)  # the card's own range rule (clamp or ignore, §3.8.10)


def _n_points() -> list[Point]:
    """``param.N<k>``: a row without a range of its own takes the 24-bit field's (manual §2.3)."""
    return [
        msgspec.structs.replace(
            point,
            minimum=tables.INT24_MIN if point.minimum is None else point.minimum,
            maximum=tables.INT24_MAX if point.maximum is None else point.maximum,
        )
        for point in parameter_points(N_TABLE, _read_n, _write_n)
    ]


def _marker_byte(n: int) -> Point:
    def put(card: Any, value: Any) -> None:
        card.write_marker_byte(n, value)

    return Point(f"marker.MB{n}", "int", f"marker byte MB{n}", "§4.4", get=lambda card: card.marker_byte(n), put=put,
                 minimum=0, maximum=255)


def _marker_bit(byte: int, bit: int) -> Point:
    def put(card: Any, value: Any) -> None:
        card.write_marker_bit(byte, bit, value)

    return Point(f"marker.M{byte}.{bit}", "bool", f"marker bit M{byte}.{bit}", "§4.4",
                 get=lambda card: bool(card.marker_byte(byte) >> bit & 1), put=put)


_param_alias = alias_hook(N_TABLE)


def _alias(name: str) -> str | None:
    """``param.n15`` / ``param.15`` → ``param.N15``; ``marker.mb4`` → ``marker.MB4``."""
    section, dot, rest = name.partition(".")
    if not dot:
        return None
    if section == "param":
        return _param_alias(name)
    if section == "marker":
        upper = rest.upper()
        if upper.startswith("MB") and ascii_digits(upper[2:]):
            return f"marker.MB{int(upper[2:])}"
        return f"marker.{upper}"
    return None


def _set_dil(field: str) -> Any:
    def put(card: Any, value: Any) -> None:
        data = card.pending_dil.dump()
        data[field] = value
        try:
            card.pending_dil = DilSwitch.parse(data)  # read at the next reset (§2.2)
        except Invalid as exc:
            raise BadValue(f"dil.{exc}") from None

    return put


def _plc_running(card: Any, value: bool) -> None:
    if value:
        card.plc.start()
    else:
        card.plc.stop()


def _message(card: Any, value: int) -> None:
    card.image.post_message(value)
    card.changed()


def _tool_offset(card: Any, value: int) -> None:
    card.coordinates.tool_offset = value


#: Commands a CNC download does not record: carried out on receipt even then (the face's
#: ``o2`` and the downloads of P_ON_RECEIPT, spec §3.8.13), by letter and the leading parameters.
_NOT_RECORDED = (("o", (2,)), ("p", (1, 100)), ("p", (1, 101)), ("p", (3, 100)), ("p", (3, 101)))
#: A command between the control blanks (:func:`~devsim.core.points.strip_blanks`; \s also took VT and FF):
#: a letter, P1[;P2[;P3]].
_COMMAND = re.compile(r"[ \t\r]*([^ \t\r])[ \t\r]*(-?\d+(?:[ \t\r]*;[ \t\r]*-?\d+){0,2})?[ \t\r]*", re.ASCII)


def command_rows(program: Any) -> list[list[Any]]:
    """A CNC program's commands as its download records them (manual §2.5): rows ``[letter,
    P1, P2, P3, parameters sent]``; the commands are texts as the manual writes them
    (``A1000``, ``+-500``, ``p10;16;2``), a list or one per line.  A command the download would
    not record (``T``, ``c``, ``N``, ``q``, ``o2``, a download) is refused, as is a parameter
    beyond 24 bits; one from 2^23 up is kept as its 24-bit pattern reads (``A16777215`` is
    ``A-1``, as on the line)."""
    # (lines end at LF or CR LF: str.splitlines also ends them at FS, GS, RS, NEL and U+2028)
    lines = program.replace("\r\n", "\n").split("\n") if isinstance(program, str) else program
    if not isinstance(lines, list) or not all(isinstance(text, str) for text in lines):
        raise BadValue("a CNC program is its commands: a list of texts, or one per line")
    rows = []
    for text in (line for line in lines if strip_blanks(line)):  # (str.strip: a line of NBSP or FS was empty)
        match = _COMMAND.fullmatch(text)
        if match is None:
            raise BadValue(f"{text!r}: a command is a letter and up to 3 numbers P1;P2;P3, e.g. A1000 or p10;16;2")
        letter = match[1]
        params = [int(p) for p in match[2].split(";")] if match[2] else []
        if letter not in QUEUED_COMMANDS or any(
            letter == cmd and tuple(params[: len(lead)]) == lead for cmd, lead in _NOT_RECORDED
        ):
            raise BadValue(f"{text!r}: not a command of a CNC program (carried out on receipt, §2.3.1)")
        if not all(S24_MIN <= p <= 0xFFFFFF for p in params):
            raise BadValue(f"{text!r}: a parameter has 24 bits (§2.3)")
        rows.append([letter, *(wrap24(p) for p in params), *[0] * (3 - len(params)), len(params)])
    return rows


def command_text(row: list[Any]) -> str:
    """A recorded row as the manual writes the command: ``A1000``, ``p10;16;2``."""
    letter, *params, count = row
    return letter + ";".join(str(p) for p in params[:count])


def _store_program(card: Any, number: int, program: Any) -> None:
    rows = command_rows(program)
    if number >= card.cfg.max_programs:
        raise BadValue(f"program {number}: the card keeps programs 0 … {card.cfg.max_programs - 1}")
    if card.flash.download is not None:
        raise BadValue("a download is running")
    if not card.flash.store_program(number, rows, card.cfg.max_total_commands):
        if card.flash.write_error:
            raise BadValue(f"program {number} not stored: the FLASH cannot be written (fault flash_error, T3;4 I.2)")
        raise BadValue(f"program {number} not stored: the programs would exceed {card.cfg.max_total_commands} "
                       "commands (T3;4 I.4)")


def _program(name: str) -> Point | None:
    match = re.fullmatch(r"program\.(\d{1,2})", name, re.ASCII)
    if match is None:
        return None
    number = int(match[1])
    return Point(name, "json", f"CNC program {number}: its commands as texts (set: stored as by its download "
                 "p3;100 … p3;101; program 0 replaces them all)", "§2.5",
                 get=lambda c: [command_text(row) for row in c.flash.programs.get(number, [])],
                 put=lambda c, v: _store_program(c, number, v))


def _register(n: int) -> Point:
    return Point(f"register.{n}", "int", f"data register {n} (4 bytes, signed)", "§4.6",
                 get=lambda card: int.from_bytes(card.image.data[4 * n : 4 * n + 4], "little", signed=True))


_PLAIN: list[Point] = [
    # -- the shared vocabulary -------------------------------------------------------------
    Point("axis.position", "float", "actual position (set-point − v/Kv), increments in the machine frame",
          "§5.1", "inc", get=lambda c: c.coordinates.physical_to_machine(c.indexer.actual()), in_state=True, shared=True),
    Point("axis.velocity", "float", "set-point velocity", "§5.1", "inc/s", get=lambda c: c.axis.velocity(),
          in_state=True, shared=True),
    Point("motion", "bool", "the axis moves (motion bit of the status byte)", "§4.3", get=lambda c: c.motion(),
          shared=True),
    Point("energized", "bool", "the position controller drives the motor", "§4.5.3",
          get=lambda c: bool(c.stage.controller and c.powered), shared=True),
    Point("ready", "bool", "powered, booted, no emergency stop, monitoring fault or NV error", "§4.5.3",
          get=lambda c: bool(c.powered and not c.booting and not c.stage.faulted()), shared=True),
    Point("fault", "bool", "an emergency stop, a monitoring fault or the NV error (T3;4 I.5) is active", "§4.5.3",
          get=lambda c: c.stage.faulted(), shared=True),
    # -- the axis ---------------------------------------------------------------------------
    Point("axis.setpoint", "float", "set-point in the machine frame", "§5.1", "inc",
          get=lambda c: c.coordinates.physical_to_machine(c.axis.position())),
    Point("axis.physical", "float", "actual position in the physical frame", "§5.1", "inc",
          get=lambda c: c.indexer.actual()),
    Point("axis.acceleration", "float", "set-point acceleration", "§5.1", "inc/s²",
          get=lambda c: c.axis.acceleration()),
    Point("axis.moving", "bool", "the set-point moves", "§5.1", get=lambda c: c.axis.moving),
    Point("axis.phase", "str", "the ramp phase of the set-point", "§5.2", get=lambda c: c.axis.phase()),
    Point("axis.following_error", "float", "following error", "§5.11", "inc",
          get=lambda c: c.indexer.following_error()),
    # -- the card ---------------------------------------------------------------------------
    Point("status", "int", "status byte (T3;0)", "§4.3", get=lambda c: c.status(), in_state=True),
    Point("K", "int", "K byte of the status Kurzsatz", "§4.3",
          get=lambda c: tables.k_from_status(c.status(), bool(c.image.markers[4])), in_state=True),
    Point("MB4", "int", "message marker byte MB4", "§4.4", get=lambda c: c.image.markers[4], in_state=True),
    Point("memory_status", "int", "memory status byte (T3;4)", "§4.3", get=lambda c: c.memory_status()),
    Point("position", "int", "set-point in the work frame (T0)", "§5.1", "inc", get=lambda c: c.coordinates.setpoint_work(),
          in_state=True),
    Point("position_setpoint", "int", "set-point in the work frame", "§5.1", "inc",
          get=lambda c: c.coordinates.setpoint_work()),
    Point("position_counter", "int", "actual position counter", "§5.1", "inc",
          get=lambda c: round(c.coordinates.physical_to_machine(c.indexer.actual()))),
    Point("following_error", "float", "following error", "§5.11", "inc", get=lambda c: c.indexer.following_error(),
          in_state=True),
    Point("current", "float", "motor current as a fraction of the maximum (T1;5)", "§5.7",
          get=lambda c: c.torque.current()),
    Point("busy", "bool", "BUSY: a command is being executed", "§4.3", get=lambda c: c.busy(), in_state=True),
    Point("idxoff", "bool", "IDXOFF: no reference", "§4.3", get=lambda c: c.stage.idxoff, in_state=True),
    Point("estop", "bool", "the emergency stop is active", "§2.2", get=lambda c: c.stage.estop, in_state=True),
    Point("monitoring", "str", "the monitoring cause ('' = none)", "§4.5.3", get=lambda c: c.stage.monitoring_cause()),
    Point("controller", "bool", "the position controller is active", "§4.5.3", get=lambda c: c.stage.controller,
          in_state=True),
    Point("speed", "float", "set-point speed", "§5.2", "inc/s", get=lambda c: abs(c.axis.velocity())),
    Point("override", "float", "override in effect", "§2.3.1 o", "%", get=lambda c: c.indexer.override_pct()),
    Point("queue_length", "int", "commands waiting in the queue", "§4.2.1", get=lambda c: len(c.executor.queue)),
    Point("rejected_moves", "int", "moves refused since power-on", "§4.2.1", get=lambda c: c.executor.rejected_moves),
    Point("g96_rpm", "float", "spindle speed computed by G96", "§5.9", "1/min", get=lambda c: c.coordinates.g96_rpm()),
    Point("programs", "json", "stored CNC programs: number → commands", "§4.9",
          get=lambda c: {k: len(v) for k, v in c.flash.programs.items()}, in_state=True),
    Point("address", "int", "the card address (DIL switch)", "§2.2", get=lambda c: c.address, in_state=True),
    Point("protocol", "str", "S or E version (DIL 7)", "§2.2", get=lambda c: c.dil.protocol, in_state=True),
    Point("booting", "bool", "the card boots and does not listen", "§2.3.1", get=lambda c: c.booting),
    Point("powered", "bool", "the card has power", "§4.1.2", get=lambda c: c.powered, in_state=True),
    Point("silent", "bool", "the card ignores the line (boot, flash erase)", "§2.3.1 p", get=lambda c: c.silent),
    Point("i2t_active", "bool", "I²t limits the current", "§4.5.3", get=lambda c: c.i2t.limiting),
    Point("i2t_latched", "bool", "the I²t fault is latched", "§4.5.3", get=lambda c: c.i2t.latched),
    Point("leds", "json", "the red, yellow and green LEDs", "§4.5.3",
          get=lambda c: {color: LEDS.get(c.stage.monitoring_cause()) == color for color in ("red", "yellow", "green")}),
    Point("link_errors", "json", "frames the link dropped, by reason", "§2.3",
          get=lambda c: dict(c.link_errors)),
    Point("param.M", "int", "maximum speed setting M", "§2.3.1 M", get=lambda c: c.feed.M, in_state=True),
    Point("param.B", "int", "acceleration setting B", "§2.3.1 B", get=lambda c: c.feed.B, in_state=True),
    Point("param.S", "int", "S setting", "§2.3.1 S", get=lambda c: c.feed.S, in_state=True),
    Point("param.f", "int", "feed rate f", "§2.3.1 f", get=lambda c: c.feed.f, in_state=True),
    Point("message", "int", "post a message (MB4 FIFO)", "§4.4", put=_message, minimum=0, maximum=255, example=1),
    Point("tool_offset", "int", "the tool offset", "§5.9", "inc", get=lambda c: c.coordinates.tool_offset,
          put=_tool_offset),
    Point("plc", "json", "the PLC's state", "§4.10", get=lambda c: c.plc.state(), in_state=True),
    Point("plc.running", "bool", "the PLC cycles (p1;1 / p1;2)", "§4.10", get=lambda c: c.plc.state()["running"],
          put=_plc_running),
    Point("plc.image", "str", "the PLC image loaded by a download", "§4.10", get=lambda c: c.flash.plc_image),
    Point("plc.frames", "json", "the downloaded PLC frames", "§4.10", get=lambda c: list(c.flash.plc_frames)),
    Point("counter", "json", "the counter input's state", "§5.10", get=lambda c: c.counter.state(), in_state=True),
    Point("counter.pulses", "int", "count pulses at the counter input (as if they arrived)", "§5.10",
          put=lambda c, v: c.counter.pulses(v), example=0),
    Point("counter.rate_hz", "float", "pulse rate at the counter input", "§5.10", "Hz",
          get=lambda c: c.counter.state().get("rate_hz", 0.0), put=lambda c, v: c.counter.set_rate(v),
          minimum=-1e7, maximum=1e7),
    *(Point(f"dil.{field}", kind, f"DIL switch {field} (read at the next reset)", "§2.2",
            get=lambda c, f=field: getattr(c.pending_dil, f), put=_set_dil(field))
      for field, kind in (("address", "int"), ("protocol", "str"), ("baud", "int"), ("interpolation", "bool"))),
]

def _marker(name: str) -> Point | None:
    rest = name.removeprefix("marker.")
    if rest == name:
        return None
    number = rest[2:]
    if rest.startswith("MB") and ascii_digits(number) and int(number) < tables.MARKER_BYTE_COUNT:
        return _marker_byte(int(number))
    try:
        area, byte, bit = parse_bit(rest)
    except ValueError:
        return None
    if area != "M" or not 0 <= byte < tables.MARKER_BYTE_COUNT or not 0 <= bit < 8:
        return None
    return _marker_bit(byte, bit)


def _numbered(prefix: str, count: int, make: Any) -> Any:
    def family(name: str) -> Point | None:
        rest = name.removeprefix(prefix)
        if rest != name and ascii_digits(rest) and int(rest) < count:
            return make(int(rest))
        return None

    return family


def _data(n: int) -> Point:
    return Point(f"data.{n}", "int", f"data byte {n}", "§4.6", get=lambda c: c.image.data[n])


def _plc_key(key: str, doc: str, kind: Any = "int") -> Point:
    return Point(f"plc.{key}", kind, doc, "§4.10", get=lambda c: c.plc.state()[key])


def _counter_key(key: str, doc: str, kind: Any = "int") -> Point:
    return Point(f"counter.{key}", kind, doc, "§5.10", get=lambda c: c.counter.state()[key])


def _set_monitoring(card: Any, value: str) -> None:
    card.signals.set("monitoring", "" if value == "clear" else value)


POINTS = PointTable.of(
    _PLAIN,
    signal_points(s for s in SIGNALS if s.name != "monitoring"),
    [
        Point("quantity.monitoring", "str", "power-stage monitoring cause ('' or clear: none): dc_undervoltage, dc_overvoltage, "
              "overtemperature (the LEDs), resolver_loss (E2.3 on resolver cards), any other text", "§4.5.3",
              get=lambda c: c.signals.get("monitoring"), put=_set_monitoring,
              in_state=True, shared=True),
    ],
    _n_points(),
    [
        _plc_key("loaded", "a PLC program is stored", "bool"),
        _plc_key("cycles", "PLC cycles run"),
        _plc_key("cycle_ms", "the PLC cycle time", "float"),
        _plc_key("storage_error", "the PLC program did not fit", "bool"),
        _plc_key("fault", "why the PLC stopped by itself (a hook raised), or null", "str"),
        _plc_key("image_bytes", "bytes of the PLC image"),
        _counter_key("mode", "counter-input mode active", "bool"),
        _counter_key("sync", "the counter is synchronised", "bool"),
        _counter_key("count", "the counter value"),
        _counter_key("weight", "the counter weight", "float"),
        _counter_key("h22", "the H22 min/max measurement", "json"),
        _counter_key("h22_running", "an H22 measurement runs", "bool"),
    ],
    alias=_alias,
    families=[
        Family("marker.MB<n>", "int", "marker byte MB0 … MB255 (MB0, MB1 overlaid by the status)", "§4.4", _marker),
        Family("marker.M<byte>.<bit>", "bool", "marker bit, e.g. M7.0", "§4.4", _marker),
        Family("data.<n>", "int", "data byte 0 … 255", "§4.6", _numbered("data.", 256, _data), "r"),
        Family("register.<n>", "int", "data register 0 … 19 (4 bytes, signed)", "§4.6",
               _numbered("register.", 20, _register), "r"),
        Family("program.<n>", "json", "CNC program 0 … 99: its commands as texts, e.g. [A1000, p10;16;2] (set: "
               "stored as by its download; program 0 replaces them all)", "§2.5", _program),
    ],
)


def _signal(name: str, value: Any) -> Any:
    def apply(card: Any, active: bool) -> None:
        card.signals.set(name, value(active))

    return apply


FAULTS = FaultTable(
    [
        Fault("blocked_axis", "the mechanics hold the axis: the following error grows until N20 trips", "§4.5.3",
              _signal("blocked", bool)),
        Fault("emergency_stop", "Notaus at 0 V: power stage off, motion aborted, queue flushed", "§2.2",
              _signal("emergency_stop", bool)),
        Fault("power", "the supply is off while active; a power-on afterwards", "§4.1.2",
              lambda card, active: card.power(not active)),
        Fault("monitoring", "power-stage monitoring trips (DC undervoltage) while active", "§4.5.3",
              _signal("monitoring", lambda active: "dc_undervoltage" if active else "")),
        Fault("flash_error", "the FLASH cannot be erased or written while active: a CNC or PLC download fails "
              "and leaves the FLASH as it was, T3;4 I.2 until one succeeds", "§2.3.1 T",
              lambda card, active: setattr(card.flash, "defective", active)),
    ]
)
