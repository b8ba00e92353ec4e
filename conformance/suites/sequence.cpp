// Saving a failing run's traffic (see sequence.h).
#include "conformance/suites/sequence.h"

#include <exception>

#include "session/session.h"

namespace moco::conformance {

void SaveFailingSession(const std::string& path, wire::Protocol protocol, const Target& target,
                        const std::string& note, const std::vector<Chunk>& traffic,
                        std::vector<std::string>& log) {
  control::SessionHeader header;
  header.protocol = protocol;
  header.device = target.Name();
  header.clock = target.VirtualClock() ? "virtual" : "real";
  header.note = note;
  try {
    control::SessionWriter w(path, header);
    for (const Chunk& ch : traffic) {
      control::SessionEntry e;
      e.t_ns = ch.t_ns;
      e.from = ch.from_host ? control::Origin::kHost : control::Origin::kDevice;
      e.bytes = ch.bytes;
      w.Append(e);
    }
    std::string error;
    if (w.Finish(&error)) {
      log.push_back("saved the failing session to " + path);
    } else {
      log.push_back("could not save the session: " + error);
    }
  } catch (const std::exception& e) {
    log.push_back(std::string("could not save the session: ") + e.what());
  }
}

}  // namespace moco::conformance
