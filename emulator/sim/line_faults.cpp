// The fault settings of an emulated line and their text form.
#include "sim/line_faults.h"

#include <charconv>
#include <cmath>

namespace moco::sim {
namespace {

std::optional<std::string> CheckRate(std::string_view name, double rate) {
  if (!(rate >= 0.0 && rate <= 1.0)) {
    return std::string(name) + " must be a probability between 0 and 1, got " +
           std::to_string(rate);
  }
  return std::nullopt;
}

std::optional<std::string> CheckSide(std::string_view side, const DirectionFaults& f) {
  const std::string s(side);
  if (auto e = CheckRate(s + " drop rate", f.drop_rate)) return e;
  if (auto e = CheckRate(s + " corrupt rate", f.corrupt_rate)) return e;
  if (auto e = CheckRate(s + " duplicate rate", f.duplicate_rate)) return e;
  if (auto e = CheckRate(s + " delay rate", f.delay_rate)) return e;
  if (f.delay_ns < 0) return s + " delay must not be negative";
  return std::nullopt;
}

std::optional<double> ParseDouble(std::string_view text) {
  // std::from_chars for double is available in libstdc++ 11+.
  double v = 0;
  const auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
  if (ec != std::errc() || ptr != text.data() + text.size() || !std::isfinite(v)) {
    return std::nullopt;
  }
  return v;
}

std::optional<uint64_t> ParseU64(std::string_view text) {
  uint64_t v = 0;
  const auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
  if (ec != std::errc() || ptr != text.data() + text.size()) return std::nullopt;
  return v;
}

}  // namespace

std::optional<std::string> FaultConfig::Validate() const {
  if (auto e = CheckSide("to-device", to_device)) return e;
  return CheckSide("to-host", to_host);
}

std::variant<FaultConfig, std::string> ParseFaultConfig(std::string_view spec) {
  FaultConfig config;
  bool to_device = true;
  bool to_host = true;
  while (!spec.empty()) {
    const size_t comma = spec.find(',');
    const std::string_view item = spec.substr(0, comma);
    spec = comma == std::string_view::npos ? std::string_view() : spec.substr(comma + 1);
    if (item.empty()) continue;
    const size_t eq = item.find('=');
    if (eq == std::string_view::npos) {
      return "fault item \"" + std::string(item) + "\" lacks '=': write key=value";
    }
    const std::string_view key = item.substr(0, eq);
    const std::string_view value = item.substr(eq + 1);
    if (key == "seed") {
      const auto v = ParseU64(value);
      if (!v) return "fault seed \"" + std::string(value) + "\" is not an unsigned integer";
      config.seed = *v;
      continue;
    }
    if (key == "dir") {
      if (value == "both") {
        to_device = to_host = true;
      } else if (value == "to-device") {
        to_device = true;
        to_host = false;
      } else if (value == "to-host") {
        to_device = false;
        to_host = true;
      } else {
        return "fault dir \"" + std::string(value) + "\": use to-device, to-host or both";
      }
      continue;
    }
    const auto v = ParseDouble(value);
    if (!v)
      return "fault value \"" + std::string(value) + "\" for " + std::string(key) +
             " is not a number";
    auto set = [&](auto member) {
      if (to_device) config.to_device.*member = *v;
      if (to_host) config.to_host.*member = *v;
    };
    if (key == "drop") {
      set(&DirectionFaults::drop_rate);
    } else if (key == "corrupt") {
      set(&DirectionFaults::corrupt_rate);
    } else if (key == "dup") {
      set(&DirectionFaults::duplicate_rate);
    } else if (key == "delay") {
      set(&DirectionFaults::delay_rate);
    } else if (key == "delay_ms") {
      if (*v < 0 || *v > 3.6e6) return std::string("fault delay_ms must be within 0..3600000");
      const auto ns = static_cast<TimeNs>(std::llround(*v * 1e6));
      if (to_device) config.to_device.delay_ns = ns;
      if (to_host) config.to_host.delay_ns = ns;
    } else {
      return "unknown fault key \"" + std::string(key) +
             "\": use seed, drop, corrupt, dup, delay, delay_ms or dir";
    }
  }
  if (auto e = config.Validate()) return *e;
  return config;
}

}  // namespace moco::sim
