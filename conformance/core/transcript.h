// The traffic of a case as people read it, for every protocol alike: each
// direction framed and described by the wire codecs (wire::TranscriptDecoder),
// one line per message or problem, with its time. The console log of a failed
// case, the random suites' failing sequences and the HTML report use it.
#ifndef MOCO_CONFORMANCE_CORE_TRANSCRIPT_H_
#define MOCO_CONFORMANCE_CORE_TRANSCRIPT_H_

#include <string>
#include <vector>

#include "conformance/core/host_link.h"
#include "wire/protocol.h"

namespace moco::conformance {

struct TrafficLine {
  TimeNs t_ns = 0;  // when the chunk that completed it crossed the link
  bool from_host = true;
  bool problem = false;  // a checksum failure, skipped bytes, a line that does not parse
  std::string text;
};

std::vector<TrafficLine> DecodeTraffic(wire::Protocol protocol, const std::vector<Chunk>& traffic);
// One line per message: "     12.345 ms  host   > ..." / "device < ...".
std::string Transcript(wire::Protocol protocol, const std::vector<Chunk>& traffic);

}  // namespace moco::conformance

#endif  // MOCO_CONFORMANCE_CORE_TRANSCRIPT_H_
