// What the StackShot 3X case files share (stackshot_cases.cpp,
// stackshot_cases_settings.cpp): the checks every case makes, typed moves,
// and the cases of stackshot_cases_settings.cpp the case table lists.
// Internal to the StackShot suites.
#ifndef MOCO_CONFORMANCE_PROTOCOLS_STACKSHOT_STACKSHOT_CASES_INTERNAL_H_
#define MOCO_CONFORMANCE_PROTOCOLS_STACKSHOT_STACKSHOT_CASES_INTERNAL_H_

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "conformance/protocols/stackshot/stackshot_suites.h"

namespace moco::conformance::ss_cases {

// Evidence at record `r` (or at the host's time when there is none).
Evidence EvOf(const SsHost& h, const SsRecord* r, std::string expected, std::string observed);
bool Expect(SsCaseContext& c, std::string_view rule, bool ok, std::string expected,
            std::string observed);
// `rule` passes when `r` has status `want`.
bool ExpectStatus(SsCaseContext& c, std::string_view rule, const SsRecord* r,
                  stackshot::Action want);
// `rule` and SS-CODE-003 pass when `r` is RSP_OK.
bool ExpectOk(SsCaseContext& c, std::string_view rule, const SsRecord* r);
// `rule` passes when `r` is answered with anything but RSP_OK.
bool ExpectRefused(SsCaseContext& c, std::string_view rule, const SsRecord* r);
// A relative CC_RAIL_MOVE of `delta_steps`.
stackshot::HostCommand Move(uint8_t axis, int64_t delta_steps, bool backlash = false);
// A relative CC_RAIL_MOVE_AT_SPEED of `delta_steps` at `fraction` of full speed.
stackshot::HostCommand MoveAtSpeed(uint8_t axis, int64_t delta_steps, float fraction);
// Moves `axis` back to `steps` (relative move from where it rests).
void ReturnTo(SsCaseContext& c, uint8_t axis, int64_t steps);
// The axes the device has: X, or X, Y and Z.
std::vector<uint8_t> Axes(const SsCaseContext& c);
// "1234", or "no position".
std::string Steps(std::optional<int64_t> p);

// --- the config, NVM, stack and curve cases (stackshot_cases_settings.cpp)
void ConfigValuesCase(SsCaseContext& c);
void ConfigRangesCase(SsCaseContext& c);
void ConfigUnitsCase(SsCaseContext& c);
void NameCase(SsCaseContext& c);
void SlotsCase(SsCaseContext& c);
void PowerOnConfigCase(SsCaseContext& c);
void NvmRegistersCase(SsCaseContext& c);
void SerialCase(SsCaseContext& c);
void NvmPersistCase(SsCaseContext& c);
void StackCase(SsCaseContext& c);
void CurveCase(SsCaseContext& c);
void BadCurveCase(SsCaseContext& c);

}  // namespace moco::conformance::ss_cases

#endif  // MOCO_CONFORMANCE_PROTOCOLS_STACKSHOT_STACKSHOT_CASES_INTERNAL_H_
