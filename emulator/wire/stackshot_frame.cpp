// Packet framing and checksums of the Cognisys StackShot / StackShot 3X
// binary protocol (stackshot-protocol.txt section 2 "Packet format", section
// 4.2 for Wi-Fi; ERRATA.md 3.2 for the checksum).
#include "wire/stackshot_frame.h"

#include <algorithm>
#include <cstring>

namespace moco::stackshot {

using wire::Writer;

// ---------------------------------------------------------------------------
// Checksum
// ---------------------------------------------------------------------------
std::string_view ChecksumAlgorithmName(ChecksumAlgorithm algorithm) {
  switch (algorithm) {
    case ChecksumAlgorithm::kNegatedSum:
      return "negated-sum";
    case ChecksumAlgorithm::kConstant69:
      return "constant-0x69";
    case ChecksumAlgorithm::kConstant00:
      return "constant-0x00";
  }
  return "?";
}

std::optional<ChecksumAlgorithm> ParseChecksumAlgorithm(std::string_view name) {
  for (auto a : {ChecksumAlgorithm::kNegatedSum, ChecksumAlgorithm::kConstant69,
                 ChecksumAlgorithm::kConstant00}) {
    if (ChecksumAlgorithmName(a) == name) return a;
  }
  return std::nullopt;
}

uint8_t ActionByte(const Packet& p) {
  return static_cast<uint8_t>((p.action & kActionMask) | ((p.axis << kAxisShift) & kAxisMask) |
                              (p.reserved_bit6 ? kReservedBit6 : 0) |
                              (p.sub_item ? kSubItemBit : 0));
}

uint8_t ComputeChecksum(ChecksumAlgorithm algorithm, const Packet& p) {
  switch (algorithm) {
    case ChecksumAlgorithm::kConstant69:
      return 0x69;
    case ChecksumAlgorithm::kConstant00:
      return 0x00;
    case ChecksumAlgorithm::kNegatedSum:
      break;
  }
  unsigned sum = (p.command >> 8) + (p.command & 0xFFu) + ActionByte(p) +
                 static_cast<unsigned>(p.data.size() & 0xFF);
  for (uint8_t b : p.data) sum += b;
  return static_cast<uint8_t>(0x100u - (sum & 0xFFu));
}

void Seal(Packet& p, ChecksumAlgorithm algorithm) { p.checksum = ComputeChecksum(algorithm, p); }

bool ChecksumMatches(const Packet& p, ChecksumAlgorithm algorithm) {
  return p.checksum == ComputeChecksum(algorithm, p);
}

// ---------------------------------------------------------------------------
// Framing
// ---------------------------------------------------------------------------
bool EncodePacket(const Packet& p, Bytes& out) {
  if (p.data.size() > kMaxDataBytes) return false;
  Writer w(out);
  w.U8(p.from_device ? kSyncDevice : kSyncHost);
  w.U16Be(p.command);
  w.U8(ActionByte(p));
  w.U8(static_cast<uint8_t>(p.data.size()));
  w.Raw(p.data);
  w.U8(p.checksum);
  return true;
}

namespace {
Packet PacketFromFrame(const uint8_t* f, size_t data_len) {
  Packet p;
  p.from_device = f[kOffsetSync] == kSyncDevice;
  p.command = static_cast<uint16_t>((f[kOffsetCommand] << 8) | f[kOffsetCommand + 1]);
  const uint8_t a = f[kOffsetAction];
  p.action = a & kActionMask;
  p.axis = static_cast<uint8_t>((a & kAxisMask) >> kAxisShift);
  p.reserved_bit6 = (a & kReservedBit6) != 0;
  p.sub_item = (a & kSubItemBit) != 0;
  p.data.assign(f + kOffsetData, f + kOffsetData + data_len);
  p.checksum = f[kOffsetData + data_len];
  return p;
}
}  // namespace

std::optional<Packet> PeekHostPacket(ByteView m) {
  if (m.size() < kHeaderBytes || m[0] != kSyncHost) return std::nullopt;
  Packet p;
  p.from_device = false;
  p.command = static_cast<uint16_t>((m[kOffsetCommand] << 8) | m[kOffsetCommand + 1]);
  const uint8_t action = m[kOffsetAction];
  p.action = action & kActionMask;
  p.axis = static_cast<uint8_t>((action & kAxisMask) >> kAxisShift);
  p.reserved_bit6 = (action & kReservedBit6) != 0;
  p.sub_item = (action & kSubItemBit) != 0;
  const size_t have = m.size() - kHeaderBytes;
  const size_t n = std::min<size_t>(m[kOffsetLength], have >= kChecksumBytes ? have - 1 : 0);
  p.data.assign(m.begin() + kOffsetData, m.begin() + static_cast<ptrdiff_t>(kOffsetData + n));
  return p;
}

Result<Packet> DecodePacket(ByteView frame) {
  if (frame.empty()) return DecodeError{DecodeError::Kind::kTruncated, 0, "empty frame"};
  if (frame[0] != kSyncHost && frame[0] != kSyncDevice) {
    return DecodeError{DecodeError::Kind::kBadValue, 0,
                       "sync byte 0x" + wire::ToHex(frame.first(1)) + " is neither 0x55 nor 0xaa"};
  }
  if (frame.size() < kMinPacketBytes) {
    return DecodeError{DecodeError::Kind::kTruncated, frame.size(),
                       "a packet has at least 6 bytes"};
  }
  const size_t data_len = frame[kOffsetLength];
  const size_t total = kMinPacketBytes + data_len;
  if (frame.size() < total) {
    return DecodeError{DecodeError::Kind::kTruncated, frame.size(),
                       "length byte announces " + std::to_string(data_len) + " data bytes"};
  }
  if (frame.size() > total) {
    return DecodeError{DecodeError::Kind::kTrailing, total,
                       std::to_string(frame.size() - total) + " byte(s) after the checksum"};
  }
  return PacketFromFrame(frame.data(), data_len);
}

PacketDecoder::PacketDecoder(bool from_device, ChecksumAlgorithm checksum)
    : sync_(from_device ? kSyncDevice : kSyncHost), checksum_(checksum) {}

size_t PacketDecoder::Feed(ByteView bytes, std::vector<DecodedPacket>& out) {
  const size_t before = out.size();
  const uint8_t* in = bytes.data();
  const size_t n = bytes.size();
  size_t i = 0;
  while (i < n) {
    if (len_ == 0) {
      const void* hit = std::memchr(in + i, sync_, n - i);
      if (hit == nullptr) {
        skipped_pending_ += n - i;
        skipped_total_ += n - i;
        break;
      }
      const auto pos = static_cast<size_t>(static_cast<const uint8_t*>(hit) - in);
      skipped_pending_ += pos - i;
      skipped_total_ += pos - i;
      buf_[0] = sync_;
      len_ = 1;
      i = pos + 1;
      continue;
    }
    const size_t need = len_ < kHeaderBytes ? kHeaderBytes : kMinPacketBytes + buf_[kOffsetLength];
    const size_t take = std::min(need - len_, n - i);
    std::memcpy(buf_.data() + len_, in + i, take);
    len_ += take;
    i += take;
    if (len_ >= kHeaderBytes && len_ == kMinPacketBytes + buf_[kOffsetLength]) Complete(out);
  }
  return out.size() - before;
}

void PacketDecoder::Complete(std::vector<DecodedPacket>& out) {
  DecodedPacket d;
  d.packet = PacketFromFrame(buf_.data(), buf_[kOffsetLength]);
  d.expected_checksum = ComputeChecksum(checksum_, d.packet);
  d.checksum_ok = d.expected_checksum == d.packet.checksum;
  d.skipped_before = skipped_pending_;
  out.push_back(std::move(d));
  skipped_pending_ = 0;
  len_ = 0;
  ++packets_total_;
}

size_t PacketDecoder::Flush() {
  const size_t dropped = len_;
  skipped_pending_ += dropped;
  skipped_total_ += dropped;
  len_ = 0;
  return dropped;
}

Result<std::vector<Bytes>> SplitForWifi(ByteView stream, size_t max_bytes) {
  std::vector<Bytes> writes;
  Bytes current;
  size_t pos = 0;
  while (pos < stream.size()) {
    if (stream[pos] != kSyncHost && stream[pos] != kSyncDevice) {
      return DecodeError{DecodeError::Kind::kBadValue, pos, "no sync byte where a packet starts"};
    }
    if (stream.size() - pos < kHeaderBytes) {
      return DecodeError{DecodeError::Kind::kTruncated, stream.size(), "partial packet header"};
    }
    const size_t total = kMinPacketBytes + stream[pos + kOffsetLength];
    if (stream.size() - pos < total) {
      return DecodeError{DecodeError::Kind::kTruncated, stream.size(), "partial packet"};
    }
    if (total > max_bytes) {
      return DecodeError{DecodeError::Kind::kBadLength, pos,
                         "a " + std::to_string(total) + "-byte packet exceeds the " +
                             std::to_string(max_bytes) + "-byte write limit"};
    }
    if (current.size() + total > max_bytes) {
      writes.push_back(std::move(current));
      current.clear();
    }
    current.insert(current.end(), stream.begin() + static_cast<std::ptrdiff_t>(pos),
                   stream.begin() + static_cast<std::ptrdiff_t>(pos + total));
    pos += total;
  }
  if (!current.empty()) writes.push_back(std::move(current));
  return writes;
}

}  // namespace moco::stackshot
