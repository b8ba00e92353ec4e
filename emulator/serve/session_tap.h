// Records a link's tap as a session file (docs/sessions.md): traffic lines
// with the scheduler timestamps and link events, through session::SessionWriter.
#ifndef MOCO_SERVE_SESSION_TAP_H_
#define MOCO_SERVE_SESSION_TAP_H_

#include <memory>
#include <optional>

#include "session/session.h"
#include "transport/traffic.h"
#include "wire/transcript.h"

namespace moco::serve {

// A TrafficObserver writing every chunk and event to a SessionWriter:
// kToDevice -> "from": "host", kToHost -> "from": "device"; an event becomes
// {"event": <kind>, "detail": <detail>}. The writer must outlive the tap and
// its header should say "clock": "virtual" (times are scheduler times).
// With a protocol, each traffic line also carries "decoded": the one-line
// descriptions of the messages that chunk completed. A switch of the
// device's line to another protocol is a "line_switch" event.
class SessionTap final : public transport::TrafficObserver {
 public:
  explicit SessionTap(session::SessionWriter& writer,
                      std::optional<wire::Protocol> protocol = std::nullopt)
      : writer_(writer),
        decoder_(protocol ? std::make_unique<wire::TranscriptDecoder>(*protocol) : nullptr) {}
  void OnTraffic(sim::TimeNs t_ns, transport::Direction dir, wire::ByteView bytes) override;
  void OnLinkEvent(sim::TimeNs t_ns, std::string_view kind, std::string_view detail) override;
  // A "line_switch" event (session::LineSwitchEvent); "decoded" follows it.
  void OnLineSwitch(sim::TimeNs t_ns, wire::Protocol protocol,
                    const wire::LineSettings& line) override;

 private:
  session::SessionWriter& writer_;
  std::unique_ptr<wire::TranscriptDecoder> decoder_;
};

}  // namespace moco::serve

#endif  // MOCO_SERVE_SESSION_TAP_H_
