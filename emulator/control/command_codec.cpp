// The control vocabulary (docs/control.md): request parsing with errors that
// name the field and the fix, the canonical JSON form, and reply lines.
#include "control/command_codec.h"

#include "base/format.h"
#include "base/json_fields.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <limits>
#include <set>

#include "wire/bytes.h"

namespace moco::control {
namespace {

using nlohmann::json;

// Longest power-off or link cut accepted: one day.
constexpr int64_t kMaxDurationMs = 24 * 60 * 60 * 1000;

// One entry of the vocabulary: the fields a command takes and an example.
struct FieldSpec {
  const char* name;
  const char* what;
};
struct CommandSpec {
  const char* name;
  const char* summary;
  std::vector<FieldSpec> fields;
  const char* example;
};

const std::vector<CommandSpec>& Specs() {
  static const std::vector<CommandSpec> specs = {
      {"estop",
       "press (engaged true) or release (engaged false) the e-stop: every motor halts at once and "
       "motion is refused until released",
       {{"engaged", "true | false (required)"}},
       R"({"cmd":"estop","engaged":true})"},
      {"limit",
       "trip (active true) or clear (active false) a hardware limit switch input, named either by "
       "limit set and input or by motor and end (through the motor's binding, 0x80 swaps the "
       "inputs)",
       {{"set", "limit set number 1..N (with input)"},
        {"input", "\"low\" | \"high\" (with set)"},
        {"motor", "motor number 1..N (with end)"},
        {"end", "\"upper\" | \"lower\" (with motor)"},
        {"active", "true = tripped, false = cleared (required)"}},
       R"({"cmd":"limit","motor":1,"end":"upper","active":true})"},
      {"gio_in",
       "set the raw level of general-purpose inputs as wired (the device debounces them): one "
       "input by bit, or all 32 at once by bits",
       {{"bit", "input bit 0..31 (with level)"},
        {"level", "true | false (with bit)"},
        {"bits", "all 32 inputs: an integer or a \"0x...\" hex string"}},
       R"({"cmd":"gio_in","bit":0,"level":true})"},
      {"power_cycle",
       "turn the device off now and on again after off_ms (through its link when served)",
       {{"off_ms", "milliseconds off, 0..86400000 (required)"}},
       R"({"cmd":"power_cycle","off_ms":500})"},
      {"cut_link",
       "cut the device's link for ms: nothing crosses either way (TCP: the host is disconnected)",
       {{"ms", "milliseconds, 1..86400000 (required)"}},
       R"({"cmd":"cut_link","ms":2000})"},
      {"faults",
       "replace the link's fault injection (\"off\" for none); keys seed, drop, corrupt, dup, "
       "delay (rates 0..1), delay_ms, and dir=to-device|to-host|both, which applies to the "
       "rates after it (default both)",
       {{"config", "fault list such as \"seed=42,dir=to-host,drop=0.01\", or \"off\" (required)"}},
       R"({"cmd":"faults","config":"seed=42,dir=to-host,drop=0.01"})"},
      {"state",
       "the device's state with its rig, GIO, link statistics and the scheduler time",
       {},
       R"({"cmd":"state"})"},
      {"events",
       "what the device did by itself (stepper stalls, head collisions of a physical rig), "
       "numbered from 1; the last 256 are kept",
       {{"after", "only events numbered above this (default 0: all kept)"}},
       R"({"cmd":"events","after":0})"},
      {"devices", "the devices served", {}, R"({"cmd":"devices"})"},
      {"help", "this vocabulary", {}, R"({"cmd":"help"})"},
  };
  return specs;
}

const CommandSpec* FindSpec(std::string_view name) {
  for (const CommandSpec& s : Specs()) {
    if (name == s.name) return &s;
  }
  return nullptr;
}

std::string CommandList() {
  std::string out;
  for (const CommandSpec& s : Specs()) {
    if (!out.empty()) out += ", ";
    out += s.name;
  }
  return out;
}

std::string TypeNameOf(const json& v) {
  if (v.is_number_integer()) return "an integer";
  if (v.is_number()) return "a number";
  if (v.is_object()) return "an object";
  if (v.is_array()) return "an array";
  return std::string("a ") + v.type_name();
}
}  // namespace

// A short, printable rendering of a value found in a request.
std::string Shown(const json& v) {
  std::string s = v.dump(-1, ' ', false, json::error_handler_t::replace);
  if (s.size() > 40) s = s.substr(0, 37) + "...";
  return s;
}

std::string_view InputName(sim::SwitchInput in) {
  return in == sim::SwitchInput::kHigh ? "high" : "low";
}
std::string_view EndName(sim::LimitEnd end) {
  return end == sim::LimitEnd::kUpper ? "upper" : "lower";
}
namespace {

// Reads the fields of one command object; the first problem wins.
class Fields {
 public:
  Fields(const json& object, const CommandSpec& spec) : object_(object), spec_(spec) {}

