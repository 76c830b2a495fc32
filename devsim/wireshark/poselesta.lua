-- poselesta.lua: POSELESTA's serial ports by the header's port byte (manual §2.6.2-§2.6.4; spec
-- poselesta.md §2.3, §3.3-§3.6, §3.10): V6 (printer, cassette, tape reader/punch, TTY) and V7
-- (DNC) carry program text, ISO (even parity in bit 7) or ASCII: "%" the start, blocks of words
-- (N, X, Y, Z, D, I, J, K, F, S, G, M, T, L with their values) each ended by CR (EOB), LF, SP
-- and DEL ignored, NUL leader; V8 carries the external keyboard's one-byte key codes.  Tables
-- from poselesta_tables.lua (generated).  Loaded by devsim.lua.
local DEVSIM = ...
if type(DEVSIM) ~= "table" or DEVSIM.kinds == nil then return end

local T = DEVSIM.tables("poselesta")

local VALID_KEY = {}
for _, code in ipairs(T.key_codes) do VALID_KEY[code] = true end
local LETTER_NAMES = {
    N = "block number", X = "X axis", Y = "Y axis", Z = "Z axis", D = "D axis",
    I = "centre I (X)", J = "centre J (Y)", K = "centre K (Z)", F = "feed", S = "spindle speed",
    G = "preparatory function", M = "miscellaneous function", T = "tool", L = "auxiliary value", P = "catalogue value",
}

local proto = Proto("devsim_poselesta", "POSELESTA serial")
local f = {
    block = ProtoField.string("poselesta.block", "Block"),
    start = ProtoField.bool("poselesta.start", "% start of transmission"),
    eob = ProtoField.bool("poselesta.eob", "End of block (CR)"),
    word = ProtoField.string("poselesta.word", "Word"),
    address = ProtoField.string("poselesta.address", "Address letter"),
    value = ProtoField.string("poselesta.value", "Value"),
    n = ProtoField.uint32("poselesta.n", "Block number N"),
    g = ProtoField.uint32("poselesta.g", "G function"),
    m = ProtoField.uint32("poselesta.m", "M function"),
    code = ProtoField.string("poselesta.code", "Code"),
    parity_error = ProtoField.uint16("poselesta.parity_errors", "Characters with a parity error"),
    leader = ProtoField.uint16("poselesta.leader", "NUL leader / trailer bytes"),
    skip = ProtoField.bool("poselesta.skip", "Block skip mark (#)"),
    key = ProtoField.uint8("poselesta.key", "Key code", base.HEX),
    key_valid = ProtoField.bool("poselesta.key.valid", "Valid key code"),
    key_display = ProtoField.uint8("poselesta.key.display", "Shown by the keyboard diagnostic (P79 N3)", base.HEX),
    parity_ok = ProtoField.bool("poselesta.parity_ok", "Even parity"),
    handshake = ProtoField.string("poselesta.handshake", "Handshake character (not defined by the manual: skipped)"),
}
proto.fields = f

-- The words whose value is a number of its own field (N10, G01, M30).
local NUMBERED = { N = f.n, G = f.g, M = f.m }

local e_parity = ProtoExpert.new("poselesta.parity", "Parity error", expert.group.MALFORMED, expert.severity.WARN)
local e_key = ProtoExpert.new("poselesta.key.invalid", "Not a key code", expert.group.MALFORMED, expert.severity.WARN)
proto.experts = { e_parity, e_key }

-- DC1..DC4 (XON, XOFF ...): the manual does not name them; the control skips them (spec §3.3).
local HANDSHAKE = { [0x11] = "DC1 (XON)", [0x12] = "DC2", [0x13] = "DC3 (XOFF)", [0x14] = "DC4" }

local function even(byte)
    local ones = 0
    while byte > 0 do ones = ones + byte % 2; byte = math.floor(byte / 2) end
    return ones % 2 == 0
end

local tape = { name = "POSELESTA" }

-- A block: everything up to and including CR (bit 7 ignored) and an LF after it.
function tape.unit(tvb, offset)
    local length = tvb:len()
    for i = offset, length - 1 do
        if bit32.band(tvb:range(i, 1):uint(), 0x7F) == 0x0D then
            local stop = i + 1
            if stop < length and bit32.band(tvb:range(stop, 1):uint(), 0x7F) == 0x0A then stop = stop + 1 end
            return stop - offset
        end
    end
    return 0
end

function tape.show(range, pinfo, tree)
    local tvb = range:tvb()
    local chars, parity_errors, nul, handshakes = {}, 0, 0, {}
    local iso = false
    for i = 0, tvb:len() - 1 do
        local b = tvb:range(i, 1):uint()
        if b >= 0x80 then iso = true end
        if not even(b) then parity_errors = parity_errors + 1 end
        local c = bit32.band(b, 0x7F)
        if c == 0 then nul = nul + 1
        elseif HANDSHAKE[c] then handshakes[#handshakes + 1] = { i, HANDSHAKE[c] }
        elseif c ~= 0x0D and c ~= 0x0A and c ~= 0x7F then chars[#chars + 1] = string.char(c) end
    end
    local text = DEVSIM.text(table.concat(chars))
    local item = tree:add(proto, range, "POSELESTA block: " .. text)
    item:add(f.block, range, text)
    if parity_errors > 0 and iso then
        item:add(f.parity_error, parity_errors):add_proto_expert_info(e_parity)
    end
    if nul > 0 then item:add(f.leader, nul) end
    for _, h in ipairs(handshakes) do item:add(f.handshake, tvb:range(h[1], 1), h[2]) end
    if text:find("%%") then item:add(f.start, true) end
    if text:find("#") then item:add(f.skip, true) end
    item:add(f.code, iso and "ISO (even parity in bit 7)" or "ASCII"):set_generated()
    local compact = text:gsub(" ", "")
    for letter, value in compact:gmatch("([NXYZDIJKFSGMTLP])([%+%-]?[%d%.]+)") do
        local w = item:add(f.word, letter .. value)
        w:add(f.address, letter .. " (" .. (LETTER_NAMES[letter] or "?") .. ")")
        w:add(f.value, value)
        local number = NUMBERED[letter] and tonumber(value)
        if number and number >= 0 and number < 2 ^ 32 and number % 1 == 0 then
            item:add(NUMBERED[letter], number):set_generated()
        end
    end
    item:add(f.eob, true)
    return text
end

local keyboard = { name = "POSELESTA V8" }

function keyboard.unit() return 1 end

function keyboard.show(range, pinfo, tree)
    local b = range:uint()
    local code = bit32.band(b, 0x7F)
    local item = tree:add(proto, range, string.format("POSELESTA V8 key %02X", code))
    local k = item:add(f.key, range, code)
    item:add(f.parity_ok, range, even(b))
    if not even(b) then k:add_proto_expert_info(e_parity) end
    item:add(f.key_valid, range, VALID_KEY[code] == true)
    if VALID_KEY[code] then
        if code ~= 0x2D then item:add(f.key_display, range, code + 1):set_generated() end
    else
        k:add_proto_expert_info(e_key)
    end
    return string.format("key %02X", code)
end

tape.select = function(port) return port == 8 and keyboard or tape end
DEVSIM.register(3, tape)
