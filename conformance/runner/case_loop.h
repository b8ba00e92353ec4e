// The per-case loop the three protocols' runners share: sharding and the case filter, the
// applicability gate, a restart and a fresh host per case, the greeting, the transcript of a failed
// case, the case's device and wall times, its outcomes and its traffic.
#ifndef MOCO_CONFORMANCE_RUNNER_CASE_LOOP_H_
#define MOCO_CONFORMANCE_RUNNER_CASE_LOOP_H_

#include <algorithm>
#include <chrono>
#include <string>
#include <vector>

#include "conformance/rules/catalogue.h"
#include "conformance/runner/runner.h"

namespace moco::conformance {

// Runs each selected case of `cases` (each has `suite`, `name`, `summary`)
// on `target` with a fresh `Host(target, verdicts, options.host)` and appends
// its CaseResult to `report.cases`.
//  - `not_applicable(k)` -> std::string: why case k cannot run on this
//    device, empty when it can (the case is then listed as not applicable);
//  - `greet_and_run(host, verdicts, k, log)`: greets the device and, when it
//    answered, runs the case (log: the case's log lines);
//  - `transcript(host)` -> std::string: the traffic, kept in the log of a
//    case whose MUST rules failed (not for the random suite, which saves a
//    shrunk session instead).
template <class Host, class CaseT, class NotApplicable, class GreetAndRun, class TranscriptFn>
void RunCases(Target& target, const RunOptions& options, const std::vector<CaseT>& cases,
              RunReport& report, NotApplicable not_applicable, GreetAndRun greet_and_run,
              TranscriptFn transcript) {
  if (options.on_progress) options.on_progress(report);
  for (size_t i = 0; i < cases.size(); ++i) {
    const CaseT& k = cases[i];
    if (const int sig = StopRequested(); sig != 0) {
      report.interrupted_by = sig;
      break;
    }
    if (i % options.shard_count != options.shard_index) continue;
    if (!options.cases.empty() && !GlobMatch(options.cases, k.suite + "/" + k.name)) continue;
    CaseResult result;
    result.suite = k.suite;
    result.name = k.name;
    result.summary = k.summary;
    if (std::string why = not_applicable(k); !why.empty()) {
      result.applicable = false;
      result.not_applicable_because = std::move(why);
      report.cases.push_back(std::move(result));
      if (options.on_progress) options.on_progress(report);
      continue;
    }
    const auto c0 = std::chrono::steady_clock::now();
    if (target.CanRestart()) target.Restart();
    Verdicts verdicts(options.rules);
    Host host(target, verdicts, options.host);
    const TimeNs t0 = host.Now();
    greet_and_run(host, verdicts, k, result.log);
    host.Close();
    if (host.link_lost()) result.log.push_back("the link to the device was lost");
    if (verdicts.MustFailed() && k.suite != "random") {
      result.log.push_back("transcript:\n" + transcript(host));
    }
    result.target_ns = std::max<TimeNs>(0, host.Now() - t0);
    result.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - c0).count();
    result.outcomes = verdicts.outcomes();
    result.KeepTraffic(host.traffic());
    report.cases.push_back(std::move(result));
    // A case cut short by a stop request is not a verdict on the device.
    if (const int sig = StopRequested(); sig != 0) {
      report.cases.pop_back();
      report.interrupted_by = sig;
      break;
    }
    if (options.on_progress) options.on_progress(report);
  }
}

}  // namespace moco::conformance

#endif  // MOCO_CONFORMANCE_RUNNER_CASE_LOOP_H_
