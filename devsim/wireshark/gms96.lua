-- gms96.lua: GMS96 on the serial line (manual M §2.3; spec gms96.md §3): the DIN 19244 /
-- IEC 60870-5-1 FT1.2 link layer (single character E5h, Kurzsatz 10h C A [AE] CS 16h, Langsatz
-- 68h L L 68h C A data CS 16h) and the GMS96 user data: letter commands with their 24-bit
-- parameters, the T read-backs and their answers, the Kurzsatz commands #0 #1 #8 #9 and the
-- K status byte with the MB4 message.  Names come from gms96_tables.lua (generated from the
-- simulator's own tables).  Loaded by devsim.lua.
local DEVSIM = ...
if type(DEVSIM) ~= "table" or DEVSIM.kinds == nil then return end

local T = DEVSIM.tables("gms96")

local START = { [0x10] = "Kurzsatz (fixed length)", [0x68] = "Langsatz (variable length)",
    [0xE5] = "E5h single character (positive acknowledgement)", [0xA2] = "A2h single character" }

local proto = Proto("devsim_gms96", "GMS96 DIN 19244 link")
local short_names = {}
for n, doc in pairs(T.short) do short_names[n] = doc end

local f = {
    frame = ProtoField.bytes("gms96.frame", "Frame"),
    start = ProtoField.uint8("gms96.start", "Start", base.HEX, START),
    length = ProtoField.uint8("gms96.length", "Length L"),
    length2 = ProtoField.uint8("gms96.length2", "Length L (repeated)"),
    start2 = ProtoField.uint8("gms96.start2", "Start (repeated)", base.HEX),
    control = ProtoField.uint8("gms96.control", "Control field (F-Feld)", base.HEX),
    prm = ProtoField.bool("gms96.control.prm", "PRM (from the primary station)", 8, nil, 0x40),
    fcb = ProtoField.bool("gms96.control.fcb", "FCB / ACD", 8, nil, 0x20),
    fcv = ProtoField.bool("gms96.control.fcv", "FCV / DFC", 8, nil, 0x10),
    fc = ProtoField.uint8("gms96.control.fc", "Function code", base.DEC, nil, 0x0F),
    address = ProtoField.uint8("gms96.address", "Address (A-Feld)"),
    extension = ProtoField.bytes("gms96.ae", "Address extension (AE)"),
    checksum = ProtoField.uint8("gms96.checksum", "Checksum", base.HEX),
    checksum_ok = ProtoField.bool("gms96.checksum.ok", "Checksum correct"),
    stop = ProtoField.uint8("gms96.end", "End", base.HEX),
    short = ProtoField.uint8("gms96.short", "Kurzsatz command", base.DEC, short_names),
    k = ProtoField.uint8("gms96.k", "Status byte K", base.HEX),
    nack = ProtoField.bool("gms96.nack", "NACK: command not accepted (queue full)"),
    mb4 = ProtoField.uint8("gms96.mb4", "Message MB4"),
    override = ProtoField.uint8("gms96.override", "Override (%)"),
    spindle = ProtoField.uint16("gms96.spindle_rpm", "Spindle speed"),
    command = ProtoField.string("gms96.command", "Command"),
    command_doc = ProtoField.string("gms96.command.name", "Meaning"),
    p1 = ProtoField.int32("gms96.p1", "P1"),
    p2 = ProtoField.int32("gms96.p2", "P2"),
    p3 = ProtoField.int32("gms96.p3", "P3"),
    count = ProtoField.uint8("gms96.params", "Parameters sent"),
    n = ProtoField.uint8("gms96.n", "N parameter"),
    n_name = ProtoField.string("gms96.n.name", "N parameter designation"),
    identifier = ProtoField.uint8("gms96.identifier", "Identifier I", base.HEX),
    value = ProtoField.int32("gms96.value", "Value"),
    value_bytes = ProtoField.bytes("gms96.value.bytes", "Value bytes"),
    status = ProtoField.uint8("gms96.status", "Status byte I (T3;0)", base.HEX),
    bit = ProtoField.string("gms96.bit", "Bit set"),
    answer_to = ProtoField.string("gms96.answer_to", "Answer to"),
    user_data = ProtoField.bytes("gms96.data", "User data"),
    garbage = ProtoField.bytes("gms96.garbage", "Bytes outside a frame"),
}
proto.fields = f

local e_checksum = ProtoExpert.new("gms96.checksum.bad", "Wrong checksum", expert.group.CHECKSUM, expert.severity.ERROR)
local e_frame = ProtoExpert.new("gms96.frame.bad", "Malformed frame", expert.group.MALFORMED, expert.severity.ERROR)
proto.experts = { e_checksum, e_frame }

local function short_extension(control, dir)
    if dir == 0 then
        local number = bit32.band(control, 0x0D)
        return (number == 8 and 2) or (number == 9 and 1) or 0
    end
    return bit32.band(control, 0x02) ~= 0 and 1 or 0
end

local function is_start(b) return b == 0x10 or b == 0x68 or b == 0xE5 or b == 0xA2 end

local kind = { name = "GMS96" }

function kind.unit(tvb, offset, dir)
    local avail = tvb:len() - offset
    local b = tvb:range(offset, 1):uint()
    if b == 0xE5 or b == 0xA2 then return 1 end
    if b == 0x10 then
        if avail < 2 then return 0 end
        local size = 5 + short_extension(tvb:range(offset + 1, 1):uint(), dir)
        return avail >= size and size or 0
    end
    if b == 0x68 then
        if avail < 4 then return 0 end
        local l, l2 = tvb:range(offset + 1, 1):uint(), tvb:range(offset + 2, 1):uint()
        if l < 2 or l ~= l2 or tvb:range(offset + 3, 1):uint() ~= 0x68 then return 1 end
        return avail >= l + 6 and l + 6 or 0
    end
    local n = 1
    while n < avail and not is_start(tvb:range(offset + n, 1):uint()) do n = n + 1 end
    return n
end

local function s24(range)
    local v = range:le_uint()
    if v >= 0x800000 then v = v - 0x1000000 end
    return v
end

local function bits(tree, value, masks)
    local names = {}
    for name, mask in pairs(masks) do
        if bit32.band(value, mask) ~= 0 then names[#names + 1] = name end
    end
    table.sort(names)
    for _, name in ipairs(names) do tree:add(f.bit, name) end
    return names
end

local function checksum(tree, body, cs)
    local sum = 0
    for i = 0, body:len() - 1 do sum = sum + body:range(i, 1):uint() end
    sum = sum % 256
    local item = tree:add(f.checksum, cs)
    local ok = sum == cs:uint()
    tree:add(f.checksum_ok, cs, ok):set_generated()
    if not ok then
        item:add_proto_expert_info(e_checksum, string.format("Wrong checksum: %02Xh, expected %02Xh", cs:uint(), sum))
    end
    return ok
end

local function control(tree, range)
    local item = tree:add(f.control, range)
    item:add(f.prm, range)
    item:add(f.fcb, range)
    item:add(f.fcv, range)
    item:add(f.fc, range)
end

-- The letters whose P1 selects a function of its own table (manual §2.3.1 G, H, m, Q, r).
local SUB_FUNCTIONS = { G = "g", H = "h", m = "m", Q = "q", r = "r" }

-- A letter command (host -> device Langsatz user data): "A" + P1 [+ P2 [+ P3]], 24 bit each.
local function letter(tree, data, pinfo)
    local command = DEVSIM.text(data:range(0, 1):raw())
    local rest = data:len() - 1
    local count = math.min(math.floor(rest / 3), 3)
    tree:add(f.command, data:range(0, 1))
    local p = { 0, 0, 0 }
    local pf = { f.p1, f.p2, f.p3 }
    for i = 1, count do
        local r = data:range(1 + 3 * (i - 1), 3)
        p[i] = s24(r)
        tree:add_le(pf[i], r, p[i])
    end
    tree:add(f.count, count):set_generated()
    local doc = T.letters[command]
    if command == "T" then
        local key = (T.t_queries[p[1] .. ";" .. p[2]] and (p[1] .. ";" .. p[2])) or (T.t_queries[tostring(p[1])] and tostring(p[1]))
        if key then doc = T.t_queries[key] end
        DEVSIM.state().t = { key = key, n = p[2], frame = pinfo.number }
        if key == "5" then
            local row = T.n[p[2]]
            tree:add(f.n, p[2]):set_generated()
            if row then tree:add(f.n_name, row.name .. " (" .. row.doc .. ")"):set_generated() end
        end
    elseif command == "N" then
        local row = T.n[p[2]]
        tree:add(f.n, p[2]):set_generated()
        if row then tree:add(f.n_name, row.name .. " (" .. row.doc .. ")"):set_generated() end
    elseif command == "p" then
        local pkey = p[1] .. ";" .. p[2]
        doc = T.p_on_receipt[pkey] or T.p_on_receipt[tostring(p[1])] or doc
    elseif SUB_FUNCTIONS[command] then
        local sub = T[SUB_FUNCTIONS[command]]
        local skey = tostring(p[1])
        if command == "m" and p[1] >= 50 and p[1] <= 89 then skey = "50..89" end
        if sub[skey] then doc = sub[skey] end
    end
    if doc then tree:add(f.command_doc, doc):set_generated() end
    local args = {}
    for i = 1, count do args[#args + 1] = tostring(p[i]) end
    return command .. table.concat(args, ";")
end

-- The answer to T: identifier I and value; T3;0 / T3;4 answer with the status byte as I.
local function t_answer(tree, data)
    local asked = DEVSIM.state().t
    local identifier = data:range(0, 1)
    local key = asked and asked.key
    if key then tree:add(f.answer_to, "T" .. key .. " (" .. (T.t_queries[key] or "") .. ")"):set_generated() end
    if key == "3;0" or key == "3;4" then
        local item = tree:add(f.status, identifier)
        local names = bits(item, identifier:uint(), key == "3;0" and T.status_bits or T.memory_status_bits)
        return string.format("status %02Xh %s", identifier:uint(), table.concat(names, ","))
    end
    tree:add(f.identifier, identifier)
    local value = data:len() > 1 and data:range(1) or nil
    if value and value:len() == 3 then
        tree:add_le(f.value, value, s24(value))
        if key == "5" and asked then
            tree:add(f.n, asked.n):set_generated()
            local row = T.n[asked.n]
            if row then tree:add(f.n_name, row.name .. " (" .. row.doc .. ")"):set_generated() end
            return string.format("N%d = %d", asked.n, s24(value))
        end
        return string.format("%s = %d", DEVSIM.text(identifier:raw()), s24(value))
    elseif value then
        tree:add(f.value_bytes, value)
        if value:len() == 2 then tree:add_le(f.value, value, value:le_uint()):set_generated() end
    end
    return "answer " .. DEVSIM.text(identifier:raw())
end

function kind.show(range, pinfo, tree, dir)
    local tvb = range:tvb()
    local b = tvb:range(0, 1):uint()
    if b == 0xE5 or b == 0xA2 then
        local item = tree:add(proto, range, "GMS96 single character")
        item:add(f.start, tvb:range(0, 1))
        return b == 0xE5 and "E5 (ack)" or "A2"
    end
    if (b ~= 0x10 and b ~= 0x68) or (b == 0x68 and range:len() < 6) then
        local item = tree:add(proto, range, "GMS96 bytes outside a frame")
        item:add(f.garbage, range)
        item:add_proto_expert_info(e_frame, "Bytes outside a frame, or a broken frame header")
        return "garbage (" .. range:len() .. " bytes)"
    end
    local n = tvb:len()
    if dir == 0 then DEVSIM.state().last_host = b end
    local item = tree:add(proto, range)
    item:add(f.start, tvb:range(0, 1))
    local last = tvb:range(n - 1, 1)
    local body, c, a
    if b == 0x10 then
        item:set_text("GMS96 Kurzsatz")
        body = tvb:range(1, n - 3)
        c, a = tvb:range(1, 1), tvb:range(2, 1)
    else
        item:set_text("GMS96 Langsatz")
        item:add(f.length, tvb:range(1, 1))
        item:add(f.length2, tvb:range(2, 1))
        item:add(f.start2, tvb:range(3, 1))
        body = tvb:range(4, n - 6)
        c, a = tvb:range(4, 1), tvb:range(5, 1)
    end
    control(item, c)
    item:add(f.address, a)
    local summary
    if b == 0x10 then
        local ext = n > 5 and tvb:range(3, n - 5) or nil
        if ext then item:add(f.extension, ext) end
        if dir == 0 then
            local number = bit32.band(c:uint(), 0x0D)
            item:add(f.short, c, number)
            summary = "#" .. number
            if number == 9 and ext then
                item:add(f.override, ext:range(0, 1))
                summary = summary .. " " .. ext:range(0, 1):uint() .. "%"
            elseif number == 8 and ext and ext:len() >= 2 then
                item:add_le(f.spindle, ext:range(0, 2))
            end
            if short_names[number] then item:add(f.command_doc, short_names[number]):set_generated() end
        elseif DEVSIM.state().last_host == 0x68 then
            -- a Kurzsatz answering a letter command: 01h NACK, the command queue is full (link option nack)
            item:add(f.nack, c, true)
            summary = string.format("NACK %02Xh (command queue full)", c:uint())
        else
            local k = item:add(f.k, c)
            local names = bits(k, c:uint(), T.k_bits)
            summary = string.format("K %02Xh %s", c:uint(), table.concat(names, ","))
            if ext then
                local mb4 = ext:range(0, 1):uint()
                local m = item:add(f.mb4, ext:range(0, 1))
                if T.messages[mb4] then m:append_text(" (" .. T.messages[mb4] .. ")") end
                summary = summary .. " MB4=" .. mb4
            end
        end
    else
        local data = tvb:len() > 8 and tvb:range(6, n - 8) or nil
        if data then
            local ud = item:add(f.user_data, data)
            if dir == 0 then
                summary = letter(ud, data:tvb(), pinfo)
            else
                summary = t_answer(ud, data:tvb())
            end
        else
            summary = "Langsatz without user data"
        end
    end
    if not checksum(item, body, tvb:range(n - 2, 1)) then summary = summary .. " [wrong checksum]" end
    local stop = item:add(f.stop, last)
    if last:uint() ~= 0x16 then stop:add_proto_expert_info(e_frame, "End byte is not 16h") end
    item:append_text(", A=" .. a:uint() .. ": " .. summary)
    return summary .. " A=" .. a:uint()
end

DEVSIM.register(2, kind)
