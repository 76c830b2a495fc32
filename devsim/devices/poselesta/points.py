"""The names of the POSELESTA (manual §2.4, §2.6; spec poselesta.md §3.2.2, §4.8, §4.9): the
panel actions that start and stop transfers, the programs, the machine parameters, the
keyboard and the signals of the host side."""

from __future__ import annotations

import re
from collections.abc import Callable
from typing import Any

import msgspec

from devsim.core.kit import Command, Fault, FaultTable, Table, signal_points
from devsim.core.parameters import alias_hook, parameter_points
from devsim.core.points import BadValue, Family, Point, PointTable, parse_bool
from devsim.devices.poselesta.diagnostics import input_image, input_screen, pots
from devsim.devices.poselesta.execution import STATES
from devsim.devices.poselesta.model import MODES, PoselestaCnc
from devsim.devices.poselesta.parameters import GAIN, PARAMETERS
from devsim.devices.poselesta.signals import AXES, SIGNALS, feed_pot, override
from devsim.devices.poselesta.transfers import FUNCTIONS

__all__ = ["FAULTS", "POINTS"]


def _transfer_points(port: str) -> list[Point]:
    names = ("idle", *(name for (p, name) in FUNCTIONS if p == port))
    functions = ", ".join(f"{name} = {FUNCTIONS[(port, name)].name}" for name in names[1:])
    return [
        Point(f"{port}.transfer", "str", f"the transfer on {port.upper()}: {functions}; idle cancels "
              f"(needs mode {'EXTERNAL_MEDIUM' if port == 'v6' else 'EXTERNAL_OPERATION'})", "§2.6",
              get=lambda m: m.links.name(port), put=lambda m, v: m.links.select(port, v), choices=names,
              in_state=True),
        Point(f"{port}.state", "str", "idle, leader, wait_start, receiving, sending, done, failed or cancelled",
              "§2.6", get=lambda m: m.links.state(port), in_state=True),
        Point(f"{port}.discarded", "int", "bytes received while no input transfer ran", "§2.6",
              get=lambda m: m.links.discarded[port]),
        Point(f"{port}.blocks", "int", "blocks of the running transfer", "§2.6",
              get=lambda m: _blocks(m, port)),
    ]


def _blocks(model: PoselestaCnc, port: str) -> int:
    running = model.links.transfers[port]
    return 0 if running is None else running.blocks


def _axis_points(a: str) -> list[Point]:
    axis = a.upper()
    return [
        Point(f"axis.{a}.position", "float", f"actual position of {axis}, increments of its resolution", "§2.2",
              "inc", get=lambda m: m.axes[a].position(), in_state=True),
        Point(f"axis.{a}.display", "str", f"actual value of {axis} on the screen: mm, or inch with V22/2 H", "§2.3.14",
              get=lambda m: m.axes.display(a, bool(m.signals.get("inch")))),
        Point(f"axis.{a}.velocity", "float", f"actual velocity of {axis}", "§2.5", "inc/s",
              get=lambda m: m.axes[a].velocity()),
        Point(f"axis.{a}.following_error", "float", f"following error of {axis}: v / Kv (P{GAIN + AXES.index(a)})",
              "§2.5", "inc", get=lambda m: m.following_error(a)),
        Point(f"axis.{a}.analog_out", "float", f"±10 V speed set-point of {axis}'s drive", "§2.5", "V",
              get=lambda m: m.analog_out(a)),
        Point(f"axis.{a}.push", "float", f"an outside force moves {axis} by this many mm (open loop only)",
              "§2.3.9", "mm", put=lambda m, v: m.manual.push(a, v)),
    ]


def _program(name: str) -> Point | None:
    match = re.fullmatch(r"program\.P(\d\d)", name, re.ASCII)
    if match is None:
        return None
    number = int(match[1])
    return Point(name, "str", f"program P{number:02d}, one block per line (setting it enters the program)",
                 "§2.6.3", get=lambda m: m.memory.program_text(number), put=lambda m, v: m.memory.set_program_text(number, v))


