// A serial line's settings: its rate and how each character is framed. The
// one type for a line, from the protocol table's default lines
// (wire/protocol.h) to the line a device model declares (devices/device.h
// DeviceLine) and the pacing a transport derives from it.
#ifndef MOCO_WIRE_LINE_H_
#define MOCO_WIRE_LINE_H_

#include <cstdint>

namespace moco::wire {

// No flow control. The defaults are 8N1 without a rate: a line nobody gave a
// rate moves 0 bytes/s, which a transport takes as "do not pace". Each
// protocol's rate is a named constant of its codec (dmc::kBaudRate,
// dfmoco::kBaudRate, stackshot::kBaudRate), read through the protocol table.
struct LineSettings {
  uint32_t baud = 0;
  uint8_t data_bits = 8;
  uint8_t stop_bits = 1;
  char parity = 'N';  // 'N', 'E' or 'O'

  // Characters per second on the wire: each carries a start bit, the data
  // bits, a parity bit unless 'N', and the stop bits (baud / 10 for 8N1).
  constexpr uint32_t BytesPerSecond() const {
    const uint32_t bits = 1u + data_bits + (parity == 'N' ? 0u : 1u) + stop_bits;
    return baud / bits;
  }
  bool operator==(const LineSettings&) const = default;
};

}  // namespace moco::wire

#endif  // MOCO_WIRE_LINE_H_
