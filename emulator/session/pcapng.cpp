// pcapng writer (pcapng specification, IETF draft-ietf-opsawg-pcapng:
// section 4.1 Section Header Block, 4.2 Interface Description Block, 4.3
// Enhanced Packet Block, 3.5 options). Little-endian, as the byte-order
// magic says; every block and option padded to 32 bits.
#include "session/pcapng.h"

#include <string_view>

namespace moco::session {
namespace {

constexpr uint32_t kSectionHeaderBlock = 0x0A0D0D0A;
constexpr uint32_t kInterfaceDescriptionBlock = 0x00000001;
constexpr uint32_t kEnhancedPacketBlock = 0x00000006;
constexpr uint32_t kByteOrderMagic = 0x1A2B3C4D;

constexpr uint16_t kOptEndOfOpt = 0;
constexpr uint16_t kOptComment = 1;
constexpr uint16_t kShbUserAppl = 4;
constexpr uint16_t kIfName = 2;
constexpr uint16_t kIfDescription = 3;
constexpr uint16_t kIfTsResol = 9;
constexpr uint16_t kEpbFlags = 2;
// epb_flags bits 0-1: 01 inbound, 10 outbound, seen from the host's side of
// the link (where a capture of Dragonframe's traffic is taken).
constexpr uint32_t kEpbInbound = 0x1;
constexpr uint32_t kEpbOutbound = 0x2;

class Block {
 public:
  explicit Block(uint32_t type) {
    U32(type);
    U32(0);  // total length, filled by Finish()
  }
  void U16(uint16_t v) {
    s_.push_back(static_cast<char>(v & 0xff));
    s_.push_back(static_cast<char>(v >> 8));
  }
  void U32(uint32_t v) {
    U16(static_cast<uint16_t>(v & 0xffff));
    U16(static_cast<uint16_t>(v >> 16));
  }
  void U64(uint64_t v) {
    U32(static_cast<uint32_t>(v & 0xffffffffu));
    U32(static_cast<uint32_t>(v >> 32));
  }
  void Raw(std::string_view bytes) {
    s_.append(bytes);
    Pad();
  }
  void Option(uint16_t code, std::string_view value) {
    // An option's value is at most 65535 bytes; longer text is cut.
    const std::string_view v = value.substr(0, 0xfffc);
    U16(code);
    U16(static_cast<uint16_t>(v.size()));
    Raw(v);
  }
  void OptionU32(uint16_t code, uint32_t value) {
    U16(code);
    U16(4);
    U32(value);
  }
  void EndOptions() {
    U16(kOptEndOfOpt);
    U16(0);
  }
  void Finish(std::string& out) {
    const auto total = static_cast<uint32_t>(s_.size() + 4);
    U32(total);
    for (int i = 0; i < 4; ++i) s_[4 + i] = static_cast<char>((total >> (8 * i)) & 0xff);
    out += s_;
  }

 private:
  void Pad() {
    while (s_.size() % 4 != 0) s_.push_back('\0');
  }
  std::string s_;
};

void Interface(const std::string& protocol, const char* direction, std::string& out) {
  Block b(kInterfaceDescriptionBlock);
  b.U16(kPcapngLinkTypeUser0);
  b.U16(0);  // reserved
  b.U32(0);  // snaplen: no limit
  b.Option(kIfName, direction);
  b.Option(kIfDescription, "mocosim " + protocol + " " + direction);
  b.U16(kIfTsResol);
  b.U16(1);
  b.Raw(std::string_view("\x09", 1));  // 10^-9 s: the session's nanoseconds
  b.EndOptions();
  b.Finish(out);
}

}  // namespace

std::string SessionToPcapng(const Session& session, PcapngStats* stats) {
  PcapngStats counted;
  std::string out;
  {
    Block b(kSectionHeaderBlock);
    b.U32(kByteOrderMagic);
    b.U16(1);             // major version
    b.U16(0);             // minor version
    b.U64(~uint64_t{0});  // section length: not given
    if (!session.header.note.empty()) b.Option(kOptComment, session.header.note);
    b.Option(kShbUserAppl, "mocosim export --pcapng");
    b.EndOptions();
    b.Finish(out);
  }
  auto interfaces = [&out](Protocol p) {
    const std::string protocol(ProtocolName(p));
    Interface(protocol, "host->device", out);
    Interface(protocol, "device->host", out);
  };
  Protocol speaking = session.header.protocol;
  interfaces(speaking);
  uint32_t pair = 0;  // 2 x the interfaces of the protocol spoken now

  for (const SessionEntry& e : session.entries) {
    if (e.is_event) {
      const std::optional<Protocol> next = LineSwitchOf(e);
      if (!next) {
        ++counted.events_left_out;
      } else if (*next != speaking) {
        speaking = *next;
        interfaces(speaking);
        pair += 2;
        ++counted.line_switches;
      }
      continue;
    }
    const bool from_host = e.from == Origin::kHost;
    const uint64_t t = e.t_ns < 0 ? 0 : static_cast<uint64_t>(e.t_ns);
    const std::string_view bytes(reinterpret_cast<const char*>(e.bytes.data()), e.bytes.size());
    for (size_t at = 0; at < bytes.size(); at += kPcapngMaxPacketBytes) {
      const std::string_view piece = bytes.substr(at, kPcapngMaxPacketBytes);
      Block b(kEnhancedPacketBlock);
      b.U32(pair + (from_host ? kPcapngHostToDevice : kPcapngDeviceToHost));
      b.U32(static_cast<uint32_t>(t >> 32));
      b.U32(static_cast<uint32_t>(t & 0xffffffffu));
      b.U32(static_cast<uint32_t>(piece.size()));  // captured
      b.U32(static_cast<uint32_t>(piece.size()));  // on the wire
      b.Raw(piece);
      b.OptionU32(kEpbFlags, from_host ? kEpbOutbound : kEpbInbound);
      b.EndOptions();
      b.Finish(out);
      ++counted.packets;
      counted.bytes += piece.size();
    }
  }
  if (stats != nullptr) *stats = counted;
  return out;
}

}  // namespace moco::session
