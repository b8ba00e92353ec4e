// DFMoco transcripts (see transcript_sides.h), also for a StackShot in
// Dragonframe's DfMoco mode.
#include <string>

#include "wire/dfmoco.h"
#include "wire/transcript_sides.h"

namespace moco::wire {
namespace {

// DFMoco and the StackShot's DfMoco dialect: lines, parsed with the dialect the
// device announced in `hi`.
class DfmocoSides final : public TranscriptSides {
 public:
  explicit DfmocoSides(bool stackshot)
      : stackshot_(stackshot),
        dialect_(stackshot ? dfmoco::StackShot3x() : dfmoco::Dfmoco2()),
        framers_{dfmoco::LineFramer(), dfmoco::LineFramer()} {}

  void Feed(Side side, ByteView bytes, std::vector<TranscriptLine>& out) override {
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

  void Finish(std::vector<TranscriptLine>& out) override {
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

}  // namespace

std::unique_ptr<TranscriptSides> MakeDfmocoTranscript() {
  return std::make_unique<DfmocoSides>(false);
}

std::unique_ptr<TranscriptSides> MakeStackshotDfmocoTranscript() {
  return std::make_unique<DfmocoSides>(true);
}

}  // namespace moco::wire
