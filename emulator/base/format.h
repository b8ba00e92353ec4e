// Small text formats every layer writes: durations in milliseconds and
// values and bytes in hexadecimal.
#ifndef MOCO_BASE_FORMAT_H_
#define MOCO_BASE_FORMAT_H_

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>

namespace moco::base {

// A duration in nanoseconds as milliseconds with `decimals` (0..9) digits
// after the point: Ms(12'345'678) is "12.3 ms", Ms(12'345'678, 3) "12.346 ms".
std::string Ms(int64_t ns, int decimals = 1);

// `v` as "0x" and lower-case hex digits, zero-padded to at least `digits`
// (1..16): Hex(0x7ff, 4) is "0x07ff", Hex(0x12345, 4) "0x12345".
std::string Hex(uint64_t v, int digits);

// Lower-case hex without separators, two digits a byte: "44460100".
std::string HexBytes(std::span<const uint8_t> bytes);

// A "0x..." or "0X..." string of 1 to 8 hex digits (either case) as its value;
// nullopt for anything else (no prefix, no digits, a non-hex character, more
// than 32 bits).
std::optional<uint32_t> ParseHex32(std::string_view text);

}  // namespace moco::base

#endif  // MOCO_BASE_FORMAT_H_