def _tool(name: str) -> Point | None:
    match = re.fullmatch(r"tool\.T(\d\d)", name, re.ASCII)
    if match is None or not 1 <= int(match[1]) <= 99:
        return None
    number = int(match[1])
    return Point(name, "json", f"tool T{number:02d} of the catalogue: radius and length", "§2.3.14",
                 get=lambda m: m.memory.tools.get(number, {"radius": 0.0, "length": 0.0}),
                 put=lambda m, v: m.memory.set_tool(number, v))


def _param_points() -> list[Point]:
    """``param.P1`` … ``param.P98`` from the parameter rows.  The points take any finite number,
    as the family of names before them did: the control checks a value itself, with its own
    messages (:func:`~devsim.devices.poselesta.parameters.check_parameter`), so the points carry
    neither the rows' ranges nor their whole-number type."""
    points = parameter_points(PARAMETERS, read=lambda m, row: m.params[row.key],
                              write=lambda m, row, value: m.set_param(row.key, value))
    return [msgspec.structs.replace(point, type="float", minimum=None, maximum=None, choices=None) for point in points]


#: The alarms as the EMCY error codes (CiA 301) a fieldbus facade sends when one starts.
EMCY_CODES = {"Fehlermeldung": 0x6100, "ENCODER_FAULT": 0x7305, "FOLLOWING_ERROR_LIMIT": 0x8611}


def _monitoring(model: PoselestaCnc, active: bool) -> None:
    model.signals.set("nc_ready", not active and not model.booting)
    model.screen.show("Fehlermeldung" if active else "")
    if active:
        model.announce("fault", 1, EMCY_CODES["Fehlermeldung"])


def _alarm(alarm: str) -> Callable[[PoselestaCnc, bool], None]:
    """An internal monitoring alarm (spec §4.10): NC ready L, set-points 0 at once, the program
    given up, the alarm on the screen; clearing the fault is ``reset_fault``."""

    def apply(model: PoselestaCnc, active: bool) -> None:
        if active:
            model.executor.emergency_stop()
            model.screen.show(alarm)
            model.record_event(alarm.lower())
            model.announce("fault", 1, EMCY_CODES[alarm])
        elif model.screen.message == alarm:
            model.screen.clear()
        model.signals.set("nc_ready", not active and not model.booting)

    return apply


class _RelaySupply:
    """The outputs as the machine sees them: all L while the relay supply is lost (S39); the
    control's logic goes on and shows again when the supply returns."""

    def __init__(self, model: PoselestaCnc) -> None:
        self.model = model

    def get(self, name: str) -> Any:
        value = self.model.signals.get(name)
        if self.model.relay_supply_lost:
            return 0 if isinstance(value, int) and not isinstance(value, bool) else False
        return value

    def set(self, name: str, value: Any) -> None:
        self.model.signals.set(name, value)


def _diagnostic(model: PoselestaCnc, number: int) -> None:
    if model.mode != "PROGRAM_ENTRY":
        raise BadValue("the diagnostic programs P79 run in PROGRAM_ENTRY")
    run = DIAGNOSTIC_PROGRAMS.get(f"N{number}")
    if run is not None:
        run(model)
    else:
        model.panel.show_page(number)  # N5, N7: pages, read as diagnostics.inputs / diagnostics.pots


def _page(model: PoselestaCnc, number: int) -> bool:
    return model.mode == "PROGRAM_ENTRY" and model.panel.page == number


def _function_keys(model: PoselestaCnc) -> list[str]:
    """The function keys the screen shows for the inputs (§2.3.1: "Solange der NC-Stop wirksam ist, wird
    die entsprechende Funktionstaste am Bildschirm abgebildet" (not in MANUAL, where it is ineffective);
    §2.3.3: the same for NC-Start while V19/3 is H and P75 takes the external button)."""
    keys = []
    if not model.signals.get("nc_stop") and model.mode != "MANUAL":
        keys.append("NC-STOP")
    if model.signals.get("nc_start") and model.params.nc_start_counts("external"):
        keys.append("NC-START")
    return keys


