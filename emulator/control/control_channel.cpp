// The control channel (docs/control.md): execution of the vocabulary's
// commands against devices and their links.
#include "control/control_channel.h"

#include <algorithm>
#include <stdexcept>

#include "sim/io.h"
#include "sim/rig.h"
#include "wire/bytes.h"

namespace moco::control {
namespace {

using nlohmann::json;

constexpr size_t kMaxDeviceNameBytes = 64;

bool ValidDeviceName(std::string_view name) {
  if (name.empty() || name.size() > kMaxDeviceNameBytes) return false;
  return std::all_of(name.begin(), name.end(), [](char ch) {
    return (ch >= 'a' && ch <= 'z') || (ch >= 'A' && ch <= 'Z') || (ch >= '0' && ch <= '9') ||
           ch == '-' || ch == '_' || ch == '.';
  });
}

json CountsJson(const LinkFaultCounts& c) {
  return {{"bytes_in", c.bytes_in},
          {"dropped", c.dropped},
          {"corrupted", c.corrupted},
          {"duplicated", c.duplicated},
          {"delayed", c.delayed}};
}

}  // namespace

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

session::SessionEntry DeviceEvent::ToSessionEntry() const {
  return session::SessionEntry::Event(SessionLine());
}

session::SessionEntry ControlEvent::ToSessionEntry() const {
  return session::SessionEntry::Event(SessionLine());
}

// ---- The channel ------------------------------------------------------------

ControlChannel::ControlChannel(sim::Scheduler& scheduler) : scheduler_(scheduler) {}

ControlChannel::~ControlChannel() {
  for (auto& t : targets_) {
    t->device->SetEventListener(nullptr);
    if (t->power_on_timer != sim::Scheduler::kNoTimer) scheduler_.Cancel(t->power_on_timer);
  }
}

void ControlChannel::AddDevice(std::string name, devices::Device& device, LinkControl* link) {
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
  t->link = link;
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
      target.link == nullptr) {
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
  if (target.link != nullptr) {
    const LinkStatus s = target.link->Status();
    r["link"] = {{"endpoint", s.endpoint},
                 {"host_open", s.host_open},
                 {"cut_active", s.cut_active},
                 {"queued_bytes", s.queued_bytes},
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
                  {{"enabled", s.faults_enabled},
                   {"to_device", CountsJson(s.faults_to_device)},
                   {"to_host", CountsJson(s.faults_to_host)}}}};
  }
  return r;
}

json ControlChannel::DevicesReply() const {
  json list = json::array();
  for (const auto& t : targets_) {
    json d = {{"name", t->name},
              {"model", std::string(t->device->Model())},
              {"powered", t->device->Powered()}};
    d["endpoint"] = t->link != nullptr ? json(t->link->Where()) : json(nullptr);
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
            if (target.link != nullptr) {
              r["via"] = "link";
              target.link->PowerCycle(off_ns);
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
            target.link->CutLink(c.ms * sim::kNsPerMs);
            r["ms"] = c.ms;
          },
          [&](const FaultsCommand& c) {
            target.link->SetFaults(c.config);
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
std::string ControlChannel::Handle(std::string_view line, std::string_view source) {
  try {
    auto parsed = ParseRequestLine(line);
    if (const auto* error = std::get_if<json>(&parsed)) return ReplyLine(*error);
    return ReplyLine(Execute(std::get<Command>(parsed), source));
  } catch (const std::exception& e) {
    // Nothing above is expected to throw; a reply is still owed for the line.
    return ReplyLine(ErrorReply(std::string("internal error: ") + e.what()));
  }
}

}  // namespace moco::control
