// The mococheck runner (see runner.h): capability discovery from MSG_HI
// (dmc-v2-protocol.txt "Capabilities"), case selection and sharding, and the
// roll-up of rule outcomes.
#include "conformance/runner/runner.h"

#include <algorithm>
#include <chrono>
#include <cstdio>

#include "conformance/runner/case_loop.h"

namespace moco::conformance {

bool CaseResult::MustFailed() const {
  for (const auto& [id, o] : outcomes) {
    const Rule* r = FindRule(id);
    if (o.status == Status::kFail && r != nullptr && r->level == Level::kMust) return true;
  }
  return false;
}

bool RunReport::MustFailed() const {
  for (const auto& [id, s] : rules) {
    const Rule* r = FindRule(id);
    if (s.status == Status::kFail && r != nullptr && r->level == Level::kMust) return true;
  }
  return false;
}

std::map<Status, size_t> RunReport::RuleCounts() const {
  std::map<Status, size_t> n;
  for (const auto& [id, s] : rules) ++n[s.status];
  return n;
}

void CaseResult::KeepTraffic(const std::vector<Chunk>& all) {
  traffic.assign(all.begin(),
                 all.begin() + static_cast<ptrdiff_t>(std::min(all.size(), kMaxTrafficChunks)));
}

int ExitCode(const RunReport& report) {
  if (!report.target_error.empty() || report.interrupted_by != 0) return 2;
  return report.MustFailed() ? 1 : 0;
}

RunReport RunDmc(Target& target, const RunOptions& options) {
  const auto wall0 = std::chrono::steady_clock::now();
  RunReport report;
  report.target = target.Name();
  report.options = options;

  // Discover what the device advertises.
  {
    Verdicts probe;
    DmcHost host(target, probe, options.host);
    if (const auto* hi = As<dmc::HiResponse>(host.Call(dmc::HiRequest{}))) report.hi = *hi;
    host.Close();
  }
  if (report.hi) {
    const dmc::HiResponse& h = *report.hi;
    char caps[16];
    std::snprintf(caps, sizeof caps, "0x%04x", h.capabilities);
    const std::string fw = std::to_string(h.fw_major) + "." + std::to_string(h.fw_minor) + "." +
                           std::to_string(h.fw_rev);
    report.device = "\"" + h.NameText() + "\" fw " + fw + ", " + std::to_string(h.motor_count) +
                    " motors, " + std::to_string(h.dmx_count) + " DMX, GIO " +
                    std::to_string(h.gio_out_count) + " out / " + std::to_string(h.gio_in_count) +
                    " in, capabilities " + caps;
    report.device_info = {{"name", h.NameText()},
                          {"firmware", fw},
                          {"motor_count", h.motor_count},
                          {"dmx_count", h.dmx_count},
                          {"gio_out_count", h.gio_out_count},
                          {"gio_in_count", h.gio_in_count},
                          {"hw_limit_count", h.hw_limit_count},
                          {"upload_frame_count", h.upload_frame_count},
                          {"capabilities", h.capabilities}};
  }
  const dmc::HiResponse hi = report.hi.value_or(dmc::HiResponse{});

  RunCases<DmcHost>(
      target, options, DmcCases(), report,
      [&](const Case& k) {
        const Rule gate{"", Level::kMust, k.needs, "", "", ""};
        return Applies(gate, hi)
                   ? std::string()
                   : "the device does not advertise " + std::string(NeedsText(k.needs));
      },
      [&](DmcHost& host, Verdicts& verdicts, const Case& k, std::vector<std::string>& log) {
        const auto* seen = As<dmc::HiResponse>(host.Call(dmc::HiRequest{}));
        if (seen == nullptr || host.link_lost()) return;
        const dmc::HiResponse device_hi = *seen;
        CaseContext ctx{host, verdicts, device_hi, target, options.host, options.random, log};
        k.run(ctx);
      },
      [](const DmcHost& host) { return Transcript(host); });

  SummarizeRules(report, DmcRules(), [&](const Rule& rule) { return Applies(rule, hi); });
  report.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  return report;
}

void SummarizeRules(RunReport& report, const std::vector<Rule>& rules,
                    const std::function<bool(const Rule&)>& applies) {
  const RunOptions& options = report.options;
  for (const Rule& rule : rules) {
    if (!options.rules.empty() && !GlobMatch(options.rules, rule.id)) continue;
    RuleSummary s;
    if (!applies(rule)) {
      s.status = Status::kNotApplicable;
    } else {
      bool noted = false;
      for (const CaseResult& c : report.cases) {
        auto it = c.outcomes.find(rule.id);
        if (it == c.outcomes.end()) continue;
        if (it->second.status == Status::kFail)
          ++s.cases_failed;
        else if (it->second.status == Status::kNoted)
          noted = true;
        else
          ++s.cases_passed;
      }
      s.status = s.cases_failed > 0   ? Status::kFail
                 : noted              ? Status::kNoted
                 : s.cases_passed > 0 ? Status::kPass
                                      : Status::kNotExercised;
    }
    report.rules.emplace(std::string(rule.id), s);
  }
}

namespace {

std::vector<CaseInfo> DmcCaseInfos() {
  std::vector<CaseInfo> out;
  for (const Case& k : DmcCases()) {
    out.push_back({k.suite, k.name, k.summary,
                   k.needs == Needs::kNothing ? std::string() : std::string(NeedsText(k.needs))});
  }
  return out;
}

// One entry per protocol with suites.
const ProtocolRunner kRunners[] = {
    {Protocol::kDmc, &RunDmc, &DmcCaseInfos},
    {Protocol::kStackshot, &RunStackshot, &StackshotCaseInfos},
    {Protocol::kDfmoco, &RunDfmoco, &DfmocoCaseInfos},
};

}  // namespace

const ProtocolRunner* FindRunner(Protocol p) {
  for (const ProtocolRunner& r : kRunners) {
    if (r.protocol == p) return &r;
  }
  return nullptr;
}

}  // namespace moco::conformance
