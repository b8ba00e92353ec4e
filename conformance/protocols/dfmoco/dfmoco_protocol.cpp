// DFMoco for the runner (see dfmoco_protocol.h).
#include "conformance/protocols/dfmoco/dfmoco_protocol.h"

#include <charconv>
#include <cstdio>
#include <string>

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

bool DfmocoApplies(Needs needs, const dfmoco::HelloReply& hello) {
  const auto version = ParseDfmocoVersion(hello.version);
  switch (needs) {
    case Needs::kNothing:
      return true;
    case Needs::kDfmMotors:
      return hello.motor_count >= 1;
    case Needs::kDfmTwoMotors:
      return hello.motor_count >= 2;
    case Needs::kDfmJogVelocity:
      return hello.motor_count >= 1 && hello.protocol_major >= 2;
    case Needs::kDfmGoMotion:
      return hello.motor_count >= 1 && version && *version >= std::array<int, 3>{1, 2, 7};
    case Needs::kDfmBlurRefusal:
      return hello.motor_count >= 1 && version && *version >= std::array<int, 3>{1, 3, 1};
    default:  // another protocol's needs
      return false;
  }
}

bool DfmocoApplies(const Rule& rule, const dfmoco::HelloReply& hello) {
  return DfmocoApplies(rule.needs, hello);
}

std::optional<dfmoco::HelloReply> DfmocoProtocol::Discover(DfmHost& probe) {
  if (const auto* hi = As<dfmoco::HelloReply>(probe.Call("hi"))) return *hi;
  return std::nullopt;
}

void DfmocoProtocol::Describe(const dfmoco::HelloReply& hello, RunReport& report) {
  const std::string line = dfmoco::FormatDevice(hello);
  report.device = "\"" + line.substr(0, line.size() - 2) + "\": DFMoco " + hello.version +
                  ", protocol " + std::to_string(hello.protocol_major) + ", " +
                  std::to_string(hello.motor_count) + " motors";
  report.device_info = {{"protocol_major", hello.protocol_major},
                        {"motor_count", hello.motor_count},
                        {"version", hello.version}};
}

std::optional<dfmoco::HelloReply> DfmocoProtocol::Greet(DfmHost& host, Target& target,
                                                        const dfmoco::HelloReply& /*discovered*/) {
  // A freshly powered device may still be starting (a UART not yet enabled
  // loses what arrives): wait for its boot greeting, up to 1 s, before
  // greeting it, so the boot `hi` is not taken for the answer.
  if (target.CanRestart()) {
    host.WaitFor(0, 1000 * sim::kNsPerMs,
                 [](const DfmLine& l) { return As<dfmoco::HelloReply>(&l) != nullptr; });
  }
  if (const auto* seen = As<dfmoco::HelloReply>(host.Call("hi"))) return *seen;
  return std::nullopt;
}

PositionSeries DfmocoProtocol::Positions(const std::vector<Chunk>& traffic) {
  PositionSeries s;
  std::string pending;
  for (const Chunk& c : traffic) {
    if (c.from_host) continue;
    pending.append(c.bytes.begin(), c.bytes.end());
    size_t nl;
    while ((nl = pending.find('\n')) != std::string::npos) {
      std::string line = pending.substr(0, nl);
      pending.erase(0, nl + 1);
      if (!line.empty() && line.back() == '\r') line.pop_back();
      int motor = 0;
      long long pos = 0;
      if (std::sscanf(line.c_str(), "mp %d %lld", &motor, &pos) == 2 && motor > 0 && motor <= 32) {
        s[motor].emplace_back(c.t_ns, pos);
      }
    }
  }
  return s;
}

}  // namespace moco::conformance
