// The mococheck runner for StackShot 3X targets (see runner.h): identity and
// axis discovery (stackshot-protocol.txt 1.1.10-1.1.15, CC_RAIL_STATUS per
// axis), case selection and sharding, and the roll-up of rule outcomes.
#include <chrono>
#include <cstdio>

#include "conformance/runner/runner.h"

#include <algorithm>
#include "conformance/suites/stackshot_suites.h"

namespace moco::conformance {
namespace {

std::string Hex32(uint32_t v) {
  char buf[16];
  std::snprintf(buf, sizeof buf, "0x%08x", v);
  return buf;
}

void Describe(const SsDeviceInfo& d, RunReport& report) {
  if (!d.answered) return;
  const std::string name = d.software_string.value_or("(no software string)");
  report.device = "\"" + name + "\"";
  report.device_info = {{"software_string", name}, {"axes", d.three_axes ? 3 : 1}};
  const std::pair<const char*, std::optional<uint32_t>> ids[] = {
      {"software_id", d.software_id},
      {"hardware_id", d.hardware_id},
      {"bootloader_id", d.bootloader_id},
      {"serial_number", d.serial_number}};
  for (const auto& [key, value] : ids) {
    if (!value) continue;
    report.device_info[key] = *value;
    report.device += std::string(", ") + key + " " + Hex32(*value);
  }
  report.device += d.three_axes ? ", axes X Y Z" : ", one axis";
}

}  // namespace

RunReport RunStackshot(Target& target, const RunOptions& options) {
  const auto wall0 = std::chrono::steady_clock::now();
  RunReport report;
  report.target = target.Name();
  report.protocol = std::string(ProtocolName(Protocol::kStackshot));
  report.options = options;

  SsDeviceInfo device;
  {
    Verdicts probe;
    SsHost host(target, probe, options.host);
    device = DiscoverStackshot(host);
    host.Close();
  }
  Describe(device, report);

  const std::vector<SsCase>& cases = StackshotCases();
  for (size_t i = 0; i < cases.size(); ++i) {
    const SsCase& k = cases[i];
    if (i % options.shard_count != options.shard_index) continue;
    const std::string full = k.suite + "/" + k.name;
    if (!options.cases.empty() && !GlobMatch(options.cases, full)) continue;
    CaseResult result;
    result.suite = k.suite;
    result.name = k.name;
    result.summary = k.summary;
    if (!SsApplies(k.needs, device)) {
      result.applicable = false;
      result.not_applicable_because = "the device does not have " + std::string(NeedsText(k.needs));
      report.cases.push_back(std::move(result));
      continue;
    }
    const auto c0 = std::chrono::steady_clock::now();
    if (target.CanRestart()) target.Restart();
    Verdicts verdicts(options.rules);
    SsHost host(target, verdicts, options.host);
    const TimeNs t0 = host.Now();
    const SsRecord* hello =
        host.Call(SsRead(stackshot::Command::kPing, stackshot::PingRequest{0x5a}));
    if (StatusOf(hello) == stackshot::Action::kRspOk && !host.link_lost()) {
      SsCaseContext ctx{host, verdicts, device, target, options.host, options.random, result.log};
      k.run(ctx);
    }
    host.Close();
    if (host.link_lost()) result.log.push_back("the link to the device was lost");
    if (verdicts.MustFailed() && k.suite != "random") {
      result.log.push_back("transcript:\n" + SsTranscript(host));
    }
    result.target_ns = std::max<TimeNs>(0, host.Now() - t0);
    result.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - c0).count();
    result.outcomes = verdicts.outcomes();
    result.KeepTraffic(host.traffic());
    report.cases.push_back(std::move(result));
  }

  SummarizeRules(report, StackshotRules(),
                 [&](const Rule& rule) { return SsApplies(rule.needs, device); });
  report.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  return report;
}

std::vector<CaseInfo> StackshotCaseInfos() {
  std::vector<CaseInfo> out;
  for (const SsCase& k : StackshotCases()) {
    out.push_back({k.suite, k.name, k.summary,
                   k.needs == Needs::kNothing ? std::string() : std::string(NeedsText(k.needs))});
  }
  return out;
}

}  // namespace moco::conformance
