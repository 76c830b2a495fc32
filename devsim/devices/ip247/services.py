"""The IP247's services for both host interfaces: a parsed request (:mod:`.pg_profile`) carried
out on the module and laid out as the response (spec ip247.md §3.6.4, §3.6.5, §3.7).

The PG port sends binary values and names pages 1 … 4; the PLC side (``plc=True``, its absolute
page numbers translated by its face) sends paths and velocities are BCD when the axis's
machine data say "AG BCD-codiert" (spec §3.3.2: errors 66/67 for digits that are not BCD).
"""

from __future__ import annotations

from collections.abc import Callable

from devsim.core.kit import Command, Table
from devsim.devices.ip247.as511 import function_token
from devsim.devices.ip247.module import Ip247Module
from devsim.devices.ip247.pg_profile import (
    ACK_ACCEPTED,
    ACK_MALFORMED,
    ACK_NEGATIVE,
    DELETE_REC,
    OBSERVE,
    OPERATE,
    READ_REC,
    WRITE_REC,
    Delete,
    Header,
    Malformed,
    Observe,
    Operate,
    ReadRecord,
    Request,
    WriteRecord,
    pack_words,
    response,
)
from devsim.devices.ip247.values import NotBcd, path_from_plc, velocity_from_plc

__all__ = ["SERVICES", "serve"]


def serve(module: Ip247Module, request: Request, *, plc: bool = False) -> bytes:
    """The response data to one request (pages 1 … 4; the PLC face translates its absolute
    page numbers)."""
    if isinstance(request, Malformed):
        return _header(module, ACK_MALFORMED, request.page, request.page, request.ba, 0)
    return SERVICES[function_token(request.function)](module, request, plc)


def _observe(module: Ip247Module, request: Request, plc: bool) -> bytes:
    """OBSERVE: the page's header and observed values; FB164's observe modes 71/73 on the data
    channel are negatively acknowledged on the PLC side (manual §6.2.4)."""
    assert isinstance(request, Observe)
    page = request.page
    if plc and module.unit(page) is None:
        return _header(module, ACK_NEGATIVE, page, page, 0, 0)
    return response(Header(ACK_ACCEPTED, page, 0, 0, *module.header(page)), module.observe(page))


def _operate_job(module: Ip247Module, request: Request, plc: bool) -> bytes:
    assert isinstance(request, Operate)
    page = request.page
    return _header(module, _operate(module, request, page, plc), page, page, request.ba, request.cmd)


def _write(module: Ip247Module, request: Request, plc: bool) -> bytes:
    assert isinstance(request, WriteRecord)
    page = request.page
    ack, result = module.channel.write_record(page, request.ba, request.db, list(request.words),
                                              overwrite=request.overwrite, from_plc=plc)
    body = tuple(result) if ack == ACK_ACCEPTED else ()
    return _header(module, ack, page, page, request.ba, 0) + pack_words(body)


def _read(module: Ip247Module, request: Request, plc: bool) -> bytes:
    assert isinstance(request, ReadRecord)
    page = request.page
    ack, words = module.channel.read_record(page, request.ba, request.db, request.bcd)
    return _header(module, ack, page, page, request.ba, 0) + pack_words(words)


def _delete(module: Ip247Module, request: Request, plc: bool) -> bytes:
    assert isinstance(request, Delete)
    page = request.page
    ack = module.channel.delete_record(page, request.ba, request.db)
    return _header(module, ack, page, page, request.ba, 0)


Service = Callable[[Ip247Module, Request, bool], bytes]

#: What each function of the profile does on the module (spec §3.6.1, §3.6.4), by token (``61H``).
SERVICES: Table[Service] = Table([
    Command(function_token(OPERATE), _operate_job, "spec §3.6.4", "an operator job: the 8-byte header"),
    Command(function_token(OBSERVE), _observe, "spec §3.6.4", "the header and 14 bytes of observed values"),
    Command(function_token(WRITE_REC), _write, "spec §3.6.4", "the header and the write's result words"),
    Command(function_token(READ_REC), _read, "spec §3.6.4", "the header and the record's words"),
    Command(function_token(DELETE_REC), _delete, "spec §3.6.4", "the header"),
])


def _header(module: Ip247Module, ack: int, page: int, asked: int, ba: int, cmd: int) -> bytes:
    state = module.header(page) if 1 <= page <= 4 else (0, 0, 0, 0)
    return Header(ack, asked, ba, cmd, *state).pack()


def _operate(module: Ip247Module, request: Operate, page: int, plc: bool) -> int:
    b, w, dd = request.b, request.w, request.dd
    unit = module.unit(page)
    if plc and unit is not None and unit.md is not None:
        try:
            dd = path_from_plc(dd, unit.md.bcd)
            w = velocity_from_plc(w, b, unit.md.bcd)
        except NotBcd as exc:
            module.set_error(unit, exc.error)
            return ACK_ACCEPTED
    return module.operate(page, request.ba, request.cmd, b, w, dd, source="ag" if plc else "pg")
