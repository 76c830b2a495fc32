-- sers.lua: the SERS serial line (manual §4.1, §4.2, §4.7, §4.8.3.1; spec sers.md §3.1, §3.2):
-- ASCII lines "#<address><statements>" ended by CR or LF from the host; from the device the echo,
-- the answers to queries ("P11=0"), the acknowledgement "ok0".."ok4" / "pgm" and the error
-- messages "*<text>" whose errno comes from the device's own error table (sers_tables.lua,
-- generated from devsim.devices.sers.errors).  Parameter numbers P<n> get the manual's
-- designation.  Loaded by devsim.lua.
local DEVSIM = ...
if type(DEVSIM) ~= "table" or DEVSIM.kinds == nil then return end

local T = DEVSIM.tables("sers")

local proto = Proto("devsim_sers", "SERS line")
local f = {
    line = ProtoField.string("sers.line", "Line"),
    kind = ProtoField.string("sers.kind", "Kind of line"),
    address = ProtoField.string("sers.address", "Drive address"),
    statement = ProtoField.string("sers.statement", "Statements"),
    keyword = ProtoField.string("sers.keyword", "Keyword"),
    keyword_doc = ProtoField.string("sers.keyword.doc", "Keyword meaning"),
    param = ProtoField.uint16("sers.param", "Parameter"),
    param_name = ProtoField.string("sers.param.name", "Parameter designation"),
    query = ProtoField.string("sers.query", "Query"),
    answer = ProtoField.string("sers.answer", "Answer"),
    value = ProtoField.string("sers.value", "Value"),
    ack = ProtoField.string("sers.ack", "Acknowledgement"),
    errno = ProtoField.uint8("sers.errno", "errno"),
    error = ProtoField.string("sers.error", "Error message"),
    error_en = ProtoField.string("sers.error.en", "Error (English)"),
    noise = ProtoField.string("sers.noise", "Bytes before #"),
    terminator = ProtoField.bytes("sers.eol", "Line end"),
}
proto.fields = f

local e_error = ProtoExpert.new("sers.error.expert", "SERS error message", expert.group.RESPONSE_CODE, expert.severity.NOTE)
proto.experts = { e_error }

-- Error texts -> errno (German and English, as the device sends them; P265 picks the language).
local ERRNO = {}
for n, row in pairs(T.errno) do
    ERRNO[row.de] = ERRNO[row.de] or n
    ERRNO[row.en] = ERRNO[row.en] or n
end

local function errno_of(text)
    if ERRNO[text] then return ERRNO[text] end
    local best, best_len = nil, 0
    for known, n in pairs(ERRNO) do  -- a text with a detail appended ("label bereits definiert: L5")
        if #known > best_len and text:sub(1, #known) == known then best, best_len = n, #known end
    end
    return best
end

local function eol(b) return b == 0x0D or b == 0x0A end

local kind = { name = "SERS" }

-- One line: leading line ends, the text, the line ends after it (0 while the line is open).
function kind.unit(tvb, offset, dir)
    local length = tvb:len()
    local i = offset
    while i < length and eol(tvb:range(i, 1):uint()) do i = i + 1 end
    if i == length then return 0 end
    while i < length and not eol(tvb:range(i, 1):uint()) do i = i + 1 end
    if i == length then return 0 end
    while i < length and eol(tvb:range(i, 1):uint()) do i = i + 1 end
    return i - offset
end

local function parameter(tree, n)
    tree:add(f.param, n):set_generated()
    local row = T.parameters[n]
    if row then tree:add(f.param_name, row.name .. " (" .. row.doc .. ")"):set_generated() end
end

-- P<n>, and the aliases (V = P91, POS = P336 ...) where they are assigned or asked (manual §4.2).
local function parameters(tree, text)
    for word, number in text:gmatch("(%a[%w]*)%s*([=%?]?)") do
        local n = word:match("^[Pp](%d+)$")
        if n then
            parameter(tree, tonumber(n))
        elseif number ~= "" and T.aliases[word:upper()] then
            parameter(tree, T.aliases[word:upper()])
        end
    end
end

local function statements(tree, text)
    parameters(tree, text)
    for word in text:gmatch("[%a]+") do
        local upper = word:upper()
        if T.keywords[upper] then
            tree:add(f.keyword, upper):set_generated()
            tree:add(f.keyword_doc, T.keywords[upper]):set_generated()
        end
    end
    for q in text:gmatch("([%w]+%?%??)") do tree:add(f.query, q):set_generated() end
end

local function host_line(item, range, text)
    local noise, rest = text:match("^([^#]*)(#.*)$")
    if not rest then
        item:add(f.noise, range, text)
        return "noise " .. text
    end
    if #noise > 0 then item:add(f.noise, noise) end
    local address, body = rest:match("^#(%d*%*?)(.*)$")
    item:add(f.kind, "command line"):set_generated()
    if address ~= "" then item:add(f.address, address) end
    item:add(f.statement, body)
    statements(item, body)
    return rest
end

local function device_line(item, text)
    if text:match("^ok%d$") or text == "pgm" then
        item:add(f.kind, "acknowledgement"):set_generated()
        item:add(f.ack, text)
        return text
    end
    if text:sub(1, 1) == "*" then
        local message = text:sub(2)
        item:add(f.kind, "error message"):set_generated()
        local e = item:add(f.error, message)
        local n = errno_of(message)
        if n then
            item:add(f.errno, n):set_generated()
            item:add(f.error_en, T.errno[n].en):set_generated()
        end
        e:add_proto_expert_info(e_error, "SERS error " .. (n or "?") .. ": " .. message)
        return "*" .. message .. (n and (" (errno " .. n .. ")") or "")
    end
    if text:sub(1, 1) == "#" then
        item:add(f.kind, "echo"):set_generated()
        local address, body = text:match("^#(%d*%*?)(.*)$")
        if address ~= "" then item:add(f.address, address) end
        item:add(f.statement, body)
        parameters(item, body)
        return "echo " .. text
    end
    local name, value = text:match("^([^=]+)=(.*)$")
    if name then
        item:add(f.kind, "answer"):set_generated()
        item:add(f.answer, name)
        item:add(f.value, value)
        parameters(item, name .. "=")
        return text
    end
    item:add(f.kind, "text"):set_generated()
    return text
end

function kind.show(range, pinfo, tree, dir)
    local tvb = range:tvb()
    local first, last = 0, tvb:len()
    while first < last and eol(tvb:range(first, 1):uint()) do first = first + 1 end
    local stop = first
    while stop < last and not eol(tvb:range(stop, 1):uint()) do stop = stop + 1 end
    local body = tvb:range(first, stop - first)
    local text = DEVSIM.text(body:raw())
    local item = tree:add(proto, range, "SERS " .. (dir == 0 and "host" or "device") .. ": " .. text)
    item:add(f.line, body, text)
    local summary = dir == 0 and host_line(item, body, text) or device_line(item, text)
    if stop < last then item:add(f.terminator, tvb:range(stop, last - stop)) end
    return summary
end

DEVSIM.register(1, kind)
