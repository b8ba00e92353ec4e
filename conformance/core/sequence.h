// What the random-sequence cases of every protocol share (dmc_random.cpp,
// dfmoco_random.cpp, stackshot_random.cpp) and the fuzz campaign: shrinking
// a failing sequence by dropping chunks of it, saving the traffic of a
// failing run as a session file (docs/sessions.md), and the driver that runs
// a drawn sequence, shrinks it when it fails and reports it.
#ifndef MOCO_CONFORMANCE_CORE_SEQUENCE_H_
#define MOCO_CONFORMANCE_CORE_SEQUENCE_H_

#include <algorithm>
#include <cstddef>
#include <functional>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "conformance/core/host_link.h"
#include "conformance/core/transcript.h"
#include "conformance/core/verdicts.h"
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

// How one protocol's random suite plays a sequence of `Step`s on its `Host`.
template <typename Host, typename Step>
struct RandomPlay {
  wire::Protocol protocol = wire::Protocol::kDmc;
  std::string note;         // the saved session's note: "mococheck random sequence"
  int shrink_budget = 300;  // fresh runs the shrinking may take
  // Greets a fresh device; false when it did not answer.
  std::function<bool(Host&)> greet;
  // Plays `steps`, checking each answer and the model's end state.
  std::function<void(Host&, Verdicts&, const std::vector<Step>&)> execute;
  std::function<std::string(const Step&)> describe;
};

// The random suite's case for every protocol: plays `steps` on the case's
// host. When a MUST rule failed, the log says so; on a restartable target the
// sequence is shrunk (chunks dropped while a fresh run still fails), played
// once more for its transcript, listed and saved (random.session_path); on
// any other target it is listed with the transcript as it ran.
template <typename Context, typename Step>
void PlayRandomSequence(Context& c, std::vector<Step> steps,
                        const RandomPlay<std::remove_reference_t<decltype(c.host)>, Step>& play) {
  using Host = std::remove_reference_t<decltype(c.host)>;
  play.execute(c.host, c.v, steps);
  if (!c.v.MustFailed()) return;
  c.log.push_back("random sequence (seed " + std::to_string(c.random.seed) + ") failed after " +
                  std::to_string(steps.size()) + " steps");
  if (!c.target.CanRestart()) {
    for (const Step& s : steps) c.log.push_back("  " + play.describe(s));
    c.log.push_back("transcript:");
    c.log.push_back(Transcript(play.protocol, c.host.traffic()));
    return;
  }
  steps = ShrinkSequence(std::move(steps), play.shrink_budget, [&](const std::vector<Step>& fewer) {
    c.target.Restart();
    Verdicts v;
    Host h(c.target, v, c.host_options);
    h.set_greeting(true);
    if (!play.greet(h)) return true;
    h.set_greeting(false);
    play.execute(h, v, fewer);
    h.Close();
    return v.MustFailed();
  });
  // The shortest failing sequence once more, for its transcript.
  c.target.Restart();
  Verdicts v;
  Host h(c.target, v, c.host_options);
  h.set_greeting(true);
  play.greet(h);
  h.set_greeting(false);
  play.execute(h, v, steps);
  h.Close();
  c.log.push_back("shrunk to " + std::to_string(steps.size()) + " step(s):");
  for (const Step& s : steps) c.log.push_back("  " + play.describe(s));
  c.log.push_back("transcript:");
  c.log.push_back(Transcript(play.protocol, h.traffic()));
  if (c.random.session_path.empty()) return;
  SaveFailingSession(c.random.session_path, play.protocol, c.target,
                     play.note + ", seed " + std::to_string(c.random.seed) + ", shrunk to " +
                         std::to_string(steps.size()) + " step(s)",
                     h.traffic(), c.log);
}

}  // namespace moco::conformance

#endif  // MOCO_CONFORMANCE_CORE_SEQUENCE_H_
