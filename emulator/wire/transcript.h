// Human-readable transcripts of host/device traffic for any of the three
// protocols: frames bytes per direction with each codec's streaming decoder and
// describes every message (used by `mocosim decode` and the reports).
#ifndef MOCO_WIRE_TRANSCRIPT_H_
#define MOCO_WIRE_TRANSCRIPT_H_

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "wire/bytes.h"
#include "wire/protocol.h"

namespace moco::wire {

// One decoded item: a message, or a framing/checksum/parse problem.
struct TranscriptLine {
  Side from = Side::kHost;
  bool problem = false;  // a checksum failure, skipped bytes, a line that does not parse
  std::string text;
};

// A protocol's decoders for both directions (wire/transcript_sides.h).
class TranscriptSides;

// Keeps one streaming decoder per direction. Not thread-safe. Follows the
// line when it changes protocol: as its traffic shows (the protocol's
// LineSwitchWatcher, wire/protocol.h), or as the caller says (SwitchTo: a
// switch recorded beside the traffic, docs/sessions.md "line_switch").
class TranscriptDecoder {
 public:
  explicit TranscriptDecoder(Protocol protocol);
  ~TranscriptDecoder();
  TranscriptDecoder(const TranscriptDecoder&) = delete;
  TranscriptDecoder& operator=(const TranscriptDecoder&) = delete;

  // Feeds a chunk that crossed the link from `from`; returns what it completed.
  std::vector<TranscriptLine> Feed(Side from, ByteView bytes);
  // The same for a chunk that crossed at t_ns (a session's clock): when the
  // chunk comes its protocol's idle gap or more after the previous chunk from
  // the same side, that side first gives up what it holds, as the device
  // does (DMC v2: a partial frame and skipped bytes, dmc::kLineIdleGapNs).
  std::vector<TranscriptLine> Feed(Side from, ByteView bytes, int64_t t_ns);
  // End of the traffic: reports what is left pending in either direction,
  // in every protocol the line spoke.
  std::vector<TranscriptLine> Finish();

  // The protocol the line speaks now.
  Protocol protocol() const { return protocol_; }
  // The line speaks `protocol` from the next byte on; nothing changes when
  // it already does. What the earlier protocol's decoders hold is reported
  // by Finish().
  void SwitchTo(Protocol protocol);

 private:
  void FeedSides(Side from, ByteView bytes, std::vector<TranscriptLine>& out);

  Protocol protocol_;
  std::unique_ptr<TranscriptSides> sides_;
  std::unique_ptr<LineSwitchWatcher> watcher_;
  // The decoders of the protocols the line spoke before, oldest first.
  std::vector<std::unique_ptr<TranscriptSides>> earlier_;
};

}  // namespace moco::wire

#endif  // MOCO_WIRE_TRANSCRIPT_H_
