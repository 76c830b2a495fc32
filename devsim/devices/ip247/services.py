"""The IP247's services for both host interfaces: a parsed request (:mod:`.pg_profile`) carried
out on the module and laid out as the response (spec ip247.md §3.6.4, §3.6.5, §3.7).

The PG port sends binary values and names pages 1 … 4; the PLC side (``plc=True``, its absolute
page numbers translated by its face) sends paths and velocities are BCD when the axis's
machine data say "AG BCD-codiert" (spec §3.3.2: errors 66/67 for digits that are not BCD).
"""

from __future__ import annotations

from devsim.devices.ip247.module import Ip247Module
from devsim.devices.ip247.pg_profile import (
    ACK_ACCEPTED,
    ACK_MALFORMED,
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

__all__ = ["serve"]


def serve(module: Ip247Module, request: Request, *, plc: bool = False) -> bytes:
    """The response data to one request (pages 1 … 4; the PLC face translates its absolute
    page numbers)."""
    asked = page = getattr(request, "page", 0)
    if isinstance(request, Malformed):
        return _header(module, ACK_MALFORMED, page, asked, request.ba, 0)
    if isinstance(request, Observe):
        return response(Header(ACK_ACCEPTED, asked, 0, 0, *module.header(page)), module.observe(page))
    if isinstance(request, Operate):
        return _header(module, _operate(module, request, page, plc), page, asked, request.ba, request.cmd)
    if isinstance(request, WriteRecord):
        ack, result = module.channel.write_record(page, request.ba, request.db, list(request.words),
                                          overwrite=request.overwrite, from_plc=plc)
        body = tuple(result) if ack == ACK_ACCEPTED else ()
        return _header(module, ack, page, asked, request.ba, 0) + pack_words(body)
    if isinstance(request, ReadRecord):
        ack, words = module.channel.read_record(page, request.ba, request.db, request.bcd)
        return _header(module, ack, page, asked, request.ba, 0) + pack_words(words)
    assert isinstance(request, Delete)
    ack = module.channel.delete_record(page, request.ba, request.db)
    return _header(module, ack, page, asked, request.ba, 0)


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
