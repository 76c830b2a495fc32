"""Standard S5 programmer-port services on the IP247's PG port, for generic AS511 tools (spec
ip247.md §3.5.2; public descriptions of B_INFO and DB_READ, libnodave's AS511 client): the
module's records appear as data blocks in one 64 KiB byte-addressed memory.

* traverse program n → **DB n** (the BA69 record: length, 00 'D', 'B' n, error, faulty block, text);
* the machine data of an axis, stored as DB d → **DX d** (the BA67 record, 70 words);
* ``18H`` system parameters: five 00H bytes, then the start addresses of the (empty) process
  images, flags, timers, counters and system data (what a client reads at connect);
* ``1AH`` B_INFO (block type, number): 00H, the address of DW0, 70H 70H, type | 40H, number, PG
  id, library number, length in words with the 5-word header; an unknown block is refused;
* ``1BH`` block address list (block type): 00H, then for block numbers 0 … 255 the address of
  its DW0 as a word, 0 where there is no such block (how a tool lists the DBs);
* ``04H`` read memory (first address, last address): five 00H bytes, then the bytes.

These services are off unless the configuration says ``s5_services: true``: the spec's vector
(f) has the module refuse 18H, and the real module's PG function codes are not public.  Pure: the
caller passes the records.
"""

from __future__ import annotations

import struct
from collections.abc import Callable

from devsim.core.kit import Command, Table
from devsim.devices.ip247.as511 import Refused, Reply, function_token

__all__ = ["DB", "DX", "S5_SERVICES", "S5Memory"]

DB, DX = 0x01, 0x0C  # block type codes
READ_MEMORY, SYSTEM_PARAMETERS, BLOCK_INFO, BLOCK_LIST = 0x04, 0x18, 0x1A, 0x1B
FIRST_BLOCK = 0x1000  # where the blocks begin; below: the (empty) images the system data name
IMAGES = (0x0080, 0x0100, 0x0200, 0x0300, 0x0400, 0x0500)  # inputs, outputs, flags, timers, counters, system


class S5Memory:
    """The blocks laid out in memory: each a 5-word header (70 70, type | 40, number, PG id,
    library, length) and its words, in the order given."""

    def __init__(self, blocks: list[tuple[int, int, list[int]]]) -> None:
        self.memory = bytearray(0x10000)
        self.info: dict[tuple[int, int], tuple[int, int]] = {}  # (type, number) → (DW0 address, words)
        address = FIRST_BLOCK
        for kind, number, words in blocks:
            length = 5 + len(words)
            if address + 2 * length > len(self.memory):
                break  # (6,000 characters of programs and three MD sets fit easily)
            header = struct.pack(">BBBBHHH", 0x70, 0x70, 0x40 | kind, number & 0xFF, 0, 0, length)
            body = struct.pack(f">{len(words)}H", *(w & 0xFFFF for w in words))
            self.memory[address : address + 10 + len(body)] = header + body
            self.info[(kind, number & 0xFF)] = (address + 10, length)
            address += 10 + len(body)

    def service(self, function: int, parameters: bytes) -> Reply:
        handler = S5_SERVICES.get(function_token(function))
        return handler(self, parameters) if handler is not None else Refused("not an S5 service")

    def _system_parameters(self, parameters: bytes) -> Reply:
        return bytes(5) + struct.pack(">6H", *IMAGES) + bytes(28)

    def _block_info(self, parameters: bytes) -> Reply:
        if len(parameters) != 2 or (parameters[0], parameters[1]) not in self.info:
            return Refused("no such block")
        address, length = self.info[(parameters[0], parameters[1])]
        return struct.pack(">BHBBBBHHH", 0, address, 0x70, 0x70, 0x40 | parameters[0], parameters[1], 0, 0, length)

    def _block_list(self, parameters: bytes) -> Reply:
        if len(parameters) != 1:
            return Refused("the block list takes a block type")
        addresses = [self.info.get((parameters[0], n), (0, 0))[0] for n in range(256)]
        return b"\x00" + struct.pack(">256H", *addresses)

    def _read_memory(self, parameters: bytes) -> Reply:
        if len(parameters) != 4:
            return Refused("read memory takes a first and a last address")
        first, last = struct.unpack(">HH", parameters)
        if last < first:
            return Refused("the last address lies before the first")
        return bytes(5) + bytes(self.memory[first : last + 1])


Service = Callable[[S5Memory, bytes], Reply]

#: The standard S5 services, by token (``1AH``); public descriptions of AS511 (spec §3.5.2).
S5_SERVICES: Table[Service] = Table([
    Command(function_token(SYSTEM_PARAMETERS), S5Memory._system_parameters, "spec §3.5.2",
            "system parameters: the start addresses of the (empty) images"),
    Command(function_token(BLOCK_INFO), S5Memory._block_info, "spec §3.5.2",
            "B_INFO (block type, number): the block's address and header"),
    Command(function_token(BLOCK_LIST), S5Memory._block_list, "spec §3.5.2",
            "block address list (block type): DW0 addresses of blocks 0 … 255"),
    Command(function_token(READ_MEMORY), S5Memory._read_memory, "spec §3.5.2",
            "read memory (first address, last address)"),
])