  const std::string& error() const { return error_; }
  bool ok() const { return error_.empty(); }

  void Fail(std::string_view key, std::string_view problem) {
    if (!error_.empty()) return;
    error_ = std::string("\"") + spec_.name + "\": field \"" + std::string(key) + "\" " +
             std::string(problem) + "; for example " + spec_.example +
             " (send {\"cmd\":\"help\"} " + "for every field)";
  }
  void Fail(std::string_view problem) {
    if (!error_.empty()) return;
    error_ = std::string("\"") + spec_.name + "\": " + std::string(problem) + "; for example " +
             spec_.example;
  }

  const json* Find(std::string_view key) const {
    auto it = object_.find(key);
    return it == object_.end() ? nullptr : &*it;
  }
  bool Has(std::string_view key) const { return Find(key) != nullptr; }

  std::optional<bool> Bool(std::string_view key, bool required) {
    const json* v = Find(key);
    if (v == nullptr) {
      if (required) Fail(key, "is missing: write true or false");
      return std::nullopt;
    }
    if (!v->is_boolean()) {
      Fail(key, "must be true or false, found " + TypeNameOf(*v) + " " + Shown(*v));
      return std::nullopt;
    }
    return v->get<bool>();
  }

  std::optional<int64_t> Int(std::string_view key, int64_t min, int64_t max, bool required) {
    const json* v = Find(key);
    const std::string range = std::to_string(min) + ".." + std::to_string(max);
    if (v == nullptr) {
      if (required) Fail(key, "is missing: write a whole number " + range);
      return std::nullopt;
    }
    std::optional<int64_t> x;
    if (v->is_number_unsigned()) {
      const uint64_t u = v->get<uint64_t>();
      if (u <= static_cast<uint64_t>(std::numeric_limits<int64_t>::max())) {
        x = static_cast<int64_t>(u);
      } else {
        x = std::numeric_limits<int64_t>::max();
      }
    } else if (v->is_number_integer()) {
      x = v->get<int64_t>();
    } else if (v->is_number_float()) {
      const double d = v->get<double>();
      if (std::isfinite(d) && d == std::floor(d) && std::fabs(d) < 9.0e15) {
        x = static_cast<int64_t>(d);
      }
    }
    if (!x) {
      Fail(key, "must be a whole number " + range + ", found " + TypeNameOf(*v) + " " + Shown(*v));
      return std::nullopt;
    }
    if (*x < min || *x > max) {
      Fail(key, "is " + Shown(*v) + ", outside " + range + ": use a value in " + range);
      return std::nullopt;
    }
    return x;
  }

  // One of `choices`; returns its index.
  std::optional<int> Choice(std::string_view key, const std::vector<std::string_view>& choices,
                            bool required) {
    const json* v = Find(key);
    std::string listed;
    for (std::string_view c : choices) {
      if (!listed.empty()) listed += " or ";
      listed += "\"" + std::string(c) + "\"";
    }
    if (v == nullptr) {
      if (required) Fail(key, "is missing: write " + listed);
      return std::nullopt;
    }
    if (v->is_string()) {
      const std::string& s = v->get_ref<const std::string&>();
      for (size_t i = 0; i < choices.size(); ++i) {
        if (s == choices[i]) return static_cast<int>(i);
      }
    }
    Fail(key, "must be " + listed + ", found " + TypeNameOf(*v) + " " + Shown(*v));
    return std::nullopt;
  }

  std::optional<std::string> String(std::string_view key, bool required) {
    const json* v = Find(key);
    if (v == nullptr) {
      if (required) Fail(key, "is missing: write a string");
      return std::nullopt;
    }
    if (!v->is_string()) {
      Fail(key, "must be a string, found " + TypeNameOf(*v) + " " + Shown(*v));
      return std::nullopt;
    }
    return v->get<std::string>();
  }

