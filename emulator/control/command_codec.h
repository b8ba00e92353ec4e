// The control vocabulary as data (docs/control.md): the commands, their
// parsing from one request line or object with errors that name the field and
// the fix, their canonical JSON form, and the reply lines. Pure: no device, no
// clock, no I/O; the ControlChannel (control_channel.h) executes what this
// parses.
#ifndef MOCO_CONTROL_COMMAND_CODEC_H_
#define MOCO_CONTROL_COMMAND_CODEC_H_

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include <nlohmann/json.hpp>

#include "sim/limits.h"
#include "sim/line_faults.h"
#include "sim/stepper_motor.h"

namespace moco::control {

// ---- Commands ---------------------------------------------------------------

// {"cmd":"estop","engaged":true}
struct EStopCommand {
  bool engaged = false;
};
// {"cmd":"limit","set":1,"input":"low","active":true} or
// {"cmd":"limit","motor":3,"end":"upper","active":true}: exactly one of the
// two forms (set + input, or motor + end).
struct LimitCommand {
  std::optional<int> set;
  sim::SwitchInput input = sim::SwitchInput::kLow;
  std::optional<int> motor;
  sim::LimitEnd end = sim::LimitEnd::kLower;
  bool active = false;
};
// {"cmd":"gio_in","bit":4,"level":true} or {"cmd":"gio_in","bits":"0x0000ff00"}:
// raw input levels as wired (the device debounces them).
struct GioInCommand {
  std::optional<int> bit;  // 0..31; when absent, `bits` sets all 32 inputs
  bool level = false;
  uint32_t bits = 0;
};
// {"cmd":"power_cycle","off_ms":500}
struct PowerCycleCommand {
  int64_t off_ms = 0;
};
// {"cmd":"cut_link","ms":2000}
struct CutLinkCommand {
  int64_t ms = 0;
};
// {"cmd":"faults","config":"seed=42,dir=to-host,drop=0.01"} or {"config":"off"}
struct FaultsCommand {
  std::string spec;  // as given ("off" for none)
  sim::FaultConfig config;
};
struct StateCommand {};
// {"cmd":"events","after":12}: the device's own events (stalls, collisions)
// with a sequence number above `after` (default 0: every one still kept).
struct EventsCommand {
  uint64_t after = 0;
};
struct DevicesCommand {};
struct HelpCommand {};

using CommandBody =
    std::variant<EStopCommand, LimitCommand, GioInCommand, PowerCycleCommand, CutLinkCommand,
                 FaultsCommand, StateCommand, EventsCommand, DevicesCommand, HelpCommand>;

struct Command {
  std::string device;  // empty: the only device served
  CommandBody body;
  nlohmann::json id;  // echoed in the reply when not null
};

// The command's name ("estop", "limit", ...).
std::string_view CommandName(const CommandBody& body);
// Whether the command changes the device or its link (queries do not).
bool IsAction(const CommandBody& body);
// The canonical JSON form of a command: "cmd", its fields, and "device" when
// given. ParseCommand(ToJson(c)) yields c again.
nlohmann::json ToJson(const Command& command);

// Parses one request object. Fields `extra_fields` are allowed besides the
// command's own (a scenario's "at_ms") and ignored. Never throws. On failure
// returns a message naming the field, what was found and what to write.
std::variant<Command, std::string> ParseCommand(const nlohmann::json& request,
                                                const std::vector<std::string>& extra_fields = {});

// One request line (a JSON object; a trailing "\r" or "\n" is ignored) ->
// the command, or the error reply owed for it ({"ok":false,"error":...},
// with the request's "id" when it has one): an empty line, malformed JSON, a
// key given twice in one object, or a request ParseCommand refuses.
std::variant<Command, nlohmann::json> ParseRequestLine(std::string_view line);

// The vocabulary as data: one entry per command with its fields and an
// example, for "help" and docs/control.md.
nlohmann::json Vocabulary();

// ---- Replies ------------------------------------------------------------------

// {"ok":false,"error":message}, with "id" when `id` is not null.
nlohmann::json ErrorReply(std::string message, const nlohmann::json& id = nullptr);
// A reply as one line with "ok" first, so a reader sees the outcome at once
// (the other keys follow in name order); no newline.
std::string ReplyLine(const nlohmann::json& reply);
// A short, printable rendering of a value found in a request (at most 40 bytes).
std::string Shown(const nlohmann::json& v);
// "low" | "high", "lower" | "upper": the vocabulary's names.
std::string_view InputName(sim::SwitchInput in);
std::string_view EndName(sim::LimitEnd end);

}  // namespace moco::control

#endif  // MOCO_CONTROL_COMMAND_CODEC_H_
