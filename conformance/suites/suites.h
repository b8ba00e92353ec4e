// The DMC v2 scenario suites of mococheck (dmc-v2-protocol.txt, every section
// a suite exercises is named in its case): fixed, deterministic cases and a
// seeded random sequence of valid requests.
#ifndef MOCO_CONFORMANCE_SUITES_SUITES_H_
#define MOCO_CONFORMANCE_SUITES_SUITES_H_

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "conformance/rules/catalogue.h"
#include "conformance/runner/host.h"
#include "conformance/targets/target.h"

namespace moco::conformance {

// Options of the random sequence suite.
struct RandomOptions {
  uint64_t seed = 1;
  int steps = 40;            // requests per sequence
  std::string session_path;  // where a failing sequence is saved (empty: not saved)
};

// What a case works with. The host has read the device's HI already.
struct CaseContext {
  DmcHost& host;
  Verdicts& v;
  const dmc::HiResponse& hi;
  Target& target;
  const HostOptions& host_options;
  const RandomOptions& random;
  std::vector<std::string>& log;  // lines for the report (transcripts, saved files)
};

struct Case {
  std::string suite;  // "connect", "motor", "errors", "limits", "rt", "gomotion", "random"
  std::string name;   // unique within the suite
  Needs needs = Needs::kNothing;
  std::string summary;
  std::function<void(CaseContext&)> run;
};

// Every DMC v2 case in run order.
const std::vector<Case>& DmcCases();

// --- used by the cases and the random suite --------------------------------------------

// Positions from MOTOR_GET_POSITION, or nullopt when the answer is missing.
std::optional<std::vector<int32_t>> GetPositions(DmcHost& host);
// Polls MOTOR_STATUS every 50 ms until nothing moves or `timeout_ns` passes.
bool WaitRest(DmcHost& host, TimeNs timeout_ns);
// The random suite's case: a sequence of valid motor requests drawn from
// `random.seed`, checked against a model of where each motor must end; a
// failing sequence is shrunk (on a restartable target), printed and saved.
void RandomSequence(CaseContext& c);

// Human-readable transcript of the host's traffic, one frame per line.
std::string Transcript(const DmcHost& host);

}  // namespace moco::conformance

#endif  // MOCO_CONFORMANCE_SUITES_SUITES_H_
