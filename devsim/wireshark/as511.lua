-- as511.lua: the IP247's PG port (manual §2.2; spec ip247.md §3.5, §3.6): the AS511 procedure
-- (STX, DLE ACK, DLE NAK, the function code, the parameter block up to DLE EOT and the data block
-- up to DLE ETX with every 10h doubled, "accept" 16 10 03 and "end" 12 10 03) and the jobs of the
-- simulator's PG profile (OPERATE with the Betriebsart and the command, OBSERVE, WRITE_REC,
-- READ_REC, DELETE_REC) and the S5 services, with the response header (ack, page, BA, error
-- number with the manual's text).  Names from ip247_tables.lua (generated).  Loaded by devsim.lua.
local DEVSIM = ...
if type(DEVSIM) ~= "table" or DEVSIM.kinds == nil then return end

local T = DEVSIM.tables("ip247")

local STX, ETX, EOT, ACK, DLE, NAK = 0x02, 0x03, 0x04, 0x06, 0x10, 0x15
local OPERATE, OBSERVE, WRITE_REC, READ_REC, DELETE_REC, READ_MEMORY = 0x61, 0x62, 0x63, 0x64, 0x65, 0x04

local FUNCTION_NAMES = {}
for code, doc in pairs(T.functions) do FUNCTION_NAMES[code] = doc:match("^([^:]+)") or doc end
local mode_names = {}
for n, m in pairs(T.modes) do mode_names[n] = "BA" .. n .. " " .. m.name end
local error_names = {}
for n, e in pairs(T.module_errors) do error_names[n] = e.de end

local proto = Proto("devsim_as511", "IP247 PG port (AS511)")
local f = {
    element = ProtoField.string("as511.element", "Element"),
    stx = ProtoField.uint8("as511.stx", "STX", base.HEX),
    control = ProtoField.string("as511.control", "Control sequence"),
    fn = ProtoField.uint8("as511.function", "Function", base.HEX, FUNCTION_NAMES),
    block = ProtoField.bytes("as511.block", "Block (DLE doubled)"),
    data = ProtoField.bytes("as511.data", "Block data (DLE removed)"),
    block_end = ProtoField.string("as511.block_end", "Block end"),
    dle_doubled = ProtoField.uint16("as511.dle_doubled", "DLE doubled"),
    page = ProtoField.uint8("as511.page", "Page (Seite)"),
    ba = ProtoField.uint8("as511.ba", "Betriebsart (BA)", base.DEC, mode_names),
    cmd = ProtoField.uint8("as511.cmd", "Command", base.DEC, T.commands),
    b = ProtoField.uint8("as511.b", "B (byte parameter)"),
    w = ProtoField.uint16("as511.w", "W (word parameter)"),
    dd = ProtoField.int32("as511.dd", "DD (double word parameter)"),
    db = ProtoField.uint8("as511.db", "DB (data block)"),
    overwrite = ProtoField.bool("as511.overwrite", "Overwrite"),
    bcd = ProtoField.bool("as511.bcd", "BCD"),
    word = ProtoField.uint16("as511.word", "Word", base.HEX),
    first = ProtoField.uint16("as511.first", "First address", base.HEX),
    last = ProtoField.uint16("as511.last", "Last address", base.HEX),
    ack = ProtoField.uint8("as511.ack", "Acknowledgement", base.HEX, T.acks),
    err = ProtoField.uint8("as511.error", "Error (Fehlernummer)", base.DEC, error_names),
    err_text = ProtoField.string("as511.error.text", "Error text (manual §7.2)"),
    err_en = ProtoField.string("as511.error.en", "Error (English)"),
    err_pg = ProtoField.uint8("as511.error.pg", "Error as COM247 shows it (AG number + 80h, manual §7.2)", base.HEX),
    btr = ProtoField.uint8("as511.btr", "Current Betriebsart (BTR)", base.DEC, mode_names),
    rmld = ProtoField.uint8("as511.rmld", "Axis attributes (RMLD)", base.HEX),
    mfkt = ProtoField.uint8("as511.mfkt", "M function (MFKT)"),
    position = ProtoField.int32("as511.position", "Actual value (Istwert)"),
    residual = ProtoField.int32("as511.residual", "Residual distance (Restweg)"),
    axis_error = ProtoField.uint8("as511.axis_error", "Error of axis / data channel", base.DEC, error_names),
    last_cmd = ProtoField.uint8("as511.last_cmd", "Last command", base.DEC, T.commands),
    flags = ProtoField.uint8("as511.flags", "Flags", base.HEX),
    noise = ProtoField.bytes("as511.noise", "Bytes outside a transaction"),
}
proto.fields = f

local e_refused = ProtoExpert.new("as511.refused", "Refused (DLE NAK)", expert.group.RESPONSE_CODE, expert.severity.NOTE)
local e_error = ProtoExpert.new("as511.error.expert", "Module error", expert.group.RESPONSE_CODE, expert.severity.NOTE)
proto.experts = { e_refused, e_error }

local function byte(tvb, i) return tvb:range(i, 1):uint() end

-- The length of a block up to and including DLE ETX / DLE EOT (0: not complete yet).
local function block_length(tvb, offset)
    local i, length = offset, tvb:len()
    while i < length do
        if byte(tvb, i) == DLE then
            if i + 1 >= length then return 0 end
            local next = byte(tvb, i + 1)
            if next == ETX or next == EOT or next == ACK or next == NAK then return i + 2 - offset end
            i = i + 2
        else
            i = i + 1
        end
    end
    return 0
end

local kind = { name = "AS511" }

-- The host side: STX, the function code, DLE ACKs, the parameter block; the device side: DLE
-- ACK/NAK, STX, "accept" / "end", the data block.  st.state: "idle", "function", "block".
function kind.unit(tvb, offset, dir, st)
    local length = tvb:len() - offset
    local b = byte(tvb, offset)
    if st.state == "function" then return 1 end
    if b == DLE then
        if length < 2 then return 0 end
        local next = byte(tvb, offset + 1)
        if next == ACK or next == NAK then return 2 end
    end
    if b == STX and st.state ~= "block" then return 1 end
    if dir == 1 and (b == 0x16 or b == 0x12) and length >= 3 and byte(tvb, offset + 1) == DLE
        and byte(tvb, offset + 2) == ETX then
        return 3
    end
    if dir == 1 and (b == 0x16 or b == 0x12) and length < 3 then return 0 end
    if st.state == "block" or dir == 1 then return block_length(tvb, offset) end
    local n = 1  -- host bytes outside a transaction
    while n < length and byte(tvb, offset + n) ~= STX do n = n + 1 end
    return n
end

local function undouble(range)
    local raw = range:raw()
    return (raw:gsub("\16\16", "\16"))
end

local function request(tree, fn, data)
    local n = data:len()
    if n == 0 then return "" end
    if fn == READ_MEMORY and n >= 4 then
        tree:add(f.first, data:range(0, 2))
        tree:add(f.last, data:range(2, 2))
        return string.format(" %04X..%04X", data:range(0, 2):uint(), data:range(2, 2):uint())
    end
    if fn < OPERATE or fn > DELETE_REC then return "" end
    tree:add(f.page, data:range(0, 1))
    local text = " page " .. data:range(0, 1):uint()
    if n >= 2 and fn ~= OBSERVE then
        tree:add(f.ba, data:range(1, 1))
        text = text .. " BA" .. data:range(1, 1):uint()
    end
    if fn == OPERATE and n >= 10 then
        tree:add(f.cmd, data:range(2, 1))
        tree:add(f.b, data:range(3, 1))
        tree:add(f.w, data:range(4, 2))
        tree:add(f.dd, data:range(6, 4))
        text = text .. " " .. (T.commands[data:range(2, 1):uint()] or "?") .. " DD=" .. data:range(6, 4):int()
    elseif (fn == WRITE_REC or fn == READ_REC or fn == DELETE_REC) and n >= 3 then
        tree:add(f.db, data:range(2, 1))
        text = text .. " DB" .. data:range(2, 1):uint()
        if fn == WRITE_REC and n >= 4 then
            tree:add(f.overwrite, data:range(3, 1), bit32.band(data:range(3, 1):uint(), 1) ~= 0)
            for i = 4, n - 2, 2 do tree:add(f.word, data:range(i, 2)) end
        elseif fn == READ_REC and n >= 4 then
            tree:add(f.bcd, data:range(3, 1), bit32.band(data:range(3, 1):uint(), 1) ~= 0)
        end
    end
    return text
end

local function response(tree, fn, data)
    local n = data:len()
    if fn == nil or fn < OPERATE or fn > DELETE_REC or n < 8 then return "" end
    tree:add(f.ack, data:range(0, 1))
    tree:add(f.page, data:range(1, 1))
    tree:add(f.ba, data:range(2, 1))
    tree:add(f.cmd, data:range(3, 1))
    local err = tree:add(f.err, data:range(4, 1))
    local code = data:range(4, 1):uint()
    local row = T.module_errors[code]
    if row then
        tree:add(f.err_text, row.de):set_generated()
        tree:add(f.err_en, row.en):set_generated()
    end
    if code < 0x80 then tree:add(f.err_pg, code + 0x80):set_generated() end
    if code ~= 0 then err:add_proto_expert_info(e_error, "Error " .. code .. ": " .. (error_names[code] or "?")) end
    tree:add(f.btr, data:range(5, 1))
    tree:add(f.rmld, data:range(6, 1))
    tree:add(f.mfkt, data:range(7, 1))
    local text = " ack " .. string.format("%02Xh", data:range(0, 1):uint()) .. " error " .. code
    if fn == OBSERVE and n >= 22 then
        tree:add(f.position, data:range(8, 4))
        tree:add(f.residual, data:range(12, 4))
        for i = 16, 19 do tree:add(f.axis_error, data:range(i, 1)) end
        tree:add(f.last_cmd, data:range(20, 1))
        tree:add(f.flags, data:range(21, 1))
        text = text .. " Istwert " .. data:range(8, 4):int()
    elseif n > 8 then
        for i = 8, n - 2, 2 do tree:add(f.word, data:range(i, 2)) end
    end
    return text
end

function kind.show(range, pinfo, tree, dir, st)
    local tvb = range:tvb()
    local n = tvb:len()
    local b = byte(tvb, 0)
    local conv = DEVSIM.state()
    local item = tree:add(proto, range)
    if st.state == "function" then
        st.state = "acks"
        st.acks = 0
        conv.fn = b
        item:add(f.fn, tvb:range(0, 1))
        local name = FUNCTION_NAMES[b] or string.format("%02Xh", b)
        item:set_text("AS511 function " .. name)
        return "function " .. name
    end
    if n == 2 and b == DLE then
        local what = byte(tvb, 1) == ACK and "DLE ACK" or "DLE NAK"
        local c = item:add(f.control, tvb:range(0, 2), what)
        item:set_text("AS511 " .. what)
        if what == "DLE NAK" then c:add_proto_expert_info(e_refused) end
        if dir == 0 and st.state == "acks" then
            st.acks = (st.acks or 0) + 1
            if st.acks == 2 then st.state = "block" end
        end
        return what
    end
    if n == 1 and b == STX then
        item:add(f.stx, tvb:range(0, 1))
        item:set_text("AS511 STX")
        if dir == 0 then st.state = "function" end
        return "STX"
    end
    if n == 3 and (b == 0x16 or b == 0x12) and byte(tvb, 1) == DLE then
        local what = b == 0x16 and "accept (16 10 03)" or "end (12 10 03)"
        item:add(f.control, tvb:range(0, 3), what)
        item:set_text("AS511 " .. what)
        return what:match("^(%a+)")
    end
    local last = byte(tvb, n - 1)
    if n >= 2 and byte(tvb, n - 2) == DLE and (last == EOT or last == ETX) then
        item:add(f.block, tvb:range(0, n))
        local body = undouble(tvb:range(0, n - 2))
        local doubled = (n - 2) - #body
        if doubled > 0 then item:add(f.dle_doubled, doubled):set_generated() end
        if #body == 0 then body = "\0" end  -- (an empty block: a Tvb needs a byte)
        local data = ByteArray.new(body, true):tvb("AS511 block")
        item:add(f.data, data:range())
        item:add(f.block_end, tvb:range(n - 2, 2), last == EOT and "DLE EOT" or "DLE ETX")
        st.state = "idle"
        local text
        if dir == 0 then
            item:set_text("AS511 parameters")
            text = "parameters" .. request(item, conv.fn, data)
        else
            item:set_text("AS511 response data")
            text = "data" .. response(item, conv.fn, data)
        end
        return text
    end
    item:add(f.noise, range)
    item:set_text("AS511 bytes outside a transaction")
    return "noise"
end

DEVSIM.register(4, kind)
