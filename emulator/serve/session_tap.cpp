// Records a link's tap as a session file (docs/sessions.md).
#include "serve/session_tap.h"

namespace moco::serve {

void SessionTap::OnTraffic(sim::TimeNs t_ns, transport::Direction dir, wire::ByteView bytes) {
  session::SessionEntry e;
  e.t_ns = t_ns;
  e.from =
      dir == transport::Direction::kToDevice ? session::Origin::kHost : session::Origin::kDevice;
  e.bytes.assign(bytes.begin(), bytes.end());
  if (decoder_) {
    const wire::Side side =
        dir == transport::Direction::kToDevice ? wire::Side::kHost : wire::Side::kDevice;
    for (const wire::TranscriptLine& l : decoder_->Feed(side, bytes)) e.decoded.push_back(l.text);
  }
  writer_.Append(e);
}

void SessionTap::OnLinkEvent(sim::TimeNs t_ns, std::string_view kind, std::string_view detail) {
  writer_.Append(session::SessionEntry::Event(
      {{"t_ns", t_ns}, {"event", std::string(kind)}, {"detail", std::string(detail)}}));
}

void SessionTap::OnLineSwitch(sim::TimeNs t_ns, wire::Protocol protocol,
                              const wire::LineSettings& line) {
  writer_.Append(session::LineSwitchEvent(t_ns, protocol, line));
  if (decoder_) decoder_->SwitchTo(protocol);
}

}  // namespace moco::serve
