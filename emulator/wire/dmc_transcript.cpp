// DMC v2 transcripts (see transcript_sides.h): one frame decoder per
// direction, each frame described as a host or device message.
#include <cstdint>
#include <optional>
#include <string>

#include "wire/dmc.h"
#include "wire/dmc_frame.h"
#include "wire/transcript_sides.h"

namespace moco::wire {
namespace {

std::string IdPrefix(uint32_t id) { return "#" + std::to_string(id) + " "; }

// DMC v2: one FrameDecoder per direction; frames decoded as host or device messages.
class DmcSide {
 public:
  explicit DmcSide(Side side) : side_(side) {}

  void Feed(ByteView bytes, std::vector<TranscriptLine>& out) {
    decoder_.Feed(bytes, [&](const dmc::FrameEvent& e) { Handle(e, out); });
  }
  void Finish(std::vector<TranscriptLine>& out) {
    decoder_.Finish([&](const dmc::FrameEvent& e) { Handle(e, out); });
  }
  // Idle line (docs/protocol-notes.md "Idle line", the DMC-16's
  // kLineIdleGapNs): a chunk from this side that comes dmc::kLineIdleGapNs or
  // more after the side's previous one first ends the partial frame the side
  // holds: it is given up and its bytes rescanned, as the device does, so a
  // damaged Length hides nothing past the gap. Skipped bytes are reported
  // there too. The side's own chunks only, as a dissector that shows each
  // line under a packet of its side can follow it (docs/wireshark.md).
  void Elapse(int64_t t_ns, std::vector<TranscriptLine>& out) {
    if (last_ns_ && t_ns - *last_ns_ >= dmc::kLineIdleGapNs &&
        (decoder_.pending_bytes() > 0 || decoder_.unreported_skipped_bytes() > 0)) {
      idle_ = true;
      decoder_.Finish([&](const dmc::FrameEvent& e) { Handle(e, out); });
      idle_ = false;
    }
    last_ns_ = t_ns;
  }

 private:
  void Handle(const dmc::FrameEvent& e, std::vector<TranscriptLine>& out) {
    if (const auto* f = std::get_if<dmc::FrameRef>(&e)) {
      std::string text = IdPrefix(f->id);
      if (side_ == Side::kHost) {
        auto m = dmc::DecodeHostMessage(f->type, f->data);
        if (!m.ok()) {
          out.push_back(
              {side_, true,
               text + dmc::TypeName(f->type) + " malformed: " + wire::Describe(m.error())});
          return;
        }
        out.push_back({side_, false, text + dmc::Describe(*m)});
      } else {
        auto m = dmc::DecodeDeviceMessage(f->type, f->data);
        if (!m.ok()) {
          out.push_back(
              {side_, true,
               text + dmc::TypeName(f->type) + " malformed: " + wire::Describe(m.error())});
          return;
        }
        out.push_back({side_, false, text + dmc::Describe(*m)});
      }
    } else if (const auto* c = std::get_if<dmc::ChecksumError>(&e)) {
      out.push_back({side_, true,
                     IdPrefix(c->id) + dmc::TypeName(c->type) + " BAD CHECKSUM (length " +
                         std::to_string(c->length) + ")"});
    } else if (const auto* fe = std::get_if<dmc::FramingError>(&e)) {
      switch (fe->kind) {
        case dmc::FramingError::Kind::kSkipped:
          out.push_back(
              {side_, true, "skipped " + std::to_string(fe->bytes) + " byte(s) outside any frame"});
          break;
        case dmc::FramingError::Kind::kOversize:
          out.push_back({side_, true,
                         "frame length " + std::to_string(fe->length) + " exceeds 1036: dropped"});
          break;
        case dmc::FramingError::Kind::kTruncated:
          out.push_back(
              {side_, true,
               (idle_ ? "frame given up after 50 ms idle (" : "stream ended inside a frame (") +
                   std::to_string(fe->bytes) + " byte(s) of it)"});
          break;
      }
    }
  }

  Side side_;
  dmc::FrameDecoder decoder_;
  std::optional<int64_t> last_ns_;  // when this side's last chunk crossed
  bool idle_ = false;               // Finish() runs for an idle gap
};

class DmcSides final : public TranscriptSides {
 public:
  void Feed(Side side, ByteView bytes, std::vector<TranscriptLine>& out) override {
    (side == Side::kHost ? host_ : device_).Feed(bytes, out);
  }
  void Elapse(Side side, int64_t t_ns, std::vector<TranscriptLine>& out) override {
    (side == Side::kHost ? host_ : device_).Elapse(t_ns, out);
  }
  void Finish(std::vector<TranscriptLine>& out) override {
    host_.Finish(out);
    device_.Finish(out);
  }

 private:
  DmcSide host_{Side::kHost};
  DmcSide device_{Side::kDevice};
};

}  // namespace

std::unique_ptr<TranscriptSides> MakeDmcTranscript() { return std::make_unique<DmcSides>(); }

}  // namespace moco::wire
