// The call log's format (recorded_target.h, docs/certificates.md): its ops,
// the primitive encodings, a bounds-checked reader and the one decoder of an
// entry, shared by the recording, the playback and the transcript.
//
// Format: "MOCOLOG2" (or the "MOCOLOG1" of mococheck 0.1.0, which has no name,
// output or pin frequency entries), the target's name (a string), its clock
// and restart ability (one byte each), then one entry per call: an op byte
// and its arguments and result. Integers are LEB128 varints, signed ones
// zigzag-coded; times are deltas from the clock value last logged; strings
// are a varint length and the bytes.
#ifndef MOCO_CONFORMANCE_TARGETS_CALL_LOG_H_
#define MOCO_CONFORMANCE_TARGETS_CALL_LOG_H_

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "conformance/targets/target.h"

namespace moco::conformance {
namespace call_log {

constexpr std::string_view kMagic = "MOCOLOG2";
constexpr std::string_view kMagicV1 = "MOCOLOG1";

enum Op : uint8_t {
  kNow = 1,
  kSend = 2,
  kReceive = 3,
  kRestart = 4,
  kOpen = 5,
  kSetEStop = 6,
  kSetLimit = 7,
  kSetGio = 8,
  kCanPress = 9,
  kPress = 10,
  kLinkLost = 11,
  kFirmwareStopped = 12,
  kFirmwareFaulted = 13,
  kBacktrace = 14,
  kPins = 15,
  kCaveats = 16,
  kName = 17,     // the target's name changed (not a call)
  kOutputs = 18,  // Outputs(): which outputs can be read
  kDmxValue = 19,
  kGioOutputs = 20,
  kCameraTrace = 21,
};

// A pin read's kinds: none, the edges since the last read, all of them (a
// new trace), all of them with the MCU's frequency.
constexpr uint8_t kPinsNone = 0, kPinsSince = 1, kPinsAll = 2, kPinsAllWithFrequency = 3;

inline const char* OpName(uint8_t op) {
  switch (op) {
    case kNow:
      return "read the clock";
    case kSend:
      return "sent bytes";
    case kReceive:
      return "waited for bytes";
    case kRestart:
      return "restarted the device";
    case kOpen:
      return "opened the device";
    case kSetEStop:
      return "set the e-stop";
    case kSetLimit:
      return "set a limit input";
    case kSetGio:
      return "set an I/O input";
    case kCanPress:
      return "asked for a button";
    case kPress:
      return "pressed a button";
    case kLinkLost:
      return "asked whether the link was lost";
    case kFirmwareStopped:
    case kFirmwareFaulted:
    case kBacktrace:
      return "asked whether the firmware stopped";
    case kPins:
      return "read the pins";
    case kCaveats:
      return "asked for the target's caveats";
    case kName:
      return "named the target";
    case kOutputs:
      return "asked for the device's outputs";
    case kDmxValue:
      return "read a DMX level";
    case kGioOutputs:
      return "read the I/O outputs";
    case kCameraTrace:
      return "read the camera lines";
    default:
      return "made an unknown call";
  }
}

inline void PutVarint(std::string& s, uint64_t v) {
  while (v >= 0x80) {
    s.push_back(static_cast<char>((v & 0x7F) | 0x80));
    v >>= 7;
  }
  s.push_back(static_cast<char>(v));
}
inline void PutSigned(std::string& s, int64_t v) {
  PutVarint(s, (static_cast<uint64_t>(v) << 1) ^ static_cast<uint64_t>(v >> 63));
}
inline void PutString(std::string& s, std::string_view v) {
  PutVarint(s, v.size());
  s.append(v);
}
inline void PutOptional(std::string& s, const std::optional<std::string>& v) {
  s.push_back(v ? 1 : 0);
  if (v) PutString(s, *v);
}
inline void PutStrings(std::string& s, const std::vector<std::string>& v) {
  PutVarint(s, v.size());
  for (const std::string& one : v) PutString(s, one);
}

// a + b, wrapping: a crafted log's deltas never overflow (and never make the
// sanitizers stop verify).
inline TimeNs Plus(TimeNs a, int64_t b) {
  return static_cast<TimeNs>(static_cast<uint64_t>(a) + static_cast<uint64_t>(b));
}
inline int64_t Minus(TimeNs a, TimeNs b) {
  return static_cast<int64_t>(static_cast<uint64_t>(a) - static_cast<uint64_t>(b));
}

// Which outputs a DeviceOutputs can read, as kOutputs logs them.
constexpr uint8_t kDmxBit = 1, kGioBit = 2, kCameraBit = 4;

// The length of the log's magic when it is one this mococheck reads, else 0.
size_t MagicLength(std::string_view log);
// Why a log with neither magic is refused.
std::string NotALog();

// Reads entries from a log; every read is bounds-checked, and a damaged log
// leaves ok() false (reads then give zeros and empty strings).
class Reader {
 public:
  Reader(std::string_view log, size_t& at) : log_(log), at_(at) {}
  bool ok() const { return ok_; }
  bool AtEnd() const { return at_ >= log_.size(); }
  uint8_t Byte() {
    if (at_ >= log_.size()) return Bad();
    return static_cast<uint8_t>(log_[at_++]);
  }
  uint64_t Varint() {
    uint64_t v = 0;
    for (int shift = 0; shift < 64; shift += 7) {
      const uint8_t b = Byte();
      if (!ok_) return 0;
      v |= static_cast<uint64_t>(b & 0x7F) << shift;
      if ((b & 0x80) == 0) return v;
    }
    return Bad();
  }
  int64_t Signed() {
    const uint64_t z = Varint();
    return static_cast<int64_t>((z >> 1) ^ (~(z & 1) + 1));
  }
  std::string_view String() {
    const uint64_t n = Varint();
    if (!ok_ || n > log_.size() - at_) {
      Bad();
      return {};
    }
    const std::string_view v = log_.substr(at_, n);
    at_ += n;
    return v;
  }
  std::optional<std::string> Optional() {
    if (Byte() == 0) return std::nullopt;
    return std::string(String());
  }
  std::vector<std::string> Strings() {
    const uint64_t n = Varint();
    std::vector<std::string> v;
    for (uint64_t i = 0; i < n && ok_; ++i) v.emplace_back(String());
    return v;
  }

