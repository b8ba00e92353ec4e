// The control vocabulary (docs/control.md): request parsing with errors that
// name the field and the fix, and execution against devices and their links.
#include "control/control_channel.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <limits>
#include <set>
#include <stdexcept>

#include "sim/io.h"
#include "sim/rig.h"
#include "transport/device_server.h"
#include "wire/bytes.h"

namespace moco::control {
namespace {

using nlohmann::json;

// Longest power-off or link cut accepted: one day.
constexpr int64_t kMaxDurationMs = 24 * 60 * 60 * 1000;
constexpr size_t kMaxDeviceNameBytes = 64;

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

// A short, printable rendering of a value found in a request.
std::string Shown(const json& v) {
  std::string s = v.dump(-1, ' ', false, json::error_handler_t::replace);
  if (s.size() > 40) s = s.substr(0, 37) + "...";
  return s;
}

std::string Hex32(uint32_t v) {
  char buf[16];
  std::snprintf(buf, sizeof buf, "0x%08x", v);
  return buf;
}

std::string_view InputName(sim::SwitchInput in) {
  return in == sim::SwitchInput::kHigh ? "high" : "low";
}
std::string_view EndName(sim::LimitEnd end) {
  return end == sim::LimitEnd::kUpper ? "upper" : "lower";
}

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
  auto parsed = transport::ParseFaultConfig(c.spec);
  if (auto* err = std::get_if<std::string>(&parsed)) {
    f.Fail("config", "is not a fault list (" + *err + ")");
    return std::nullopt;
  }
  c.config = std::get<transport::FaultConfig>(parsed);
  if (auto err = c.config.Validate()) {
    f.Fail("config", "is out of range (" + *err + ")");
    return std::nullopt;
  }
  return c;
}

bool ValidDeviceName(std::string_view name) {
  if (name.empty() || name.size() > kMaxDeviceNameBytes) return false;
  return std::all_of(name.begin(), name.end(), [](char ch) {
    return (ch >= 'a' && ch <= 'z') || (ch >= 'A' && ch <= 'Z') || (ch >= '0' && ch <= '9') ||
           ch == '-' || ch == '_' || ch == '.';
  });
}

json ErrorReply(std::string message, const json& id = nullptr) {
  json r = json::object();
  r["ok"] = false;
  r["error"] = std::move(message);
  if (!id.is_null()) r["id"] = id;
  return r;
}

// A reply as one line with "ok" first, so a reader sees the outcome at once
// (the other keys follow in name order).
std::string Dump(const json& reply) {
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

json CountsJson(const transport::FaultCounts& c) {
  return {{"bytes_in", c.bytes_in},
          {"dropped", c.dropped},
          {"corrupted", c.corrupted},
          {"duplicated", c.duplicated},
          {"delayed", c.delayed}};
}

}  // namespace

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
                     j["bits"] = Hex32(c.bits);
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

// ---- Events -----------------------------------------------------------------

json ControlEvent::SessionLine() const {
  json line = json::object();
  line["t_ns"] = t_ns;
  for (const auto& [key, value] : request.items()) {
    if (key == "cmd") {
      line["event"] = value;
    } else {
      line[key] = value;
    }
  }
  line["source"] = source;
  if (index >= 0) line["index"] = index;
  const bool ok = reply.is_object() && reply.value("ok", false);
  line["ok"] = ok;
  if (!ok && reply.is_object() && reply.contains("error")) line["error"] = reply["error"];
  return line;
}

json DeviceEvent::SessionLine() const {
  json line = json::object();
  line["t_ns"] = t_ns;
  if (event.is_object()) {
    for (const auto& [key, value] : event.items()) line[key] = value;
  }
  line["source"] = "device";
  line["seq"] = seq;
  return line;
}

SessionEntry DeviceEvent::ToSessionEntry() const { return SessionEntry::Event(SessionLine()); }

SessionEntry ControlEvent::ToSessionEntry() const { return SessionEntry::Event(SessionLine()); }

// ---- The channel ------------------------------------------------------------

ControlChannel::ControlChannel(sim::Scheduler& scheduler) : scheduler_(scheduler) {}

ControlChannel::~ControlChannel() {
  for (auto& t : targets_) {
    t->device->SetEventListener(nullptr);
    if (t->power_on_timer != sim::Scheduler::kNoTimer) scheduler_.Cancel(t->power_on_timer);
  }
}

void ControlChannel::AddDevice(std::string name, devices::Device& device,
                               transport::DeviceServer* server) {
  if (!ValidDeviceName(name)) {
    throw std::invalid_argument("control: device name \"" + name +
                                "\" is not usable: use 1..64 letters, digits, '-', '_' or '.'");
  }
  for (const auto& t : targets_) {
    if (t->name == name) {
      throw std::invalid_argument("control: device name \"" + name +
                                  "\" is used twice: give each device its own name");
    }
  }
  auto t = std::make_unique<Target>();
  t->name = std::move(name);
  t->device = &device;
  t->server = server;
  Target* target = t.get();
  device.SetEventListener([this, target](const json& e) { OnDeviceEvent(*target, e); });
  targets_.push_back(std::move(t));
}

void ControlChannel::OnDeviceEvent(Target& target, const json& event) {
  DeviceEvent ev;
  ev.t_ns = scheduler_.Now();
  ev.device = target.name;
  ev.seq = ++target.events_seen;
  ev.event = event;
  target.events.push_back(ev);
  while (target.events.size() > kEventsKept) target.events.pop_front();
  if (device_event_listener_) device_event_listener_(target.events.back());
}

json ControlChannel::EventsOf(const Target& target, uint64_t after) const {
  json list = json::array();
  for (const DeviceEvent& e : target.events) {
    if (e.seq > after) list.push_back(e.SessionLine());
  }
  // Events numbered (after, first kept) were dropped before anyone asked.
  const uint64_t first_kept =
      target.events.empty() ? target.events_seen + 1 : target.events.front().seq;
  return {{"events", std::move(list)},
          {"last_seq", target.events_seen},
          {"missed", first_kept > after + 1 ? first_kept - after - 1 : 0}};
}

std::vector<std::string> ControlChannel::DeviceNames() const {
  std::vector<std::string> names;
  for (const auto& t : targets_) names.push_back(t->name);
  return names;
}

ControlChannel::Target* ControlChannel::Find(const std::string& device_name,
                                             std::string* error) const {
  auto names = [this] {
    std::string s;
    for (const auto& t : targets_) {
      if (!s.empty()) s += ", ";
      s += t->name;
    }
    return s;
  };
  if (targets_.empty()) {
    *error = "no device is served";
    return nullptr;
  }
  if (device_name.empty()) {
    if (targets_.size() == 1) return targets_.front().get();
    *error =
        "several devices are served (" + names() + "): add \"device\":\"<name>\" to the request";
    return nullptr;
  }
  for (const auto& t : targets_) {
    if (t->name == device_name) return t.get();
  }
  *error = "unknown device " + Shown(json(device_name)) + "; devices served: " + names();
  return nullptr;
}

std::optional<std::string> ControlChannel::CheckTarget(const Target& target,
                                                       const CommandBody& body) const {
  const std::string who =
      "device \"" + target.name + "\" (" + std::string(target.device->Model()) + ")";
  sim::Rig* rig = target.device->rig();
  if (std::holds_alternative<EStopCommand>(body) || std::holds_alternative<LimitCommand>(body)) {
    if (rig == nullptr) {
      return who + " has no rig: it emulates no e-stop or limit switch";
    }
  }
  if (const auto* c = std::get_if<LimitCommand>(&body)) {
    if (c->set && (*c->set < 1 || *c->set > rig->limit_set_count())) {
      if (rig->limit_set_count() == 0) return who + " has no hardware limit sets";
      return "limit set " + std::to_string(*c->set) + " does not exist on " + who +
             ": use a set 1.." + std::to_string(rig->limit_set_count());
    }
    if (c->motor && !rig->ValidMotor(*c->motor)) {
      return "motor " + std::to_string(*c->motor) + " does not exist on " + who +
             ": use a motor 1.." + std::to_string(rig->motor_count());
    }
  }
  if (std::holds_alternative<GioInCommand>(body) && target.device->gio() == nullptr) {
    return who + " has no general-purpose inputs";
  }
  if ((std::holds_alternative<CutLinkCommand>(body) ||
       std::holds_alternative<FaultsCommand>(body)) &&
      target.server == nullptr) {
    return who + " runs in-process without a link: \"" + std::string(CommandName(body)) +
           "\" needs a device served on a pty or tcp endpoint";
  }
  return std::nullopt;
}

std::optional<std::string> ControlChannel::Check(const Command& command) const {
  if (std::holds_alternative<DevicesCommand>(command.body) ||
      std::holds_alternative<HelpCommand>(command.body)) {
    return std::nullopt;
  }
  std::string error;
  const Target* t = Find(command.device, &error);
  if (t == nullptr) return error;
  return CheckTarget(*t, command.body);
}

json ControlChannel::StateOf(const Target& target) const {
  json r = json::object();
  r["device"] = target.name;
  r["model"] = std::string(target.device->Model());
  r["t_ns"] = scheduler_.Now();
  r["powered"] = target.device->Powered();
  json state = target.device->State();
  r["state"] = state.is_object() ? std::move(state) : json::object();
  if (const sim::Rig* rig = target.device->rig()) {
    json inputs = json::array();
    for (int set = 1; set <= rig->limit_set_count(); ++set) {
      inputs.push_back({{"set", set},
                        {"low", rig->InputActive(set, sim::SwitchInput::kLow)},
                        {"high", rig->InputActive(set, sim::SwitchInput::kHigh)}});
    }
    json motors = json::array();
    for (int id = 1; id <= rig->motor_count(); ++id) {
      const sim::HardLimitBinding b = rig->binding(id);
      motors.push_back({{"motor", id},
                        {"position_steps", rig->motor(id).Position()},
                        {"moving", rig->motor(id).IsMoving()},
                        {"limit_set", b.set},
                        {"swapped", b.swapped}});
    }
    r["rig"] = {{"estop", rig->estop_engaged()},
                {"motors", std::move(motors)},
                {"limit_inputs", std::move(inputs)}};
  }
  if (const sim::GioPort* gio = target.device->gio()) {
    r["gio"] = {
        {"raw_inputs", gio->raw_inputs()}, {"inputs", gio->inputs()}, {"outputs", gio->outputs()}};
  }
  if (target.server != nullptr) {
    transport::Link& link = target.server->link();
    const transport::LinkStats& s = link.stats();
    r["link"] = {{"endpoint", target.server->Where()},
                 {"host_open", link.host_open()},
                 {"cut_active", link.cut_active()},
                 {"queued_bytes", link.queued_bytes()},
                 {"stats",
                  {{"bytes_from_host", s.bytes_from_host},
                   {"bytes_to_device", s.bytes_to_device},
                   {"bytes_from_device", s.bytes_from_device},
                   {"bytes_to_host", s.bytes_to_host},
                   {"overflowed", s.overflowed},
                   {"discarded", s.discarded},
                   {"cut_dropped", s.cut_dropped},
                   {"reclaimed", s.reclaimed},
                   {"connections", s.connections}}},
                 {"faults",
                  {{"enabled", link.faults().enabled()},
                   {"to_device", CountsJson(link.faults().counts(transport::Direction::kToDevice))},
                   {"to_host", CountsJson(link.faults().counts(transport::Direction::kToHost))}}}};
  }
  return r;
}

json ControlChannel::DevicesReply() const {
  json list = json::array();
  for (const auto& t : targets_) {
    json d = {{"name", t->name},
              {"model", std::string(t->device->Model())},
              {"powered", t->device->Powered()}};
    d["endpoint"] = t->server != nullptr ? json(t->server->Where()) : json(nullptr);
    list.push_back(std::move(d));
  }
  return {{"ok", true}, {"cmd", "devices"}, {"devices", std::move(list)}};
}

json ControlChannel::Run(Target& target, const CommandBody& body) {
  json r = json::object();
  r["ok"] = true;
  r["cmd"] = std::string(CommandName(body));
  r["device"] = target.name;
  r["t_ns"] = scheduler_.Now();
  devices::Device& device = *target.device;
  std::visit(
      wire::Overloaded{
          [&](const EStopCommand& c) {
            sim::Rig& rig = *device.rig();
            r["was_engaged"] = rig.estop_engaged();
            if (c.engaged) {
              rig.EngageEStop();
            } else {
              rig.ReleaseEStop();
            }
            r["engaged"] = rig.estop_engaged();
          },
          [&](const LimitCommand& c) {
            sim::Rig& rig = *device.rig();
            int set = 0;
            sim::SwitchInput input = c.input;
            if (c.set) {
              set = *c.set;
            } else {
              const sim::HardLimitBinding b = rig.binding(*c.motor);
              if (b.set == 0) {
                r = ErrorReply("motor " + std::to_string(*c.motor) + " of device \"" + target.name +
                               "\" is bound to no limit set (the host binds one with its "
                               "set-limits message), so its " +
                               std::string(EndName(c.end)) +
                               " switch does not exist: name the input by set instead, e.g. "
                               "{\"cmd\":\"limit\",\"set\":1,\"input\":\"high\",\"active\":true}");
                return;
              }
              set = b.set;
              // The 0x80 flag swaps the inputs: LOW then guards the upper end.
              const bool upper = c.end == sim::LimitEnd::kUpper;
              input = upper != b.swapped ? sim::SwitchInput::kHigh : sim::SwitchInput::kLow;
              r["motor"] = *c.motor;
              r["end"] = std::string(EndName(c.end));
              r["swapped"] = b.swapped;
            }
            rig.ForceInput(set, input, c.active);
            r["set"] = set;
            r["input"] = std::string(InputName(input));
            r["active"] = c.active;
            r["input_active"] = rig.InputActive(set, input);
          },
          [&](const GioInCommand& c) {
            sim::GioPort& gio = *device.gio();
            if (c.bit) {
              gio.SetRawInput(*c.bit, c.level);
            } else {
              gio.SetRawInputs(c.bits);
            }
            r["raw_inputs"] = gio.raw_inputs();
            r["debounce_ns"] = gio.debounce_ns();
          },
          [&](const PowerCycleCommand& c) {
            const sim::TimeNs off_ns = c.off_ms * sim::kNsPerMs;
            r["off_ms"] = c.off_ms;
            r["power_on_at_ns"] = scheduler_.Now() + off_ns;
            if (target.server != nullptr) {
              r["via"] = "link";
              target.server->PowerCycle(off_ns);
              return;
            }
            r["via"] = "in-process";
            if (target.power_on_timer != sim::Scheduler::kNoTimer) {
              scheduler_.Cancel(target.power_on_timer);
            }
            device.PowerOff();
            Target* t = &target;
            target.power_on_timer = scheduler_.After(off_ns, [t] {
              t->power_on_timer = sim::Scheduler::kNoTimer;
              t->device->PowerOn();
            });
          },
          [&](const CutLinkCommand& c) {
            target.server->CutLink(c.ms * sim::kNsPerMs);
            r["ms"] = c.ms;
          },
          [&](const FaultsCommand& c) {
            target.server->link().SetFaults(c.config);
            r["config"] = c.spec;
            r["enabled"] = c.config.Any();
          },
          [&](const StateCommand&) {
            json s = StateOf(target);
            for (auto& [key, value] : s.items()) r[key] = value;
          },
          [&](const EventsCommand& c) {
            json s = EventsOf(target, c.after);
            for (auto& [key, value] : s.items()) r[key] = value;
          },
          [](const DevicesCommand&) {},
          [](const HelpCommand&) {},
      },
      body);
  return r;
}

json ControlChannel::Execute(const Command& command, std::string_view source, int index) {
  json reply;
  if (std::holds_alternative<DevicesCommand>(command.body)) {
    reply = DevicesReply();
  } else if (std::holds_alternative<HelpCommand>(command.body)) {
    reply = {{"ok", true}, {"cmd", "help"}, {"commands", Vocabulary()}};
  } else {
    std::string error;
    Target* t = Find(command.device, &error);
    if (t == nullptr) {
      reply = ErrorReply(error);
    } else if (auto problem = CheckTarget(*t, command.body)) {
      reply = ErrorReply(*problem);
    } else {
      reply = Run(*t, command.body);
    }
  }
  if (!command.id.is_null()) reply["id"] = command.id;
  if (listener_ && IsAction(command.body)) {
    ControlEvent ev;
    ev.t_ns = scheduler_.Now();
    ev.source = std::string(source);
    ev.index = index;
    ev.request = ToJson(command);
    ev.reply = reply;
    listener_(ev);
  }
  return reply;
}

json ParseJsonNotingDuplicateKeys(std::string_view text, std::string& duplicate) {
  duplicate.clear();
  std::vector<std::set<std::string, std::less<>>> keys;  // per open object
  const json::parser_callback_t note_keys = [&keys, &duplicate](int, json::parse_event_t event,
                                                                json& parsed) {
    if (event == json::parse_event_t::object_start) {
      keys.emplace_back();
    } else if (event == json::parse_event_t::object_end) {
      if (!keys.empty()) keys.pop_back();
    } else if (event == json::parse_event_t::key && !keys.empty() && parsed.is_string()) {
      if (!keys.back().insert(parsed.get<std::string>()).second && duplicate.empty()) {
        duplicate = parsed.get<std::string>();
      }
    }
    return true;
  };
  return json::parse(text, note_keys);
}

std::string ControlChannel::Handle(std::string_view line, std::string_view source) {
  try {
    while (!line.empty() && (line.back() == '\r' || line.back() == '\n')) line.remove_suffix(1);
    if (line.find_first_not_of(" \t") == std::string_view::npos) {
      return Dump(
          ErrorReply("empty request: send one JSON object per line, e.g. {\"cmd\":\"help\"}"));
    }
    json request;
    // A key given twice in one object ({"engaged":true,"engaged":false}) is
    // refused, not settled silently by the last one.
    std::string duplicate;
    try {
      request = ParseJsonNotingDuplicateKeys(line, duplicate);
    } catch (const json::parse_error& e) {
      return Dump(ErrorReply("malformed JSON at byte " + std::to_string(e.byte) +
                             ": send one JSON object per line, e.g. {\"cmd\":\"state\"}"));
    } catch (const json::exception&) {
      // A number beyond the range of a double (1e400).
      return Dump(ErrorReply(
          "malformed JSON: a number is out of range; send one JSON object per line, e.g. "
          "{\"cmd\":\"state\"}"));
    }
    json id = nullptr;
    if (request.is_object()) {
      if (auto it = request.find("id"); it != request.end()) id = *it;
    }
    if (!duplicate.empty()) {
      return Dump(ErrorReply(
          "the key \"" + duplicate + "\" appears twice in one object; give each key once", id));
    }
    auto parsed = ParseCommand(request);
    if (auto* err = std::get_if<std::string>(&parsed)) return Dump(ErrorReply(*err, id));
    return Dump(Execute(std::get<Command>(parsed), source));
  } catch (const std::exception& e) {
    // Nothing above is expected to throw; a reply is still owed for the line.
    return Dump(ErrorReply(std::string("internal error: ") + e.what()));
  }
}

}  // namespace moco::control
