// What every protocol's host shares (dmc_host, dfmoco_host, stackshot_host):
// the timing options of the checks, the traffic as it crossed the link, and
// the link itself: writes that read what the device wrote at once, reads
// until a deadline, and a lost link that ends every wait.
#ifndef MOCO_CONFORMANCE_CORE_HOST_LINK_H_
#define MOCO_CONFORMANCE_CORE_HOST_LINK_H_

#include <functional>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "conformance/core/verdicts.h"
#include "conformance/targets/target.h"
#include "wire/bytes.h"

namespace moco::conformance {

// Timing options of the checks, in the target's clock.
struct HostOptions {
  TimeNs deadline_ns = 250 * sim::kNsPerMs;  // DMC-DL-*: an answer within this
  // Per request kind, overriding deadline_ns: "hi" (DMC-DL-001), "query"
  // (DL-002), "command" (DL-003), "upload" (DL-004), "rt" (DL-005).
  std::map<std::string, TimeNs, std::less<>> deadline_by_kind_ns;
  TimeNs answer_timeout_ns = 2000 * sim::kNsPerMs;  // DMC-ACK-001: no answer after this
  TimeNs position_gap_ns = 200 * sim::kNsPerMs;     // DMC-POS-002: largest update gap
  TimeNs quiet_ns = 50 * sim::kNsPerMs;             // listened for after a case
  // DFMoco only (--dialect): "auto" (the StackShot 3X dialect when `hi` is
  // exactly the StackShot's, else the sketch's), "sketch" or "stackshot3x".
  std::string dfmoco_dialect = "auto";
};

// The request kinds of HostOptions::deadline_by_kind_ns.
inline constexpr const char* kDeadlineKinds[] = {"hi", "query", "command", "upload", "rt"};

// One chunk of traffic as it crossed the link.
struct Chunk {
  TimeNs t_ns = 0;
  bool from_host = true;
  wire::Bytes bytes;
};

// The link between a host and its target. Every byte either way is kept in
// traffic(); every byte the device sends goes to `on_bytes`.
class HostLink {
 public:
  // `target` must outlive the link and be open.
  HostLink(Target& target, std::function<void(wire::ByteView)> on_bytes)
      : target_(target), on_bytes_(std::move(on_bytes)) {}

  // Writes `bytes` as they are, then reads what the device wrote at once
  // (in-process: the answer).
  void Write(wire::ByteView bytes);
  // Writes `bytes` without reading: for a host answering the device from
  // within `on_bytes` (an ACK of an unsolicited message).
  void WriteWithoutReading(wire::ByteView bytes);
  // Writes `bytes` one at a time, reading in between.
  void WriteBytewise(wire::ByteView bytes);
  // Reads once, until bytes arrive or `deadline_ns`.
  void Pump(TimeNs deadline_ns);
  // Reads for `duration_ns` (less when the link is lost).
  void Idle(TimeNs duration_ns);
  // Reads until `done()` holds; false when `until` passed or the link was
  // lost first.
  template <typename Done>
  bool ReadUntil(TimeNs until, Done&& done) {
    while (!done()) {
      if (lost_ || Now() >= until) return false;
      Pump(until);
    }
    return true;
  }
  // Reads until an item of `items` (a container the device's bytes fill)
  // with index >= `from` satisfies `pred` or `timeout_ns` passes; returns its
  // index or -1.
  template <typename Items, typename Pred>
  int WaitFor(const Items& items, size_t from, TimeNs timeout_ns, Pred&& pred) {
    const TimeNs until = Now() + timeout_ns;
    size_t i = from;
    for (;;) {
      for (; i < items.size(); ++i) {
        if (pred(items[i])) return static_cast<int>(i);
      }
      if (lost_ || Now() >= until) return -1;
      Pump(until);
    }
  }

  TimeNs Now() const { return target_.Now(); }
  bool lost() const { return lost_; }
  const std::vector<Chunk>& traffic() const { return traffic_; }

 private:
  Target& target_;
  std::function<void(wire::ByteView)> on_bytes_;
  std::vector<Chunk> traffic_;
  bool lost_ = false;
};

// What every protocol's host is made of (DmcHost, DfmHost, SsHost): its link
// to the target, the verdicts it judges into and the timing options of the
// checks. The host derives from it and hands the link its own byte handler.
class HostBase {
 public:
  HostBase(const HostBase&) = delete;
  HostBase& operator=(const HostBase&) = delete;

  TimeNs Now() const { return link_.Now(); }
  bool link_lost() const { return link_.lost(); }
  const std::vector<Chunk>& traffic() const { return link_.traffic(); }
  Verdicts& verdicts() { return verdicts_; }
  const HostOptions& options() const { return options_; }
  // Reads for `duration_ns`.
  void Idle(TimeNs duration_ns) { link_.Idle(duration_ns); }

 protected:
  // `target` and `verdicts` must outlive the host; `on_bytes` gets every byte
  // the device sends (it is first called after construction).
  HostBase(Target& target, Verdicts& verdicts, HostOptions options,
           std::function<void(wire::ByteView)> on_bytes)
      : link_(target, std::move(on_bytes)), verdicts_(verdicts), options_(std::move(options)) {}
  ~HostBase() = default;

  HostLink link_;
  Verdicts& verdicts_;
  HostOptions options_;
};

}  // namespace moco::conformance

#endif  // MOCO_CONFORMANCE_CORE_HOST_LINK_H_
