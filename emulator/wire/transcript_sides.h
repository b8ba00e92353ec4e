// What a protocol gives the transcript decoder (wire/transcript.h): its
// decoders for both directions, made by the factory its row of the protocol
// table names (wire/protocol.h). One file per protocol implements it
// (dmc_transcript.cpp, dfmoco_transcript.cpp, stackshot_transcript.cpp).
#ifndef MOCO_WIRE_TRANSCRIPT_SIDES_H_
#define MOCO_WIRE_TRANSCRIPT_SIDES_H_

#include <memory>
#include <vector>

#include "wire/bytes.h"
#include "wire/protocol.h"
#include "wire/transcript.h"

namespace moco::wire {

class TranscriptSides {
 public:
  virtual ~TranscriptSides() = default;
  // Frames and describes a chunk that crossed the link from `side`.
  virtual void Feed(Side side, ByteView bytes, std::vector<TranscriptLine>& out) = 0;
  // A chunk from `side` is about to be fed at t_ns: when its line has been
  // idle long enough, the side gives up what it holds. The default keeps
  // everything until Finish().
  virtual void Elapse(Side side, int64_t t_ns, std::vector<TranscriptLine>& out) {
    (void)side;
    (void)t_ns;
    (void)out;
  }
  // End of the traffic: what is left pending in either direction.
  virtual void Finish(std::vector<TranscriptLine>& out) = 0;
};

std::unique_ptr<TranscriptSides> MakeDmcTranscript();
std::unique_ptr<TranscriptSides> MakeDfmocoTranscript();
std::unique_ptr<TranscriptSides> MakeStackshotTranscript();
std::unique_ptr<TranscriptSides> MakeStackshotDfmocoTranscript();

}  // namespace moco::wire

#endif  // MOCO_WIRE_TRANSCRIPT_SIDES_H_
