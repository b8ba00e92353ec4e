// How long mococheck takes to judge a broken device, next to a good one
// (docs/benchmarks.md "Broken devices"). Each run is the full DMC suite
// in-process, in virtual time: the target time of a run is what the same run
// waits over a serial port or a PTY, where the device's time is real time.
// Broken devices: the emulated DMC-16 with every frame's checksum wrong,
// every ID wrong, no answer to MOTOR_STATUS, and one that stops writing
// halfway through the run. Each broken device runs twice: as the runner
// does by default (a case stops once its requests go unanswered) and with
// every answer waited out (--wait-every-answer), and the two must fail the
// same rules.
#include <cstdio>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "conformance/protocols/dmc/dmc_broken_device.h"
#include "conformance/protocols/dmc/dmc_protocol.h"

namespace moco::conformance {
namespace {

using dmc_testing::Breakage;
using dmc_testing::BrokenDmc16;

struct Outcome {
  double target_s = 0;
  double wall_s = 0;
  std::set<std::string> failing;  // MUST and SHOULD rules that failed
  size_t frames = 0;              // frames the device wrote (before its breakage)
};

Outcome RunOnce(const Breakage& breakage, bool wait_every_answer) {
  auto frames = std::make_shared<size_t>(0);
  InProcessTarget target("dmc16-broken",
                         [breakage, frames](sim::Scheduler& s, devices::ByteSink& out) {
                           return std::make_unique<BrokenDmc16>(
                               s, out,
                               [breakage, frames](const dmc::FrameRef& f, wire::Bytes raw,
                                                  sim::Scheduler& sch, devices::ByteSink& o) {
                                 ++*frames;
                                 breakage(f, std::move(raw), sch, o);
                               },
                               "");
                         });
  Outcome outcome;
  if (auto error = target.Open()) {
    std::fprintf(stderr, "cannot open the in-process device: %s\n", error->c_str());
    return outcome;
  }
  RunOptions options;
  if (wait_every_answer) options.host.give_up_after_unanswered = 0;
  const RunReport report = RunDmc(target, options);
  for (const CaseResult& c : report.cases)
    outcome.target_s += static_cast<double>(c.target_ns) / 1e9;
  outcome.wall_s = report.wall_s;
  for (const auto& [id, summary] : report.rules) {
    if (summary.status == Status::kFail) outcome.failing.insert(id);
  }
  outcome.frames = *frames;
  return outcome;
}

std::string Join(const std::set<std::string>& ids) {
  std::string out;
  for (const std::string& id : ids) out += (out.empty() ? "" : " ") + id;
  return out;
}

}  // namespace
}  // namespace moco::conformance

int main() {
  using namespace moco;
  using namespace moco::conformance;
  const Outcome good = RunOnce(dmc_testing::PassThrough, false);
  const size_t half = good.frames / 2;
  struct Device {
    const char* name;
    Breakage breakage;
  };
  auto written = std::make_shared<size_t>(0);
  const std::vector<Device> devices = {
      {"wrong checksum (every frame)",
       [](const dmc::FrameRef&, wire::Bytes raw, sim::Scheduler&, devices::ByteSink& out) {
         raw.back() = static_cast<uint8_t>(raw.back() ^ 0x5a);
         out.Write(raw);
       }},
      {"wrong ID (every frame, ID + 0x100)",
       [](const dmc::FrameRef& f, wire::Bytes, sim::Scheduler&, devices::ByteSink& out) {
         out.Write(dmc_testing::Reencode(f, f.id + 0x100, f.data));
       }},
      {"wrong checksum (every frame but HI)",
       [](const dmc::FrameRef& f, wire::Bytes raw, sim::Scheduler&, devices::ByteSink& out) {
         if (f.type != dmc::ToWire(dmc::MsgType::kHi))
           raw.back() = static_cast<uint8_t>(raw.back() ^ 0x5a);
         out.Write(raw);
       }},
      {"wrong ID (every frame but HI)",
       [](const dmc::FrameRef& f, wire::Bytes raw, sim::Scheduler&, devices::ByteSink& out) {
         if (f.type == dmc::ToWire(dmc::MsgType::kHi)) {
           out.Write(raw);
         } else {
           out.Write(dmc_testing::Reencode(f, f.id + 0x100, f.data));
         }
       }},
      {"no answer to MOTOR_STATUS",
       [](const dmc::FrameRef& f, wire::Bytes raw, sim::Scheduler&, devices::ByteSink& out) {
         if (f.type != dmc::ToWire(dmc::MsgType::kMotorStatus)) out.Write(raw);
       }},
      {"stops writing halfway through the run",
       [written, half](const dmc::FrameRef&, wire::Bytes raw, sim::Scheduler&,
                       devices::ByteSink& out) {
         if ((*written)++ < half) out.Write(raw);
       }},
  };
  std::printf("DMC suite in-process; target time = what a serial or PTY run waits\n\n");
  std::printf("| device | target time | x good | waiting every answer | same failing rules |\n");
  std::printf("| --- | --- | --- | --- | --- |\n");
  std::printf("| good | %.1f s | 1.00 | - | %zu failing |\n", good.target_s, good.failing.size());
  int worse = 0;
  for (const Device& d : devices) {
    *written = 0;
    const Outcome fast = RunOnce(d.breakage, false);
    *written = 0;
    const Outcome slow = RunOnce(d.breakage, true);
    const double ratio = fast.target_s / good.target_s;
    const bool same = fast.failing == slow.failing;
    std::printf("| %s | %.1f s | %.2f | %.1f s | %s (%zu) |\n", d.name, fast.target_s, ratio,
                slow.target_s, same ? "yes" : "NO", fast.failing.size());
    if (!same) {
      std::set<std::string> only_fast, only_slow;
      for (const auto& id : fast.failing) {
        if (!slow.failing.count(id)) only_fast.insert(id);
      }
      for (const auto& id : slow.failing) {
        if (!fast.failing.count(id)) only_slow.insert(id);
      }
      std::printf("|   only when stopping early: %s; only when waiting: %s | | | | |\n",
                  Join(only_fast).c_str(), Join(only_slow).c_str());
    }
    worse += (ratio > 2.0 || !same);
  }
  return worse == 0 ? 0 : 1;
}
