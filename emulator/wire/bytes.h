// Byte-order helpers shared by the three codecs: little- and big-endian
// integers, IEEE-754 f32, a bounds-checked reader and the decode error value.
// Pure functions only: no I/O, no clock, no logging (ARCHITECTURE "wire").
#ifndef MOCO_WIRE_BYTES_H_
#define MOCO_WIRE_BYTES_H_

#include <bit>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <variant>
#include <vector>

#include "base/format.h"
#include "base/result.h"

namespace moco::wire {

using Bytes = std::vector<uint8_t>;
using ByteView = std::span<const uint8_t>;

// Why a decode failed, and where (byte offset from the start of the input
// handed to the decoding function).
struct DecodeError {
  enum class Kind {
    kTruncated,    // fewer bytes than the layout needs
    kTrailing,     // more bytes than the layout allows
    kBadValue,     // a field holds a value the spec does not allow
    kBadLength,    // a length field is outside the spec's bounds
    kBadChecksum,  // check bytes do not verify
    kBadSyntax,    // (ASCII) a line that does not parse
    kUnknown,      // a message type/command the codec does not know
  };
  Kind kind = Kind::kBadValue;
  size_t offset = 0;
  std::string detail;

  bool operator==(const DecodeError&) const = default;
};

std::string_view KindName(DecodeError::Kind kind);
std::string Describe(const DecodeError& e);

// Result of a decode: the value, or the reason it failed.
template <typename T>
using Result = base::Result<T, DecodeError>;

// Appends fixed-width values to a byte vector. The vector must outlive the writer.
class Writer {
 public:
  explicit Writer(Bytes& out) : out_(out) {}
  void U8(uint8_t v) { out_.push_back(v); }
  void U16Le(uint16_t v) {
    U8(static_cast<uint8_t>(v));
    U8(static_cast<uint8_t>(v >> 8));
  }
  void U32Le(uint32_t v) {
    U16Le(static_cast<uint16_t>(v));
    U16Le(static_cast<uint16_t>(v >> 16));
  }
  void I16Le(int16_t v) { U16Le(static_cast<uint16_t>(v)); }
  void I32Le(int32_t v) { U32Le(static_cast<uint32_t>(v)); }
  void F32Le(float v) { U32Le(std::bit_cast<uint32_t>(v)); }
  void U16Be(uint16_t v) {
    U8(static_cast<uint8_t>(v >> 8));
    U8(static_cast<uint8_t>(v));
  }
  void Raw(ByteView v) { out_.insert(out_.end(), v.begin(), v.end()); }
  void Raw(std::string_view v) { out_.insert(out_.end(), v.begin(), v.end()); }
  size_t size() const { return out_.size(); }

 private:
  Bytes& out_;
};

// Reads fixed-width values from a byte span, never past its end. Each getter
// returns false (and leaves the output untouched) when too few bytes remain.
// The span's storage must outlive the reader.
class Reader {
 public:
  explicit Reader(ByteView in, size_t base_offset = 0) : in_(in), base_(base_offset) {}
  size_t remaining() const { return in_.size() - pos_; }
  bool empty() const { return pos_ == in_.size(); }
  // Offset of the next byte, counted from the caller's origin (base_offset).
  size_t offset() const { return base_ + pos_; }

  bool U8(uint8_t& v) {
    if (remaining() < 1) return false;
    v = in_[pos_++];
    return true;
  }
  bool U16Le(uint16_t& v) {
    if (remaining() < 2) return false;
    v = static_cast<uint16_t>(in_[pos_] | (in_[pos_ + 1] << 8));
    pos_ += 2;
    return true;
  }
  bool U32Le(uint32_t& v) {
    if (remaining() < 4) return false;
    v = static_cast<uint32_t>(in_[pos_]) | (static_cast<uint32_t>(in_[pos_ + 1]) << 8) |
        (static_cast<uint32_t>(in_[pos_ + 2]) << 16) | (static_cast<uint32_t>(in_[pos_ + 3]) << 24);
    pos_ += 4;
    return true;
  }
  bool I16Le(int16_t& v) {
    uint16_t u = 0;
    if (!U16Le(u)) return false;
    v = static_cast<int16_t>(u);
    return true;
  }
  bool I32Le(int32_t& v) {
    uint32_t u = 0;
    if (!U32Le(u)) return false;
    v = static_cast<int32_t>(u);
    return true;
  }
  bool F32Le(float& v) {
    uint32_t u = 0;
    if (!U32Le(u)) return false;
    v = std::bit_cast<float>(u);
    return true;
  }
  bool U16Be(uint16_t& v) {
    if (remaining() < 2) return false;
    v = static_cast<uint16_t>((in_[pos_] << 8) | in_[pos_ + 1]);
    pos_ += 2;
    return true;
  }
  // Takes the next n bytes as a view into the input.
  bool Take(size_t n, ByteView& v) {
    if (remaining() < n) return false;
    v = in_.subspan(pos_, n);
    pos_ += n;
    return true;
  }
  ByteView Rest() {
    ByteView v = in_.subspan(pos_);
    pos_ = in_.size();
    return v;
  }

  // Error values positioned at the reader's current offset.
  DecodeError Truncated(std::string_view what) const {
    return {DecodeError::Kind::kTruncated, offset(), "truncated: " + std::string(what)};
  }
  DecodeError Trailing(std::string_view what) const {
    return {
        DecodeError::Kind::kTrailing, offset(),
        std::to_string(remaining()) + " unexpected trailing byte(s) after " + std::string(what)};
  }

 private:
  ByteView in_;
  size_t pos_ = 0;
  size_t base_ = 0;
};

// Visitor built from lambdas, for std::visit over the codecs' message variants.
template <class... Ts>
struct Overloaded : Ts... {
  using Ts::operator()...;
};
template <class... Ts>
Overloaded(Ts...) -> Overloaded<Ts...>;

// Lower-case hex without separators ("44460100"): base::HexBytes.
inline std::string ToHex(ByteView bytes) { return base::HexBytes(bytes); }
// Parses hex, ignoring spaces, colons and dashes; nullopt on an odd digit
// count or a non-hex character.
std::optional<Bytes> FromHex(std::string_view text);

}  // namespace moco::wire

#endif  // MOCO_WIRE_BYTES_H_
