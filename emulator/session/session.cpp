// Session files: timestamped host/device traffic in JSON Lines (docs/sessions.md).
#include "session/session.h"

#include <sstream>
#include <stdexcept>
#include <system_error>

namespace moco::session {
namespace {

using nlohmann::json;

constexpr const char* kKnownHeaderFields[] = {"mocosim_session", "protocol", "device",
                                              "clock",           "note",     "tolerances"};

bool IsKnownHeaderField(const std::string& k) {
  for (const char* f : kKnownHeaderFields) {
    if (k == f) return true;
  }
  return false;
}

SessionError Err(size_t line, std::string message) { return {line, std::move(message)}; }

std::optional<SessionError> ParseHeader(const json& j, SessionHeader& h) {
  if (!j.is_object() || !j.contains("mocosim_session")) {
    return Err(1,
               "line 1 is not a session header: expected an object with \"mocosim_session\": 1 "
               "(see docs/sessions.md)");
  }
  const json& v = j["mocosim_session"];
  if (!v.is_number_integer()) {
    return Err(1, "\"mocosim_session\" must be an integer format version");
  }
  if (v.get<int64_t>() > kSessionFormatVersion) {
    return Err(1, "session format version " + std::to_string(v.get<int64_t>()) +
                      " is newer than this program reads (" +
                      std::to_string(kSessionFormatVersion) + "): upgrade mocosim");
  }
  if (!j.contains("protocol") || !j["protocol"].is_string()) {
    return Err(1,
               "header lacks \"protocol\": set it to one of dmc, dfmoco, stackshot, "
               "stackshot-dfmoco");
  }
  auto p = ParseProtocol(j["protocol"].get<std::string>());
  if (!p) {
    return Err(1, "unknown protocol \"" + j["protocol"].get<std::string>() +
                      "\": use one of dmc, dfmoco, stackshot, stackshot-dfmoco");
  }
  h.protocol = *p;
  if (j.contains("device") && j["device"].is_string()) h.device = j["device"];
  if (j.contains("clock")) {
    if (!j["clock"].is_string() || (j["clock"] != "virtual" && j["clock"] != "real")) {
      return Err(1, "\"clock\" must be \"virtual\" or \"real\"");
    }
    h.clock = j["clock"];
  }
  if (j.contains("note") && j["note"].is_string()) h.note = j["note"];
  if (j.contains("tolerances")) {
    const json& t = j["tolerances"];
    if (!t.is_object()) return Err(1, "\"tolerances\" must be an object");
    if (t.contains("position_steps")) {
      if (!t["position_steps"].is_number_integer() || t["position_steps"].get<int64_t>() < 0) {
        return Err(1, "\"tolerances.position_steps\" must be a non-negative integer");
      }
      h.tolerance_position_steps = t["position_steps"].get<int64_t>();
    }
    if (t.contains("time_ms")) {
      if (!t["time_ms"].is_number_integer() || t["time_ms"].get<int64_t>() < 0) {
        return Err(1, "\"tolerances.time_ms\" must be a non-negative integer");
      }
      h.tolerance_time_ms = t["time_ms"].get<int64_t>();
    }
  }
  for (auto it = j.begin(); it != j.end(); ++it) {
    if (!IsKnownHeaderField(it.key())) h.extra[it.key()] = it.value();
  }
  return std::nullopt;
}

std::optional<SessionError> ParseEntry(const json& j, size_t line, int64_t prev_t,
                                       SessionEntry& e) {
  const std::string where = "line " + std::to_string(line) + ": ";
  if (!j.is_object()) return Err(line, where + "expected a JSON object");
  if (!j.contains("t_ns") || !j["t_ns"].is_number_integer()) {
    return Err(line, where + "missing integer \"t_ns\" (nanoseconds since session start)");
  }
  e.t_ns = j["t_ns"].get<int64_t>();
  if (e.t_ns < prev_t) {
    return Err(line, where + "\"t_ns\" goes backwards (" + std::to_string(e.t_ns) + " < " +
                         std::to_string(prev_t) + "): times must be non-decreasing");
  }
  if (j.contains("event")) {
    if (!j["event"].is_string()) return Err(line, where + "\"event\" must be a string");
    e.is_event = true;
    e.event = j;
    return std::nullopt;
  }
  if (!j.contains("from") || !j["from"].is_string()) {
    return Err(line, where + "a traffic line needs \"from\": \"host\" or \"device\"");
  }
  const std::string from = j["from"];
  if (from == "host") {
    e.from = Origin::kHost;
  } else if (from == "device") {
    e.from = Origin::kDevice;
  } else {
    return Err(line, where + "\"from\" is \"" + from + "\": use \"host\" or \"device\"");
  }
  if (!j.contains("hex") || !j["hex"].is_string()) {
    return Err(line, where + "a traffic line needs \"hex\": the bytes as hex digits");
  }
  auto bytes = wire::FromHex(j["hex"].get<std::string>());
  if (!bytes) {
    return Err(line, where + "\"hex\" is not an even number of hex digits");
  }
  e.bytes = std::move(*bytes);
  if (j.contains("decoded") && j["decoded"].is_array()) {
    for (const auto& d : j["decoded"]) {
      if (d.is_string()) e.decoded.push_back(d);
    }
  }
  return std::nullopt;
}

}  // namespace

std::variant<Session, SessionError> ParseSession(std::string_view text) {
  Session s;
  size_t line_no = 0;
  bool have_header = false;
  int64_t prev_t = 0;
  size_t pos = 0;
  while (pos <= text.size()) {
    size_t end = text.find('\n', pos);
    if (end == std::string_view::npos) end = text.size();
    std::string_view line = text.substr(pos, end - pos);
    pos = end + 1;
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    if (line.find_first_not_of(" \t") == std::string_view::npos) {
      if (end == text.size()) break;
      continue;
    }
    json j = json::parse(line, nullptr, /*allow_exceptions=*/false);
    if (j.is_discarded()) {
      // A recording that stopped mid-line (the process was killed) keeps
      // every whole line before it: the writer flushes line by line.
      if (end == text.size() && have_header) {
        s.cut_line = line_no;
        break;
      }
      return Err(line_no, "line " + std::to_string(line_no) + " is not valid JSON");
    }
    if (!have_header) {
      if (auto e = ParseHeader(j, s.header)) {
        e->line = line_no;
        return *e;
      }
      have_header = true;
      continue;
    }
    SessionEntry entry;
    if (auto e = ParseEntry(j, line_no, prev_t, entry)) return *e;
    prev_t = entry.t_ns;
    s.entries.push_back(std::move(entry));
    if (end == text.size()) break;
  }
  if (!have_header) {
    return Err(1, "empty session: the first line must be a header (see docs/sessions.md)");
  }
  return s;
}

std::string SessionWarning(const Session& s) {
  if (s.cut_line == 0) return {};
  return "line " + std::to_string(s.cut_line) +
         " is cut short (the recording did not finish); lines 1.." +
         std::to_string(s.cut_line - 1) + " are read";
}

std::variant<Session, SessionError> LoadSession(const std::filesystem::path& path) {
  std::string text;
  if (auto error = base::ReadFileBounded(
          path.string(), &text, {.max_bytes = 0, .max_line_bytes = kMaxSessionLineBytes})) {
    return Err(0, "session file " + path.string() + " " + *error);
  }
  return ParseSession(text);
}

nlohmann::json HeaderToJson(const SessionHeader& h) {
  json j = h.extra;
  j["mocosim_session"] = kSessionFormatVersion;
  j["protocol"] = std::string(ProtocolName(h.protocol));
  if (!h.device.empty()) j["device"] = h.device;
  j["clock"] = h.clock;
  if (!h.note.empty()) j["note"] = h.note;
  if (h.tolerance_position_steps || h.tolerance_time_ms) {
    json t = json::object();
    if (h.tolerance_position_steps) t["position_steps"] = *h.tolerance_position_steps;
    if (h.tolerance_time_ms) t["time_ms"] = *h.tolerance_time_ms;
    j["tolerances"] = t;
  }
  return j;
}

SessionEntry SessionEntry::Event(nlohmann::json line) {
  SessionEntry e;
  e.is_event = true;
  if (line.is_object()) {
    if (const auto it = line.find("t_ns"); it != line.end() && it->is_number_integer()) {
      e.t_ns = it->get<int64_t>();
    }
    line.erase("t_ns");
  }
  e.event = std::move(line);
  return e;
}

SessionEntry LineSwitchEvent(int64_t t_ns, Protocol protocol, const wire::LineSettings& line,
                             std::string_view detail) {
  json j = {{"event", "line_switch"},
            {"protocol", std::string(ProtocolName(protocol))},
            {"baud", line.baud}};
  if (!detail.empty()) j["detail"] = std::string(detail);
  SessionEntry e = SessionEntry::Event(std::move(j));
  e.t_ns = t_ns;
  return e;
}

std::optional<Protocol> LineSwitchOf(const SessionEntry& e) {
  if (!e.is_event || !e.event.is_object() || e.event.value("event", "") != "line_switch") {
    return std::nullopt;
  }
  const auto it = e.event.find("protocol");
  if (it == e.event.end() || !it->is_string()) return std::nullopt;
  return ParseProtocol(it->get<std::string>());
}

nlohmann::json EntryToJson(const SessionEntry& e) {
  if (e.is_event) {
    json j = e.event;
    j["t_ns"] = e.t_ns;
    return j;
  }
  json j;
  j["t_ns"] = e.t_ns;
  j["from"] = e.from == Origin::kHost ? "host" : "device";
  j["hex"] = wire::ToHex(e.bytes);
  if (!e.decoded.empty()) j["decoded"] = e.decoded;
  return j;
}

namespace {

// A string as JSON, as nlohmann writes it: printable ASCII stands for
// itself, '"' and '\\' take a backslash; anything else (control characters,
// UTF-8, invalid bytes: escaped, checked, replaced) goes through nlohmann.
void AppendJsonString(std::string_view s, std::string& out) {
  for (const char c : s) {
    if (c < 0x20 || c > 0x7e) {
      out += json(s).dump(-1, ' ', false, json::error_handler_t::replace);
      return;
    }
  }
  out += '"';
  size_t from = 0;
  for (size_t i = 0; i < s.size(); ++i) {
    if (s[i] != '"' && s[i] != '\\') continue;
    out.append(s.data() + from, i - from);
    out += '\\';
    from = i;
  }
  out.append(s.data() + from, s.size() - from);
  out += '"';
}

}  // namespace

void AppendEntryLine(const SessionEntry& e, std::string& out) {
  if (e.is_event) {
    out += EntryToJson(e).dump(-1, ' ', false, json::error_handler_t::replace);
    out += '\n';
    return;
  }
  // EntryToJson(e).dump() written directly, keys in its (sorted) order: a
  // traffic line is most of a recording.
  static constexpr char kDigits[] = "0123456789abcdef";
  out += '{';
  if (!e.decoded.empty()) {
    out += "\"decoded\":[";
    for (size_t i = 0; i < e.decoded.size(); ++i) {
      if (i > 0) out += ',';
      AppendJsonString(e.decoded[i], out);
    }
    out += "],";
  }
  out +=
      e.from == Origin::kHost ? "\"from\":\"host\",\"hex\":\"" : "\"from\":\"device\",\"hex\":\"";
  const size_t hex_at = out.size();
  out.resize(hex_at + 2 * e.bytes.size());
  char* hex = out.data() + hex_at;
  for (const uint8_t b : e.bytes) {
    *hex++ = kDigits[b >> 4];
    *hex++ = kDigits[b & 0xF];
  }
  out += "\",\"t_ns\":";
  out += std::to_string(e.t_ns);
  out += "}\n";
}

SessionWriter::SessionWriter(std::filesystem::path path, const SessionHeader& header)
    : path_(std::move(path)) {
  if (auto error = file_.Open(path_.string())) {
    throw std::runtime_error("recording: " + *error);
  }
  WriteLine(HeaderToJson(header));
}

SessionWriter::~SessionWriter() {
  if (!finished_) Finish(nullptr);
}

void SessionWriter::WriteLine(const nlohmann::json& j) {
  // An error is kept by the file and reported by Finish().
  (void)file_.Write(j.dump(-1, ' ', false, json::error_handler_t::replace) + '\n');
}

void SessionWriter::Append(const SessionEntry& entry) {
  if (finished_) return;
  std::string line;
  AppendEntryLine(entry, line);
  (void)file_.Write(line);
}

void SessionWriter::Append(std::span<const SessionEntry> entries) {
  if (finished_ || entries.empty()) return;
  std::string text;
  for (const SessionEntry& e : entries) AppendEntryLine(e, text);
  // An error is kept by the file and reported by Finish().
  (void)file_.Write(text);
}

void SessionWriter::Abandon() {
  finished_ = true;
  file_.Abandon();
}

bool SessionWriter::Finish(std::string* error) {
  if (finished_) return true;
  finished_ = true;
  if (auto e = file_.Commit()) {
    if (error) *error = *e;
    return false;
  }
  return true;
}

}  // namespace moco::session
