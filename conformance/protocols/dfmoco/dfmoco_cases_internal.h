// What the DFMoco case files share (dfmoco_cases.cpp and dfmoco_cases_*.cpp): the
// timing constants (dfmoco_timing.h), the checks and queries every case makes, and the
// cases of the other files that the case table in dfmoco_cases.cpp lists. Internal to
// the DFMoco suites.
#ifndef MOCO_CONFORMANCE_PROTOCOLS_DFMOCO_DFMOCO_CASES_INTERNAL_H_
#define MOCO_CONFORMANCE_PROTOCOLS_DFMOCO_DFMOCO_CASES_INTERNAL_H_

#include <cstdint>
#include <functional>
#include <initializer_list>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "conformance/protocols/dfmoco/dfmoco_suites.h"
#include "conformance/protocols/dfmoco/dfmoco_timing.h"

namespace moco::conformance::dfmoco_cases {

std::string Str(int64_t v);
// Evidence at line `l` (or at the host's time when there is none).
Evidence EvOf(const DfmHost& h, const DfmLine* l, std::string expected, std::string observed);
bool Expect(DfmCaseContext& c, std::string_view rule, bool ok, std::string expected,
            std::string observed);
// "mm 1 500": a command word and its arguments.
std::string Cmd(std::string_view word, std::initializer_list<int64_t> args);
// The answer deadline of the run's host options.
TimeNs Tolerance(const DfmCaseContext& c);
// Positions of motors 1..n, or nullopt when one is missing.
std::optional<std::vector<int32_t>> Positions(DfmHost& h, int32_t n);
// "[1, 2, 3]".
std::string Vec(const std::vector<int32_t>& v);
// Rest, judged by DFM-MS-004; `while_moving` as DfmWaitRest's.
DfmRest Rest(DfmCaseContext& c, const std::function<void()>& while_moving = {});
// Whether the `ms` answer `l` shows motor `motor` moving.
bool ShowsMoving(const DfmLine* l, int32_t motor);

// --- the motor and shoot cases (dfmoco_cases_motor.cpp)
void Move(DfmCaseContext& c);
void PulseRate(DfmCaseContext& c);
void Stop(DfmCaseContext& c);
void StopAll(DfmCaseContext& c);
void FastReversal(DfmCaseContext& c);
void NewPositionZero(DfmCaseContext& c);
void Jog(DfmCaseContext& c);
void Inch(DfmCaseContext& c);
void Shoot(DfmCaseContext& c);

// --- the go-motion cases (dfmoco_cases_gomotion.cpp)
void Blur(DfmCaseContext& c);
void GoAtOnce(DfmCaseContext& c);
void BlurTooFast(DfmCaseContext& c);

// --- the StackShot 3X dialect's cases (dfmoco_cases_stackshot.cpp)
void SsPositionsAll(DfmCaseContext& c);
void SsMoveReports(DfmCaseContext& c);
void SsNewPosition(DfmCaseContext& c);
void SsStopAllMotor(DfmCaseContext& c);
void SsPulseRate(DfmCaseContext& c);
void SsNoGoMotion(DfmCaseContext& c);

}  // namespace moco::conformance::dfmoco_cases

#endif  // MOCO_CONFORMANCE_PROTOCOLS_DFMOCO_DFMOCO_CASES_INTERNAL_H_
