// Packet framing of the Cognisys StackShot / StackShot 3X binary protocol
// (stackshot-protocol.txt section 2 "Packet format", section 4.2 for Wi-Fi;
// ERRATA.md 3.2): the frame as bytes, its checksum, a streaming decoder.
// The typed payloads are in wire/stackshot.h. Pure functions only.
//
// Checksums (ERRATA 3.2): the spec only says the byte is "sent but not
// currently verified", and known hosts send a constant (0x69 or 0x00, see
// FACTS.md). Decoding therefore never rejects a packet for its checksum; the
// streaming decoder flags a mismatch against the configured algorithm. The
// default algorithm (kNegatedSum) is the two's-complement negation of the
// 8-bit sum of every byte after the sync byte up to the last data byte, so
// that the 8-bit sum of command, action, length, data and checksum is zero.
#ifndef MOCO_WIRE_STACKSHOT_FRAME_H_
#define MOCO_WIRE_STACKSHOT_FRAME_H_

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string_view>
#include <vector>

#include "wire/bytes.h"
#include "wire/stackshot_constants.h"

namespace moco::stackshot {

using wire::Bytes;
using wire::ByteView;
using wire::DecodeError;
using wire::Result;

// ---------------------------------------------------------------------------
// Checksum
// ---------------------------------------------------------------------------
enum class ChecksumAlgorithm : uint8_t {
  kNegatedSum,  // -(sum of bytes 1 .. 4+len) mod 256; the emulator's default
  kConstant69,  // always 0x69 (one published Python/C++ host family)
  kConstant00,  // always 0x00 (one published Java host)
};
inline constexpr ChecksumAlgorithm kDefaultChecksum = ChecksumAlgorithm::kNegatedSum;

std::string_view ChecksumAlgorithmName(ChecksumAlgorithm algorithm);  // "negated-sum", ...
std::optional<ChecksumAlgorithm> ParseChecksumAlgorithm(std::string_view name);

// ---------------------------------------------------------------------------
// Packet framing
// ---------------------------------------------------------------------------
struct Packet {
  bool from_device = false;    // sync 0xAA (true) or 0x55 (false)
  uint16_t command = 0;        // big-endian on the wire
  uint8_t action = 0;          // low nibble of the action/status byte (comm_action_t)
  uint8_t axis = 0;            // bits 4-5: 0 = X, 1 = Y, 2 = Z (3 is carried, undefined)
  bool sub_item = false;       // bit 7: second item of a shutter output
  bool reserved_bit6 = false;  // bit 6: undocumented, carried so re-encoding is exact
  Bytes data;                  // at most kMaxDataBytes
  uint8_t checksum = 0;        // as received, or as set by Seal()

  bool operator==(const Packet&) const = default;
};

// The action/status byte of p. REQUIRES: p.action < 16, p.axis < 4.
uint8_t ActionByte(const Packet& p);
// The checksum `algorithm` gives for p's header and data (p.checksum ignored).
uint8_t ComputeChecksum(ChecksumAlgorithm algorithm, const Packet& p);
// Sets p.checksum from the algorithm.
void Seal(Packet& p, ChecksumAlgorithm algorithm);
bool ChecksumMatches(const Packet& p, ChecksumAlgorithm algorithm);

// Appends the packet's bytes (with p.checksum as stored) to out. Returns false
// and appends nothing when p.data is longer than kMaxDataBytes.
bool EncodePacket(const Packet& p, Bytes& out);
// Decodes a buffer that holds exactly one packet. Errors: kBadValue at 0
// (no sync byte), kTruncated, kTrailing. The checksum is not verified.
Result<Packet> DecodePacket(ByteView frame);

// The packet that starts at bytes[0] taken apart without judging it (for the
// fuzz mutator): a host packet (sync 0x55) with a whole header; its data runs
// to the length byte or to what is there before the checksum byte. nullopt
// when no host packet header starts there.
std::optional<Packet> PeekHostPacket(ByteView bytes);

// One packet cut from a byte stream.
struct DecodedPacket {
  Packet packet;
  bool checksum_ok = true;        // packet.checksum equals the configured algorithm's
  uint8_t expected_checksum = 0;  // what the configured algorithm gives
  size_t skipped_before = 0;      // garbage bytes dropped since the previous packet

  bool operator==(const DecodedPacket&) const = default;
};

// Cuts packets from a byte stream delivered in any chunking. Hunts for the
// sync byte of one direction (host 0x55 or device 0xAA), drops and counts
// anything else, and holds at most one partial packet (kMaxPacketBytes).
// Every length is valid (u8), so a sync byte inside garbage starts a false
// packet that runs for its length byte; the spec's 2 ms inter-frame gap is
// the recovery, and a transport that sees such a gap calls Flush().
class PacketDecoder {
 public:
  explicit PacketDecoder(bool from_device, ChecksumAlgorithm checksum = kDefaultChecksum);

  // Consumes all of `bytes`; appends each completed packet to out.
  // Returns the number of packets appended.
  size_t Feed(ByteView bytes, std::vector<DecodedPacket>& out);
  // Drops a partial packet (inter-frame gap). Returns the bytes dropped,
  // which also count as skipped.
  size_t Flush();

  size_t pending_bytes() const { return len_; }
  // Bytes skipped (no sync byte, or a dropped partial packet) that no packet
  // has reported yet as its `skipped_before`.
  size_t skipped_pending() const { return skipped_pending_; }
  uint64_t skipped_total() const { return skipped_total_; }
  uint64_t packets_total() const { return packets_total_; }
  bool from_device() const { return sync_ == kSyncDevice; }

 private:
  void Complete(std::vector<DecodedPacket>& out);

  uint8_t sync_;
  ChecksumAlgorithm checksum_;
  std::array<uint8_t, kMaxPacketBytes> buf_{};
  size_t len_ = 0;
  size_t skipped_pending_ = 0;
  uint64_t skipped_total_ = 0;
  uint64_t packets_total_ = 0;
};

// Wi-Fi (section 4.2): "The maximum size of a single packet is set to 1000
// bytes. Any command exceeding this amount will have to be broken into
// smaller packet transmissions." No serial packet exceeds kMaxPacketBytes
// (261), so no command is ever split; the rule bounds how many whole packets
// one TCP write may batch. SplitForWifi cuts a stream of whole encoded
// packets into writes of at most max_bytes without splitting any packet.
// Errors: kBadValue where a packet should start but no sync byte is,
// kTruncated for a partial packet at the end, kBadLength when one packet is
// longer than max_bytes.
Result<std::vector<Bytes>> SplitForWifi(ByteView stream, size_t max_bytes = kWifiMaxPacketBytes);

}  // namespace moco::stackshot

#endif  // MOCO_WIRE_STACKSHOT_FRAME_H_
