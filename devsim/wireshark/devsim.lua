-- devsim.lua: Wireshark dissector for devsim's serial-line captures (LINKTYPE_USER0 = 147).
--
-- Every record is one chunk that crossed a serial line in one direction: a 16-byte devsim header
-- (magic "ds", version 1, direction, protocol, port, the host's line settings, a mismatch flag;
-- docs/wireshark-dissectors.md) and the bytes.  This file decodes the header and hands the bytes
-- to the kind's dissector by the protocol byte:
--   1 SERS, 2 GMS96 (DIN 19244 / FT1.2), 3 POSELESTA, 4 IP247 PG port (AS511),
--   5 PCD4.H3 serial S-Bus (data mode), 16 Modbus RTU (Wireshark's own mbrtu).
-- The kinds' dissectors (gms96.lua, sers.lua, as511.lua, poselesta.lua, sbus_serial.lua) are loaded from this
-- file's directory and get the DEVSIM table below as their argument; loaded on their own (a plugins
-- folder loads every .lua file) they do nothing.
--
-- Load by hand:  tshark -X lua_script:/path/to/devsim/wireshark/devsim.lua -r trace.pcap
-- or copy the directory's .lua files into Wireshark's personal Lua plugins folder
-- (`devsim wireshark --install` does that).

if _G.devsim_dissector_loaded then return end  -- loaded twice (plugins folder and -X lua_script)
_G.devsim_dissector_loaded = true

local function here()
    local source = debug.getinfo(1, "S").source
    return (source:sub(1, 1) == "@" and source:sub(2):match("^(.*[/\\])")) or ""
end

local DEVSIM = { dir = here(), kinds = {} }

local HEADER_SIZE = 16
local PROTOCOLS = {
    [0] = "unknown", [1] = "SERS", [2] = "GMS96 (DIN 19244 / FT1.2)", [3] = "POSELESTA",
    [4] = "IP247 PG (AS511)", [5] = "PCD4.H3 serial S-Bus", [16] = "Modbus RTU",
}
local DIRECTIONS = { [0] = "host -> device", [1] = "device -> host" }
local PARITIES = { [0] = "not known", [0x4E] = "N (none)", [0x45] = "E (even)", [0x4F] = "O (odd)",
    [0x4D] = "M (mark)", [0x53] = "S (space)" }

local proto = Proto("devsim", "devsim serial line")
local f = {
    magic = ProtoField.string("devsim.magic", "Magic"),
    version = ProtoField.uint8("devsim.version", "Version"),
    dir = ProtoField.uint8("devsim.dir", "Direction", base.DEC, DIRECTIONS),
    protocol = ProtoField.uint8("devsim.protocol", "Protocol", base.DEC, PROTOCOLS),
    port = ProtoField.uint8("devsim.port", "Port"),
    baud = ProtoField.uint32("devsim.baud", "Baud rate (host)"),
    bits = ProtoField.uint8("devsim.bits", "Data bits"),
    parity = ProtoField.uint8("devsim.parity", "Parity", base.HEX, PARITIES),
    stop = ProtoField.float("devsim.stop", "Stop bits"),
    flags = ProtoField.uint8("devsim.flags", "Flags", base.HEX),
    mismatch = ProtoField.bool("devsim.mismatch", "Host settings differ from the device's", 8, nil, 0x01),
    reserved = ProtoField.uint16("devsim.reserved", "Reserved", base.HEX),
    data = ProtoField.bytes("devsim.data", "Data"),
    pending = ProtoField.bytes("devsim.pending", "Incomplete (continued in a later chunk)"),
    unframed = ProtoField.bytes("devsim.unframed", "Bytes without a telegram end (not carried on)"),
}
proto.fields = f

local e_mismatch = ProtoExpert.new("devsim.mismatch.expert", "Line settings mismatch: the device sees garbage",
    expert.group.COMMENTS_GROUP, expert.severity.WARN)
local e_magic = ProtoExpert.new("devsim.magic.expert", "Not a devsim header", expert.group.MALFORMED,
    expert.severity.ERROR)
