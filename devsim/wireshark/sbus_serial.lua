-- sbus_serial.lua: the PCD4.H3 simulator's serial S-Bus (data mode SM2; spec pcd4h3.md §9.2,
-- §9.4 -- the simulator's proposal: the module's manual, seed 002, documents no serial link):
-- FS B5h, the attribute (00h request, 01h response, 02h ACK/NAK), station and command with its
-- parameters (reads: count - 1 and address; writes: byte count, address, data), the response data,
-- the ACK/NAK code, the CRC-16 (XMODEM) over FS .. data; after FS every B5h travels as C5h 00h and
-- every C5h as C5h 01h.  Command names from pcd4h3_tables.lua (generated).  Loaded by devsim.lua.
local DEVSIM = ...
if type(DEVSIM) ~= "table" or DEVSIM.kinds == nil then return end

local T = DEVSIM.tables("pcd4h3")

local FS, DLE = 0xB5, 0xC5
local ATTRIBUTES = { [0] = "request", [1] = "response", [2] = "ACK/NAK" }
local command_names = {}
for code, row in pairs(T.commands) do command_names[code] = row.doc end

local proto = Proto("devsim_sbus_serial", "S-Bus serial data mode")
local f = {
    fs = ProtoField.uint8("sbusserial.fs", "Frame synchronisation (FS)", base.HEX),
    att = ProtoField.uint8("sbusserial.att", "Attribute", base.HEX, ATTRIBUTES),
    station = ProtoField.uint8("sbusserial.station", "Station"),
    command = ProtoField.uint8("sbusserial.command", "Command", base.HEX, command_names),
    count = ProtoField.uint16("sbusserial.count", "Elements"),
    bytes = ProtoField.uint8("sbusserial.bytes", "Byte count"),
    address = ProtoField.uint16("sbusserial.address", "Address"),
    data = ProtoField.bytes("sbusserial.data", "Data"),
    register = ProtoField.int32("sbusserial.register", "Register value"),
    code = ProtoField.uint16("sbusserial.ack", "ACK/NAK code", base.DEC, T.acks),
    crc = ProtoField.uint16("sbusserial.crc", "CRC", base.HEX),
    crc_ok = ProtoField.bool("sbusserial.crc.ok", "CRC correct"),
    stuffed = ProtoField.uint16("sbusserial.stuffed", "Stuffed bytes (C5h 00h / C5h 01h)"),
    noise = ProtoField.bytes("sbusserial.noise", "Bytes outside a telegram"),
}
proto.fields = f

local e_crc = ProtoExpert.new("sbusserial.crc.bad", "Wrong CRC", expert.group.CHECKSUM, expert.severity.ERROR)
local e_nak = ProtoExpert.new("sbusserial.nak", "NAK", expert.group.RESPONSE_CODE, expert.severity.NOTE)
proto.experts = { e_crc, e_nak }

local CRC_TABLE = {}
for i = 0, 255 do
    local c = i * 256
    for _ = 1, 8 do
        if bit32.band(c, 0x8000) ~= 0 then c = bit32.band(bit32.bxor(c * 2, 0x1021), 0xFFFF)
        else c = bit32.band(c * 2, 0xFFFF) end
    end
    CRC_TABLE[i] = c
end

local function crc_step(crc, byte)
    return bit32.band(bit32.bxor(crc * 256, CRC_TABLE[bit32.bxor(bit32.rshift(crc, 8), byte)]), 0xFFFF)
end

-- The telegram at offset, unstuffed: its length on the wire (0: not complete yet) -- the first
-- end where the CRC over FS .. CRC comes out 0 -- or the bytes up to the next FS when it breaks.
local function scan(tvb, offset)
    local length, i, crc, n, raw = tvb:len(), offset + 1, crc_step(0, FS), 1, { FS }
    while i < length do
        local b = tvb:range(i, 1):uint()
        if b == FS then return i - offset, nil end  -- a new telegram: this one is broken
        if b == DLE then
            if i + 1 >= length then return 0, nil end
            b = tvb:range(i + 1, 1):uint() == 0 and FS or DLE
            i = i + 2
        else
            i = i + 1
        end
        crc, n = crc_step(crc, b), n + 1
        raw[n] = b
        if n >= 4 and crc == 0 then return i - offset, raw end
    end
    return 0, nil
end

local kind = { name = "S-Bus serial" }

function kind.unit(tvb, offset)
    if tvb:range(offset, 1):uint() ~= FS then
        local n, length = 1, tvb:len() - offset
        while n < length and tvb:range(offset + n, 1):uint() ~= FS do n = n + 1 end
        return n
    end
    return (scan(tvb, offset))
end

local function telegram(item, t, n)
    local att = t:range(1, 1):uint()
    item:add(f.att, t:range(1, 1))
    local body = n - 4  -- between the attribute and the CRC
    if att == 0 and body >= 2 then
        item:add(f.station, t:range(2, 1))
        local code = t:range(3, 1):uint()
        item:add(f.command, t:range(3, 1))
        local row = T.commands[code]
        local name = row and (row.doc:match("^(.-) %(") or row.doc) or string.format("command %02Xh", code)
        local text = string.format("station %d %s", t:range(2, 1):uint(), name)
        if row and row.layout == "reads" and body >= 5 then
            item:add(f.count, t:range(4, 1), t:range(4, 1):uint() + 1)
            item:add(f.address, t:range(5, 2))
            text = text .. string.format(" %d from %d", t:range(4, 1):uint() + 1, t:range(5, 2):uint())
        elseif row and row.layout == "writes" and body >= 5 then
            item:add(f.bytes, t:range(4, 1))
            item:add(f.address, t:range(5, 2))
            if body > 5 then item:add(f.data, t:range(7, body - 5)) end
            text = text .. string.format(" at %d", t:range(5, 2):uint())
        end
        return text
    elseif att == 1 then
        if body > 0 then
            local data = t:range(2, body)
            local d = item:add(f.data, data)
            if body % 4 == 0 then
                for i = 0, body - 4, 4 do d:add(f.register, data:range(i, 4)) end
            end
        end
        return "response (" .. body .. " bytes)"
    elseif att == 2 and body == 2 then
        local c = item:add(f.code, t:range(2, 2))
        local code = t:range(2, 2):uint()
        if code ~= 0 then c:add_proto_expert_info(e_nak) end
        return (T.acks[code] or "NAK") .. " " .. code
    end
    return "attribute " .. att
end

function kind.show(range, pinfo, tree)
    local item = tree:add(proto, range)
    local b = range:range(0, 1):uint()
    if b ~= FS then
        item:set_text("S-Bus bytes outside a telegram")
        item:add(f.noise, range)
        return "noise"
    end
    local wire, raw = scan(range:tvb(), 0)
    if raw == nil or wire ~= range:len() then
        item:set_text("S-Bus broken telegram")
        item:add(f.noise, range)
        item:add_proto_expert_info(e_crc, "No CRC ends this telegram before the next FS")
        return "broken telegram"
    end
    local t = ByteArray.new(string.char(table.unpack(raw)), true):tvb("S-Bus telegram")
    local n = t:len()
    item:add(f.fs, range:range(0, 1))
    if wire > n then item:add(f.stuffed, wire - n):set_generated() end
    local text = telegram(item, t, n)
    item:add(f.crc, t:range(n - 2, 2))
    item:add(f.crc_ok, true):set_generated()
    item:set_text("S-Bus " .. text)
    return text
end

DEVSIM.register(5, kind)
