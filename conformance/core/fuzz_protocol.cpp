// The mutation source and the exact replay matcher (see fuzz_protocol.h).
#include "conformance/core/fuzz_protocol.h"

#include <cstring>
#include <iterator>

namespace moco::conformance {
namespace {

// Values at integer edges, and sizes near common receive buffers (a DMC-16's
// 1036 and 1048 bytes, ERRATA 1.2).
constexpr uint32_t kInteresting32[] = {
    0,       1,          2,          0x7f,       0x80,       0xff, 0x100, 0x7fff, 0x8000, 0xffff,
    0x10000, 0x7fffffff, 0x80000000, 0xfffffffe, 0xffffffff, 1000, 10000, 1048,   1036,   100000};

class Exact final : public ReplayMatcher {
 public:
  explicit Exact(std::string why) : why_(std::move(why)) {}
  bool Match(const wire::Bytes&, const wire::Bytes&, TimeNs, int64_t, std::string& why) override {
    why = why_;
    return false;
  }

 private:
  std::string why_;
};

}  // namespace

MutationSource::MutationSource(uint64_t seed) : state_(seed ^ 0x9e3779b97f4a7c15ULL) {}

uint64_t MutationSource::Next() {
  uint64_t z = (state_ += 0x9e3779b97f4a7c15ULL);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

uint64_t MutationSource::Below(uint64_t n) { return Next() % n; }

bool MutationSource::Chance(uint32_t percent) { return Below(100) < percent; }

void MutationSource::MutateDataBytes(wire::Bytes& data) {
  switch (Below(6)) {
    case 0:  // flip one bit
      if (!data.empty()) data[Below(data.size())] ^= static_cast<uint8_t>(1u << Below(8));
      Note("bit-flip");
      break;
    case 1: {  // an interesting value, 1, 2 or 4 bytes wide, little-endian
      const uint32_t v = kInteresting32[Below(std::size(kInteresting32))];
      const size_t width = size_t{1} << Below(3);
      if (data.size() >= width) {
        const size_t at = Below(data.size() - width + 1);
        for (size_t k = 0; k < width; ++k) data[at + k] = static_cast<uint8_t>(v >> (8 * k));
      }
      Note("field-value");
      break;
    }
    case 2:  // a random byte
      if (!data.empty()) data[Below(data.size())] = static_cast<uint8_t>(Next());
      Note("byte");
      break;
    case 3:  // truncate
      if (!data.empty()) data.resize(Below(data.size()));
      Note("truncate");
      break;
    case 4: {  // extend
      const size_t n = 1 + Below(Chance(10) ? 1100 : 8);
      for (size_t k = 0; k < n; ++k) data.push_back(static_cast<uint8_t>(Next()));
      Note("extend");
      break;
    }
    default:  // negate an int32 at an aligned offset
      if (data.size() >= 4) {
        const size_t at = 4 * Below(data.size() / 4);
        uint32_t v = 0;
        std::memcpy(&v, &data[at], 4);
        v = ~v + 1;
        std::memcpy(&data[at], &v, 4);
      }
      Note("negate");
      break;
  }
}

std::string_view FindingKindName(FuzzVerdict::Kind kind) {
  using K = FuzzVerdict::Kind;
  switch (kind) {
    case K::kInvariant:
      return "invariant";
    case K::kHang:
      return "hang";
    case K::kCrash:
      return "crash";
    case K::kStackOverflow:
      return "stack-overflow";
    case K::kStackSmash:
      return "stack-smash";
    case K::kDivisionByZero:
      return "division-by-zero";
    case K::kReset:
      return "reset";
    case K::kPinLaw:
      return "pin-law";
  }
  return "invariant";
}

FuzzVerdict::Kind FindingKindOf(FirmwareFaultKind kind) {
  using K = FuzzVerdict::Kind;
  switch (kind) {
    case FirmwareFaultKind::kCrash:
      return K::kCrash;
    case FirmwareFaultKind::kStackOverflow:
      return K::kStackOverflow;
    case FirmwareFaultKind::kStackSmash:
      return K::kStackSmash;
    case FirmwareFaultKind::kDivisionByZero:
      return K::kDivisionByZero;
    case FirmwareFaultKind::kReset:
      return K::kReset;
  }
  return K::kCrash;
}

std::unique_ptr<ReplayMatcher> ExactMatcher(std::string why) {
  return std::make_unique<Exact>(std::move(why));
}

}  // namespace moco::conformance
