// Records a link's tap as a session file (docs/sessions.md).
#include "transport/session_tap.h"

namespace moco::transport {

void SessionTap::OnTraffic(sim::TimeNs t_ns, Direction dir, wire::ByteView bytes) {
  control::SessionEntry e;
  e.t_ns = t_ns;
  e.from = dir == Direction::kToDevice ? control::Origin::kHost : control::Origin::kDevice;
  e.bytes.assign(bytes.begin(), bytes.end());
  if (decoder_) {
    const wire::Side side = dir == Direction::kToDevice ? wire::Side::kHost : wire::Side::kDevice;
    for (const wire::TranscriptLine& l : decoder_->Feed(side, bytes)) e.decoded.push_back(l.text);
  }
  writer_.Append(e);
}

void SessionTap::OnLinkEvent(sim::TimeNs t_ns, std::string_view kind, std::string_view detail) {
  writer_.Append(control::SessionEntry::Event(
      {{"t_ns", t_ns}, {"event", std::string(kind)}, {"detail", std::string(detail)}}));
}

}  // namespace moco::transport
