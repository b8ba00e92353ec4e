// mococheck's command line (docs/exit-codes.md): one file per subcommand
// (run, replay, fuzz, certify/keygen/verify, and the rules/cases listings), each adding its options
// to the program's CLI11 app and running once they are parsed, and the one
// place a --target text becomes an open target.
#ifndef MOCO_CONFORMANCE_CLI_COMMANDS_H_
#define MOCO_CONFORMANCE_CLI_COMMANDS_H_

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include <CLI/CLI.hpp>

#include "conformance/rules/catalogue.h"
#include "conformance/targets/target.h"

namespace moco::conformance::cli {

inline constexpr int kExitUsage = 2;

// Prints "mococheck: MESSAGE" to stderr; returns kExitUsage.
int Fail(const std::string& message);

// From now on SIGINT, SIGTERM and SIGHUP ask the command to stop
// (RequestStop, targets/target.h): every wait of a target ends at once (a
// firmware spinning under simavr included) and the command writes what it has
// (`run` its reports, `fuzz` its summary and findings). A second signal changes
// nothing; a third ends mococheck at once.
void InstallStopHandlers();

// What a command knows when it picks its target.
struct TargetRequest {
  std::string text;            // --target as given; "" takes the session's device
  std::string session_device;  // the recorded device ("dfmoco-uno"), for an empty --target
  std::string profile;         // --profile (in-process targets only)
  uint32_t baud = 0;           // --baud; 0: the protocol's own line rate
  // The protocol the traffic speaks when the command already knows it (a
  // session's); nullopt: --protocol, else the in-process model's, else DMC v2.
  std::optional<Protocol> protocol;
  std::string protocol_option;  // --protocol as given ("" when not)
  // What the traffic is called in messages: "the session's", "the sessions'".
  std::string traffic_name = "the session's";
  // The message when --target is empty and the session's device is not an
  // emulated model.
  std::string no_device_message;
  // Only targets on a virtual clock, in-process devices and firmware under
  // simavr (fuzz: each mutant needs a fresh device in virtual time): the
  // message for any other kind.
  std::string virtual_clock_only_message;
};

struct ResolvedTarget {
  TargetSpec spec;
  Protocol protocol = Protocol::kDmc;
  std::unique_ptr<Target> target;  // not opened yet
  // An in-process model that starts speaking another protocol it also speaks
  // (devices::LineFor; in-process:stackshot3x with --protocol dfmoco: its
  // DfMoco mode); nullopt: its own.
  std::optional<Protocol> speaking;
};

// Parses the target, settles the protocol (a model that speaks another
// protocol than the traffic is refused) and builds the target. An error
// message names the problem and the fix.
std::variant<ResolvedTarget, std::string> ResolveTarget(const TargetRequest& request);

// --- the subcommands --------------------------------------------------------------------
// Each Add*() registers its subcommand and options on `app` and returns the
// function that runs it once the command line is parsed (its exit code).
using Runner = std::function<int()>;
Runner AddRunCommand(CLI::App& app, CLI::App*& sub);
Runner AddReplayCommand(CLI::App& app, CLI::App*& sub);
Runner AddFuzzCommand(CLI::App& app, CLI::App*& sub);
Runner AddRulesCommand(CLI::App& app, CLI::App*& sub);
Runner AddCasesCommand(CLI::App& app, CLI::App*& sub);
Runner AddCertifyCommand(CLI::App& app, CLI::App*& sub);
Runner AddKeygenCommand(CLI::App& app, CLI::App*& sub);
Runner AddVerifyCommand(CLI::App& app, CLI::App*& sub);

}  // namespace moco::conformance::cli

#endif  // MOCO_CONFORMANCE_CLI_COMMANDS_H_
