// The one runner every protocol uses (ARCHITECTURE "conformance"): learns
// what the device is, runs the selected and applicable cases of the
// protocol's suites on the target, each with a restart (when the target can)
// and a fresh host that greets the device first, and rolls the rule outcomes
// up over the run. What differs per protocol is its traits type
// (conformance/protocols/*/..._protocol.h):
//
//   struct Traits {
//     static constexpr wire::Protocol kProtocol;
//     using Host;    // constructed as Host(target, verdicts, host_options)
//     using Device;  // what the device says of itself
//     using Case;    // CaseOf<CaseContextOf<Host, Device>>
//     // How a case that needs more reads: "the device does not advertise ".
//     static constexpr std::string_view kLacking;
//     static const std::vector<Case>& Cases();
//     static const std::vector<Rule>& Rules();
//     // Asks the device what it is (twice, as a host retries); nullopt when
//     // it did not answer.
//     static std::optional<Device> Discover(Host& probe);
//     // Optional: the rule a missed first introduction fails ("DMC-HI-016").
//     static constexpr std::string_view kIntroductionRule;
//     // Optional, for a protocol whose devices speak several dialects: the
//     // ones HostOptions::dialect may name besides kAutoDialect, and which
//     // of them kAutoDialect picks ("sketch unless `hi` says otherwise").
//     static constexpr DialectChoice kDialects[];
//     static constexpr std::string_view kAutoPicks;
//     // The console line and JSON fields of report.device / device_info.
//     static void Describe(const Device& device, RunReport& report);
//     // Whether a rule or case with `needs` applies to the device: decides
//     // the protocol's own needs (rules/<p>_needs.h) and SharedNeeds::kNothing
//     // (SharedNeeds::kPins is the target's to meet, never asked here).
//     static bool Applies(const Need& needs, const Device& device);
//     // Greets the device at the start of a case; what it answered, or
//     // nullopt (the host has judged the silence).
//     static std::optional<Device> Greet(Host& host, Target& target, const Device& discovered);
//     // The motor positions the device reported in `traffic`, for plots.
//     static PositionSeries Positions(const std::vector<Chunk>& traffic);
//     // Optional, for a protocol with a pin family (core/pin_judge.h): its
//     // rule prefix ("DFM-") and the position events of `traffic`.
//     static constexpr std::string_view kPinRulePrefix;
//     static std::vector<PinPositionEvent> PinEvents(const std::vector<Chunk>& traffic);
//     // The fuzzer's and replay's hooks of each protocol the folder speaks
//     // (core/fuzz_protocol.h).
//     static std::span<const FuzzHooks> Fuzz();
//   };
//
// The introduction is sent twice, as a host retries after its answer timeout;
// a device that answers only the second fails the protocol's introduction
// rule (Traits::kIntroductionRule, judged in a "connect/introduction" entry)
// and is judged on everything else. A device that sent nothing at all to
// either is a target error (exit 2): no case runs, whatever the subset or
// shard. A device that sent bytes but no introduction is treated the same
// for every protocol: the cases and rules that need nothing still run (their
// greeting goes unanswered, which fails the run), the others are not
// applicable. When such a device has still sent no byte after
// kSilentCasesBeforeGivingUp cases, the rest are not run (each says why), so
// a dead link ends the run in a few answer timeouts instead of one per case.
#ifndef MOCO_CONFORMANCE_CORE_RUN_H_
#define MOCO_CONFORMANCE_CORE_RUN_H_

#include <algorithm>
#include <chrono>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "conformance/core/cases.h"
#include "conformance/core/fuzz_protocol.h"
#include "conformance/core/pin_judge.h"
#include "conformance/core/run_report.h"
#include "conformance/core/transcript.h"
#include "conformance/rules/catalogue.h"
#include "conformance/rules/needs.h"
#include "conformance/targets/target.h"

