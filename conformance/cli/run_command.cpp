// `mococheck run`: the conformance suites against a device, the console
// streamed as cases end, and the JUnit, JSON and HTML reports (docs/files.md,
// docs/exit-codes.md). The options and the steps it shares with `certify`
// are in run_setup.*.
#include "conformance/cli/run_setup.h"

namespace moco::conformance::cli {
namespace {

int Run(const RunArgs& a) {
  int exit_code = kExitUsage;
  std::optional<PreparedRun> p = PrepareRun(a, exit_code);
  if (!p) return exit_code;
  // From here a signal stops the run and the reports of what ran are written.
  InstallStopHandlers();
  std::unique_ptr<Target> target = std::move(p->resolved.target);
  const std::optional<RunReport> report = ExecuteRun(a, *p, *target);
  if (!report) return kExitUsage;
  return WriteReports(a, *report);
}

}  // namespace

Runner AddRunCommand(CLI::App& app, CLI::App*& sub) {
  auto a = std::make_shared<RunArgs>();
  sub = app.add_subcommand("run", "Run the conformance suites against a device");
  AddRunOptions(sub, *a, true);
  return [a] { return Run(*a); };
}

}  // namespace moco::conformance::cli