local e_malformed = ProtoExpert.new("devsim.malformed", "Malformed", expert.group.MALFORMED, expert.severity.ERROR)
proto.experts = { e_mismatch, e_magic, e_malformed }

-- Reassembly across chunks: a kind's telegram may be split over two reads.  On the first pass the
-- bytes left over after the last complete telegram of a chunk are carried to the next chunk of the
-- same direction (and remembered per frame, for the later passes of the GUI).
local pending = {}
local carried = {}
--- The most bytes carried to the next chunk: a line that never ends (garbage, a wrong baud rate)
--- must not make every later chunk longer.
local MAX_PENDING = 4096
local conversation = {}
local saved_conversation = {}
local active = {}

function proto.init()
    pending, carried, conversation, saved_conversation, active = {}, {}, {}, {}, {}
end

--- The conversation state of the kind being dissected (both directions), e.g. the request the
--- next answer answers.  Kinds replace its values (never change a table inside it): it is saved per
--- packet on the first pass by a shallow copy.
function DEVSIM.state()
    return active
end

local function copy(t)
    local c = {}
    for k, v in pairs(t) do c[k] = v end
    return c
end

--- Dissect ``tvb`` (the bytes of one chunk) as a sequence of telegrams of ``kind``:
--- kind.unit(tvb, offset, dir, st) returns the length of the telegram at offset (0: incomplete),
--- kind.show(tvb_range, pinfo, tree, dir, st) adds it to the tree and returns a summary for Info.
--- ``st`` is the kind's state for this direction (a table the kind keeps its parser state in); it
--- is saved per frame on the first pass so that later passes (the GUI) see what the first saw.
function DEVSIM.units(kind, tvb, pinfo, tree, dir)
    local key = kind.name .. ":" .. dir
    local prefix, st
    if not pinfo.visited then
        local p = pending[key] or { bytes = "", st = {} }
        prefix, st = p.bytes, p.st
        carried[pinfo.number] = { bytes = prefix, st = copy(st) }
        conversation[kind.name] = conversation[kind.name] or {}
        active = conversation[kind.name]
        saved_conversation[pinfo.number] = copy(active)
    else
        local c = carried[pinfo.number] or { bytes = "", st = {} }
        prefix, st = c.bytes, copy(c.st)
        active = copy(saved_conversation[pinfo.number] or {})
    end
    local data = tvb
    if #prefix > 0 then
        local bytes = ByteArray.new(prefix, true)
        bytes:append(tvb:bytes())
        data = bytes:tvb("Reassembled " .. kind.name)
    end
    local offset, length, summaries = 0, data:len(), {}
    while offset < length do
        local n = kind.unit(data, offset, dir, st)
        if n == nil or n <= 0 or offset + n > length then break end
        local summary = kind.show(data:range(offset, n), pinfo, tree, dir, st)
        if summary then summaries[#summaries + 1] = summary end
        offset = offset + n
    end
    local rest = length - offset
    local carry = rest > 0 and rest <= MAX_PENDING
    if not pinfo.visited then
        pending[key] = { bytes = carry and data:raw(offset) or "", st = st }
    end
    if carry then
        tree:add(f.pending, data:range(offset))
        summaries[#summaries + 1] = "[" .. rest .. " bytes continue]"
    elseif rest > 0 then
        tree:add(f.unframed, data:range(offset))
        summaries[#summaries + 1] = "[" .. rest .. " bytes without an end, dropped]"
    end
    pinfo.cols.protocol:set(kind.name)
    pinfo.cols.info:set((dir == 0 and "H>D " or "D>H ") .. table.concat(summaries, "; "))
end

--- Register a kind's dissector for a protocol byte.
function DEVSIM.register(number, kind)
    DEVSIM.kinds[number] = kind
end

--- A kind's generated tables (<name>_tables.lua beside this file).
function DEVSIM.tables(name)
    return dofile(DEVSIM.dir .. name .. "_tables.lua")
end

local function valid_utf8(s)
    local i, n = 1, #s
    while i <= n do
        local c = s:byte(i)
        local size = (c < 0x80 and 1) or (c >= 0xC2 and c <= 0xDF and 2) or (c >= 0xE0 and c <= 0xEF and 3)
            or (c >= 0xF0 and c <= 0xF4 and 4) or nil
        if size == nil or i + size - 1 > n then return false end
        for k = i + 1, i + size - 1 do
            local b = s:byte(k)
            if b < 0x80 or b > 0xBF then return false end
        end
        i = i + size
    end
    return true
end

--- Bytes from the line as text to show: UTF-8 as it is, anything else read as Latin-1 (the SERS
--- sends its texts in Latin-1 by default), control characters as <XX>.
function DEVSIM.text(raw)
    if not valid_utf8(raw) then
        raw = raw:gsub("[\128-\255]", function(c)
            local b = c:byte()
            return string.char(0xC0 + math.floor(b / 64), 0x80 + b % 64)
        end)
    end
    return (raw:gsub("[%z\1-\31\127]", function(c) return string.format("<%02X>", c:byte()) end))
end

local data_dissector = Dissector.get("data")
local mbrtu = Dissector.get("mbrtu")

function proto.dissector(tvb, pinfo, tree)
    if tvb:len() < HEADER_SIZE then return 0 end
    local root = tree:add(proto, tvb:range(0, HEADER_SIZE), "devsim serial line")
    local magic = tvb:range(0, 2)
    root:add(f.magic, magic)
    if magic:string() ~= "ds" then
        root:add_proto_expert_info(e_magic)
        return 0
    end
    root:add(f.version, tvb:range(2, 1))
    local dir = tvb:range(3, 1):uint()
    root:add(f.dir, tvb:range(3, 1))
    local protocol = tvb:range(4, 1):uint()
    root:add(f.protocol, tvb:range(4, 1))
    root:add(f.port, tvb:range(5, 1))
    root:add(f.baud, tvb:range(6, 4))
    root:add(f.bits, tvb:range(10, 1))
    root:add(f.parity, tvb:range(11, 1))
    root:add(f.stop, tvb:range(12, 1), tvb:range(12, 1):uint() / 10)
    local flags = root:add(f.flags, tvb:range(13, 1))
    flags:add(f.mismatch, tvb:range(13, 1))
    if bit32.band(tvb:range(13, 1):uint(), 1) ~= 0 then root:add_proto_expert_info(e_mismatch) end
    root:add(f.reserved, tvb:range(14, 2))
    local baud = tvb:range(6, 4):uint()
    root:append_text(string.format(", %s, %s%s", DIRECTIONS[dir] or "?", PROTOCOLS[protocol] or "?",
        baud > 0 and (", " .. baud .. " baud") or ""))
    pinfo.p2p_dir = dir == 0 and P2P_DIR_SENT or P2P_DIR_RECV
    pinfo.cols.src:set(dir == 0 and "host" or "device")
    pinfo.cols.dst:set(dir == 0 and "device" or "host")
    if tvb:len() == HEADER_SIZE then return HEADER_SIZE end
    local payload = tvb:range(HEADER_SIZE):tvb()
    local kind = DEVSIM.kinds[protocol]
    if kind ~= nil then
        local port = tvb:range(5, 1):uint()
        DEVSIM.units(kind.select and kind.select(port) or kind, payload, pinfo, tree, dir)
    elseif protocol == 16 and mbrtu ~= nil then
        -- (mbrtu throws on a frame too short for it: shown as malformed, not as a Lua error)
        if not pcall(Dissector.call, mbrtu, payload, pinfo, tree) then
            root:add_proto_expert_info(e_malformed, "Not a complete Modbus RTU frame")
            tree:add(f.data, payload:range())
        end
    else
        tree:add(f.data, payload:range())
        data_dissector:call(payload, pinfo, tree)
        pinfo.cols.protocol:set("devsim")
    end
    return tvb:len()
end

DissectorTable.get("wtap_encap"):add(wtap.USER0, proto)

for _, name in ipairs({ "gms96", "sers", "as511", "poselesta", "sbus_serial" }) do
    local path = DEVSIM.dir .. name .. ".lua"
    local chunk = loadfile(path)
    if chunk then chunk(DEVSIM) end
end
