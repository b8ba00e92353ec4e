// Transcripts of a case's traffic (see transcript.h).
#include "conformance/core/transcript.h"

#include <cstdio>

#include "wire/transcript.h"

namespace moco::conformance {

std::vector<TrafficLine> DecodeTraffic(wire::Protocol protocol, const std::vector<Chunk>& traffic) {
  wire::TranscriptDecoder d(protocol);
  std::vector<TrafficLine> out;
  for (const Chunk& c : traffic) {
    for (auto& l : d.Feed(c.from_host ? wire::Side::kHost : wire::Side::kDevice, c.bytes)) {
      out.push_back({c.t_ns, l.from == wire::Side::kHost, l.problem, std::move(l.text)});
    }
  }
  const TimeNs end = traffic.empty() ? 0 : traffic.back().t_ns;
  for (auto& l : d.Finish()) {
    out.push_back({end, l.from == wire::Side::kHost, l.problem, std::move(l.text)});
  }
  return out;
}

std::string Transcript(wire::Protocol protocol, const std::vector<Chunk>& traffic) {
  std::string out;
  for (const TrafficLine& l : DecodeTraffic(protocol, traffic)) {
    char t[32];
    std::snprintf(t, sizeof t, "%10.3f ms  ", static_cast<double>(l.t_ns) / 1e6);
    out += t;
    out += l.from_host ? "host   > " : "device < ";
    out += l.text;
    out += "\n";
  }
  return out;
}

}  // namespace moco::conformance
