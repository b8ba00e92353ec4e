// StackShot 3X transcripts (see transcript_sides.h). A line switched to
// DfMoco mode (wire/stackshot_mode_switch.h) is followed by the transcript
// decoder, as every line that changes protocol (wire/transcript.h).
#include <map>
#include <string>

#include "wire/stackshot.h"
#include "wire/stackshot_constants.h"
#include "wire/transcript_sides.h"

namespace moco::wire {
namespace {

// StackShot binary: packets per direction; a reply is read in the light of the
// action of the last host packet for the same command.
class StackshotSides final : public TranscriptSides {
 public:
  StackshotSides() : host_(false), device_(true) {}

  void Feed(Side side, ByteView bytes, std::vector<TranscriptLine>& out) override {
    std::vector<stackshot::DecodedPacket> packets;
    (side == Side::kHost ? host_ : device_).Feed(bytes, packets);
    Describe(side, packets, out);
  }

  void Finish(std::vector<TranscriptLine>& out) override {
    for (const Side side : {Side::kHost, Side::kDevice}) {
      stackshot::PacketDecoder& d = side == Side::kHost ? host_ : device_;
      const size_t partial = d.Flush();
      // Bytes after the last packet with no sync byte among them are skipped
      // too, though no packet follows to report them.
      if (const size_t junk = d.skipped_pending() - partial; junk > 0) {
        out.push_back(
            {side, true,
             "skipped " + std::to_string(junk) + " byte(s) at the end, with no sync byte"});
      }
      if (partial > 0) {
        out.push_back({side, true, std::to_string(partial) + " byte(s) of an incomplete packet"});
      }
    }
  }

 private:
  void Describe(Side side, const std::vector<stackshot::DecodedPacket>& packets,
                std::vector<TranscriptLine>& out) {
    for (const auto& d : packets) {
      if (d.skipped_before > 0) {
        out.push_back(
            {side, true,
             "skipped " + std::to_string(d.skipped_before) + " byte(s) before a sync byte"});
      }
      out.push_back(Line(side, d));
    }
  }

  // A packet's line, refused or not, ends with the checksum note when its
  // checksum byte is not the default algorithm's (ERRATA 3.2: never a reason
  // to refuse it, but a damaged packet often explains a refused layout).
  TranscriptLine Line(Side side, const stackshot::DecodedPacket& d) {
    const std::string note =
        d.checksum_ok ? "" : " [checksum byte differs from the default algorithm]";
    if (side == Side::kHost) {
      last_action_[d.packet.command] = static_cast<stackshot::Action>(d.packet.action);
      auto c = stackshot::DecodeHostPacket(d.packet);
      if (!c.ok()) {
        return {side, true,
                stackshot::Describe(d.packet) + ": " + wire::Describe(c.error()) + note};
      }
      return {side, false, stackshot::Describe(*c) + note};
    }
    stackshot::ReplyContext ctx;
    if (auto it = last_action_.find(d.packet.command); it != last_action_.end()) {
      ctx.request_action = it->second;
    }
    auto r = stackshot::DecodeDevicePacket(d.packet, ctx);
    if (!r.ok()) {
      return {side, true, stackshot::Describe(d.packet) + ": " + wire::Describe(r.error()) + note};
    }
    return {side, false, stackshot::Describe(*r) + note};
  }

  stackshot::PacketDecoder host_;
  stackshot::PacketDecoder device_;
  std::map<uint16_t, stackshot::Action> last_action_;
};

}  // namespace

std::unique_ptr<TranscriptSides> MakeStackshotTranscript() {
  return std::make_unique<StackshotSides>();
}

}  // namespace moco::wire
