"""Write the Lua tables the Wireshark dissectors read, from the kinds' own tables.

``python -m devsim.wireshark.generate`` writes the ``devsim/wireshark/*_tables.lua`` files below: command names, parameter designations, error texts and status bits as the simulator itself
declares them (manual sections in the kinds' tables), so that a dissector never names a telegram
differently from the simulator.  ``tests/wireshark/test_tables.py`` checks that the committed files
are current.  Pure apart from :func:`main`: :func:`render` returns the text of one file.
"""

from __future__ import annotations

import sys
from collections.abc import Callable, Iterable, Mapping
from pathlib import Path
from typing import Any

__all__ = ["GENERATORS", "HERE", "lua_value", "main", "render"]

HERE = Path(__file__).resolve().parent


def lua_string(text: str) -> str:
    """A Lua string literal (UTF-8 bytes, the specials escaped)."""
    out = []
    for char in text:
        if char in '\\"':
            out.append("\\" + char)
        elif char == "\n":
            out.append("\\n")
        elif ord(char) < 0x20 or ord(char) == 0x7F:
            out.append(f"\\{ord(char):03d}")
        else:
            out.append(char)
    return '"' + "".join(out) + '"'


def lua_key(key: Any) -> str:
    if isinstance(key, bool):
        raise TypeError("a boolean is no table key")
    if isinstance(key, int):
        return f"[{key}]"
    return f"[{lua_string(str(key))}]"


def lua_value(value: Any, indent: str = "") -> str:
    """``value`` (str, int, bool, a mapping or a sequence of them) as a Lua expression."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, str):
        return lua_string(value)
    inner = indent + "  "
    if isinstance(value, Mapping):
        if not value:
            return "{}"
        keys = sorted(value, key=lambda k: (isinstance(k, str), k))
        rows = [f"{inner}{lua_key(k)} = {lua_value(value[k], inner)}," for k in keys]
        return "{\n" + "\n".join(rows) + f"\n{indent}}}"
    if isinstance(value, Iterable):
        items = list(value)
        if not items:
            return "{}"
        return "{" + ", ".join(lua_value(v, inner) for v in items) + "}"
    raise TypeError(f"no Lua form for {value!r}")


def _docs(table: Any) -> dict[str, str]:
    """A :class:`devsim.core.kit.Table` as token -> "doc (section)"."""
    return {row.token: row.doc for row in table}


def _gms96() -> dict[str, Any]:
    from devsim.devices.gms96 import commands, face, tables

    letters = _docs(commands.QUEUED_COMMANDS) | _docs(face.ON_RECEIPT)
    return {
        "letters": letters,
        "short": {int(k): v for k, v in _docs(face.SHORT_COMMANDS).items()},
        "t_queries": _docs(face.T_QUERIES),
        "p_on_receipt": _docs(face.P_ON_RECEIPT),
        "g": _docs(commands.G_FUNCTIONS),
        "h": _docs(commands.H_FUNCTIONS),
        "m": _docs(commands.M_FUNCTIONS),
        "q": _docs(commands.Q_TYPES),
        "r": _docs(commands.RESET_FUNCTIONS),
        "n": {int(r.key): {"name": r.name, "doc": r.doc, "unit": r.unit} for r in tables.N_TABLE.rows.values()},
        "status_bits": dict(tables.STATUS_BITS),
        "memory_status_bits": dict(tables.MEMORY_STATUS_BITS),
        "k_bits": dict(tables.K_BITS),
        "messages": dict(tables.MESSAGES),
    }


def _sers() -> dict[str, Any]:
    from devsim.devices.sers import errors, parameters, statements

    return {
        "errno": {n: {"de": de, "en": en} for n, (de, en) in errors.ERRNO.items()},
        "parameters": {int(n): {"name": row.name, "doc": row.doc} for n, row in parameters.PARAMETERS.items()},
        "aliases": {alias: int(n) for n, row in parameters.PARAMETERS.items() for alias in row.aliases},
        "keywords": _docs(statements.KEYWORDS),
    }


def _ip247() -> dict[str, Any]:
    from devsim.devices.ip247 import pg_profile, s5_services, tables

    functions = {int(k[:-1], 16): v for k, v in (_docs(pg_profile.FUNCTIONS) | _docs(s5_services.S5_SERVICES)).items()}
    return {
        "functions": functions,
        "modes": {n: {"name": m.name, "english": m.english} for n, m in tables.MODES.items()},
        "commands": dict(pg_profile.COMMANDS),
        "acks": {
            pg_profile.ACK_ACCEPTED: "accepted",
            pg_profile.ACK_QUEUED: "queued",
            pg_profile.ACK_NEGATIVE: "negative",
            pg_profile.ACK_FULL: "job list full",
            pg_profile.ACK_MALFORMED: "malformed",
        },
        "module_errors": {n: {"de": de, "en": en} for n, (de, en) in tables.MODULE_ERRORS.items()},
    }


def _poselesta() -> dict[str, Any]:
    from devsim.devices.poselesta import codes, tape

    return {
        "key_codes": sorted(codes.KEY_CODES),
        "address_letters": tape.ADDRESS_LETTERS_ORDER,
        "baud_codes": dict(codes.BAUD_CODES),
        "overflow": codes.WERTBEREICHES_UEBERLAUF,
    }


def _pcd4h3() -> dict[str, Any]:
    from devsim.devices.pcd4h3 import sbus, services

    layouts = {sbus.Reads: "reads", sbus.Writes: "writes", sbus.NoParameters: "none"}
    return {
        "commands": {int(row.token[:-1], 16): {"doc": row.doc, "layout": layouts[type(row.handler.telegram)]}
                     for row in services.SERVICES},
        "acks": {sbus.ACK: "ACK", sbus.NAK: "NAK"},
    }


#: The Lua table files the dissectors load (``DEVSIM.tables(...)``) and what each holds.  Keyed by
#: file, not by kind: the kinds are registered once, by their entry points (tests/test_structure.py).
GENERATORS: dict[str, Callable[[], dict[str, Any]]] = {
    "gms96_tables.lua": _gms96,
    "sers_tables.lua": _sers,
    "ip247_tables.lua": _ip247,
    "poselesta_tables.lua": _poselesta,
    "pcd4h3_tables.lua": _pcd4h3,
}


def render(name: str) -> str:
    """The text of the table file ``name``."""
    return (
        f"-- {name}: generated by `python -m devsim.wireshark.generate` from devsim's own tables.\n"
        "-- Do not edit: change the kind's table and run the generator again.\n"
        f"return {lua_value(GENERATORS[name]())}\n"
    )


def main(argv: list[str] | None = None) -> int:
    """Write every table file next to this module; print the files written."""
    for name in GENERATORS:
        path = HERE / name
        path.write_text(render(name), encoding="utf-8")
        print(path)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