 private:
  uint8_t Bad() {
    ok_ = false;
    at_ = log_.size();
    return 0;
  }
  std::string_view log_;
  size_t& at_;
  bool ok_ = true;
};

}  // namespace call_log

// One call of a log, decoded: which fields hold what depends on `op` (see
// DecodeEntry).
struct LogEntry {
  struct PinEdgeDelta {
    int64_t dt_ns = 0;  // from the signal's previous edge (0 for its first)
    uint64_t cycle = 0;
    bool level = false;
  };
  struct PinSignalRead {
    bool initial = false;  // kPinsAll*: the level before the first edge
    std::vector<PinEdgeDelta> edges;
  };

  uint8_t op = 0;
  int64_t num = 0;    // a time delta; a limit set, I/O bit or DMX channel; the I/O outputs
  int64_t value = 0;  // a DMX level
  uint8_t flags = 0;  // a byte argument: a level, limit flags, a fault's kind, a pin read's kind,
                      // the outputs that can be read
  bool ok = false;    // the call's result; kFirmwareFaulted: a fault was reported
  std::string_view bytes;                     // bytes sent or received, a button, a name, a fault
  std::optional<std::string> text;            // kOpen, kLinkLost, kFirmwareStopped
  std::vector<std::string> texts;             // a backtrace, caveats
  uint64_t frequency_hz = 0;                  // kPinsAllWithFrequency
  std::vector<PinSignalRead> pins;            // kPins
  std::vector<sim::CameraPort::Edge> camera;  // kCameraTrace, times absolute
};

namespace call_log {

// Reads the entry at the reader's position into `e`; false when it is cut
// short or its op is unknown (`e.op` holds the op read).
bool DecodeEntry(Reader& r, LogEntry& e);

}  // namespace call_log
}  // namespace moco::conformance

#endif  // MOCO_CONFORMANCE_TARGETS_CALL_LOG_H_
