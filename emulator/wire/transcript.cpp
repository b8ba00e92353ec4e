// Human-readable transcripts of host/device traffic for every protocol: the
// protocol table names each protocol's decoder (wire/protocol.h).
#include "wire/transcript.h"

#include <algorithm>

#include "wire/transcript_sides.h"

namespace moco::wire {
namespace {

// A line of a transcript is text a terminal shows: bytes a device sent that
// are control characters (an ESC sequence that would clear the screen, a NUL
// that would cut the line) or not ASCII are written as \xNN.
std::vector<TranscriptLine> Printable(std::vector<TranscriptLine> lines) {
  static constexpr char kHex[] = "0123456789abcdef";
  for (TranscriptLine& l : lines) {
    const bool clean = std::all_of(l.text.begin(), l.text.end(), [](char c) {
      const auto u = static_cast<unsigned char>(c);
      return u >= 0x20 && u < 0x7f;
    });
    if (clean) continue;
    std::string text;
    for (const char c : l.text) {
      const auto u = static_cast<unsigned char>(c);
      if (u >= 0x20 && u < 0x7f) {
        text.push_back(c);
      } else {
        text += "\\x";
        text.push_back(kHex[u >> 4]);
        text.push_back(kHex[u & 0xF]);
      }
    }
    l.text = std::move(text);
  }
  return lines;
}

}  // namespace

TranscriptDecoder::TranscriptDecoder(Protocol protocol)
    : protocol_(protocol),
      sides_(Info(protocol).transcript()),
      watcher_(WatchLineSwitches(protocol)) {}

TranscriptDecoder::~TranscriptDecoder() = default;

void TranscriptDecoder::SwitchTo(Protocol protocol) {
  if (protocol == protocol_) return;
  earlier_.push_back(std::move(sides_));
  protocol_ = protocol;
  sides_ = Info(protocol).transcript();
  watcher_ = WatchLineSwitches(protocol);
}

void TranscriptDecoder::FeedSides(Side from, ByteView bytes, std::vector<TranscriptLine>& out) {
  while (watcher_ != nullptr) {
    const std::optional<LineSwitchAt> at = watcher_->Feed(from, bytes);
    if (!at) break;
    sides_->Feed(from, bytes.first(at->offset), out);
    out.push_back({from, false, "(the line switches to " + at->note + ")"});
    SwitchTo(at->protocol);
    bytes = bytes.subspan(at->offset);
  }
  sides_->Feed(from, bytes, out);
}

std::vector<TranscriptLine> TranscriptDecoder::Feed(Side from, ByteView bytes) {
  std::vector<TranscriptLine> out;
  FeedSides(from, bytes, out);
  return Printable(std::move(out));
}

std::vector<TranscriptLine> TranscriptDecoder::Feed(Side from, ByteView bytes, int64_t t_ns) {
  std::vector<TranscriptLine> out;
  sides_->Elapse(from, t_ns, out);
  FeedSides(from, bytes, out);
  return Printable(std::move(out));
}

std::vector<TranscriptLine> TranscriptDecoder::Finish() {
  std::vector<TranscriptLine> out;
  for (const auto& s : earlier_) s->Finish(out);
  sides_->Finish(out);
  return Printable(std::move(out));
}

}  // namespace moco::wire
