// The call log's format: the one decoder of its entries (call_log.h).
#include "conformance/targets/call_log.h"

namespace moco::conformance::call_log {

size_t MagicLength(std::string_view log) {
  for (std::string_view m : {kMagic, kMagicV1}) {
    if (log.substr(0, m.size()) == m) return m.size();
  }
  return 0;
}

std::string NotALog() {
  return "not a call log (it does not start with " + std::string(kMagic) + " or " +
         std::string(kMagicV1) + ")";
}

bool DecodeEntry(Reader& r, LogEntry& e) {
  e = LogEntry{};
  e.op = r.Byte();
  switch (e.op) {
    case kNow:
      e.num = r.Signed();
      break;
    case kSend:
      e.bytes = r.String();
      e.ok = r.Byte() != 0;
      break;
    case kReceive:
      e.num = r.Signed();
      e.ok = r.Byte() != 0;
      e.bytes = r.String();
      break;
    case kRestart:
      break;
    case kOpen:
    case kLinkLost:
    case kFirmwareStopped:
      e.text = r.Optional();
      break;
    case kSetEStop:
      e.flags = r.Byte();
      e.ok = r.Byte() != 0;
      break;
    case kSetLimit:
    case kSetGio:
      e.num = r.Signed();
      e.flags = r.Byte();
      e.ok = r.Byte() != 0;
      break;
    case kCanPress:
    case kPress:
      e.bytes = r.String();
      e.ok = r.Byte() != 0;
      break;
    case kName:
      e.bytes = r.String();
      break;
    case kFirmwareFaulted:
      e.ok = r.Byte() != 0;
      if (e.ok) {
        e.flags = r.Byte();
        e.bytes = r.String();
        e.texts = r.Strings();
      }
      break;
    case kBacktrace:
    case kCaveats:
      e.texts = r.Strings();
      break;
    case kPins: {
      e.flags = r.Byte();
      if (e.flags == kPinsNone) break;
      if (e.flags > kPinsAllWithFrequency) return false;
      const bool all = e.flags != kPinsSince;
      const uint64_t n = r.Varint();
      if (e.flags == kPinsAllWithFrequency) e.frequency_hz = r.Varint();
      for (uint64_t i = 0; i < n && r.ok(); ++i) {
        LogEntry::PinSignalRead& s = e.pins.emplace_back();
        if (all) s.initial = r.Byte() != 0;
        const uint64_t count = r.Varint();
        for (uint64_t k = 0; k < count && r.ok(); ++k) {
          LogEntry::PinEdgeDelta& d = s.edges.emplace_back();
          d.dt_ns = r.Signed();
          d.cycle = r.Varint();
          d.level = r.Byte() != 0;
        }
      }
      e.num = r.Signed();  // complete_until_ns
      break;
    }
    case kOutputs:
      e.flags = r.Byte();
      break;
    case kDmxValue:
      e.num = r.Signed();
      e.value = r.Signed();
      break;
    case kGioOutputs:
      e.num = static_cast<int64_t>(r.Varint());
      break;
    case kCameraTrace: {
      const uint64_t n = r.Varint();
      TimeNs t = 0;
      for (uint64_t i = 0; i < n && r.ok(); ++i) {
        t = Plus(t, r.Signed());
        const uint8_t b = r.Byte();
        e.camera.push_back({t, static_cast<sim::CameraPort::Line>(b & 0x7F), (b & 0x80) != 0});
      }
      break;
    }
    default:
      return false;
  }
  return r.ok();
}

}  // namespace moco::conformance::call_log
