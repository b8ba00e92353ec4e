// What the random-sequence cases of every protocol share (random.cpp,
// dfmoco_random.cpp, stackshot_random.cpp) and the fuzz campaign: shrinking
// a failing sequence by dropping chunks of it, and saving the traffic of a
// failing run as a session file (docs/sessions.md).
#ifndef MOCO_CONFORMANCE_SUITES_SEQUENCE_H_
#define MOCO_CONFORMANCE_SUITES_SEQUENCE_H_

#include <algorithm>
#include <cstddef>
#include <string>
#include <utility>
#include <vector>

#include "conformance/runner/host.h"
#include "conformance/targets/target.h"
#include "wire/transcript.h"

namespace moco::conformance {

// Drops chunks of `items` (half the sequence, then halves of that, down to
// single items) while `still_fails(fewer)` says the shorter sequence still
// fails; at most `budget` attempts. Returns the shortest failing sequence found.
template <typename T, typename StillFails>
std::vector<T> ShrinkSequence(std::vector<T> items, int budget, StillFails&& still_fails) {
  for (size_t chunk = std::max<size_t>(items.size() / 2, 1); chunk >= 1 && budget > 0; chunk /= 2) {
    for (size_t at = 0; at < items.size() && budget > 0;) {
      std::vector<T> fewer = items;
      fewer.erase(fewer.begin() + static_cast<std::ptrdiff_t>(at),
                  fewer.begin() + static_cast<std::ptrdiff_t>(std::min(at + chunk, fewer.size())));
      --budget;
      if (still_fails(fewer)) {
        items = std::move(fewer);
      } else {
        at += chunk;
      }
    }
    if (chunk == 1) break;
  }
  return items;
}

// Writes `traffic` (as it crossed the link to `target`) to `path` as a
// session of `protocol` with `note`, atomically, and adds a line to `log`
// saying where it went or why it could not be written.
void SaveFailingSession(const std::string& path, wire::Protocol protocol, const Target& target,
                        const std::string& note, const std::vector<Chunk>& traffic,
                        std::vector<std::string>& log);

}  // namespace moco::conformance

#endif  // MOCO_CONFORMANCE_SUITES_SEQUENCE_H_