namespace moco::conformance {

// Why a case or rule with `needs` cannot run on `device` ("" when it can).
template <typename Traits>
std::string NotApplicableBecause(const Need& needs,
                                 const std::optional<typename Traits::Device>& device) {
  if (needs == SharedNeeds::kNothing) return "";
  if (!device) return "the device did not introduce itself";
  if (Traits::Applies(needs, *device)) return "";
  return std::string(Traits::kLacking) + std::string(needs.text);
}

// How many cases a device that never introduced itself may spend without
// sending a single byte before the run stops trying.
inline constexpr size_t kSilentCasesBeforeGivingUp = 2;
inline constexpr const char* kGaveUpOnSilence =
    "not run: the device has sent nothing (no introduction, and no byte in the first cases); "
    "check the port, the cable, the baud rate and that the device is powered";

// What a run whose device sent nothing to its introductions reports.
inline constexpr std::string_view kNoIntroduction =
    "the device sent nothing in answer to two introductions (the second after the answer "
    "timeout); no rule can be judged: check the port, the cable, the baud rate, that the "
    "device is powered and that no other program is reading the port";

// Whether the device sent any byte in `traffic`.
inline bool DeviceSpoke(const std::vector<Chunk>& traffic) {
  return std::any_of(traffic.begin(), traffic.end(),
                     [](const Chunk& c) { return !c.from_host && !c.bytes.empty(); });
}

// The same, where SharedNeeds::kPins asks the target: it must watch pins.
template <typename Traits>
std::string NotApplicableOn(const Target& target, const Need& needs,
                            const std::optional<typename Traits::Device>& device) {
  if (needs != SharedNeeds::kPins) return NotApplicableBecause<Traits>(needs, device);
  if (!device) return "the device did not introduce itself";
  if (target.Pins() == nullptr) {
    return "the target watches no pins (give --board with a simavr: or native: target)";
  }
  return "";
}

// Why a case is not applicable beyond its needs ("" when it is): a protocol
// whose devices speak dialects (DFMoco: the sketch's or the StackShot 3X's)
// gives Traits::CaseNotApplicable(case, device).
template <typename Traits>
std::string CaseNotApplicable(const typename Traits::Case& k,
                              const std::optional<typename Traits::Device>& device) {
  if constexpr (requires { Traits::CaseNotApplicable(k, *device); }) {
    if (device) return Traits::CaseNotApplicable(k, *device);
  }
  return "";
}
// The same for a rule (Traits::RuleNotApplicable(rule, device)).
template <typename Traits>
std::string RuleNotApplicable(const Rule& rule,
                              const std::optional<typename Traits::Device>& device) {
  if constexpr (requires { Traits::RuleNotApplicable(rule, *device); }) {
    if (device) return Traits::RuleNotApplicable(rule, *device);
  }
  return "";
}

// What the probe before the cases found: the device's introduction, whether
// the device sent anything at all, and whether the link was lost meanwhile.
template <typename Traits>
struct ProbeResult {
  std::optional<typename Traits::Device> device;
  bool device_spoke = false, lost = false;
};

// The probe before the cases: a host introduces itself to the device.
template <typename Traits>
ProbeResult<Traits> Probe(Target& target, const RunOptions& options,
                          const HostOptions& host_options, RunReport& report) {
  using Host = typename Traits::Host;
  ProbeResult<Traits> out;
  Verdicts probe(options.rules);
  Host host(target, probe, host_options);
  const TimeNs t0 = host.Now();
  const auto c0 = std::chrono::steady_clock::now();
  host.set_greeting(true);
  out.device = Traits::Discover(host);
  host.Close();
  out.device_spoke = DeviceSpoke(host.traffic());
  out.lost = host.link_lost();
  // The introduction's own rule (the first HI answered) is judged here,
  // where the host's first request is; the rest of what the probe saw is
  // judged again by every case's greeting.
  if constexpr (requires { Traits::kIntroductionRule; }) {
    const auto it = probe.outcomes().find(Traits::kIntroductionRule);
    if (out.device && it != probe.outcomes().end() && it->second.status == Status::kFail) {
      CaseResult intro;
      intro.suite = "connect";
      intro.name = "introduction";
      intro.summary = "How the device answered the host's first introduction";
      intro.outcomes.emplace(it->first, it->second);
      intro.log.push_back(
          "the first introduction went unanswered; the second, sent after the "
          "answer timeout, was answered and the run goes on");
      intro.target_ns = std::max<TimeNs>(0, host.Now() - t0);
      intro.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - c0).count();
      intro.KeepTraffic(host.traffic());
      report.cases.push_back(std::move(intro));
    }
  }
  return out;
}

// Runs case `k` on a host of its own (on the target restarted when it can),
// with its pins judged when they are watched, into `result`. Whether the
// device sent anything during the case.
template <typename Traits>
bool RunCase(Target& target, const typename Traits::Case& k, const RunOptions& options,
             const HostOptions& host_options, const std::optional<typename Traits::Device>& device,
             CaseResult& result) {
  using Host = typename Traits::Host;
  using Device = typename Traits::Device;
  using Case = typename Traits::Case;
  const auto c0 = std::chrono::steady_clock::now();
  if (target.CanRestart()) target.Restart();
  Verdicts verdicts(options.rules);
  Host host(target, verdicts, host_options);
  const TimeNs t0 = host.Now();
  host.set_greeting(true);
  const std::optional<Device> seen = Traits::Greet(host, target, device.value_or(Device{}));
  host.set_greeting(false);
  if (seen && !host.link_lost()) {
    typename Case::Context ctx{host,         verdicts,       *seen,     target,
                               host_options, options.random, result.log};
    k.run(ctx);
  }
  host.Close();
  if (const PinTrace* pins = target.Pins(); pins != nullptr && options.pins) {
    // What a step driver saw during the case (conformance/rules/pin_rules.cpp).
    if constexpr (requires { Traits::PinEvents(host.traffic()); }) {
      JudgePins(Traits::kPinRulePrefix, *pins, Traits::PinEvents(host.traffic()), *options.pins,
                host.Now(), verdicts);
    }
    result.pins = std::make_shared<const PinTrace>(*pins);
  }
  if (host.link_lost()) result.log.push_back("the link to the device was lost");
  result.not_waited_for = host.NotWaitedForSummary();
  // The random suite saves a shrunk session of its own instead.
  if (verdicts.MustFailed() && k.suite != "random") {
    result.log.push_back("transcript:\n" + Transcript(Traits::kProtocol, host.traffic()));
  }
  result.target_ns = std::max<TimeNs>(0, host.Now() - t0);
  result.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - c0).count();
  const bool spoke = DeviceSpoke(host.traffic());
  result.outcomes = verdicts.outcomes();
  result.not_exercised = verdicts.not_exercised();
  result.KeepTraffic(host.traffic());
  result.positions = Traits::Positions(result.traffic);
  return spoke;
}

