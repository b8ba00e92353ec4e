// Value Change Dump text (IEEE 1364 section 18): one-bit wires, 1 ns timescale.
#include "base/vcd.h"

#include <algorithm>
#include <tuple>

namespace moco::base {
namespace {

std::string Clean(std::string_view text) {
  std::string out;
  for (const char c : text) {
    const bool plain = c > ' ' && c < 127 && c != '$';
    out.push_back(plain ? c : '_');
  }
  return out.empty() ? "_" : out;
}

}  // namespace

std::string VcdIdentifier(size_t index) {
  constexpr size_t kBase = 94;  // '!' .. '~'
  std::string id;
  do {
    id.push_back(static_cast<char>('!' + index % kBase));
    index /= kBase;
  } while (index > 0);
  return id;
}

std::string VcdText(std::string_view scope, std::string_view comment,
                    const std::vector<VcdWire>& wires) {
  std::string out;
  out += "$version mocosim $end\n";
  if (!comment.empty()) {
    std::string c(comment);
    std::replace(c.begin(), c.end(), '\n', ' ');
    // "$end" inside a comment would end it early.
    for (size_t at = c.find("$end"); at != std::string::npos; at = c.find("$end", at)) c[at] = '_';
    out += "$comment " + c + " $end\n";
  }
  out += "$timescale 1 ns $end\n";
  out += "$scope module " + Clean(scope) + " $end\n";
  for (size_t i = 0; i < wires.size(); ++i) {
    out += "$var wire 1 " + VcdIdentifier(i) + " " + Clean(wires[i].name) + " $end\n";
  }
  out += "$upscope $end\n$enddefinitions $end\n";
  out += "#0\n$dumpvars\n";
  for (size_t i = 0; i < wires.size(); ++i) {
    out += (wires[i].initial ? "1" : "0") + VcdIdentifier(i) + "\n";
  }
  out += "$end\n";
  // (time, wire, level), merged; a wire's changes stay in their order.
  std::vector<std::tuple<int64_t, size_t, size_t>> order;  // time, wire, index
  for (size_t i = 0; i < wires.size(); ++i) {
    for (size_t k = 0; k < wires[i].changes.size(); ++k) {
      order.emplace_back(std::max<int64_t>(0, wires[i].changes[k].first), i, k);
    }
  }
  std::stable_sort(order.begin(), order.end(),
                   [](const auto& a, const auto& b) { return std::get<0>(a) < std::get<0>(b); });
  std::vector<bool> level(wires.size());
  for (size_t i = 0; i < wires.size(); ++i) level[i] = wires[i].initial;
  int64_t now = 0;
  for (const auto& [t, i, k] : order) {
    const bool v = wires[i].changes[k].second;
    if (v == level[i]) continue;
    level[i] = v;
    if (t != now) {
      now = t;
      out += "#" + std::to_string(t) + "\n";
    }
    out += (v ? "1" : "0") + VcdIdentifier(i) + "\n";
  }
  return out;
}

}  // namespace moco::base
