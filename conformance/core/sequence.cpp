// Saving a failing run's traffic (see sequence.h).
#include "conformance/core/sequence.h"

#include <exception>

#include "session/session.h"

namespace moco::conformance {

void SaveFailingSession(const std::string& path, wire::Protocol protocol, const Target& target,
                        const std::string& note, const std::vector<Chunk>& traffic,
                        std::vector<std::string>& log) {
  session::SessionHeader header;
  header.protocol = protocol;
  header.device = target.Name();
  header.clock = target.VirtualClock() ? "virtual" : "real";
  header.note = note;
  try {
    session::SessionWriter w(path, header);
    for (const Chunk& ch : traffic) {
      session::SessionEntry e;
      e.t_ns = ch.t_ns;
      e.from = ch.from_host ? session::Origin::kHost : session::Origin::kDevice;
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
