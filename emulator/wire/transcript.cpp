// Human-readable transcripts of host/device traffic for every protocol: the
// protocol table names each protocol's decoder (wire/protocol.h).
#include "wire/transcript.h"

#include "wire/transcript_sides.h"

namespace moco::wire {

TranscriptDecoder::TranscriptDecoder(Protocol protocol) : sides_(Info(protocol).transcript()) {}

TranscriptDecoder::~TranscriptDecoder() = default;

std::vector<TranscriptLine> TranscriptDecoder::Feed(Side from, ByteView bytes) {
  std::vector<TranscriptLine> out;
  sides_->Feed(from, bytes, out);
  return out;
}

std::vector<TranscriptLine> TranscriptDecoder::Finish() {
  std::vector<TranscriptLine> out;
  sides_->Finish(out);
  return out;
}

}  // namespace moco::wire
