-- Wireshark / tshark dissector for mocosim captures (docs/wireshark.md):
-- DMC v2 (dmc-v2-protocol.txt), DFMoco (dfmoco-protocol.txt) and the
-- StackShot 3X binary protocol (stackshot-protocol.txt), as written by
-- `mocosim export --pcapng`: LINKTYPE_USER0, one interface per direction
-- whose description names the protocol ("mocosim dmc host->device").
--
--   wireshark -X lua_script:tools/wireshark/mocosim.lua capture.pcapng
--   tshark -X lua_script:tools/wireshark/mocosim.lua -r capture.pcapng \
--          -T fields -e mocosim.direction -e mocosim.message
--
-- A packet is one chunk as it crossed the link, so a message may be split
-- across packets or share one with others. Each direction is framed as a
-- stream, as `mocosim decode` frames it (same resynchronisation, same
-- checksum verdicts, same message text); a message completed by a packet is
-- shown under that packet, reassembled when its bytes began in earlier ones.
-- Field names follow the decode text: dmc.motor, dmc.max_velocity, ...

local mocosim = Proto("mocosim", "mocosim serial link")
local dmc = Proto("dmc", "DMC v2")
local stackshot = Proto("stackshot", "StackShot 3X binary")
local dfmoco = Proto("dfmoco", "DFMoco")

local protocol_names = { "auto", "dmc", "dfmoco", "stackshot", "stackshot-dfmoco" }
local protocol_pref = {}
for i, n in ipairs(protocol_names) do protocol_pref[i] = { i, n, i } end
mocosim.prefs.protocol = Pref.enum("Protocol", 1, "Protocol of the link's bytes (auto: from the capture's interface description)",
                                   protocol_pref, false)

local pf = {
  direction = ProtoField.string("mocosim.direction", "Direction"),
  protocol = ProtoField.string("mocosim.protocol", "Protocol"),
  message = ProtoField.string("mocosim.message", "Message"),
  problem = ProtoField.bool("mocosim.problem", "Problem"),
  reassembled = ProtoField.uint32("mocosim.reassembled_from", "Begins in packet"),
  skipped_so_far = ProtoField.uint32("mocosim.skipped_so_far",
                                     "Bytes skipped so far, not yet reported"),
}
mocosim.fields = { pf.direction, pf.protocol, pf.message, pf.problem, pf.reassembled,
                   pf.skipped_so_far }

-- DMC fields: header, checksum, and every field name the decode text uses.
local dmc_f = {
  id = ProtoField.uint32("dmc.id", "ID"),
  type = ProtoField.uint16("dmc.type", "Type", base.HEX),
  type_name = ProtoField.string("dmc.type_name", "Type name"),
  ack = ProtoField.bool("dmc.ack", "ACK"),
  length = ProtoField.uint16("dmc.length", "Length"),
  checksum = ProtoField.uint16("dmc.checksum", "Check bytes", base.HEX),
  checksum_status = ProtoField.string("dmc.checksum.status", "Checksum"),
  code = ProtoField.string("dmc.code", "Response code"),
  skipped = ProtoField.uint32("dmc.skipped", "Bytes skipped outside any frame"),
}
local dmc_value_fields = {}
local function dmc_value_field(name)
  local f = dmc_value_fields[name]
  if not f then
    f = ProtoField.string("dmc." .. name, name)
    dmc_value_fields[name] = f
  end
  return f
end
for _, n in ipairs({ "motor", "position", "speed", "destination", "flags", "max_velocity",
                     "max_accel", "lower_enable", "lower", "upper_enable", "upper", "hw_set",
                     "start_frame", "end_frame", "start_index", "last", "positions", "channel",
                     "levels", "mask", "points", "frame", "fps", "preroll_ms", "postroll_ms",
                     "sync_dmx", "bloop_outputs", "bloop_dmx_channel", "bloop_ms", "open_angle",
                     "close_angle", "direction", "exposure_ms", "blur", "motors", "axis",
                     "enable", "x", "y", "z", "ramp", "values", "triggers", "name", "fw",
                     "motors_count", "dmx", "gio_out", "gio_in", "hw_limits", "upload_frames",
                     "caps", "protocol", "moving", "time", "reason", "track", "ew", "ns", "pan",
                     "tilt", "roll", "aim_enabled", "aim", "data", "code_bytes", "rig_type" }) do
  dmc_value_field(n)
