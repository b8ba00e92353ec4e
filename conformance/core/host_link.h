// What every protocol's host shares (dmc_host, dfmoco_host, stackshot_host):
// the timing options of the checks, the traffic as it crossed the link, and
// the link itself: writes that read what the device wrote at once, reads
// until a deadline, and a lost link that ends every wait.
#ifndef MOCO_CONFORMANCE_CORE_HOST_LINK_H_
#define MOCO_CONFORMANCE_CORE_HOST_LINK_H_

#include <functional>
#include <map>
#include <memory>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "conformance/core/verdicts.h"
#include "conformance/targets/target.h"
#include "wire/bytes.h"

namespace moco::conformance {

// HostOptions::dialect when the protocol picks the dialect itself.
inline constexpr std::string_view kAutoDialect = "auto";

// A dialect a protocol's devices may speak, as mococheck run --dialect names
// it: "sketch", "Dragonframe's Arduino sketch".
struct DialectChoice {
  std::string_view name;
  std::string_view description;
};

// Timing options of the checks, in the target's clock. The defaults are the
// runner's, for every protocol (mococheck run --deadline-ms,
// --answer-timeout-ms, --position-gap-ms); no specification gives a number for
// them. A protocol's own timing is in its <p>_timing.h.
struct HostOptions {
  TimeNs deadline_ns = 250 * sim::kNsPerMs;  // the *-DL-* rules: an answer within this
  // Per request kind, overriding deadline_ns: "hi" (DMC-DL-001), "query"
  // (DL-002), "command" (DL-003), "upload" (DL-004), "rt" (DL-005).
  std::map<std::string, TimeNs, std::less<>> deadline_by_kind_ns;
  TimeNs answer_timeout_ns = 2000 * sim::kNsPerMs;  // DMC-ACK-001: no answer after this
  TimeNs position_gap_ns = 200 * sim::kNsPerMs;     // DMC-POS-002: largest update gap
  TimeNs quiet_ns = 50 * sim::kNsPerMs;             // listened for after a case
  // Once the device has left this many requests of a kind unanswered in a
  // row (with no answer of that kind in between), or this many requests of
  // any kind, the hosts of the run stop waiting for answers it has shown it
  // does not give: such a request is judged unanswered at once, as it would
  // be after the answer timeout, until the device answers again. A broken
  // device is then judged in about the time of a good one, with the same
  // rules failing. 0: every answer is waited out (mococheck run
  // --wait-every-answer).
  int give_up_after_unanswered = 3;
  // What the hosts of one run learned of the device's unanswered requests
  // (the runner shares one per run); null: each host keeps its own.
  std::shared_ptr<struct UnansweredRequests> unanswered;
  // The dialect the device is judged in (mococheck run --dialect):
  // kAutoDialect (the protocol tells it from the device's introduction) or
  // one of the protocol's dialects (its traits' kDialects, core/run.h). A
  // protocol without dialects takes kAutoDialect only.
  std::string dialect = std::string(kAutoDialect);
};

// The request kinds of HostOptions::deadline_by_kind_ns.
inline constexpr const char* kDeadlineKinds[] = {"hi", "query", "command", "upload", "rt"};

// The requests the device left unanswered, shared by the hosts of a run:
// per kind ("MOTOR_STATUS", "mm", "CC_RAIL_MOVE write"), and of any kind, how
// many in a row.
struct UnansweredRequests {
  std::map<std::string, int, std::less<>> by_kind;
  int in_a_row = 0;
};

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
  // The answers this host did not wait for, the device having shown it does
  // not give them: "" or "answers not waited for (...): MOTOR_STATUS x12, HI x1".
  std::string NotWaitedForSummary() const;
  // While a case greets the device (the runner's preparation and the
  // introduction), only a kind's own unanswered requests make it hopeless, not
  // a run of unanswered requests of any kind: the greeting is how the run
  // learns whether the device still answers at all.
  void set_greeting(bool greeting) { greeting_ = greeting; }

 protected:
  // `target` and `verdicts` must outlive the host; `on_bytes` gets every byte
  // the device sends (it is first called after construction).
  HostBase(Target& target, Verdicts& verdicts, HostOptions options,
           std::function<void(wire::ByteView)> on_bytes);
  ~HostBase() = default;

  // Whether the host stops waiting for answers the device does not give
  // (options().give_up_after_unanswered > 0).
  bool gives_up() const { return options_.give_up_after_unanswered > 0; }
  // Records that a request of `kind` went unanswered (its rule judged).
  void Unanswered(std::string_view kind);
  // Records that a request of `kind` was answered (late answers too).
  void Answered(std::string_view kind);
  // When waiting for the answer to a request of `kind` is pointless
  // (Hopeless), judges it unanswered at once: `fail(observed)` judges the
  // request's rule, and the request counts as unanswered. True when so: the
  // caller returns without waiting.
  template <typename Fail>
  bool JudgedWithoutWaiting(std::string_view kind, Fail&& fail) {
    const std::string why = Hopeless(kind);
    if (why.empty()) return false;
    fail("not waited for: " + why);
    NotWaitedFor(kind);
    Unanswered(kind);
    return true;
  }

  HostLink link_;
  Verdicts& verdicts_;
  HostOptions options_;

 private:
  // Why waiting for the answer to a request of `kind` is pointless ("" when it
  // is not): the device left the last give_up_after_unanswered requests of
  // that kind, or (outside a greeting) of any kind, unanswered.
  std::string Hopeless(std::string_view kind) const;
  void NotWaitedFor(std::string_view kind) { ++not_waited_for_[std::string(kind)]; }

  std::map<std::string, int, std::less<>> not_waited_for_;  // by kind
  bool greeting_ = false;
};

}  // namespace moco::conformance

#endif  // MOCO_CONFORMANCE_CORE_HOST_LINK_H_
