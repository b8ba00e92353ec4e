// Durations in milliseconds and hexadecimal text (see format.h).
#include "base/format.h"

#include <algorithm>
#include <cstdio>

namespace moco::base {

std::string Ms(int64_t ns, int decimals) {
  char buf[48];
  std::snprintf(buf, sizeof buf, "%.*f ms", std::clamp(decimals, 0, 9),
                static_cast<double>(ns) / 1e6);
  return buf;
}

std::string Hex(uint64_t v, int digits) {
  char buf[24];
  std::snprintf(buf, sizeof buf, "0x%0*llx", std::clamp(digits, 1, 16),
                static_cast<unsigned long long>(v));
  return buf;
}

std::string HexBytes(std::span<const uint8_t> bytes) {
  static constexpr char kDigits[] = "0123456789abcdef";
  std::string s;
  s.reserve(bytes.size() * 2);
  for (const uint8_t b : bytes) {
    s.push_back(kDigits[b >> 4]);
    s.push_back(kDigits[b & 0xF]);
  }
  return s;
}

std::optional<uint32_t> ParseHex32(std::string_view text) {
  if (text.size() < 3 || text.size() > 10 || text[0] != '0' || (text[1] != 'x' && text[1] != 'X')) {
    return std::nullopt;
  }
  uint32_t x = 0;
  for (const char c : text.substr(2)) {
    uint32_t d = 0;
    if (c >= '0' && c <= '9') {
      d = static_cast<uint32_t>(c - '0');
    } else if (c >= 'a' && c <= 'f') {
      d = static_cast<uint32_t>(c - 'a' + 10);
    } else if (c >= 'A' && c <= 'F') {
      d = static_cast<uint32_t>(c - 'A' + 10);
    } else {
      return std::nullopt;
    }
    x = x * 16 + d;
  }
  return x;
}

}  // namespace moco::base