end
do
  local list = {}
  for _, f in pairs(dmc_f) do list[#list + 1] = f end
  for _, f in pairs(dmc_value_fields) do list[#list + 1] = f end
  dmc.fields = list
end

local ss_f = {
  command = ProtoField.uint16("stackshot.command", "Command", base.HEX),
  command_name = ProtoField.string("stackshot.command_name", "Command name"),
  action = ProtoField.string("stackshot.action", "Action"),
  axis = ProtoField.string("stackshot.axis", "Axis"),
  length = ProtoField.uint8("stackshot.length", "Length"),
  data = ProtoField.bytes("stackshot.data", "Data"),
  checksum = ProtoField.uint8("stackshot.checksum", "Checksum", base.HEX),
  checksum_status = ProtoField.string("stackshot.checksum.status", "Checksum"),
  skipped = ProtoField.uint32("stackshot.skipped", "Bytes skipped before a sync byte"),
}
stackshot.fields = { ss_f.command, ss_f.command_name, ss_f.action, ss_f.axis, ss_f.length,
                     ss_f.data, ss_f.checksum, ss_f.checksum_status, ss_f.skipped }

local dfm_f = {
  line = ProtoField.string("dfmoco.line", "Line"),
  command = ProtoField.string("dfmoco.command", "Command"),
  args = ProtoField.string("dfmoco.args", "Arguments"),
}
dfmoco.fields = { dfm_f.line, dfm_f.command, dfm_f.args }

local f_if_desc = Field.new("frame.interface_description")
local f_if_id = Field.new("frame.interface_id")
local f_time = Field.new("frame.time_relative")

-- Little helpers over Lua strings (byte 1 is the first).
local function u8(s, i) return s:byte(i) end
local function u16le(s, i) return s:byte(i) + 256 * s:byte(i + 1) end
local function u32le(s, i) return u16le(s, i) + 65536 * u16le(s, i + 2) end
local function i16le(s, i)
  local v = u16le(s, i)
  if v >= 32768 then v = v - 65536 end
  return v
end
local function i32le(s, i)
  local v = u32le(s, i)
  if v >= 2147483648 then v = v - 4294967296 end
  return v
end
local function hex(v, digits) return string.format("0x%0" .. digits .. "x", v) end
local function tohex(s)
  return (s:gsub(".", function(c) return string.format("%02x", c:byte()) end))
end
local function dec(v) return string.format("%d", v) end

------------------------------------------------------------------------------
-- DMC v2
------------------------------------------------------------------------------
local DMC_NAMES = {
  [0x0001] = "HI", [0x0020] = "DMX", [0x0021] = "GIO_OUT", [0x0022] = "GIO_IN",
  [0x0023] = "GIO_CAM", [0x0030] = "MOTOR_STATUS", [0x0031] = "MOTOR_MOVE",
  [0x0032] = "MOTOR_STOP", [0x0033] = "MOTOR_STOP_ALL", [0x0034] = "MOTOR_GET_POSITION",
  [0x0035] = "MOTOR_RESET_POSITION", [0x0036] = "MOTOR_JOG", [0x0037] = "MOTOR_CONFIGURE",
  [0x0038] = "MOTOR_SET_SPEED", [0x0039] = "MOTOR_SET_LIMITS", [0x003a] = "MOTOR_HARD_STOP",
  [0x0100] = "RT_UPLOAD_MOVE_BEGIN", [0x0101] = "RT_UPLOAD_MOVE_AXIS",
  [0x0102] = "RT_UPLOAD_MOVE_DMX", [0x0103] = "RT_UPLOAD_MOVE_END",
  [0x0104] = "RT_UPLOAD_MOVE_TRIGGERS", [0x0110] = "RT_POSITION_FRAME",
  [0x0111] = "RT_RUN_MOVE", [0x0112] = "RT_SHOOT_FRAME", [0x0113] = "RT_GO",
  [0x0114] = "RT_END", [0x0115] = "RT_SHOOT_FRAME2", [0x0116] = "RT_STOP_LOOP",
  [0x0120] = "RT_JOG_ALL", [0x0200] = "VIRT_CONFIG", [0x0201] = "VIRT_MOVE",
  [0x0202] = "VIRT_STOP", [0x0203] = "VIRT_JOG", [0x0205] = "VIRT_GET_POSITION",
  [0x0206] = "VIRT_JOG_ON_LINE", [0x0207] = "VIRT_AIM_POINT",
}
local DMC_ACK_CODES = {
  [0x10] = "OK", [0x11] = "ERR_CHECKSUM", [0x12] = "ERR_MOVING", [0x13] = "ERR_UNSUPPORTED",
  [0x14] = "ERR_RANGE", [0x15] = "ERR_GENERAL", [0x16] = "ERR_NOT_IN_POSITION",
  [0x17] = "ERR_PREROLL", [0x18] = "ERR_POSTROLL", [0x19] = "ERR_AIM_POINT",
  [0x20] = "ERR_SOFT_UP", [0x21] = "ERR_SOFT_LOW", [0x22] = "ERR_HARD_UP", [0x23] = "ERR_HARD_LOW",
}
local DMC_REASONS = { [0] = "E_STOP", [1] = "UPPER_LIMIT", [2] = "LOWER_LIMIT",
                      [100] = "ENGINE_EXCEPTION" }
local DMC_MAX_DATA = 1036

local function dmc_type_name(t)
  local ack = t >= 0x8000
  local plain = ack and t - 0x8000 or t
  return (ack and "ACK " or "") .. (DMC_NAMES[plain] or hex(plain, 4))
end

-- Layouts of the data sections (dmc-v2-protocol.txt "Message Types"), in
-- the order and under the names `mocosim decode` prints them. Kinds: u8,
-- u16, u32, i16, i32 (decimal), h2/h4/h8 (hex digits), idx (START INDEX
-- with its last-set bit: start_index and last), then the rest of the data:
-- li32 (list of i32), lu8 (list of u8), trig (frame:values pairs), blur
-- (motor:a:b triples); opt_* only when the bytes are there.
local L = {}
local HOST = {
  [0x0020] = { { "u8", "ramp" }, { "u16", "start_channel" }, { "lu8", "values" } },
  [0x0021] = { { "h8", "triggers" } },
  [0x0023] = { { "h8", "flags" } },
  [0x0031] = { { "u8", "motor" }, { "i32", "position" } },
  [0x0032] = { { "u8", "motor" } },
  [0x0033] = { { "opt_h8", "flags" } },
  [0x0035] = { { "u8", "motor" }, { "i32", "position" } },
  [0x0036] = { { "u8", "motor" }, { "u16", "speed" }, { "i32", "destination" } },
  [0x0037] = { { "u8", "motor" }, { "h2", "flags" } },
  [0x0038] = { { "u8", "motor" }, { "u32", "max_velocity" }, { "u32", "max_accel" } },
  [0x0039] = { { "u8", "motor" }, { "u8", "lower_enable" }, { "i32", "lower" },
               { "u8", "upper_enable" }, { "i32", "upper" }, { "h2", "hw_set" } },
  [0x0100] = { { "u32", "start_frame" }, { "u32", "end_frame" } },
  [0x0101] = { { "u8", "motor" }, { "idx" }, { "li32", "positions" } },
  [0x0102] = { { "u16", "channel" }, { "idx" }, { "lu8", "levels" } },
  [0x0104] = { { "h8", "mask" }, { "trig", "points" } },
  [0x0110] = { { "u32", "frame" } },
  [0x0111] = { { "u32", "fps" }, { "u32", "start_frame" }, { "u32", "end_frame" },
               { "u32", "preroll_ms" }, { "u32", "postroll_ms" }, { "u8", "sync_dmx" },
               { "h8", "bloop_outputs" }, { "u16", "bloop_dmx_channel" }, { "u16", "bloop_ms" },
               { "opt_h4", "flags" }, { "opt_u16", "open_angle" }, { "opt_u16", "close_angle" } },
  [0x0112] = { { "u32", "frame" }, { "u8", "direction" }, { "u32", "exposure_ms" },
               { "u16", "blur" }, { "blur", "motors" } },
  [0x0115] = { { "u32", "frame" }, { "u32", "exposure_ms" }, { "u16", "open_angle" },
               { "u16", "close_angle" }, { "blur", "motors" } },
  [0x0120] = { { "u32", "fps" }, { "u32", "destination" } },
  [0x0200] = { { "u8", "rig_type" }, { "rest", "data" } },
  [0x0201] = { { "u8", "axis" }, { "i32", "position" } },
  [0x0202] = { { "u8", "axis" } },
  [0x0203] = { { "u8", "axis" }, { "u16", "speed" }, { "i32", "destination" } },
  [0x0206] = { { "u8", "axis" }, { "i16", "speed" } },
  [0x0207] = { { "u8", "enable" }, { "i32", "x" }, { "i32", "y" }, { "i32", "z" } },
}
for _, t in ipairs({ 0x0001, 0x0022, 0x0030, 0x0034, 0x0103, 0x0113, 0x0116, 0x0205 }) do
  HOST[t] = {}
end
local DEVICE = {
  [0x0001] = { { "name32", "name" }, { "fw", "fw" }, { "u8", "motors" }, { "u16", "dmx" },
               { "u8", "gio_out" }, { "u8", "gio_in" }, { "u8", "hw_limits" },
               { "u32", "upload_frames" }, { "h8", "caps" }, { "opt_u16", "protocol" } },
  [0x0030] = { { "h8", "moving" }, { "u8", "dmx" } },
  [0x0031] = { { "u8", "moving" } },
  [0x0034] = { { "u32", "time" }, { "li32", "positions" } },
  [0x0022] = { { "h8", "triggers" } },
  [0x003a] = { { "reason", "reason" } },
  [0x0114] = {},
  [0x0205] = { { "i32", "track" }, { "i32", "ew" }, { "i32", "ns" }, { "i32", "pan" },
               { "i32", "tilt" }, { "i32", "roll" }, { "aim" } },
  [0x0207] = HOST[0x0207],
}

local SIZES = { u8 = 1, u16 = 2, u32 = 4, i16 = 2, i32 = 4, h2 = 1, h4 = 2, h8 = 4, idx = 4,
                name32 = 32, fw = 3, reason = 1 }

local function quoted(s)
  return '"' .. s:gsub('[%z\1-\31\127-\255"\\]', function(c)
    return string.format("\\x%02x", c:byte())
  end) .. '"'
end
-- DFMoco text as wire/dfmoco.cpp quotes it: '"' and '\' after a backslash,
-- other bytes outside printable ASCII as \xNN.
local function dfm_quoted(s)
  return '"' .. s:gsub('[%z\1-\31\127-\255"\\]', function(c)
    if c == '"' or c == "\\" then return "\\" .. c end
    return string.format("\\x%02x", c:byte())
  end) .. '"'
end

-- Decodes a data section by its layout: returns the text after the type
-- name and a list of {name, value} pairs, or nil and a reason.
local function dmc_fields(layout, d)
  local out, pairs_ = {}, {}
  local pos = 1
  local function put(name, value)
    out[#out + 1] = name .. "=" .. value
    pairs_[#pairs_ + 1] = { name, value }
  end
  for _, item in ipairs(layout) do
    local kind, name = item[1], item[2]
    local opt = kind:sub(1, 4) == "opt_"
    if opt then kind = kind:sub(5) end
    local size = SIZES[kind]
    if size and #d - pos + 1 < size then
      if opt then break end
      return nil, "data ends before " .. (name or "START INDEX")
    end
    if kind == "u8" then put(name, dec(u8(d, pos)))
    elseif kind == "u16" then put(name, dec(u16le(d, pos)))
    elseif kind == "u32" then put(name, dec(u32le(d, pos)))
    elseif kind == "i16" then put(name, dec(i16le(d, pos)))
    elseif kind == "i32" then put(name, dec(i32le(d, pos)))
    elseif kind == "h2" then put(name, hex(u8(d, pos), 2))
    elseif kind == "h4" then put(name, hex(u16le(d, pos), 4))
    elseif kind == "h8" then put(name, hex(u32le(d, pos), 8))
    elseif kind == "idx" then
      local v = u32le(d, pos)
      local last = v >= 2147483648
      put("start_index", dec(last and v - 2147483648 or v))
      put("last", last and "1" or "0")
    elseif kind == "name32" then
      put(name, quoted((d:sub(pos, pos + 31):gsub("%z.*$", ""))))
    elseif kind == "fw" then
      put(name, dec(u8(d, pos)) .. "." .. dec(u8(d, pos + 1)) .. "." .. dec(u8(d, pos + 2)))
    elseif kind == "reason" then
      local r = u8(d, pos)
      put(name, DMC_REASONS[r] or dec(r))
      if r == 1 or r == 2 or #d > pos then
        if #d < pos + 1 then return nil, "data ends before MOTOR" end
        put("motor", dec(u8(d, pos + 1)))
        pos = pos + 1
      end
    elseif kind == "li32" or kind == "lu8" or kind == "trig" or kind == "blur" then
      local step = ({ li32 = 4, lu8 = 1, trig = 8, blur = 9 })[kind]
      local vals = {}
      while #d - pos + 1 >= step do
        if kind == "li32" then vals[#vals + 1] = dec(i32le(d, pos))
        elseif kind == "lu8" then vals[#vals + 1] = dec(u8(d, pos))
        elseif kind == "trig" then
          vals[#vals + 1] = dec(u32le(d, pos)) .. ":" .. hex(u32le(d, pos + 4), 8)
        else
          vals[#vals + 1] = dec(u8(d, pos)) .. ":" .. dec(i32le(d, pos + 1)) .. ":" ..
                            dec(i32le(d, pos + 5))
        end
        pos = pos + step
      end
      put(name, "[" .. table.concat(vals, ",") .. "]")
      size = 0
    elseif kind == "aim" then
      if #d - pos + 1 >= 13 then
        put("aim_enabled", dec(u8(d, pos)))
        put("aim", dec(i32le(d, pos + 1)) .. "," .. dec(i32le(d, pos + 5)) .. "," ..
                   dec(i32le(d, pos + 9)))
        pos = pos + 13
      end
      size = 0
    elseif kind == "rest" then
      put(name, tohex(d:sub(pos)))
      pos = #d + 1
      size = 0
    end
    pos = pos + (size or 0)
  end
  return table.concat(out, " "), pairs_
end

-- The text `mocosim decode` gives a good frame, and its field pairs.
local function dmc_describe(from_host, t, d)
  local prefix = "#"
  local name = dmc_type_name(t)
  if t >= 0x8000 then
    if #d == 2 or #d == 4 then
      local code = #d == 2 and u16le(d, 1) or u32le(d, 1)
      local text = name .. " code=" .. (DMC_ACK_CODES[code] or hex(code, code > 0xffff and 8 or 4))
      local p = { { "code", DMC_ACK_CODES[code] or hex(code, 4) } }
      if #d == 4 then text = text .. " code_bytes=4" end
      return text, p
    end
    return nil, "ACK response code must be 2 or 4 bytes, got " .. #d
  end
  local layout = (from_host and HOST or DEVICE)[t]
  if not layout then
    return "UNKNOWN type=" .. hex(t, 4) .. " data=" .. tohex(d), { { "data", tohex(d) } }
  end
  local text, p = dmc_fields(layout, d)
  if not text then return nil, p end
  if text == "" then return name, p end
  return name .. " " .. text, p
end

local function fletcher16(s)
  local sum1, sum2 = 0, 0
  for i = 1, #s do
    sum1 = sum1 + s:byte(i)
    sum2 = sum2 + sum1
    if i % 20 == 0 then
      sum1 = sum1 % 255
      sum2 = sum2 % 255
    end
  end
  return (sum2 % 255) * 256 + (sum1 % 255)
end

-- One direction's DMC stream: FrameDecoder's rules (wire/dmc_frame.h): hunt
-- for "DF", a Length above 1036 is dropped as oversize, a frame whose
-- checksum is not zero is reported with its header; after either the scan
-- resumes at the byte after the candidate's 'D'. Skipped bytes are reported
-- once, just before the next other event.
-- Idle line (docs/protocol-notes.md "Idle line"; wire/dmc_transcript.cpp):
-- a packet that comes 50 ms or more after the previous packet of its
-- direction first ends the partial frame the direction holds (st.give_up):
-- it is given up, its bytes rescanned, and skipped bytes reported, as the
-- DMC-16 and `mocosim decode` do.
local DMC_IDLE_GAP_NS = 50000000
local function dmc_stream(from_host)
  local st = { buf = "", base = 0, skipped = 0 }
  -- Scans st.buf; with at_end, a candidate that needs more bytes is given
  -- up (and its bytes after the 'D' rescanned) instead of kept.
  local function scan(emit, at_end)
    local function flush()
      if st.skipped > 0 then
        emit({ problem = true, text = "skipped " .. st.skipped .. " byte(s) outside any frame",
               fields = { { "skipped", st.skipped } } })
        st.skipped = 0
      end
    end
    local function drop(n, counted)
      st.buf = st.buf:sub(n + 1)
      st.base = st.base + n
      if counted then st.skipped = st.skipped + n end
    end
    while #st.buf > 0 do
      local b = st.buf
      local need_more = false
      if b:byte(1) ~= 0x44 then
        local j = b:find("D", 1, true)
        drop(j and j - 1 or #b, true)
      elseif #b < 2 then need_more = true
      elseif b:byte(2) ~= 0x46 then drop(1, true)
      elseif #b < 10 then need_more = true
      else
        local id, t, length = u32le(b, 3), u16le(b, 7), u16le(b, 9)
        if length > DMC_MAX_DATA then
          flush()
          emit({ problem = true, text = "frame length " .. length .. " exceeds 1036: dropped",
                 start = st.base, raw = b:sub(1, 10) })
          drop(1, true)
        elseif #b < 12 + length then need_more = true
        else
          local frame = b:sub(1, 12 + length)
          flush()
          local head = "#" .. string.format("%d", id) .. " "
          local common = { { "id", id }, { "type", t }, { "type_name", dmc_type_name(t) },
                           { "ack", t >= 0x8000 }, { "length", length },
                           { "checksum", frame:byte(11 + length) * 256 + frame:byte(12 + length) } }
          if fletcher16(frame) ~= 0 then
            common[#common + 1] = { "checksum.status", "bad" }
            emit({ problem = true, start = st.base, raw = frame, fields = common,
                   text = head .. dmc_type_name(t) .. " BAD CHECKSUM (length " .. length .. ")" })
            drop(1, true)
          else
            common[#common + 1] = { "checksum.status", "good" }
            local data = frame:sub(11, 10 + length)
            local text, p = dmc_describe(from_host, t, data)
            if text then
              for _, kv in ipairs(p) do common[#common + 1] = kv end
              emit({ problem = false, start = st.base, raw = frame, fields = common,
                     text = head .. text })
            else
              emit({ problem = true, start = st.base, raw = frame, fields = common,
                     text = head .. dmc_type_name(t) .. " malformed: " .. p })
            end
            drop(#frame, false)
          end
        end
      end
      if need_more then
        if not at_end then break end
        flush()
        emit({ problem = true, start = st.base, raw = b,
               text = "frame given up after 50 ms idle (" .. #b .. " byte(s) of it)" })
        drop(1, true)
      end
    end
    if at_end then flush() end
  end
  function st.feed(bytes, emit)
    st.buf = st.buf .. bytes
    scan(emit, false)
  end
  function st.give_up(emit)
    scan(emit, true)
  end
  return st
end

------------------------------------------------------------------------------
-- StackShot 3X binary (stackshot-protocol.txt section 2; ERRATA 3.2)
------------------------------------------------------------------------------
local SS_NAMES = {
  [0x1000] = "CC_RAIL_MOVE", [0x1001] = "CC_RAIL_POSITION_TARGET",
  [0x1002] = "CC_RAIL_POSITION_CURRENT", [0x1003] = "CC_RAIL_POSITION_ZERO",
  [0x1004] = "CC_RAIL_SHUTTER_FIRE", [0x1005] = "CC_RAIL_STATUS", [0x1006] = "CC_RAIL_STOP",
  [0x1007] = "CC_RAIL_MOVE_AT_SPEED", [0x1008] = "CC_RAIL_STACK",
  [0x1009] = "CC_RAIL_STACK_STATUS", [0x100A] = "CC_RAIL_STACK_POSITION",
  [0x100B] = "CC_RAIL_STOP_RAMP", [0x1080] = "CC_RAIL_CONFIG_NAME",
  [0x1081] = "CC_RAIL_CONFIG_BACKLIGHT", [0x1082] = "CC_RAIL_CONFIG_MODE",
  [0x1083] = "CC_RAIL_CONFIG_UNITS", [0x1084] = "CC_RAIL_CONFIG_TORQUE",
  [0x1085] = "CC_RAIL_CONFIG_NUM_STEPS", [0x1086] = "CC_RAIL_CONFIG_NUM_PULSES",
  [0x1087] = "CC_RAIL_CONFIG_TOTAL_DISTANCE", [0x1088] = "CC_RAIL_CONFIG_DISTANCE_PER_STEP",
  [0x1089] = "CC_RAIL_CONFIG_SETTLE_TIME", [0x108A] = "CC_RAIL_CONFIG_OFF_TIME",
  [0x108B] = "CC_RAIL_CONFIG_SPEED", [0x108C] = "CC_RAIL_CONFIG_RAMP_TIME",
  [0x108D] = "CC_RAIL_CONFIG_DISTANCE_PER_REV", [0x108E] = "CC_RAIL_CONFIG_SHUTTER_DISABLE",
  [0x108F] = "CC_RAIL_CONFIG_AUTO_RETURN", [0x1090] = "CC_RAIL_CONFIG_SAVE",
  [0x1091] = "CC_RAIL_CONFIG_LOAD", [0x1092] = "CC_RAIL_CONFIG_AXIS",
  [0x1093] = "CC_RAIL_CONFIG_TIMELAPSE", [0x1094] = "CC_RAIL_CONFIG_PULSE_TIME",
  [0x1095] = "CC_RAIL_CONFIG_BACKLASH", [0x1096] = "CC_RAIL_CONFIG_HOLDING_TORQUE",
  [0x1097] = "CC_RAIL_CONFIG_SPEED_MOVE", [0x1098] = "CC_RAIL_CONFIG_POLARITY",
  [0x1099] = "CC_RAIL_CONFIG_IO_MODE", [0x109A] = "CC_RAIL_CONFIG_IO_DIR",
  [0x109B] = "CC_RAIL_CONFIG_ROTARY_BACKLASH", [0x109C] = "CC_RAIL_CONFIG_ROTARY_RATIO",
  [0x109D] = "CC_RAIL_CONFIG_ROTARY_DEGREES", [0x109E] = "CC_RAIL_CONFIG_GLOBAL_MODE",
  [0x109F] = "CC_RAIL_CONFIG_TOFF_FINAL", [0x10A0] = "CC_RAIL_CONFIG_SHUTTER",
  [0x1100] = "CC_RESET", [0x1101] = "CC_REFLASH", [0x1102] = "CC_SOFTWARE_STRING",
  [0x1103] = "CC_SOFTWARE_ID", [0x1104] = "CC_HARDWARE_ID", [0x1105] = "CC_BOOTLOADER_ID",
  [0x1106] = "CC_SOFTWARE_CHECKSUM", [0x1107] = "CC_SERIAL_NUMBER", [0x1108] = "CC_NVM_ACCESS",
  [0x1109] = "CC_NAND_ACCESS", [0x110A] = "CC_NOR_ACCESS", [0x110B] = "CC_PING",
  [0x110C] = "CC_LOG", [0x110D] = "CC_WIFI", [0x110E] = "CC_CLOSE", [0x1200] = "CC_WAD",
  [0x1600] = "CC_MOTION_CONFIG", [0x1601] = "CC_MOTION_START",
}
-- The data layouts of each command (wire/stackshot_table.cpp, which cites
-- the section 2 tables and ERRATA 3.4, 3.5): { read request, read response,
-- write request }, each a byte count, or "uq" (0 or 1: a units byte or
-- none), "text" (a string: nothing after its NUL), "stack" (44 or 48),
-- "log" (1 or 4), "start" (3, or padded to 132), "raw" (anything), false
-- (the action is not allowed).
local SS_SHAPES = {
  [0x1000] = { false, false, 7 }, [0x1001] = { "uq", 5, false }, [0x1002] = { "uq", 5, false },
  [0x1003] = { false, false, 0 }, [0x1004] = { false, false, 10 }, [0x1005] = { 0, 4, false },
  [0x1006] = { false, false, 0 }, [0x1007] = { false, false, 10 },
  [0x1008] = { false, false, "stack" }, [0x1009] = { 0, 4, false }, [0x100A] = { 0, 4, false },
  [0x100B] = { false, false, 0 }, [0x1080] = { 0, "text", "text" }, [0x1081] = { 0, 1, 1 },
  [0x1082] = { 0, 1, 1 }, [0x1083] = { 0, 1, 1 }, [0x1084] = { 0, 1, 1 }, [0x1085] = { 0, 2, 2 },
  [0x1086] = { 0, 2, 2 }, [0x1087] = { "uq", 5, 5 }, [0x1088] = { "uq", 5, 5 },
  [0x1089] = { 0, 4, 4 }, [0x108A] = { 0, 4, 4 }, [0x108B] = { "uq", 5, 5 }, [0x108C] = { 0, 4, 4 },
  [0x108D] = { "uq", 5, 5 }, [0x108E] = { 0, 1, 1 }, [0x108F] = { 0, 1, 1 },
  [0x1090] = { false, false, 1 }, [0x1091] = { false, false, 1 }, [0x1092] = { 0, 1, 1 },
  [0x1093] = { 0, 4, 4 }, [0x1094] = { 0, 4, 4 }, [0x1095] = { "uq", 5, 5 }, [0x1096] = { 0, 1, 1 },
  [0x1097] = { "uq", 5, 5 }, [0x1098] = { 0, 1, 1 }, [0x1099] = { 0, 1, 1 }, [0x109A] = { 0, 1, 1 },
  [0x109B] = { 0, 4, 4 }, [0x109C] = { 0, 4, 4 }, [0x109D] = { 0, 4, 4 }, [0x109E] = { 0, 1, 1 },
  [0x109F] = { 0, 1, 1 }, [0x10A0] = { 0, 1, 1 }, [0x1100] = { false, false, 0 },
  [0x1101] = { false, false, 0 }, [0x1102] = { 0, "text", false }, [0x1103] = { 0, 4, false },
  [0x1104] = { 0, 4, false }, [0x1105] = { 0, 4, false }, [0x1106] = { 0, 4, false },
  [0x1107] = { 0, 4, 4 }, [0x1108] = { 1, 4, 5 }, [0x1109] = { "raw", "raw", "raw" },
  [0x110A] = { "raw", "raw", "raw" }, [0x110B] = { 1, 2, false }, [0x110C] = { "log", "text", false },
  [0x110D] = { "raw", "raw", "raw" }, [0x110E] = { false, false, 0 },
  [0x1200] = { "raw", "raw", "raw" }, [0x1600] = { false, false, 132 },
  [0x1601] = { false, false, "start" },
}
local SS_PING_TABLE_ID = 0x110A     -- CC_PING's table id (NOR_ACCESS by the enum)
local SS_AUTO_RETURN = 0x108F       -- its garbled read table lists a bool

-- Why `data` does not fit `shape`, as wire/stackshot.cpp ParseShape says
-- it; nil when it fits.
local function ss_shape_error(shape, data, name, what)
  local n = #data
  local function expects(lo, hi)
    return "bad length at byte 4: " .. name .. " " .. what .. " expects " .. lo ..
           (hi and (" or " .. hi) or "") .. " data byte(s), got " .. n
  end
  if type(shape) == "number" then
    if n ~= shape then return expects(shape) end
  elseif shape == "uq" then
    if n > 1 then return expects(0, 1) end
  elseif shape == "text" then
    local nul = data:find("\0", 1, true)
    if nul and nul < n then
      return "trailing bytes at byte " .. (5 + nul) .. ": " .. (n - nul) ..
             " byte(s) after the string's terminating NUL"
    end
  elseif shape == "stack" then
    if n ~= 44 and n ~= 48 then return expects(44, 48) end
  elseif shape == "log" then
    if n ~= 1 and n ~= 4 then return expects(1, 4) end
  elseif shape == "start" then
    if n ~= 3 and n ~= 132 then return expects(3) end
  end
  return nil
end

-- Why a host packet is refused (wire/stackshot.cpp DecodeHostPacket), or nil.
local function ss_host_error(command, action, data)
  local shapes, name = SS_SHAPES[command], SS_NAMES[command]
  if not shapes then return nil end
  if action > 1 then
    return "bad value at byte 3: " .. name .. ": host action " .. action ..
           " is neither READ nor WRITE"
  end
  local is_read = action == 0
  if is_read and #data == 1 and (command == SS_PING_TABLE_ID or command == SS_AUTO_RETURN) then
    return nil
  end
  local shape = shapes[is_read and 1 or 3]
  if shape == false then
    return "bad value at byte 3: " .. name .. " is " .. (is_read and "write" or "read") .. "-only"
  end
  return ss_shape_error(shape, data, name, is_read and "read request" or "write request")
end

-- Why a device packet is refused (wire/stackshot.cpp DecodeDevicePacket),
-- or nil; `asked` is the action of the host's last packet of the command.
local function ss_device_error(command, status, data, asked)
  if status ~= 2 then return nil end  -- an error status carries any data
  if command == SS_PING_TABLE_ID and #data == 2 and (asked == nil or asked == 0) then return nil end
  local shapes, name = SS_SHAPES[command], SS_NAMES[command]
  if not shapes or shapes[2] == "raw" then return nil end
  local read_response
  if shapes[2] == false then read_response = false
  elseif shapes[3] == false then read_response = true
  elseif asked ~= nil then read_response = asked == 0
  else read_response = #data > 0 end
  if not read_response then
    if #data > 0 then
      return "bad length at byte 4: " .. name .. " write acknowledgement expects 0 data byte(s), got " ..
             #data
    end
    return nil
  end
  return ss_shape_error(shapes[2], data, name, "read response")
end

local SS_ACTIONS = { [0] = "read", "write", "ok", "bad-param", "unsupported-action",
                     "unsupported-cmd", "failed", "not-empty", "busy" }
local SS_AXES = { [0] = "X", "Y", "Z", "3" }

-- One direction's packets (wire/stackshot_frame.h PacketDecoder): hunt for
-- the direction's sync byte (host 0x55, device 0xAA), then command (BE),
-- action/status, length, data, checksum. The checksum is never a reason to
-- drop a packet (ERRATA 3.2); a byte other than the negated 8-bit sum is
-- flagged as `mocosim decode` flags it.
-- `line` is shared by both directions: a host's write of
-- CC_RAIL_CONFIG_GLOBAL_MODE = 8 (Motion->DfMoco) acknowledged "ok" switches
-- the line to DFMoco text from the byte after the acknowledgement (section 3;
-- wire/stackshot_mode_switch.h); the bytes after it are left in line.rest.
local function stackshot_stream(from_host, line)
  local sync = from_host and 0x55 or 0xAA
  local st = { buf = "", base = 0, skipped = 0 }
  function st.feed(bytes, emit)
    st.buf = st.buf .. bytes
    while #st.buf > 0 do
      local b = st.buf
      if b:byte(1) ~= sync then
        local j = b:find(string.char(sync), 1, true)
        local n = j and j - 1 or #b
        st.buf, st.base, st.skipped = b:sub(n + 1), st.base + n, st.skipped + n
      elseif #b < 5 or #b < 6 + b:byte(5) then break
      else
        local len = b:byte(5)
        local packet = b:sub(1, 6 + len)
        if st.skipped > 0 then
          emit({ problem = true, text = "skipped " .. st.skipped .. " byte(s) before a sync byte",
                 fields = { { "skipped", st.skipped } } })
          st.skipped = 0
        end
        local command = b:byte(2) * 256 + b:byte(3)
        local ab = b:byte(4)
        local action, axis = ab % 16, math.floor(ab / 16) % 4
        local sum = 0
        for i = 2, 5 + len do sum = sum + packet:byte(i) end
        local expected = (256 - sum % 256) % 256
        local ok = packet:byte(6 + len) == expected
        local name = SS_NAMES[command] or string.format("UNKNOWN(0x%04x)", command)
        local text = name .. " " .. (SS_ACTIONS[action] or ("action#" .. action)) .. " axis=" ..
                     SS_AXES[axis]
        if ab >= 128 then text = text .. " item=2" end
        if math.floor(ab / 64) % 2 == 1 then text = text .. " bit6=1" end
        local data = packet:sub(6, 5 + len)
        if len > 0 then text = text .. " data=" .. tohex(data) end
        -- The command's data layout for the action (a reply's in the light of
        -- the host's last action for the same command), as decode checks it.
        local err
        if from_host then
          err = ss_host_error(command, action, data)
          line.asked[command] = action
        else
          err = ss_device_error(command, action, data, line.asked[command])
        end
        if err then text = text .. ": " .. err end
        if not ok then text = text .. " [checksum byte differs from the default algorithm]" end
        local problem = err ~= nil
        emit({ problem = problem, start = st.base, raw = packet, text = text,
               fields = { { "command", command }, { "command_name", name },
                          { "action", SS_ACTIONS[action] or ("action#" .. action) },
                          { "axis", SS_AXES[axis] }, { "length", len },
                          { "checksum", packet:byte(6 + len) },
                          { "checksum.status", ok and "good" or "differs" } } })
        st.buf, st.base = b:sub(#packet + 1), st.base + #packet
        if command == 0x109E and from_host and action == 1 then
          -- The latest mode write decides.
          line.requested = err == nil and packet:byte(6) == 8
        elseif command == 0x109E and not from_host and line.requested then
          line.requested = false
          if action == 2 then
            emit({ problem = false,
                   text = "(the line switches to DfMoco mode: DFMoco text at 57600 baud)" })
            line.switched, line.rest = true, st.buf
            st.buf = ""
            return
          end
        end
      end
    end
  end
  return st
end

------------------------------------------------------------------------------
-- DFMoco (dfmoco-protocol.txt; ERRATA 2.1: the sketch ends a line only at
-- "\r\n" and ignores a bare "\n")
------------------------------------------------------------------------------
local DFM_MAX_LINE = 512

-- As wire/dfmoco.cpp splits a line: the word is everything before the first
-- space (a leading space gives an empty word), the arguments the runs of
-- non-space bytes after it.
local function words(line)
  local w = { line:match("^[^ ]*") }
  for t in line:sub(#w[1] + 1):gmatch("[^ ]+") do w[#w + 1] = t end
  return w
end
-- Strict decimals: an optional '-' and digits, within int32 ("-0" is 0).
local function ints(args, first)
  local v = {}
  for i = first, #args do
    local n = args[i]:match("^%-?%d+$")
    if not n then return nil end
    local x = tonumber(n)
    if x > 2147483647 or x < -2147483648 then return nil end
    if x == 0 then x = 0 end
    v[#v + 1] = x
  end
  return v
end

local function dfm_host(line, dialect)
  local a = words(line)
  local w = a[1] or ""
  local n = #a - 1
  local known = { hi = 1, ms = 1, mm = 1, mp = 1, sm = 1, sa = 1, jm = 1, im = 1, pr = 1,
                  zm = 1, np = 1, bf = 1, go = 1 }
  if not known[w] then return "unknown command " .. dfm_quoted(line) .. " (no reply)" end
  if n >= 40 then return nil end
  if w == "mp" and dialect.stackshot and n == 1 and a[2] == "*" then
    return "position query, all motors"
  end
  local v = ints(a, 2)
  if not v then return nil end
  if w == "hi" and n == 0 then return "hello" end
  if w == "ms" and n == 0 then return "motor status query" end
  if w == "go" and n == 0 then return "go (start go-motion move)" end
  if w == "sa" then
    if n == 0 then return "stop all motors" end
    if n == 1 and dialect.stackshot then return "stop all motors (motor " .. v[1] .. " given)" end
    return nil
  end
  if n == 1 and w == "mp" then return "position query, motor " .. v[1] end
  if n == 1 and w == "sm" then return "stop motor " .. v[1] end
  if n == 1 and w == "zm" then return "zero motor " .. v[1] end
  if n == 2 and w == "mm" then return "move motor " .. v[1] .. " to " .. v[2] end
  if n == 2 and w == "im" then return "inch motor " .. v[1] .. " toward " .. v[2] end
  if n == 2 and w == "pr" then
    return "set pulse rate of motor " .. v[1] .. " to " .. v[2] .. " steps/s"
  end
  if n == 2 and w == "np" then
    return "set position of motor " .. v[1] .. " to " .. v[2] .. " (no movement)"
  end
  if w == "jm" and (n == 2 or (n == 3 and dialect.major >= 2)) then
    local d = "jog motor " .. v[1] .. " toward " .. v[2]
    if n == 3 then
      if v[3] < 0 or v[3] > 10000 then return nil end
      d = d .. " at velocity " .. v[3] .. "/10000"
    end
    return d
  end
  if w == "bf" and n >= 2 and (n - 2) % 4 == 0 then
    local d = "blur frame: exposure " .. v[1] .. " ms, blur " .. v[2] .. "/1000, " ..
              ((n - 2) / 4) .. " channel(s)"
    for i = 3, n, 4 do
      d = d .. "; ch " .. v[i] .. " " .. v[i + 1] .. " -> " .. v[i + 2] .. " -> " .. v[i + 3]
    end
    return d
  end
  return nil
end

local function dfm_device(line, dialect)
  local t = line:gsub(" +$", "")
  if t == "parse error" then return "parse error" end
  if t == "error: too many args" then return "error: too many args (40 or more arguments)" end
  local a = words(t)
  local w = a[1] or ""
  local n = #a - 1
  if w == "hi" and n == 3 then
    local v = ints({ a[1], a[2], a[3] }, 2)
    if not v or not a[4]:match("^[!-~]+$") then return nil end
    local major = v[1]
    dialect.major = major
    return "hello: protocol " .. dec(v[1]) .. ", " .. dec(v[2]) .. " motors, firmware " .. a[4]
  end
  if w == "ms" and n == 1 and a[2]:match("^[01]+$") then
    local moving = {}
    for i = 1, #a[2] do
      if a[2]:sub(i, i) == "1" then moving[#moving + 1] = tostring(i) end
    end
    return "motor status: " .. #a[2] .. " motors, moving: " ..
           (#moving == 0 and "none" or table.concat(moving, ","))
  end
  local want = ({ mm = 2, mp = 2, pr = 2, np = 2, sm = 1, jm = 1, im = 1, zm = 1, bf = 1,
                  sa = 0, go = 0 })[w]
  if want == nil or n ~= want then return nil end
  if w == "sa" then return "stopping all motors" end
  if w == "go" then return "go-motion move started" end
  local v = ints(a, 2)
  if not v then return nil end
  if w == "mm" then
    if dialect.stackshot then return "motor " .. v[1] .. " moving, now at " .. v[2] end
    return "motor " .. v[1] .. " moving to " .. v[2]
  end
  if w == "mp" then return "motor " .. v[1] .. " at " .. v[2] end
  if w == "pr" then return "motor " .. v[1] .. " pulse rate " .. v[2] .. " steps/s" end
  if w == "np" then return "motor " .. v[1] .. " position set to " .. v[2] end
  if w == "sm" then return "stopping motor " .. v[1] end
  if w == "jm" then return "jogging motor " .. v[1] end
  if w == "im" then return "inching motor " .. v[1] end
  if w == "zm" then return "zeroed motor " .. v[1] end
  if v[1] == 0 then return "blur frame refused: a speed would exceed 20000 steps/s" end
  return "blur frame prepared (" .. v[1] .. ")"
end

local function dfmoco_stream(from_host, dialect)
  local st = { line = "", base = 0, pos = 0, start = 0, pending_cr = false, discarding = false }
  local function append(c, emit)
    if st.discarding then return end
    if #st.line >= DFM_MAX_LINE then
      emit({ problem = true, text = "line longer than " .. DFM_MAX_LINE .. " bytes" })
      st.line = ""
      st.discarding = true
      return
    end
    if #st.line == 0 then st.start = st.pos end
    st.line = st.line .. c
  end
  function st.feed(bytes, emit)
    for i = 1, #bytes do
      local c = bytes:sub(i, i)
      if c == "\n" then
        if st.pending_cr then
          st.pending_cr = false
          if not st.discarding then
            local line = st.line
            local text
            if from_host then text = dfm_host(line, dialect) else text = dfm_device(line, dialect) end
            local a = words(line)
            local item = { problem = text == nil, start = st.start, rawlen = st.pos + 1 - st.start,
                           text = text or (dfm_quoted(line) .. ": does not parse"),
                           fields = { { "line", line }, { "command", a[1] or "" },
                                      { "args", table.concat(a, " ", 2) } } }
            if from_host and text and text:sub(1, 16) == "unknown command " then
              item.fields[2][2] = a[1] or ""
            end
            emit(item)
          end
          st.line = ""
          st.discarding = false
        end
      else
        if st.pending_cr then append("\r", emit) end
        st.pending_cr = c == "\r"
        if not st.pending_cr then append(c, emit) end
      end
      st.pos = st.pos + 1
    end
  end
  return st
end

------------------------------------------------------------------------------
-- The link: per-direction stream state built on the first, in-order pass
-- and kept per packet number for every later look at a packet.
------------------------------------------------------------------------------
local streams = {}
local results = {}

function mocosim.init()
  streams = {}
  results = {}
end

local function protocol_of()
  if mocosim.prefs.protocol ~= 1 then return protocol_names[mocosim.prefs.protocol] end
  local d = f_if_desc()
  if d then
    local p = tostring(d.value):match("^mocosim ([%w%-]+) ")
    if p then return p end
  end
  return "dmc"
end

local function stream_for(protocol, from_host)
  local key = protocol .. (from_host and ":host" or ":device")
  if not streams[key] then
    streams.line = streams.line or { asked = {} }
    if protocol == "dmc" then streams[key] = dmc_stream(from_host)
    elseif protocol == "stackshot" then streams[key] = stackshot_stream(from_host, streams.line)
    else
      streams.dialect = streams.dialect or
                        { major = protocol == "stackshot-dfmoco" and 1 or 2,
                          stackshot = protocol == "stackshot-dfmoco" }
      streams[key] = dfmoco_stream(from_host, streams.dialect)
    end
  end
  return streams[key]
end

local sub_protos = { dmc = { dmc, dmc_f, dmc_value_fields }, stackshot = { stackshot, ss_f },
                     dfmoco = { dfmoco, dfm_f }, ["stackshot-dfmoco"] = { dfmoco, dfm_f } }

local function add_fields(tree, range, protocol, fields)
  local sp = sub_protos[protocol]
  for _, kv in ipairs(fields or {}) do
    local f = sp[2][kv[1]:gsub("%.", "_")] or (sp[3] and sp[3][kv[1]])
    if kv[1] == "checksum.status" then f = sp[2].checksum_status end
    if f then
      local v = kv[2]
      if sp[3] and sp[3][kv[1]] then v = tostring(v) end
      if range then tree:add(f, range, v) else tree:add(f, v) end
    end
  end
end

function mocosim.dissector(tvb, pinfo, tree)
  local iface = f_if_id()
  -- Interfaces come in pairs, host -> device first: a line switch recorded
  -- in the session starts a new pair named with the new protocol.
  local from_host = not iface or iface.value % 2 == 0

  local r = results[pinfo.number]
  local protocol
  if r then
    protocol = r.protocol
  else
    protocol = protocol_of()
    local pair = iface and math.floor(iface.value / 2) or 0
    local switched_to = nil
    if streams.pair and pair ~= streams.pair and protocol ~= streams.speaking then
      -- A recorded line switch (docs/sessions.md "line_switch") to another
      -- protocol: its decoders start afresh, as mocosim decode's do.
      streams = {}
      switched_to = protocol
    end
    streams.pair = pair
    -- A StackShot line that switched to DfMoco mode carries DFMoco text.
    if protocol == "stackshot" and streams.line and streams.line.switched then
      protocol = "stackshot-dfmoco"
    end
    streams.speaking = protocol
    local st = stream_for(protocol, from_host)
    -- r.base: the stream offset of this packet's first byte.
    r = { base = st.fed or 0, items = {}, protocol = protocol }
    local function keep(item) r.items[#r.items + 1] = item end
    if switched_to then keep({ text = "(the line switches to " .. switched_to .. ")" }) end
    local t = f_time()
    local now = t and (t.value.secs * 1000000000 + t.value.nsecs)
    if st.give_up and now and st.last_ns and now - st.last_ns >= DMC_IDLE_GAP_NS then
      st.give_up(keep)
    end
    st.last_ns = now
    st.feed(tvb:raw(), keep)
    st.fed = r.base + tvb:len()
    -- Bytes skipped so far and not yet reported (they are, before the next
    -- message or at an idle gap): the packet is marked a problem all the
    -- same, so junk with nothing after it still shows.
    if (st.skipped or 0) > 0 then r.skipped_so_far = st.skipped end
    if streams.line and streams.line.rest then
      -- The bytes after the acknowledgement of the switch, in the same packet.
      local rest = streams.line.rest
      streams.line.rest = nil
      local dst = stream_for("stackshot-dfmoco", from_host)
      dst.feed(rest, function(item)
        item.protocol, item.start = "stackshot-dfmoco", nil
        r.items[#r.items + 1] = item
      end)
      dst.fed = (dst.fed or 0) + #rest
    end
    results[pinfo.number] = r
    -- Where each message's bytes began, for the packets it spans.
    streams.first = streams.first or {}
    local key = protocol .. (from_host and ":host" or ":device")
    streams.first[key] = streams.first[key] or {}
    local list = streams.first[key]
    list[#list + 1] = { base = r.base, number = pinfo.number }
    for _, item in ipairs(r.items) do
      if item.start and item.start < r.base then
        for k = #list, 1, -1 do
          if list[k].base <= item.start then
            item.from_packet = list[k].number
            break
          end
        end
      end
    end
  end

  pinfo.cols.protocol = protocol == "stackshot-dfmoco" and "DFMOCO" or protocol:upper()
  local root = tree:add(mocosim, tvb())
  root:add(pf.direction, from_host and "host->device" or "device->host")
  root:add(pf.protocol, protocol)
  local texts = {}
  for _, item in ipairs(r.items) do
    local text = (item.problem and "!! " or "") .. item.text
    texts[#texts + 1] = text
    local range
    local len = item.raw and #item.raw or item.rawlen
    if item.start and len then
      if item.start >= r.base and item.start - r.base + len <= tvb:len() then
        range = tvb(item.start - r.base, len)
      elseif item.raw then
        range = ByteArray.new(item.raw, true):tvb("Reassembled message")()
      end
    end
    local item_protocol = item.protocol or protocol
    local sp = sub_protos[item_protocol][1]
    local sub = range and tree:add(sp, range) or tree:add(sp)
    sub:set_text(sp.description .. ": " .. text)
    sub:add(pf.message, text)
    if item.problem then sub:add(pf.problem, true) end
    if item.from_packet then sub:add(pf.reassembled, item.from_packet) end
    add_fields(sub, nil, item_protocol, item.fields)
  end
  if r.skipped_so_far then
    local sub = root:add(pf.skipped_so_far, r.skipped_so_far)
    sub:set_text("!! " .. r.skipped_so_far .. " byte(s) skipped so far, not yet reported")
    root:add(pf.problem, true)
    if #texts == 0 then texts[1] = "!! (" .. r.skipped_so_far .. " byte(s) skipped so far)" end
  end
  local arrow = from_host and "host -> dev " or "dev  -> host"
  if #texts == 0 then
    pinfo.cols.info = arrow .. "  (part of a message)"
  else
    pinfo.cols.info = arrow .. "  " .. table.concat(texts, "; ")
  end
  return tvb:len()
end

DissectorTable.get("wtap_encap"):add(wtap.USER0, mocosim)
