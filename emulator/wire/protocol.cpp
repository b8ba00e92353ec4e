// The protocol table (see protocol.h). Framing comes from each codec's
// constants: DMC v2 frames (dmc-v2-protocol.txt "Message Format"), DFMoco lines
// (dfmoco-protocol.txt "Message Format"), StackShot packets
// (stackshot-protocol.txt section 2). Each default line is the rate its codec
// names, 8N1: dmc::kBaudRate, dfmoco::kBaudRate, stackshot::kBaudRate, and
// stackshot::kDfMocoBaudRate for a StackShot in DfMoco mode (ERRATA 3.7).
#include "wire/protocol.h"

#include <algorithm>
#include <array>

#include "wire/dfmoco.h"
#include "wire/dmc_constants.h"
#include "wire/dmc_frame.h"
#include "wire/stackshot.h"
#include "wire/stackshot_constants.h"
#include "wire/stackshot_mode_switch.h"
#include "wire/transcript_sides.h"

namespace moco::wire {
namespace {

MessageCut DmcNext(Side /*side*/, ByteView b) {
  for (size_t i = 0; i < b.size(); ++i) {
    if (const size_t n = dmc::WholeFrameAt(b.subspan(i)); n > 0) return {i, n};
  }
  return {b.size(), 0};
}

MessageCut LineNext(Side /*side*/, ByteView b) {
  const auto nl = std::find(b.begin(), b.end(), uint8_t{'\n'});
  if (nl == b.end()) return {b.size(), 0};
  return {0, static_cast<size_t>(nl - b.begin()) + 1};
}

MessageCut StackshotNext(Side side, ByteView b) {
  const uint8_t sync = side == Side::kHost ? stackshot::kSyncHost : stackshot::kSyncDevice;
  for (size_t i = 0; i + stackshot::kMinPacketBytes <= b.size(); ++i) {
    if (b[i] != sync) continue;
    const size_t total = stackshot::kMinPacketBytes + b[i + stackshot::kOffsetLength];
    if (i + total <= b.size()) return {i, total};
  }
  return {b.size(), 0};
}

void DmcRepair(Bytes& m) {
  const auto h = dmc::PeekHeader(m);
  if (!h) return;
  // The data runs to the declared Length, or to what is there before the check bytes.
  const size_t have = m.size() - dmc::kHeaderSize;
  const size_t n = std::min<size_t>(
      {h->length, have >= dmc::kCheckSize ? have - dmc::kCheckSize : 0, dmc::kMaxDataLength});
  const Bytes data(m.begin() + dmc::kHeaderSize,
                   m.begin() + static_cast<ptrdiff_t>(dmc::kHeaderSize + n));
  m.clear();
  dmc::EncodeFrame(h->id, h->type, data, m);
}

void LineRepair(Bytes& m) {
  if (!m.empty() && m.back() == '\n') return;
  if (!m.empty() && m.back() == '\r') m.pop_back();
  m.push_back('\r');
  m.push_back('\n');
}

void StackshotRepair(Bytes& m) {
  auto p = stackshot::PeekHostPacket(m);
  if (!p) return;
  if (p->data.size() > stackshot::kMaxDataBytes) p->data.resize(stackshot::kMaxDataBytes);
  stackshot::Seal(*p, stackshot::kDefaultChecksum);
  m.clear();
  stackshot::EncodePacket(*p, m);
}

Bytes DmcGreeting() {
  Bytes out;
  dmc::EncodeFrame(1, dmc::ToWire(dmc::MsgType::kHi), {}, out);
  return out;
}

Bytes LineGreeting() { return Bytes{'h', 'i', '\r', '\n'}; }

Bytes StackshotGreeting() {
  stackshot::Packet p;
  p.command = static_cast<uint16_t>(stackshot::Command::kPing);
  stackshot::Seal(p, stackshot::kDefaultChecksum);
  Bytes out;
  stackshot::EncodePacket(p, out);
  return out;
}

// One row per protocol, in the enum's order.
const std::array<ProtocolInfo, 4> kProtocols = {{
    {Protocol::kDmc,
     "dmc",
     "DMC v2",
     "DMC-",
     "dmc2",
     {dmc::kBaudRate},
     &DmcNext,
     &DmcRepair,
     &DmcGreeting,
     &MakeDmcTranscript},
    {Protocol::kDfmoco,
     "dfmoco",
     "DFMoco",
     "DFM-",
     "",
     {dfmoco::kBaudRate},
     &LineNext,
     &LineRepair,
     &LineGreeting,
     &MakeDfmocoTranscript},
    {Protocol::kStackshot,
     "stackshot",
     "StackShot 3X",
     "SS-",
     "stackshot3x",
     {stackshot::kBaudRate},
     &StackshotNext,
     &StackshotRepair,
     &StackshotGreeting,
     &MakeStackshotTranscript,
     &stackshot::WatchDfmocoModeSwitch},
    // A StackShot switched to Dragonframe's DfMoco mode speaks DFMoco lines
    // (stackshot-protocol.txt section 3).
    {Protocol::kStackshotDfmoco,
     "stackshot-dfmoco",
     "StackShot 3X (DfMoco mode)",
     "",
     "",
     {stackshot::kDfMocoBaudRate},
     &LineNext,
     &LineRepair,
     &LineGreeting,
     &MakeStackshotDfmocoTranscript,
     nullptr,
     Protocol::kDfmoco},
}};

}  // namespace

std::span<const ProtocolInfo> Protocols() { return kProtocols; }

const ProtocolInfo& Info(Protocol p) { return kProtocols.at(static_cast<size_t>(p)); }

std::unique_ptr<LineSwitchWatcher> WatchLineSwitches(Protocol p) {
  const ProtocolInfo& info = Info(p);
  return info.line_switches != nullptr ? info.line_switches() : nullptr;
}

std::string_view ProtocolName(Protocol p) { return Info(p).name; }

std::optional<Protocol> ParseProtocol(std::string_view name) {
  for (const ProtocolInfo& i : kProtocols) {
    if (i.name == name) return i.id;
  }
  return std::nullopt;
}

std::optional<Protocol> ParseProtocolOrAlias(std::string_view text) {
  for (const ProtocolInfo& i : kProtocols) {
    if (i.name == text || (!i.alias.empty() && i.alias == text)) return i.id;
  }
  return std::nullopt;
}

std::string NameList(std::span<const Protocol> protocols) {
  std::string s;
  for (size_t i = 0; i < protocols.size(); ++i) {
    if (i > 0) s += i + 1 == protocols.size() ? " or " : ", ";
    s += ProtocolName(protocols[i]);
  }
  return s;
}

std::string DefaultBaudList() {
  const auto baud = [](Protocol p) { return std::to_string(Info(p).line.baud); };
  return "DMC v2 " + baud(Protocol::kDmc) + ", DFMoco " + baud(Protocol::kDfmoco) + ", StackShot " +
         baud(Protocol::kStackshot);
}

std::vector<Bytes> SplitMessages(Protocol p, Side side, ByteView stream) {
  std::vector<Bytes> out;
  const auto next = Info(p).next_message;
  size_t i = 0;
  while (i < stream.size()) {
    const MessageCut c = next(side, stream.subspan(i));
    if (c.skip > 0)
      out.emplace_back(stream.begin() + static_cast<ptrdiff_t>(i),
                       stream.begin() + static_cast<ptrdiff_t>(i + c.skip));
    i += c.skip;
    if (c.length == 0) break;
    out.emplace_back(stream.begin() + static_cast<ptrdiff_t>(i),
                     stream.begin() + static_cast<ptrdiff_t>(i + c.length));
    i += c.length;
  }
  return out;
}

Bytes JoinMessages(const std::vector<Bytes>& messages) {
  Bytes out;
  for (const Bytes& m : messages) out.insert(out.end(), m.begin(), m.end());
  return out;
}

}  // namespace moco::wire
