// DFMoco for the runner (see dfmoco_protocol.h).
#include "conformance/protocols/dfmoco/dfmoco_protocol.h"

#include <charconv>
#include <string>

#include "conformance/protocols/dfmoco/dfmoco_timing.h"

namespace moco::conformance {

std::optional<std::array<int, 3>> ParseDfmocoVersion(std::string_view text) {
  std::array<int, 3> v{0, 0, 0};
  size_t at = 0;
  for (size_t part = 0; part < v.size(); ++part) {
    const char* begin = text.data() + at;
    const char* end = text.data() + text.size();
    const auto [ptr, ec] = std::from_chars(begin, end, v[part]);
    if (ec != std::errc()) {
      if (part == 0) return std::nullopt;
      break;
    }
    at = static_cast<size_t>(ptr - text.data());
    if (at >= text.size() || text[at] != '.') break;
    ++at;
  }
  return v;
}

bool DfmocoApplies(const Need& needs, const dfmoco::HelloReply& hello) {
  using N = DfmocoNeeds;
  const auto version = ParseDfmocoVersion(hello.version);
  const auto since = [&](std::array<int, 3> first) {
    return hello.motor_count >= 1 && version && *version >= first;
  };
  if (needs == N::kNothing) return true;
  if (needs == N::kMotors) return hello.motor_count >= 1;
  if (needs == N::kTwoMotors) return hello.motor_count >= 2;
  if (needs == N::kJogVelocity) return hello.motor_count >= 1 && hello.protocol_major >= 2;
  if (needs == N::kGoMotion) return since({1, 2, 7});
  if (needs == N::kBlurRefusal) return since({1, 3, 1});
  return false;  // another protocol's need
}

bool DfmocoApplies(const Rule& rule, const dfmoco::HelloReply& hello) {
  return DfmocoApplies(rule.needs, hello);
}

namespace {

// What the sketch does and the StackShot 3X's DfMoco mode does not (its
// section 3 says otherwise, or says nothing where the rule quotes FACTS
// DFMoco, the sketch's source): rule ids and case names, with the reason.
struct Excluded {
  std::string_view what;
  std::string_view why;
};
constexpr Excluded kSketchOnly[] = {
    {"DFM-HI-001", "documents no `hi` at power-on (docs/device-facts.md, DFMoco, is the sketch's)"},
    {"DFM-HI-007", "is not one of the sketch's versions: it answers `hi 1 3 1.2.6`"},
    {"DFM-LINE-007",
     "documents no bare \"\\n\" framing (docs/device-facts.md, DFMoco, is the sketch's)"},
    {"DFM-MM-001",
     "answers `mm <motor> <current position>`, not the target (DFM-SS-002 judges it)"},
    {"DFM-MP-002", "reports a moving motor with `mm` lines, not `mp` (DFM-SS-003 judges them)"},
    {"DFM-MP-003", "reports a moving motor with `mm` lines, not `mp` (DFM-SS-003 judges them)"},
    {"DFM-MP-004", "reports a moving motor with `mm` lines, not `mp` (DFM-SS-003 judges them)"},
    {"DFM-PR-001",
     "answers a rate above the controller's maximum with the maximum, not the "
     "sketch's 100..20000 clamp (DFM-SS-008 judges it)"},
    {"DFM-PR-002",
     "answers a rate above the controller's maximum with the maximum, not the "
     "sketch's 100..20000 clamp (DFM-SS-008 judges it)"},
    {"DFM-IM-003", "documents an inch as \"a slow crawl\", not the sketch's few steps"},
    {"DFM-ERR-003",
     "documents no `error: too many args` (docs/device-facts.md, DFMoco, is the sketch's)"},
    {"connect/boot-hi", "documents no `hi` at power-on"},
    {"connect/line-end", "documents no bare \"\\n\" framing"},
    {"errors/too-many-args", "documents no `error: too many args`"},
};

}  // namespace

std::string DfmocoDialectExcludes(std::string_view rule_or_case, const DfmDevice& device) {
  const bool ss_only =
      rule_or_case.starts_with("DFM-SS-") || rule_or_case.starts_with("stackshot/");
  if (!device.stackshot) {
    return ss_only ? "the StackShot 3X DfMoco dialect only (stackshot-protocol.txt section 3); "
                     "the device is judged in the sketch's dialect"
                   : "";
  }
  for (const Excluded& e : kSketchOnly) {
    if (!e.what.empty() && e.what == rule_or_case) {
      return "the sketch's dialect only; the StackShot 3X DfMoco dialect " + std::string(e.why);
    }
  }
  return "";
}

std::optional<DfmDevice> DfmocoProtocol::Discover(DfmHost& probe) {
  // Asked twice, as a host does after its answer timeout: a device that
  // missed the first `hi` (DFM-HI-008) is still judged on everything else.
  for (int attempt = 0; attempt < 2 && !probe.link_lost(); ++attempt) {
    if (const auto* hi = As<dfmoco::HelloReply>(probe.Call("hi"))) {
      return DfmDevice{*hi, probe.stackshot()};
    }
  }
  return std::nullopt;
}

void DfmocoProtocol::Describe(const DfmDevice& device, RunReport& report) {
  const dfmoco::HelloReply& hello = device;
  const std::string line = dfmoco::FormatDevice(hello);
  const std::string dialect(device.stackshot ? kStackshotDialect : kSketchDialect);
  report.device = "\"" + line.substr(0, line.size() - 2) +
                  "\": " + (device.stackshot ? "StackShot 3X DfMoco " : "DFMoco ") + hello.version +
                  ", protocol " + std::to_string(hello.protocol_major) + ", " +
                  std::to_string(hello.motor_count) + " motors, dialect " + dialect;
  report.device_info = {{"protocol_major", hello.protocol_major},
                        {"motor_count", hello.motor_count},
                        {"version", hello.version},
                        {"dialect", dialect}};
}

std::optional<DfmDevice> DfmocoProtocol::Greet(DfmHost& host, Target& target,
                                               const DfmDevice& discovered) {
  // The rules of the other dialect are not judged in this case at all.
  auto exclude = [&host](const DfmDevice& device) {
    host.verdicts().set_excluded(
        [device](std::string_view id) { return !DfmocoDialectExcludes(id, device).empty(); });
  };
  exclude(discovered);
  // A freshly powered device may still be starting (a UART not yet enabled
  // loses what arrives): wait for its boot greeting, up to 1 s, before
  // greeting it, so the boot `hi` is not taken for the answer.
  if (target.CanRestart()) {
    host.WaitFor(0, dfmoco_cases::kBootHiWithinNs,
                 [](const DfmLine& l) { return As<dfmoco::HelloReply>(&l) != nullptr; });
  }
  for (int attempt = 0; attempt < 2 && !host.link_lost(); ++attempt) {
    if (const auto* seen = As<dfmoco::HelloReply>(host.Call("hi"))) {
      DfmDevice device{*seen, host.stackshot()};
      exclude(device);
      return device;
    }
  }
  return std::nullopt;
}

}  // namespace moco::conformance