#: The diagnostic programs of P79 that run (spec §4.7): the keyboard test and the output test.
DIAGNOSTIC_PROGRAMS: Table[Callable[[PoselestaCnc], None]] = Table([
    Command("N3", lambda model: _keyboard_test(model, "true"), "§2.6.4",
            "keyboard test: each key's code + 1 on the screen, key 2D ends it"),
    Command("N6", lambda model: model.output_test.start(), "§2.4.11",
            "output test: every output in ascending binary code, 250 ms a step"),
])


def _keyboard_test(model: PoselestaCnc, value: str) -> None:
    try:
        on = parse_bool(value)  # (value.strip().lower() took '\u3000true' as true)
    except BadValue:
        on = False  # anything else ends it, as before
    if on:
        if model.mode != "PROGRAM_ENTRY":
            raise BadValue("the diagnostic programs P79 run in PROGRAM_ENTRY")
        model.panel.keyboard_test_on(True)
    else:
        model.panel.keyboard_test_on(False)


def _relay_supply(model: PoselestaCnc, active: bool) -> None:
    model.relay_supply_lost = active


POINTS = PointTable.of(
    [
        Point("panel.mode", "str", "operating mode (Betriebsart); EXTERNAL_MEDIUM = Σ (V6), "
              "EXTERNAL_OPERATION = EXT (V7)", "§2.4.1", get=lambda m: m.mode,
              put=lambda m, v: m.select_mode(v), choices=tuple(MODES), in_state=True),
        Point("panel.program", "int", "pre-selected program Pxx (the target or source of a transfer)", "§2.6.3",
              get=lambda m: m.program, put=lambda m, v: m.select_program(v), minimum=0, maximum=99, in_state=True),
        Point("panel.message", "str", "screen message, e.g. WERTBEREICHES-UEBERLAUF", "§2.6",
              get=lambda m: m.message, in_state=True),
        Point("panel.clear_message", "bool", "clear the screen message", "§2.6",
              put=lambda m, v: m.screen.clear() if v else None, example=True),
        Point("programs", "json", "numbers of the stored programs", "§2.6.3",
              get=lambda m: sorted(m.memory.programs), in_state=True),
        Point("panel.protect", "int", "protect program Pxx against change and read-in (POS III)", "§2.3.21",
              put=lambda m, v: m.memory.protect(v, True), minimum=0, maximum=98, example=0),
        Point("panel.release", "int", "release a protected program; only with the program lock open (V22/9 H)",
              "§2.3.21", put=lambda m, v: m.memory.protect(v, False), minimum=0, maximum=98, example=0),
        Point("protected", "json", "numbers of the protected programs", "§2.3.21",
              get=lambda m: sorted(m.memory.protected), in_state=True),
        Point("handwheel.turn", "int", "turn the handwheel V5 by this many detents (negative: backwards)", "§2.2.3",
              put=lambda m, v: m.manual.turn(v), example=0),
        Point("handwheel.factor", "int", "hand panel selector: 10 (position 1) or 1 (position 2)", "§3.4",
              get=lambda m: m.manual.handwheel_factor, put=lambda m, v: setattr(m.manual, "handwheel_factor", v),
              choices=(1, 10)),
        Point("handwheel.rate_hz", "float", "detents per second of a turn", "§2.2.3", "1/s",
              get=lambda m: m.manual.handwheel_rate, put=lambda m, v: setattr(m.manual, "handwheel_rate", v),
              minimum=0.1, maximum=1000.0),
        Point("panel.reference", "str", "home an axis (x, y, z or d) in MANUAL: to its reference mark", "§2.3.23",
              put=lambda m, v: m.field.reference(v), choices=tuple(AXES), example="x"),
        Point("referenced", "json", "the axes that are referenced (their software limits act)", "§2.3.23",
              get=lambda m: sorted(m.field.referenced), in_state=True),
        Point("panel.key", "str", "press a front-panel key: a name of v8_keymap (P) or its hex code (48)", "§2.6.4",
              put=lambda m, v: m.press_key(v), example="P"),
        Point("panel.edit_block", "str", "enter one block of a program: '20: N5 X10' (PROGRAM_ENTRY rules of a "
              "read-in)", "§2.6.3", put=lambda m, v: m.memory.edit_block(v), example="0: N1 X0"),
        Point("panel.diagnostic", "int", "run P79 Nn in PROGRAM_ENTRY: 3 keyboard test, 6 output test (5 and 7 "
              "are the pages diagnostics.inputs and diagnostics.pots)", "§2.3.25",
              put=lambda m, v: _diagnostic(m, v), choices=(3, 5, 6, 7), example=5),
        Point("panel.override", "float", "the override pot's value as the screen shows it (V23/4)", "§2.3.22", "%",
              get=lambda m: round(override(m.signals) * 100, 1)),
        Point("panel.feed", "float", "the feed pot's value as the screen shows it (V23/1)", "§2.3.22", "%",
              get=lambda m: round(feed_pot(m.signals) * 100, 1)),
        Point("cassette.tape", "str", "what the simulated cassette recorder holds (config v6_peer: cassette), "
              "as hex bytes", "§2.6.2.2", get=lambda m: m.cassette.tape.hex(" ") if m.cassette else ""),
        Point("cassette.eject", "bool", "erase the simulated cassette", "§2.6.2.2",
              put=lambda m, v: m.cassette.eject() if v and m.cassette else None, example=False),
        Point("panel.nc_start", "bool", "the NC-Start key of the front panel (P75 = 0 or 1)", "§2.3.3",
              put=lambda m, v: m.executor.nc_start("panel") if v else None, example=True),
        Point("panel.mdi", "str", "the block entered for Hand-Einzelsatz (MANUAL_SINGLE_BLOCK), e.g. N1 G00 X10",
              "§2.4.7", get=lambda m: m.memory.mdi, put=lambda m, v: setattr(m.memory, "mdi", v)),
        Point("diagnostics.inputs", "json", "P79 N5 (panel.diagnostic 5 in PROGRAM_ENTRY, a mode key ends it): every "
              "input level the control sees as ports 1A … 4B (bit = 1: H); null while the page is not shown",
              "§2.3.25", get=lambda m: input_image(m.signals) if _page(m, 5) else None),
        Point("diagnostics.input_screen", "str", "P79 N5 as the screen shows it (Port n EIN A7…A0 B7…B0); empty "
              "while the page is not shown", "§2.3.25",
              get=lambda m: input_screen(m.signals) if _page(m, 5) else "", in_state=True),
        Point("panel.function_keys", "json", "the function keys the screen shows for the inputs: NC-STOP while "
              "NC-Stop is effective (V19/1 L, not in MANUAL), NC-START while V19/3 is H (P75 = 0 or 2)", "§2.3.3",
              get=_function_keys, in_state=True),
        Point("diagnostics.output_test", "bool", "P79 N6: true starts the output test (PROGRAM_ENTRY), false is "
              "key C: all outputs L until a power cycle", "§2.4.11", get=lambda m: m.output_test.running,
              put=lambda m, v: m.output_test.start() if v else m.output_test.stop()),
        Point("diagnostics.output_cycles", "int", "P79 N6: passes of the output test (64 s each)", "§2.4.11",
              get=lambda m: m.output_test.cycles),
        Point("diagnostics.keyboard_test", "str", "P79 N3: set true to start; shows each key's code + 1 in hex "
              "(key P, 48, shows 49); key 2D ends it (then empty)", "§2.6.4",
              get=lambda m: m.panel.keyboard_test or "", put=lambda m, v: _keyboard_test(m, v), example="false"),
        Point("xy_plotter", "bool", "X/Y plotter operation (POS III, V22/8 sampled at power-on): set-points = "
              "position over the working field in 14 bits", "§2.3.20", get=lambda m: m.plotter, in_state=True),
        Point("diagnostics.pots", "json", "P79 N7 (panel.diagnostic 7 in PROGRAM_ENTRY, a mode key ends it): feed "
              "and override pot as hex 00 … FF; null while the page is not shown", "§2.3.26",
              get=lambda m: pots(m.signals) if _page(m, 7) else None),
        Point("program.compensation", "str", "cutter radius compensation in force: G40, G41 or G42 (recorded; "
              "the path has no offset)", "§2.3.15", get=lambda m: f"G{m.functions.compensation}"),
        Point("program.tool", "int", "the tool T last programmed (0: none)", "§2.4.8",
              get=lambda m: m.functions.tool, in_state=True),
        Point("program.state", "str", f"the block cycle: {', '.join(STATES)}", "§2.4.10",
              get=lambda m: m.executor.state, choices=STATES, in_state=True),
        Point("program.block", "int", "number N of the block being executed (-1: none)", "§2.3.13",
              get=lambda m: m.executor.block_number, in_state=True),
        Point("keyboard.last_key", "int", "code of the last key taken from V8 (-1: none)", "§2.6.4",
              get=lambda m: -1 if m.panel.last_key is None else m.panel.last_key),
        Point("keyboard.accepted", "int", "keys taken from V8", "§2.6.4", get=lambda m: m.keyboard.accepted),
        Point("keyboard.lost", "int", "keys lost because they came less than 100 ms apart", "§2.6.4",
              get=lambda m: m.keyboard.lost),
    ],
    *(_axis_points(a) for a in AXES),
    _transfer_points("v6"),
    _transfer_points("v7"),
    signal_points([d for d in SIGNALS if d.kind != "output"], bank=lambda m: m.terminals),
    signal_points([d for d in SIGNALS if d.kind == "output"], bank=lambda m: _RelaySupply(m)),
    _param_points(),
    alias=alias_hook(PARAMETERS),
    families=[
        Family("program.P<nn>", "str", "program P00 … P98, one block per line", "§2.6.3", _program),
        Family("tool.T<nn>", "json", "tool T01 … T99 of the tool catalogue: {radius, length}", "§2.3.14", _tool),
    ],
)