  // An unsigned 32-bit value as an integer or a "0x..." hex string.
  std::optional<uint32_t> Bits32(std::string_view key) {
    const json* v = Find(key);
    if (v == nullptr) return std::nullopt;
    if (v->is_string()) {
      const std::string& s = v->get_ref<const std::string&>();
      if (s.size() > 2 && s.size() <= 10 && s[0] == '0' && (s[1] == 'x' || s[1] == 'X')) {
        uint32_t out = 0;
        const char* first = s.data() + 2;
        const char* last = s.data() + s.size();
        auto [ptr, ec] = std::from_chars(first, last, out, 16);
        if (ec == std::errc() && ptr == last) return out;
      }
      Fail(key, "must be an integer 0..4294967295 or a hex string \"0x0\"..\"0xffffffff\", found " +
                    Shown(*v));
      return std::nullopt;
    }
    const std::optional<int64_t> x = Int(key, 0, 0xffffffffLL, false);
    if (!x) return std::nullopt;
    return static_cast<uint32_t>(*x);
  }

 private:
  const json& object_;
  const CommandSpec& spec_;
  std::string error_;
};

std::optional<LimitCommand> ParseLimit(Fields& f) {
  LimitCommand c;
  const bool by_set = f.Has("set") || f.Has("input");
  const bool by_motor = f.Has("motor") || f.Has("end");
  if (by_set && by_motor) {
    f.Fail("give either \"set\" + \"input\" or \"motor\" + \"end\", not both");
    return std::nullopt;
  }
  if (!by_set && !by_motor) {
    f.Fail("name the switch by \"set\" + \"input\" or by \"motor\" + \"end\"");
    return std::nullopt;
  }
  if (by_set) {
    const auto set = f.Int("set", 1, 127, true);
    const auto input = f.Choice("input", {"low", "high"}, true);
    if (!set || !input) return std::nullopt;
    c.set = static_cast<int>(*set);
    c.input = *input == 1 ? sim::SwitchInput::kHigh : sim::SwitchInput::kLow;
  } else {
    const auto motor = f.Int("motor", 1, 255, true);
    const auto end = f.Choice("end", {"lower", "upper"}, true);
    if (!motor || !end) return std::nullopt;
    c.motor = static_cast<int>(*motor);
    c.end = *end == 1 ? sim::LimitEnd::kUpper : sim::LimitEnd::kLower;
  }
  const auto active = f.Bool("active", true);
  if (!active) return std::nullopt;
  c.active = *active;
  return c;
}

std::optional<GioInCommand> ParseGioIn(Fields& f) {
  GioInCommand c;
  const bool one = f.Has("bit") || f.Has("level");
  if (one && f.Has("bits")) {
    f.Fail("give either \"bit\" + \"level\" (one input) or \"bits\" (all 32), not both");
    return std::nullopt;
  }
  if (one) {
    const auto bit = f.Int("bit", 0, 31, true);
    const auto level = f.Bool("level", true);
    if (!bit || !level) return std::nullopt;
    c.bit = static_cast<int>(*bit);
    c.level = *level;
    return c;
  }
  if (!f.Has("bits")) {
    f.Fail("set one input with \"bit\" + \"level\" or all 32 with \"bits\"");
    return std::nullopt;
  }
  const auto bits = f.Bits32("bits");
  if (!bits) return std::nullopt;
  c.bits = *bits;
  return c;
}

std::optional<FaultsCommand> ParseFaults(Fields& f) {
  const auto spec = f.String("config", true);
  if (!spec) return std::nullopt;
  FaultsCommand c;
  c.spec = *spec;
  if (c.spec == "off" || c.spec.empty()) {
    c.spec = "off";
    return c;
  }
  // "dir=" applies to the rates after it, so a trailing one is a rate given
  // on the wrong side, not a no-op the user meant.
  std::string_view last_item;
  for (size_t pos = 0; pos <= c.spec.size();) {
    size_t comma = c.spec.find(',', pos);
    if (comma == std::string::npos) comma = c.spec.size();
    std::string_view item = std::string_view(c.spec).substr(pos, comma - pos);
    while (!item.empty() && item.front() == ' ') item.remove_prefix(1);
    if (!item.empty()) last_item = item;
    pos = comma + 1;
  }
  if (last_item.rfind("dir=", 0) == 0) {
    f.Fail("config",
           "ends with a \"dir=\" that applies to no rate (dir= applies to the rates "
           "after it): move it before them, e.g. \"seed=42,dir=to-host,drop=0.01\"");
    return std::nullopt;
  }
  auto parsed = sim::ParseFaultConfig(c.spec);
  if (auto* err = std::get_if<std::string>(&parsed)) {
    f.Fail("config", "is not a fault list (" + *err + ")");
    return std::nullopt;
  }
  c.config = std::get<sim::FaultConfig>(parsed);
  if (auto err = c.config.Validate()) {
    f.Fail("config", "is out of range (" + *err + ")");
    return std::nullopt;
  }
  return c;
}
}  // namespace

json ErrorReply(std::string message, const json& id) {
  json r = json::object();
  r["ok"] = false;
  r["error"] = std::move(message);
  if (!id.is_null()) r["id"] = id;
  return r;
}

std::string ReplyLine(const json& reply) {
  const auto dump = [](const json& j) {
    return j.dump(-1, ' ', false, json::error_handler_t::replace);
  };
  if (!reply.is_object() || !reply.contains("ok")) return dump(reply);
  json rest = reply;
  rest.erase("ok");
  std::string out = "{\"ok\":" + dump(reply["ok"]);
  const std::string tail = dump(rest);  // "{}" or "{...}"
  if (tail.size() > 2)
    out += "," + tail.substr(1);
  else
    out += "}";
  return out;
}

// ---- Commands ---------------------------------------------------------------

std::string_view CommandName(const CommandBody& body) {
  return std::visit(wire::Overloaded{
                        [](const EStopCommand&) { return std::string_view("estop"); },
                        [](const LimitCommand&) { return std::string_view("limit"); },
                        [](const GioInCommand&) { return std::string_view("gio_in"); },
                        [](const PowerCycleCommand&) { return std::string_view("power_cycle"); },
                        [](const CutLinkCommand&) { return std::string_view("cut_link"); },
                        [](const FaultsCommand&) { return std::string_view("faults"); },
                        [](const StateCommand&) { return std::string_view("state"); },
                        [](const EventsCommand&) { return std::string_view("events"); },
                        [](const DevicesCommand&) { return std::string_view("devices"); },
                        [](const HelpCommand&) { return std::string_view("help"); },
                    },
                    body);
}

bool IsAction(const CommandBody& body) {
  return !std::holds_alternative<StateCommand>(body) &&
         !std::holds_alternative<EventsCommand>(body) &&
         !std::holds_alternative<DevicesCommand>(body) &&
         !std::holds_alternative<HelpCommand>(body);
}

json ToJson(const Command& command) {
  json j = json::object();
  j["cmd"] = std::string(CommandName(command.body));
  if (!command.device.empty()) j["device"] = command.device;
  std::visit(wire::Overloaded{
                 [&](const EStopCommand& c) { j["engaged"] = c.engaged; },
                 [&](const LimitCommand& c) {
                   if (c.set) {
                     j["set"] = *c.set;
                     j["input"] = std::string(InputName(c.input));
                   } else {
                     j["motor"] = c.motor.value_or(0);
                     j["end"] = std::string(EndName(c.end));
                   }
                   j["active"] = c.active;
                 },
                 [&](const GioInCommand& c) {
                   if (c.bit) {
                     j["bit"] = *c.bit;
                     j["level"] = c.level;
                   } else {
                     j["bits"] = base::Hex(c.bits, 8);
                   }
                 },
                 [&](const PowerCycleCommand& c) { j["off_ms"] = c.off_ms; },
                 [&](const CutLinkCommand& c) { j["ms"] = c.ms; },
                 [&](const FaultsCommand& c) { j["config"] = c.spec; },
                 [](const StateCommand&) {},
                 [&](const EventsCommand& c) {
                   if (c.after > 0) j["after"] = c.after;
                 },
                 [](const DevicesCommand&) {},
                 [](const HelpCommand&) {},
             },
             command.body);
  return j;
}

std::variant<Command, std::string> ParseCommand(const json& request,
                                                const std::vector<std::string>& extra_fields) {
  if (!request.is_object()) {
    return "a request must be a JSON object, found " + TypeNameOf(request) +
           "; write e.g. {\"cmd\":\"state\"}";
  }
  const auto cmd_it = request.find("cmd");
  if (cmd_it == request.end()) {
    return "missing field \"cmd\": write e.g. {\"cmd\":\"state\"}; commands: " + CommandList();
  }
  if (!cmd_it->is_string()) {
    return "field \"cmd\" must be a command name string, found " + TypeNameOf(*cmd_it) +
           "; commands: " + CommandList();
  }
  const std::string& name = cmd_it->get_ref<const std::string&>();
  const CommandSpec* spec = FindSpec(name);
  if (spec == nullptr) {
    return "unknown command " + Shown(*cmd_it) + "; commands: " + CommandList() +
           " (send {\"cmd\":\"help\"} for their fields)";
  }

  // Unknown fields are refused, so a typo never silently means "absent".
  for (const auto& item : request.items()) {
    const std::string& key = item.key();
    if (key == "cmd" || key == "device" || key == "id") continue;
    if (std::find(extra_fields.begin(), extra_fields.end(), key) != extra_fields.end()) continue;
    const bool known = std::any_of(spec->fields.begin(), spec->fields.end(),
                                   [&](const FieldSpec& fs) { return key == fs.name; });
    if (known) continue;
    std::string fields;
    for (const FieldSpec& fs : spec->fields) {
      if (!fields.empty()) fields += ", ";
      fields += fs.name;
    }
    return "\"" + name + "\": unknown field " +
           json(key).dump(-1, ' ', false, json::error_handler_t::replace) + "; its fields are " +
           (fields.empty() ? std::string("none") : fields) +
           " (and \"device\", \"id\"); for example " + spec->example;
  }

  Command out;
  if (const auto it = request.find("id"); it != request.end()) out.id = *it;
  if (const auto it = request.find("device"); it != request.end()) {
    if (!it->is_string() || it->get_ref<const std::string&>().empty()) {
      return "field \"device\" must be a device name string, found " + TypeNameOf(*it) + " " +
             Shown(*it) + "; send {\"cmd\":\"devices\"} for the names";
    }
    out.device = it->get<std::string>();
  }

  Fields f(request, *spec);
  const std::string_view n = name;
  if (n == "estop") {
    const auto engaged = f.Bool("engaged", true);
    if (engaged) out.body = EStopCommand{*engaged};
  } else if (n == "limit") {
    if (auto c = ParseLimit(f)) out.body = *c;
  } else if (n == "gio_in") {
    if (auto c = ParseGioIn(f)) out.body = *c;
  } else if (n == "power_cycle") {
    const auto off = f.Int("off_ms", 0, kMaxDurationMs, true);
    if (off) out.body = PowerCycleCommand{*off};
  } else if (n == "cut_link") {
    const auto ms = f.Int("ms", 1, kMaxDurationMs, true);
    if (ms) out.body = CutLinkCommand{*ms};
  } else if (n == "faults") {
    if (auto c = ParseFaults(f)) out.body = std::move(*c);
  } else if (n == "state") {
    out.body = StateCommand{};
  } else if (n == "events") {
    const auto after = f.Int("after", 0, std::numeric_limits<int64_t>::max(), false);
    out.body = EventsCommand{static_cast<uint64_t>(after.value_or(0))};
  } else if (n == "devices") {
    out.body = DevicesCommand{};
  } else {
    out.body = HelpCommand{};
  }
  if (!f.ok()) return f.error();
  return out;
}

json Vocabulary() {
  json out = json::array();
  for (const CommandSpec& s : Specs()) {
    json fields = json::object();
    for (const FieldSpec& fs : s.fields) fields[fs.name] = fs.what;
    fields["device"] = "device name (optional when one device is served)";
    fields["id"] = "any JSON value, echoed in the reply (optional)";
    out.push_back({{"cmd", s.name},
                   {"summary", s.summary},
                   {"fields", std::move(fields)},
                   {"example", s.example}});
  }
  return out;
}
std::variant<Command, json> ParseRequestLine(std::string_view line) {
  while (!line.empty() && (line.back() == '\r' || line.back() == '\n')) line.remove_suffix(1);
  if (line.find_first_not_of(" \t") == std::string_view::npos) {
    return ErrorReply("empty request: send one JSON object per line, e.g. {\"cmd\":\"help\"}");
  }
  json request;
  // A key given twice in one object ({"engaged":true,"engaged":false}) is
  // refused, not settled silently by the last one.
  std::string duplicate;
  try {
    request = base::ParseJsonNotingDuplicateKeys(line, duplicate);
  } catch (const json::parse_error& e) {
    return ErrorReply("malformed JSON at byte " + std::to_string(e.byte) +
                      ": send one JSON object per line, e.g. {\"cmd\":\"state\"}");
  } catch (const json::exception&) {
    // A number beyond the range of a double (1e400).
    return ErrorReply(
        "malformed JSON: a number is out of range; send one JSON object per line, e.g. "
        "{\"cmd\":\"state\"}");
  }
  json id = nullptr;
  if (request.is_object()) {
    if (auto it = request.find("id"); it != request.end()) id = *it;
  }
  if (!duplicate.empty()) {
    return ErrorReply(
        "the key \"" + duplicate + "\" appears twice in one object; give each key once", id);
  }
  auto parsed = ParseCommand(request);
  if (auto* err = std::get_if<std::string>(&parsed)) return ErrorReply(*err, id);
  return std::get<Command>(std::move(parsed));
}

}  // namespace moco::control
