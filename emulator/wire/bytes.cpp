// Byte-order helpers shared by the three codecs (hex text and error naming).
#include "wire/bytes.h"

namespace moco::wire {

std::string_view KindName(DecodeError::Kind kind) {
  switch (kind) {
    case DecodeError::Kind::kTruncated:
      return "truncated";
    case DecodeError::Kind::kTrailing:
      return "trailing bytes";
    case DecodeError::Kind::kBadValue:
      return "bad value";
    case DecodeError::Kind::kBadLength:
      return "bad length";
    case DecodeError::Kind::kBadChecksum:
      return "bad checksum";
    case DecodeError::Kind::kBadSyntax:
      return "bad syntax";
    case DecodeError::Kind::kUnknown:
      return "unknown";
  }
  return "?";
}

std::string Describe(const DecodeError& e) {
  return std::string(KindName(e.kind)) + " at byte " + std::to_string(e.offset) + ": " + e.detail;
}

std::optional<Bytes> FromHex(std::string_view text) {
  Bytes out;
  int high = -1;
  for (char c : text) {
    if (c == ' ' || c == ':' || c == '-' || c == '\t' || c == '\n') continue;
    int v;
    if (c >= '0' && c <= '9') {
      v = c - '0';
    } else if (c >= 'a' && c <= 'f') {
      v = c - 'a' + 10;
    } else if (c >= 'A' && c <= 'F') {
      v = c - 'A' + 10;
    } else {
      return std::nullopt;
    }
    if (high < 0) {
      high = v;
    } else {
      out.push_back(static_cast<uint8_t>((high << 4) | v));
      high = -1;
    }
  }
  if (high >= 0) return std::nullopt;
  return out;
}

}  // namespace moco::wire
