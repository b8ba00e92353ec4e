// Proving tests of the DFMoco pin rules (conformance/rules/pin_rules.cpp;
// FACTS "Step drivers", "DFMoco"): the DFMoco test firmware
// (fixtures/firmware/dfmoco_avr) built with one fault switch each (dfmoco.c
// "Fault switches", fixtures/firmware/CMakeLists.txt) runs under the simavr
// target with its STEP/DIR pins watched, as `mococheck run --target simavr:ELF
// --board fixtures/boards/own-dfmoco.json --driver a4988` runs it
// (targets/simavr_pins_cli_test.sh); the fault fails its rule and no other,
// and the firmware without a fault passes every pin rule.
#include <gtest/gtest.h>

#include <cstdlib>
#include <set>
#include <string>
#include <variant>

#include "conformance/protocols/dfmoco/dfmoco_pin_proofs_testing.h"
#include "conformance/targets/simavr_pins.h"
#include "conformance/targets/simavr_target.h"

namespace moco::conformance {
namespace {

// Every DFMoco case of the firmware `elf` under simavr, its pins judged.
RunReport RunWithPins(const char* elf) {
  SimavrTarget target(SimavrSpec{elf, "", 0});
  return RunOwnDfmocoWithPins(target);
}

void ExpectOnly(const RunReport& r, const std::string& rule, bool must) {
  ExpectOnlyRuleFailed(r, rule, must);
}

// The firmware without a fault passes every pin rule, through the command
// line: CTest mococheck_simavr_pins_own_firmware_passes (simavr_pins_cli_test.sh).

TEST(SimavrPinProofs, AStepCountedButNeverPulsedIsCaughtByPin001) {
  // FAULT_LOST_STEP: every 1000th step moves the position, not the STEP pin.
  ExpectOnly(RunWithPins(MOCO_DFMOCO_FAULT_LOST_STEP_ELF), "DFM-PIN-001", true);
}

TEST(SimavrPinProofs, AMovingPositionReportingTheDestinationIsCaughtByPin002) {
  // FAULT_REPORT_TARGET: the once-a-second `mp` of a moving motor names its target.
  ExpectOnly(RunWithPins(MOCO_DFMOCO_FAULT_REPORT_TARGET_ELF), "DFM-PIN-002", true);
}

TEST(SimavrPinProofs, AStepPulseShorterThanTheDriverNeedsIsCaughtByPin003) {
  // FAULT_SHORT_PULSE: STEP is lowered a few cycles after it rises (A4988: >= 1 us).
  ExpectOnly(RunWithPins(MOCO_DFMOCO_FAULT_SHORT_PULSE_ELF), "DFM-PIN-003", true);
}

TEST(SimavrPinProofs, DirWrittenWithTheStepEdgeIsCaughtByPin004) {
  // FAULT_DIR_WITH_STEP: DIR changes in the port write that raises STEP (A4988: 200 ns setup).
  ExpectOnly(RunWithPins(MOCO_DFMOCO_FAULT_DIR_WITH_STEP_ELF), "DFM-PIN-004", true);
}

TEST(SimavrPinProofs, StepsFasterThanTheBoardsMaximumAreCaughtByPin005) {
  // FAULT_OVERSPEED: a 50 kHz step timer lets pr 20000 run at 25000 steps/s.
  ExpectOnly(RunWithPins(MOCO_DFMOCO_FAULT_OVERSPEED_ELF), "DFM-PIN-005", true);
}

TEST(SimavrPinProofs, AMoveStartingAtFullSpeedIsCaughtByPin006) {
  // FAULT_NO_RAMP: no acceleration ramp.
  ExpectOnly(RunWithPins(MOCO_DFMOCO_FAULT_NO_RAMP_ELF), "DFM-PIN-006", false);
}

TEST(SimavrPinProofs, DirFlippedAtSpeedIsCaughtByPin007) {
  // FAULT_REVERSE_AT_SPEED: DIR flips as soon as a new target lies behind.
  ExpectOnly(RunWithPins(MOCO_DFMOCO_FAULT_REVERSE_AT_SPEED_ELF), "DFM-PIN-007", false);
}

}  // namespace
}  // namespace moco::conformance