template <typename Traits>
RunReport Run(Target& target, const RunOptions& options) {
  using Device = typename Traits::Device;
  using Case = typename Traits::Case;
  const auto wall0 = std::chrono::steady_clock::now();
  RunReport report;
  report.target = target.Name();
  report.protocol = std::string(wire::ProtocolName(Traits::kProtocol));
  report.options = options;

  // The hosts of the run share what they learn of the requests the device
  // leaves unanswered (HostOptions::give_up_after_unanswered).
  HostOptions host_options = options.host;
  host_options.unanswered = std::make_shared<UnansweredRequests>();

  ProbeResult<Traits> probed = Probe<Traits>(target, options, host_options, report);
  std::optional<Device> device = std::move(probed.device);
  const bool device_spoke = probed.device_spoke, probe_lost = probed.lost;
  if (device) Traits::Describe(*device, report);
  // A device that sent nothing at all to two introductions gives the run
  // nothing to judge: that is a target error in every subset and shard, never
  // a PASS of the cases that need nothing.
  if (!device && !device_spoke) {
    if (const int sig = StopRequested(); sig != 0) {
      report.interrupted_by = sig;
    } else if (probe_lost) {
      // A firmware that crashed or halted, a port that closed: the target's
      // name says what happened.
      report.target_error =
          "the link to the device was lost before it introduced itself (" + target.Name() + ")";
    } else {
      report.target_error = std::string(kNoIntroduction);
    }
    if (options.on_progress) options.on_progress(report);
    SummarizeRules(report, Traits::Rules(), [&](const Rule& rule) {
      return !(rule.needs == SharedNeeds::kPins && !options.pins);
    });
    report.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
    return report;
  }

  if (options.on_progress) options.on_progress(report);
  const std::vector<Case>& cases = Traits::Cases();
  size_t total = 0, started = 0, silent_cases = 0;
  for (size_t i = 0; i < cases.size(); ++i) {
    total += CaseSelected(options, i, cases[i].suite + "/" + cases[i].name);
  }
  for (size_t i = 0; i < cases.size(); ++i) {
    const Case& k = cases[i];
    if (const int sig = StopRequested(); sig != 0) {
      report.interrupted_by = sig;
      break;
    }
    if (!CaseSelected(options, i, k.suite + "/" + k.name)) continue;
    ++started;
    if (options.on_case_start)
      options.on_case_start(report, k.suite + "/" + k.name, started, total);
    CaseResult result;
    result.suite = k.suite;
    result.name = k.name;
    result.summary = k.summary;
    std::string why = NotApplicableOn<Traits>(target, k.needs, device);
    if (why.empty()) why = CaseNotApplicable<Traits>(k, device);
    if (why.empty() && !device && silent_cases >= kSilentCasesBeforeGivingUp) {
      why = kGaveUpOnSilence;
    }
    if (!why.empty()) {
      result.applicable = false;
      result.not_applicable_because = std::move(why);
      report.cases.push_back(std::move(result));
      if (options.on_progress) options.on_progress(report);
      continue;
    }
    const bool spoke = RunCase<Traits>(target, k, options, host_options, device, result);
    silent_cases = spoke ? 0 : silent_cases + 1;
    report.cases.push_back(std::move(result));
    // A case cut short by a stop request is not a verdict on the device.
    if (const int sig = StopRequested(); sig != 0) {
      report.interrupted_case = report.cases.back().suite + "/" + report.cases.back().name;
      report.cases.pop_back();
      report.interrupted_by = sig;
      break;
    }
    if (options.on_progress) options.on_progress(report);
  }

  SummarizeRules(report, Traits::Rules(), [&](const Rule& rule) {
    if (rule.needs == SharedNeeds::kPins && !options.pins) return false;
    return NotApplicableOn<Traits>(target, rule.needs, device).empty() &&
           RuleNotApplicable<Traits>(rule, device).empty();
  });
  report.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  return report;
}

}  // namespace moco::conformance

#endif  // MOCO_CONFORMANCE_CORE_RUN_H_
