// The link between a sketch built against the host Arduino core and the runner
// that drives it (ARCHITECTURE "conformance": the native target drives the core
// through a small clock-and-serial interface): one SOCK_SEQPACKET socket the
// runner hands the firmware process as file descriptor kLinkFd, one message per
// packet, integers little-endian. Time is the firmware's simulated time in
// nanoseconds since the process started; it moves only while the runner has
// granted it (Run), so two runs of the same traffic are identical.
//
//   runner -> firmware
//     kRun      i64 until_ns, u8 stop_at_output, then the host's bytes for the
//               protocol port (they enter its line at the current time)
//     kAttach   u8 port (Port), then u16 pins to watch, each a pin number;
//               sent once, first, before any kRun
//   firmware -> runner
//     kHello    u32 version (kLinkVersion), the board's name (u8 length + text),
//               u16 count, then per pin of the board's port map: u16 pin,
//               u8 port letter ('B', 'D', ...), u8 bit; sent once, at start
//     kOutput   per byte: i64 t_ns (its stop bit has been sent), u8 value
//     kEdges    per edge: i64 t_ns, u16 pin, u8 level
//     kNote     text: something the core does not model that the sketch used,
//               said once each (a caveat for the run report)
//     kYield    i64 now_ns, i64 line_free_ns (the host's line is idle from
//               here), i64 frame_ns (one byte on the host's line; 0: not paced),
//               u32 bytes dropped by a full receive buffer since the last kYield;
//               ends every kRun's answer
//     kStopped  u8 fault (Fault), then text: the sketch can run no further (an
//               API the core refuses, or a fault signal: a bad memory access,
//               an illegal instruction, a division by zero, an abort); the
//               process exits after it
#ifndef MOCO_CONFORMANCE_ARDUINO_LINK_H_
#define MOCO_CONFORMANCE_ARDUINO_LINK_H_

#include <cstdint>
#include <cstring>
#include <string>
#include <string_view>
#include <vector>

namespace moco::arduino::link {

inline constexpr int kLinkFd = 3;
inline constexpr uint32_t kLinkVersion = 1;
// The environment variable that tells the core it runs under the runner.
inline constexpr const char* kLinkEnv = "MOCO_NATIVE_LINK";
// Where a packet is cut: larger output is sent in several packets.
inline constexpr size_t kMaxPacketBytes = 60 * 1024;

enum class Type : uint8_t {
  kRun = 1,
  kAttach = 2,
  kHello = 16,
  kOutput = 17,
  kEdges = 18,
  kNote = 19,
  kYield = 20,
  kStopped = 21,
};

// What stopped the sketch (kStopped).
enum class Fault : uint8_t { kRefused = 0, kCrash = 1, kDivisionByZero = 2 };

// Which of the sketch's serial ports carries the protocol.
enum class Port : uint8_t { kSerial = 0, kSerial1 = 1, kSerial2 = 2, kBluetooth = 3 };

inline void Put(std::vector<uint8_t>& out, uint64_t v, int bytes) {
  for (int i = 0; i < bytes; ++i) out.push_back(static_cast<uint8_t>(v >> (8 * i)));
}

// Reads a packet front to back; a read past its end gives 0 and sets `bad`.
class Reader {
 public:
  Reader(const uint8_t* data, size_t size) : data_(data), size_(size) {}
  uint64_t Get(int bytes) {
    if (size_ - pos_ < static_cast<size_t>(bytes)) {
      bad = true;
      pos_ = size_;
      return 0;
    }
    uint64_t v = 0;
    for (int i = 0; i < bytes; ++i) v |= uint64_t{data_[pos_ + i]} << (8 * i);
    pos_ += bytes;
    return v;
  }
  int64_t GetI64() { return static_cast<int64_t>(Get(8)); }
  std::string_view Rest() {
    const std::string_view r(reinterpret_cast<const char*>(data_ + pos_), size_ - pos_);
    pos_ = size_;
    return r;
  }
  size_t left() const { return size_ - pos_; }
  bool bad = false;

 private:
  const uint8_t* data_;
  size_t size_;
  size_t pos_ = 0;
};

inline constexpr size_t kOutputRecord = 9;  // i64 t_ns, u8 value
inline constexpr size_t kEdgeRecord = 11;   // i64 t_ns, u16 pin, u8 level

}  // namespace moco::arduino::link

#endif  // MOCO_CONFORMANCE_ARDUINO_LINK_H_
