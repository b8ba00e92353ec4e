// The mococheck runner for StackShot 3X targets (see runner.h): identity and
// axis discovery (stackshot-protocol.txt 1.1.10-1.1.15, CC_RAIL_STATUS per
// axis), case selection and sharding, and the roll-up of rule outcomes.
#include <chrono>
#include <cstdio>

#include "conformance/runner/case_loop.h"
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

  RunCases<SsHost>(
      target, options, StackshotCases(), report,
      [&](const SsCase& k) {
        return SsApplies(k.needs, device)
                   ? std::string()
                   : "the device does not have " + std::string(NeedsText(k.needs));
      },
      [&](SsHost& host, Verdicts& verdicts, const SsCase& k, std::vector<std::string>& log) {
        const SsRecord* hello =
            host.Call(SsRead(stackshot::Command::kPing, stackshot::PingRequest{0x5a}));
        if (StatusOf(hello) != stackshot::Action::kRspOk || host.link_lost()) return;
        SsCaseContext ctx{host, verdicts, device, target, options.host, options.random, log};
        k.run(ctx);
      },
      [](const SsHost& host) { return SsTranscript(host); });

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
