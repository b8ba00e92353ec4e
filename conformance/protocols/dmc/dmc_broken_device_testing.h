// Test support: a DMC-16 broken on purpose. The real emulated device with a
// filter on its output (each frame it writes handed to a Breakage) and,
// optionally, on its input (the host's bytes changed before it reads them),
// run through the whole runner; proving tests plant a fault this way and show
// the rule that names it failing (conformance/core/rule_proof_testing.h).
#ifndef MOCO_CONFORMANCE_PROTOCOLS_DMC_DMC_BROKEN_DEVICE_TESTING_H_
#define MOCO_CONFORMANCE_PROTOCOLS_DMC_DMC_BROKEN_DEVICE_TESTING_H_

#include <gtest/gtest.h>

#include <functional>
#include <memory>
#include <string>

#include "conformance/core/report.h"
#include "conformance/core/rule_proof_testing.h"
#include "conformance/protocols/dmc/dmc_broken_device.h"
#include "conformance/protocols/dmc/dmc_protocol.h"

namespace moco::conformance::dmc_testing {

using dmc::MsgType;
using dmc::ToWire;

inline RunReport RunBroken(Breakage b, RunOptions options = {}, const std::string& profile = "",
                           InputBreakage in = {}) {
  InProcessTarget target("dmc16-broken",
                         [b, profile, in](sim::Scheduler& s, devices::ByteSink& out) {
                           return std::make_unique<BrokenDmc16>(s, out, b, profile, in);
                         });
  EXPECT_FALSE(target.Open().has_value());
  return RunDmc(target, options);
}

using proof::ExpectCaught;

}  // namespace moco::conformance::dmc_testing

#endif  // MOCO_CONFORMANCE_PROTOCOLS_DMC_DMC_BROKEN_DEVICE_TESTING_H_
