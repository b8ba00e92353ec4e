// mococheck: the conformance runner for DMC v2, DFMoco and StackShot 3X
// devices (the three vendor specs; ERRATA; docs/rules.md). Drives
// Dragonframe-style traffic at a device and checks every byte against the
// rule catalogue. Exit: 0 every MUST rule passed, 1 a MUST rule failed, 2
// usage or target error, or a run cut short by a signal (docs/exit-codes.md).
// Each subcommand lives in conformance/cli/.
#include <csignal>

#include <CLI/CLI.hpp>

#include "cli_numbers.h"
#include "conformance/cli/commands.h"

int main(int argc, char** argv) {
  // A closed pipe or socket is a failed write (EPIPE), handled where it
  // happens, never a silent death: a TCP target that hangs up is a target
  // error with the reports written, and `| head` only loses console text.
  std::signal(SIGPIPE, SIG_IGN);
  namespace cli = moco::conformance::cli;
  CLI::App app{
      "mococheck: conformance runner for motion-control devices.\n"
      "Plays Dragonframe-style traffic (DMC v2, DFMoco or StackShot 3X) at a device and checks\n"
      "every byte against the rules in docs/rules.md. Exit status: 0 when every MUST rule passed, "
      "1 when one failed,\n"
      "2 on a usage or target error or when a signal cut the run short (docs/exit-codes.md).\n\n"
      "Examples:\n"
      "  mococheck run --target in-process:dmc16\n"
      "  mococheck run --target pty:/tmp/dmc16 --baud 115200 --junit report.xml\n"
      "  mococheck run --target tcp:127.0.0.1:5000 --rules 'DMC-ACK-*,DMC-CSUM-*'\n"
      "  mococheck replay fixtures/sessions/dmc16-workflow.jsonl --target in-process:dmc16\n"
      "  mococheck fuzz fixtures/sessions/*.jsonl --target in-process:dmc16 --seconds 30\n"
      "  mococheck keygen --out vendor.key\n"
      "  mococheck certify --target pty:/dev/ttyACM0 --protocol dfmoco --key vendor.key --out "
      "cert.json\n"
      "  mococheck verify cert.json --key vendor.key.pub --replay\n"
      "  mococheck rules --markdown > docs/rules.md\n"
      "  mococheck cases"};
  app.require_subcommand(1);
  struct Command {
    CLI::App* sub = nullptr;
    cli::Runner run;
  };
  Command commands[8];
  commands[0].run = cli::AddRunCommand(app, commands[0].sub);
  commands[1].run = cli::AddRulesCommand(app, commands[1].sub);
  commands[2].run = cli::AddCasesCommand(app, commands[2].sub);
  commands[3].run = cli::AddReplayCommand(app, commands[3].sub);
  commands[4].run = cli::AddFuzzCommand(app, commands[4].sub);
  commands[5].run = cli::AddCertifyCommand(app, commands[5].sub);
  commands[6].run = cli::AddKeygenCommand(app, commands[6].sub);
  commands[7].run = cli::AddVerifyCommand(app, commands[7].sub);
  if (const auto exit_code = moco::cli::ParseCommandLine(app, argc, argv, cli::kExitUsage)) {
    return *exit_code;
  }
  for (const Command& c : commands) {
    if (c.sub->parsed()) return c.run();
  }
  return cli::kExitUsage;  // require_subcommand(1) leaves no other case
}
