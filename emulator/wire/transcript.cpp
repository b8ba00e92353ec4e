// Human-readable transcripts of host/device traffic for the three protocols.
#include "wire/transcript.h"

#include <map>
#include <utility>

#include "wire/dfmoco.h"
#include "wire/dmc.h"
#include "wire/dmc_frame.h"
#include "wire/stackshot.h"

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
               "stream ended inside a frame (" + std::to_string(fe->bytes) + " byte(s) of it)"});
          break;
      }
    }
  }

  Side side_;
  dmc::FrameDecoder decoder_;
};

// DFMoco and the StackShot's DfMoco dialect: lines, parsed with the dialect the
// device announced in `hi`.
class DfmocoSides {
 public:
  explicit DfmocoSides(bool stackshot)
      : stackshot_(stackshot),
        dialect_(stackshot ? dfmoco::StackShot3x() : dfmoco::Dfmoco2()),
        framers_{dfmoco::LineFramer(), dfmoco::LineFramer()} {}

  void Feed(Side side, ByteView bytes, std::vector<TranscriptLine>& out) {
    std::string_view text(reinterpret_cast<const char*>(bytes.data()), bytes.size());
    auto& framer = framers_[side == Side::kHost ? 0 : 1];
    framer.Feed(text, [&](const dfmoco::FrameEvent& e) {
      if (e.kind == dfmoco::FrameEvent::Kind::kOverflow) {
        out.push_back(
            {side, true, "line longer than " + std::to_string(dfmoco::kMaxLineBytes) + " bytes"});
        return;
      }
      Line(side, e.text, out);
    });
  }

  void Finish(std::vector<TranscriptLine>& out) {
    for (int i = 0; i < 2; ++i) {
      if (framers_[i].buffered() > 0) {
        out.push_back({i == 0 ? Side::kHost : Side::kDevice, true,
                       std::to_string(framers_[i].buffered()) +
                           " byte(s) of an unterminated line (no \\r\\n)"});
        framers_[i].Reset();
      }
    }
  }

 private:
  void Line(Side side, std::string_view line, std::vector<TranscriptLine>& out) {
    if (side == Side::kHost) {
      auto c = dfmoco::ParseHostLine(line, dialect_);
      if (!c.ok()) {
        out.push_back({side, true, "\"" + std::string(line) + "\": " + Describe(c.error())});
        return;
      }
      out.push_back({side, false, dfmoco::Describe(*c)});
      return;
    }
    auto r = dfmoco::ParseDeviceLine(line, dialect_);
    if (!r.ok()) {
      out.push_back({side, true, "\"" + std::string(line) + "\": " + Describe(r.error())});
      return;
    }
    if (const auto* hi = std::get_if<dfmoco::HelloReply>(&*r)) {
      dialect_ = dfmoco::DialectFrom(*hi, stackshot_);
    }
    out.push_back({side, false, dfmoco::Describe(*r, dialect_)});
  }

  bool stackshot_;
  dfmoco::Dialect dialect_;
  dfmoco::LineFramer framers_[2];
};

// StackShot binary: packets per direction; a reply is read in the light of the
// action of the last host packet for the same command.
class StackshotSides {
 public:
  StackshotSides() : host_(false), device_(true) {}

  void Feed(Side side, ByteView bytes, std::vector<TranscriptLine>& out) {
    std::vector<stackshot::DecodedPacket> packets;
    (side == Side::kHost ? host_ : device_).Feed(bytes, packets);
    for (const auto& d : packets) {
      if (d.skipped_before > 0) {
        out.push_back(
            {side, true,
             "skipped " + std::to_string(d.skipped_before) + " byte(s) before a sync byte"});
      }
      std::string note;
      if (!d.checksum_ok) note = " [checksum byte differs from the default algorithm]";
      if (side == Side::kHost) {
        last_action_[d.packet.command] = static_cast<stackshot::Action>(d.packet.action);
        auto c = stackshot::DecodeHostPacket(d.packet);
        if (!c.ok()) {
          out.push_back(
              {side, true, stackshot::Describe(d.packet) + ": " + wire::Describe(c.error())});
          continue;
        }
        out.push_back({side, false, stackshot::Describe(*c) + note});
      } else {
        stackshot::ReplyContext ctx;
        if (auto it = last_action_.find(d.packet.command); it != last_action_.end()) {
          ctx.request_action = it->second;
        }
        auto r = stackshot::DecodeDevicePacket(d.packet, ctx);
        if (!r.ok()) {
          out.push_back(
              {side, true, stackshot::Describe(d.packet) + ": " + wire::Describe(r.error())});
          continue;
        }
        out.push_back({side, false, stackshot::Describe(*r) + note});
      }
    }
  }

  void Finish(std::vector<TranscriptLine>& out) {
    if (size_t n = host_.Flush()) {
      out.push_back({Side::kHost, true, std::to_string(n) + " byte(s) of an incomplete packet"});
    }
    if (size_t n = device_.Flush()) {
      out.push_back({Side::kDevice, true, std::to_string(n) + " byte(s) of an incomplete packet"});
    }
  }

 private:
  stackshot::PacketDecoder host_;
  stackshot::PacketDecoder device_;
  std::map<uint16_t, stackshot::Action> last_action_;
};

}  // namespace

struct TranscriptDecoder::Impl {
  Protocol protocol;
  std::optional<DmcSide> dmc_host, dmc_device;
  std::optional<DfmocoSides> dfmoco;
  std::optional<StackshotSides> stackshot;
};

TranscriptDecoder::TranscriptDecoder(Protocol protocol) : impl_(std::make_unique<Impl>()) {
  impl_->protocol = protocol;
  switch (protocol) {
    case Protocol::kDmc:
      impl_->dmc_host.emplace(Side::kHost);
      impl_->dmc_device.emplace(Side::kDevice);
      break;
    case Protocol::kDfmoco:
      impl_->dfmoco.emplace(false);
      break;
    case Protocol::kStackshotDfmoco:
      impl_->dfmoco.emplace(true);
      break;
    case Protocol::kStackshot:
      impl_->stackshot.emplace();
      break;
  }
}

TranscriptDecoder::~TranscriptDecoder() = default;

std::vector<TranscriptLine> TranscriptDecoder::Feed(Side from, ByteView bytes) {
  std::vector<TranscriptLine> out;
  if (impl_->dmc_host) {
    (from == Side::kHost ? *impl_->dmc_host : *impl_->dmc_device).Feed(bytes, out);
  } else if (impl_->dfmoco) {
    impl_->dfmoco->Feed(from, bytes, out);
  } else {
    impl_->stackshot->Feed(from, bytes, out);
  }
  return out;
}

std::vector<TranscriptLine> TranscriptDecoder::Finish() {
  std::vector<TranscriptLine> out;
  if (impl_->dmc_host) {
    impl_->dmc_host->Finish(out);
    impl_->dmc_device->Finish(out);
  } else if (impl_->dfmoco) {
    impl_->dfmoco->Finish(out);
  } else {
    impl_->stackshot->Finish(out);
  }
  return out;
}

}  // namespace moco::wire