FAULTS = FaultTable(
    [
        Fault("monitoring", "internal monitoring error: NC ready goes L, an error message shows", "§2.4.5",
              _monitoring),
        *(Fault(f"encoder_loss_{a}", f"the encoder of {a.upper()} is lost: alarm ENCODER_FAULT, NC ready L, "
                "set-points 0, the program given up", "§2.2", _alarm("ENCODER_FAULT")) for a in AXES),
        *(Fault(f"rm_missing_{a}", f"the reference mark signal of {a.upper()} is lost: homing never finds a mark",
                "§2.2.2", lambda m, on, a=a: (m.field.rm_missing.add if on else m.field.rm_missing.discard)(a)) for a in AXES),
        *(Fault(f"count_loss_{a}", f"the encoder of {a.upper()} drops count_loss_increments counts (overspeed, "
                "noise): the actual value falls behind the true position", "§2.2",
                lambda m, on, a=a: on and m.field.lose_counts(a, m.cfg.count_loss_increments)) for a in AXES),
        Fault("following_error", "a following error beyond the limit (a blocked drive): alarm "
              "FOLLOWING_ERROR_LIMIT, NC ready L, set-points 0", "§2.5", _alarm("FOLLOWING_ERROR_LIMIT")),
        Fault("relay_supply", "the 24 V supply of the output relays is lost: every output reads L; the "
              "control's state shows again when it returns", "§2.7", _relay_supply),
    ]
)


